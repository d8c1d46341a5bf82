#!/usr/bin/env python3
"""Medians of `tools/side_by_side.sh` output (`scene tool round seconds` per line): one row per
scene with each tool's median and the original's median divided by each of ours."""
import statistics
import sys
from collections import defaultdict

runs = defaultdict(lambda: defaultdict(list))
for line in open(sys.argv[1]):
    parts = line.split()
    if len(parts) == 4:
        runs[parts[0]][parts[1]].append(float(parts[3]))

for scene, tools in runs.items():
    med = {tool: statistics.median(times) for tool, times in tools.items()}
    cells = [f"{tool}={t:.4g}" for tool, t in med.items()]
    if "original" in med:
        cells += [f"ratio({tool})={med['original'] / t:.2f}" for tool, t in med.items() if tool != "original"]
    print(scene, " ".join(cells))
