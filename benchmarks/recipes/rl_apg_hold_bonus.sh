#!/usr/bin/env bash
# APG from an open-loop teacher, time-scaled, holding the goal over the last 20 control periods before T_con with the
# heading's error at 10 per radian (the heading-10 entry) and a smooth stand-in for the arrival bonus in that window
# (hold_bonus 10: 10 x sigmoid((1 cm - d) / 5 mm)), on DWRPointStabilization-v2:
# apg-hold-bonus-heading10-time-scaled-30min-v2 (560 M env steps), SEEDS (5) seeds, JOBS (2) runs side by side on one
# core each (about 40 minutes a pair on 2 cores with the evaluation, about 2 hours in all), on the benchmark's sets and
# at T_con 10, 20, 40 and 60 s. Writes docs/rl_benchmark/apg_hold_bonus.json (tables rl-apg-hold-bonus and
# rl-apg-hold-bonus-per-T_con in docs/rl-apg-levers.md) and its curves. It ships no agent (docs/rl-apg-levers.md, "A smooth
# arrival bonus"); `python -m benchmarks run ship-rl-agents "$OUT" --also ENTRY` would ship the best seed.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-hold-bonus}
dwr-gym benchmark --agents "apg-hold-bonus-heading10-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_hold_bonus.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_hold_bonus_curves_steps.png
python -m benchmarks render
