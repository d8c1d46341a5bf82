"""Sweeps on Ray (`starkrs.sweep`): the sweep files of `stark sweep`, one Ray task per case."""

import json
import pathlib

import pytest

from starkrs import sweep

SCENES = pathlib.Path(__file__).resolve().parents[3] / "scenes"


def write_sweep(tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(
        f"""
scene_file = "{SCENES / 'rb_pendulum_chain.toml'}"
out = "runs"
results = "results"
threads = 1
duration_s = 0.1
checkpoint_every_s = 0.05
[grid]
"settings.time_step_s" = [0.02, 0.01]
"""
    )
    return f


def test_plan_names_cases_as_the_cli_does(tmp_path):
    p = sweep.plan(write_sweep(tmp_path))
    assert [c["name"] for c in p["cases"]] == [
        "rb_pendulum_chain__time_step_s=0.02",
        "rb_pendulum_chain__time_step_s=0.01",
    ]
    assert p["cases"][0]["overrides"] == ["settings.time_step_s=0.02"]
    bad = tmp_path / "bad.toml"
    bad.write_text('out = "a"\nresults = "b"\n')
    with pytest.raises(ValueError, match="exactly one of"):
        sweep.plan(bad)


def test_two_cases_on_ray_then_nothing_left(tmp_path):
    ray = pytest.importorskip("ray")
    f = write_sweep(tmp_path)
    try:
        ray.init(num_cpus=2, include_dashboard=False)
        results = sweep.run(f)
        assert [r["case"] for r in results] == [
            "rb_pendulum_chain__time_step_s=0.02",
            "rb_pendulum_chain__time_step_s=0.01",
        ]
        for r in results:
            assert abs(r["summary"]["simulated_time_s"] - 0.1) < 1e-9
            assert r["checked_every_step"]
        # Each ran with its own time step (chunks of 0.05 s end on a shortened step).
        steps = [r["summary"]["steps"] for r in results]
        assert 5 <= steps[0] < steps[1], steps
        assert (tmp_path / "runs" / results[0]["case"]).is_dir()
        # Finished cases are skipped: a second run changes no result file.
        before = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "results").glob("*__*.json")}
        again = sweep.run(f)
        after = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "results").glob("*__*.json")}
        assert before == after and len(again) == 2
        summary = json.loads((tmp_path / "results" / "summary.json").read_text())
        assert len(summary) == 2
    finally:
        ray.shutdown()
