#!/usr/bin/env bash
# APG from an open-loop teacher, time-scaled, holding the goal over the last tenth of each episode's T_con (hold_fraction
# 0.1: 20 control periods at T_con 10 s, 120 at 60 s) with the heading's error in that window at 10 per radian, on
# DWRPointStabilization-v2: apg-hold-fraction-heading10-time-scaled-30min-v2 (560 M env steps), SEEDS (5) seeds, two
# runs side by side on one core each (about 40 minutes a pair on 2 cores with the evaluation, about 2 hours in all),
# on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes docs/rl_benchmark/apg_hold_fraction.json (tables
# rl-apg-hold-fraction and rl-apg-hold-fraction-per-T_con in docs/rl-apg-levers.md) and its curves. It ships no agent:
# its seeds spend more energy than the heading-10 entry's for no more arrivals (docs/rl-apg-levers.md, "Levers for the
# short deadline"); `python -m benchmarks run ship-rl-agents "$OUT" --also ENTRY` would ship the best seed.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-hold-fraction}
dwr-gym benchmark --agents "apg-hold-fraction-heading10-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_hold_fraction.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_hold_fraction_curves_steps.png
python -m benchmarks render
