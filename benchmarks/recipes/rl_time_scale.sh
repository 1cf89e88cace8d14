#!/usr/bin/env bash
# ES from reward on DWRPointStabilization-v2 with and without time-scaled actions, five seeds each, then 4x the budget.
# Time-scaled actions on DWRPointStabilization-v2 (docs/rl-v2.md, 'Time-scaled actions'): ES from
# reward alone on v2 (train/hyperparams/es.yml, 100 M env steps a seed), as shipped and with --action-time-scale 10
# (the action times min(1, 10 s / T_con), train.learning.time_scale), five seeds each, two runs side by side (about
# 25 minutes on 2 quiet cores). Writes docs/rl_benchmark/time_scale.json. Then the time-scaled
# entry at four times the budget (400 M env steps, two seeds side by side, about 12 minutes): does it keep climbing?
# Writes docs/rl_benchmark/time_scale_long.json.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-time-scale}
dwr-gym benchmark --agents 'es-v2:threads=1' 'es-time-scaled-v2:threads=1' \
  --seeds 5 --jobs 2 --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/time_scale.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/time_scale_curves_steps.png
LONG=${LONG:-results/rl-time-scale-long}
dwr-gym benchmark --agents 'es-time-scaled-v2:total_timesteps=400000000,eval_freq=50000000,checkpoint_freq=50000000,threads=1' \
  --seeds 2 --jobs 2 --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$LONG"
cp "$LONG/benchmark.json" docs/rl_benchmark/time_scale_long.json
python -m benchmarks render
