#!/usr/bin/env bash
# APG from the teacher, time-scaled, the near-miss changes and the miss before T_con in the gradient, v2, 30 min a seed.
# APG from an open-loop teacher, time-scaled, with the near-miss entry's two changes (clone_steps 16000,
# near_miss_clip 16) and the miss over the last 20 control periods before T_con in the gradient too (hold_steps 20)
# on DWRPointStabilization-v2: apg-hold-time-scaled-30min-v2 (560 M env steps: the goal's 30 minutes of a core), and
# apg-hold-heading-time-scaled-30min-v2 with the heading's error over the same window too (hold_heading_weight 5),
# SEEDS (5) seeds of each, two runs side by side on one core each (about 30 minutes a pair on 2 cores with the
# evaluation: about 2.5 hours in all), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes
# docs/rl_benchmark/apg_hold.json (tables rl-apg-hold and rl-apg-hold-per-T_con; rows of docs/what-was-tried.md) and its
# curves.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-hold}
dwr-gym benchmark --agents "apg-hold-time-scaled-30min-v2:threads=1" "apg-hold-heading-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_hold.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_hold_curves_steps.png
python -m benchmarks render
