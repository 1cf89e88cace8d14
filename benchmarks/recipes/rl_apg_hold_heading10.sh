#!/usr/bin/env bash
# APG holding the goal before T_con with the heading's error in that window at twice the weight, v2, 30 min a seed.
# APG from an open-loop teacher, time-scaled, holding the goal over the last 20 control periods before T_con with the
# heading's error in the same window at 10 per radian (hold_heading_weight 10, twice that of
# apg-hold-heading-time-scaled-30min-v2) on DWRPointStabilization-v2: apg-hold-heading10-time-scaled-30min-v2 (560 M env
# steps: the goal's 30 minutes of a core), SEEDS (5) seeds, two runs side by side on one core each (about 30 minutes a
# pair on 2 cores with the evaluation, about 1.5 hours in all; 40 minutes a pair on a machine 1.37x slower), on the benchmark's sets and at T_con 10, 20, 40 and
# 60 s. Writes docs/rl_benchmark/apg_hold_heading10.json (tables rl-apg-hold-heading10 and
# rl-apg-hold-heading10-per-T_con; rows of docs/what-was-tried.md) and its curves, and ships the best seed as
# train/pretrained/apg_v2.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-hold-heading10}
dwr-gym benchmark --agents "apg-hold-heading10-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_hold_heading10.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_hold_heading10_curves_steps.png
python -m benchmarks run ship-rl-agents "$OUT"
python -m benchmarks render
