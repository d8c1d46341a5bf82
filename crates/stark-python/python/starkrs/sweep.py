"""Sweeps from Python: the sweep files of ``stark sweep`` run as one task per case, locally or on
a Ray cluster.

A sweep file names a base scene and a grid (see ``sweeps/kobuki_towel.toml``)::

    from starkrs import sweep
    sweep.run("sweeps/kobuki_towel.toml")                          # Ray on this machine
    sweep.run("sweeps/kobuki_towel.toml", ray_address="auto")      # a running Ray cluster

Each case is a Ray task calling this module (``run_case``): it builds the scene, continues
from the case's checkpoint if there is one, runs in chunks of ``checkpoint_every_s`` writing a
checkpoint after each, and writes the case's result file (the run summary, and for the
robot–towel scenes the outcome and the lab's) to the sweep's ``results`` folder. Finished cases
(their result file exists) are skipped, so a sweep stopped anywhere continues where it was. The
files are the same as ``stark sweep`` writes: either tool can continue the other's sweep. On a
cluster, ``out`` and ``results`` must be on a file system every node sees (or run on one node
per sweep), and each task asks Ray for ``threads`` CPUs.
"""

from __future__ import annotations

import itertools
import json
import os
import pathlib
from typing import Any, Optional

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover
    import tomli as tomllib  # type: ignore[no-redef]


def _value_text(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def plan(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a sweep file: its settings (paths made absolute) and its cases, in the order and
    with the names ``stark sweep`` gives them."""
    path = pathlib.Path(path)
    with open(path, "rb") as f:
        s = tomllib.load(f)
    known = {"scene", "scene_file", "out", "results", "jobs", "threads", "checkpoint_every_s", "duration_s", "grid"}
    unknown = set(s) - known
    if unknown:
        raise ValueError(f"{path}: unknown field(s) {sorted(unknown)}; known: {sorted(known)}")
    if ("scene" in s) == ("scene_file" in s):
        raise ValueError(f"{path}: give exactly one of `scene` (a built-in scene) and `scene_file`")
    base = path.parent
    grid: dict[str, list[Any]] = dict(sorted(s.get("grid", {}).items()))
    cases = []
    for combo in itertools.product(*[[(k, _value_text(v)) for v in vs] for k, vs in grid.items()]):
        scene = s.get("scene")
        overrides, parts = [], []
        for key, value in combo:
            if "." in key:
                overrides.append(f"{key}={value}")
                parts.append(f"{key.rsplit('.', 1)[-1]}={value}")
            elif scene is not None and "{" + key + "}" in scene:
                scene = scene.replace("{" + key + "}", value)
            else:
                raise ValueError(f"{path}: grid `{key}` is neither used in `scene` nor a dotted `--set` key")
        stem = scene if scene is not None else pathlib.Path(s["scene_file"]).stem
        name = stem if not parts else f"{stem}__{'_'.join(parts)}"
        cases.append(
            {
                "name": name,
                "scene": scene,
                "scene_file": str(base / s["scene_file"]) if "scene_file" in s else None,
                "overrides": overrides,
            }
        )
    return {
        "out": str(base / s["out"]),
        "results": str(base / s["results"]),
        "jobs": int(s.get("jobs", 1)),
        "threads": int(s.get("threads", 1)),
        "checkpoint_every_s": float(s.get("checkpoint_every_s", 0.25)),
        "duration_s": s.get("duration_s"),
        "cases": cases,
    }


def run_case(case: dict[str, Any], settings: dict[str, Any]) -> dict[str, Any]:
    """Run (or continue) one case of a sweep and write its result file; returns the result."""
    import starkrs

    run_dir = pathlib.Path(settings["out"]) / case["name"]
    run_dir.mkdir(parents=True, exist_ok=True)
    if case["scene"] is not None:
        s = starkrs.Settings()
        s.output.directory = str(run_dir)
        s.threads = settings["threads"]
        scene = starkrs.builtin_scene(case["scene"], s)
        if case["overrides"]:
            raise ValueError(f"case {case['name']}: `--set` overrides of a built-in scene are for `stark sweep`")
    else:
        scene = starkrs.load_scene(
            case["scene_file"], output_directory=str(run_dir), threads=settings["threads"], overrides=case["overrides"]
        )
    sim = scene.simulation
    checkpoint = run_dir / f"{scene.name}.ckpt"
    if checkpoint.exists():
        sim.restore_checkpoint(str(checkpoint))
    end = settings["duration_s"] if settings["duration_s"] is not None else scene.duration_s
    chunk = settings["checkpoint_every_s"]

    def check(sim: Any) -> None:
        # As `stark sweep` runs its cases with `--check`: every state (before each step and at the
        # end), independently of the solver; an intersection fails the case.
        c = sim.state_check()
        if c["intersections"] or c["inverted_tets"]:
            raise RuntimeError(
                f"case {case['name']}: at t = {sim.time:.6f} s {len(c['intersections'])} intersection(s) "
                f"({'; '.join(c['intersections'][:3])}) and {c['inverted_tets']} inverted tet(s)"
            )

    summary = None
    while sim.time < end - 1e-9:
        summary = sim.run(min(chunk, end - sim.time), callback=check)
        sim.save_checkpoint(str(checkpoint))
    check(sim)
    if summary is None:
        summary = sim.summary()
    result: dict[str, Any] = {"case": case["name"], "summary": summary, "checked_every_step": True}
    probe = run_dir / f"{scene.name}.robot_towel.jsonl"
    if probe.exists():
        result["outcome"] = starkrs.classify_robot_towel(str(probe))
        result["lab_outcome"] = starkrs.robot_towel_lab_outcome(scene.name)
    results = pathlib.Path(settings["results"])
    results.mkdir(parents=True, exist_ok=True)
    (results / f"{case['name']}.json").write_text(json.dumps(result, indent=2) + "\n")
    return result


def run(
    path: str | os.PathLike[str],
    ray_address: Optional[str] = None,
    num_cpus: Optional[int] = None,
) -> list[dict[str, Any]]:
    """Run a sweep file on Ray: every unfinished case as a task asking for ``threads`` CPUs.
    ``ray_address`` connects to a cluster (``"auto"``: the one this machine belongs to);
    without it Ray starts on this machine with ``num_cpus`` CPUs. Returns every finished
    case's result, in the sweep's order."""
    import ray

    p = plan(path)
    settings = {k: v for k, v in p.items() if k != "cases"}
    results = pathlib.Path(p["results"])
    todo = [c for c in p["cases"] if not (results / f"{c['name']}.json").exists()]
    if not ray.is_initialized():
        if ray_address is not None:
            ray.init(address=ray_address)
        else:
            ray.init(num_cpus=num_cpus, include_dashboard=False)
    task = ray.remote(num_cpus=p["threads"])(run_case)
    ray.get([task.remote(c, settings) for c in todo])
    out = []
    for c in p["cases"]:
        f = results / f"{c['name']}.json"
        if f.exists():
            out.append(json.loads(f.read_text()))
    (results / "summary.json").write_text(json.dumps(out, indent=2) + "\n")
    return out
