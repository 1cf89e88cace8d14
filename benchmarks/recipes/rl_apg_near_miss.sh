#!/usr/bin/env bash
# APG from the teacher, time-scaled, its lesson fitted longer and its near misses clipped wider, v2, 30 min a seed.
# APG from an open-loop teacher, time-scaled, with the lesson fitted four times longer (clone_steps 16000) and the
# episodes that end near the goal but outside its tolerance clipped at 16 (near_miss_clip) on DWRPointStabilization-v2:
# apg-near-miss-time-scaled-30min-v2 (train/hyperparams/apg_teacher.yml with those two, --action-time-scale 10, 560 M env
# steps: the goal's 30 minutes of a core), SEEDS (5) seeds, two runs side by side on one core each (about 35 minutes a
# pair on 2 cores with the evaluation), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes
# docs/rl_benchmark/apg_near_miss.json (tables rl-apg-near-miss and rl-apg-near-miss-per-T_con; rows of docs/what-was-tried.md)
# and its curves.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-near-miss}
dwr-gym benchmark --agents "apg-near-miss-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_near_miss.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_near_miss_curves_steps.png
python -m benchmarks render
