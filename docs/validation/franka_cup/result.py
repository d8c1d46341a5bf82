"""The small result file of a franka_cup run (committed beside VALIDATION.md):

    python docs/validation/franka_cup/result.py OUT_DIR SCENE "COMMAND" > docs/validation/franka_cup/SCENE.json

OUT_DIR is the run's output directory (with SCENE.grasp.jsonl and SCENE.steps.jsonl). The file
holds the outcome (`starkrs.grasp_outcome`: the break, the 1 mm slip), the run's steps, Newton
iterations and wall times (whole run and first 2 s), and the probe every 0.2 s."""

import datetime
import json
import sys
from pathlib import Path

import starkrs

POUR_START_S = 1.2


def main(out_dir, scene, command):
    out = Path(out_dir)
    steps = [json.loads(line) for line in open(out / f"{scene}.steps.jsonl")]
    probe = [json.loads(line) for line in open(out / f"{scene}.grasp.jsonl")]
    outcome = starkrs.grasp_outcome(str(out / f"{scene}.grasp.jsonl"), POUR_START_S)
    samples, next_t = [], 0.2
    for line in probe:
        if line["time_s"] >= next_t - 1e-9:
            g = dict(line["grasp"], time_s=line["time_s"])
            g["drop_m"] = outcome["reference_height_m"] - (g["held_z_m"] - g["jaw_z_m"])
            samples.append(g)
            next_t += 0.2
    result = {
        "scene": scene,
        "command": command,
        "date": datetime.date.today().isoformat(),
        "steps": len(steps),
        "newton_per_step": sum(s["newton_iterations"] for s in steps) / len(steps),
        "wall_s": sum(s["wall_time_s"] for s in steps),
        "wall_s_first_2_s": sum(s["wall_time_s"] for s in steps if s["time_s"] <= 2.0 + 1e-9),
        "outcome": outcome,
        "samples_every_0_2_s": samples,
    }
    json.dump(result, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main(*sys.argv[1:4])
