#!/usr/bin/env bash
# The time-scaled ES from reward alone on DWRPointStabilization-v2 at the budget issue 40's goal states: 30 minutes of
# training a seed (wall clock, one core each), two seeds side by side (about 40 minutes on 2 quiet cores with the
# evaluation). The entry es-time-scaled-v2 (train/hyperparams/es.yml, --action-time-scale 10) with a time limit of
# 1800 s and a budget of env steps it does not reach. Writes docs/rl_benchmark/time_scale_30min.json (tables
# rl-time-scale-30min and rl-time-scale-30min-per-T_con in docs/rl-v2.md).
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-time-scale-30min}
dwr-gym benchmark --agents 'es-time-scaled-v2:time_limit=1800,total_timesteps=5000000000,eval_freq=100000000,checkpoint_freq=100000000,threads=1' \
  --seeds 2 --jobs 2 --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/time_scale_30min.json
cp "$OUT/curves_wall.png" docs/rl_benchmark/time_scale_30min_curves_wall.png
python -m benchmarks render
