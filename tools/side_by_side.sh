#!/usr/bin/env bash
# Ours against the original C++ Stark, side by side in one sitting (BENCHMARKS.md's protocol):
# per scene one warm-up run of the original (its JIT kernels compile on first use), then N rounds
# alternating the original's `build-and-run.sh run NAME` and our `stark bench --scenes NAME
# --threads 1` (each binary in OURS in turn), timing the whole process. One line per run on
# stdout: `scene tool round seconds`; `tools/medians.py` summarises such a file.
#
#   SCENES="hanging_cloth simple_grasp" OURS="target/release/stark" N=3 tools/side_by_side.sh > runs.txt
#   python3 tools/medians.py runs.txt
#
# Env: STARK_SRC (the original's build, default ~/.cache/stark-original), ORIGINAL_SCRIPT (default
# ../shared/tools/stark-original/build-and-run.sh), NO_ORIGINAL=1 to time ours only.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
script=${ORIGINAL_SCRIPT:-$here/../shared/tools/stark-original/build-and-run.sh}
scenes=${SCENES:-"hanging_cloth hanging_deformable_box deformable_and_rigid_collisions simple_grasp rb_point twisting_cloth spinning_box_cloth"}
ours=${OURS:-$here/target/release/stark}
rounds=${N:-3}

wall() { # seconds of wall clock of the command, its output discarded
    local start end
    start=$(date +%s.%N)
    "$@" > /dev/null 2>&1 || { echo "failed: $*" >&2; return 1; }
    end=$(date +%s.%N)
    echo "$end - $start" | bc -l | xargs printf '%.4f\n'
}

for scene in $scenes; do
    [ "${NO_ORIGINAL:-0}" = 1 ] || wall "$script" run "$scene" > /dev/null
    for round in $(seq 1 "$rounds"); do
        if [ "${NO_ORIGINAL:-0}" != 1 ]; then
            echo "$scene original $round $(wall "$script" run "$scene")"
        fi
        for bin in $ours; do
            echo "$scene $bin $round $(wall "$bin" bench --scenes "$scene" --threads 1)"
        done
    done
done
