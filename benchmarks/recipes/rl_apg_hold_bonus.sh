#!/usr/bin/env bash
# APG from an open-loop teacher, time-scaled, holding the goal over the last 20 control periods before T_con with the
# heading's error at 10 per radian (the heading-10 entry) and a smooth stand-in for the arrival bonus in that window
# (hold_bonus B: B x sigmoid((1 cm - d) / 5 mm)), on DWRPointStabilization-v2, at each weight of WEIGHTS (10 3):
# apg-hold-bonus-heading10-time-scaled-30min-v2 (B 10) and apg-hold-bonus3-heading10-time-scaled-30min-v2 (B 3),
# 560 M env steps a seed, SEEDS (5) seeds, JOBS (2) runs side by side on one core each (about 40 minutes a pair on 2
# cores with the evaluation, about 2 hours a weight), on the benchmark's sets and at T_con 10, 20, 40 and 60 s.
# Writes docs/rl_benchmark/apg_hold_bonus.json and apg_hold_bonus3.json (rows of docs/what-was-tried.md)
# and their curves. It ships no agent; `python -m benchmarks run ship-rl-agents "$OUT" --also ENTRY`
# would ship the best seed. A run already finished in results/rl-apg-hold-bonus(3) is only aggregated again.
set -euo pipefail
export OMP_NUM_THREADS=1
for weight in ${WEIGHTS:-10 3}; do
  case "$weight" in
    10) entry=apg-hold-bonus-heading10-time-scaled-30min-v2; name=apg_hold_bonus; out=results/rl-apg-hold-bonus ;;
    3) entry=apg-hold-bonus3-heading10-time-scaled-30min-v2; name=apg_hold_bonus3; out=results/rl-apg-hold-bonus3 ;;
    *) echo "WEIGHTS: $weight is not one of 10 3" >&2; exit 2 ;;
  esac
  dwr-gym benchmark --agents "$entry:threads=1" \
    --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
    --out "$out"
  cp "$out/benchmark.json" "docs/rl_benchmark/$name.json"
  cp "$out/curves_steps.png" "docs/rl_benchmark/${name}_curves_steps.png"
done
python -m benchmarks render
