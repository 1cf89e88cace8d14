#!/usr/bin/env bash
# The learners on DWRPointStabilization-v2, five seeds each, per T_con too, and the best seed of each shipped.
# The learners on DWRPointStabilization-v2 (docs/rl-v2.md, 'Learning v2'), five seeds each on the
# benchmark's sets and at T_con 10, 20, 40 and 60 s, the reference controllers evaluated on v2 too: ES on a residual
# on PTC (train/hyperparams/residual_es.yml), the residual PPO on PTC inside the jitted loop, and the jitted PPO from
# reward alone with its noise on a fixed schedule (train/hyperparams/ppo_jax_v2.yml). Budgets sized for one shared
# core of 2, the PPO runs bounded to 4 minutes each (about 90 minutes in all on a shared machine). Writes
# docs/rl_benchmark/v2.json.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-v2}
dwr-gym benchmark --agents \
  'es-residual-v2:threads=1' \
  'residual-ppo-jax-v2:total_timesteps=3000000,time_limit=240,eval_freq=500000,threads=1' \
  'ppo-jax-fixed-noise-v2:total_timesteps=3000000,time_limit=240,eval_freq=500000,threads=1' \
  --seeds 5 --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/v2.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/v2_curves_steps.png
cp "$OUT/curves_wall.png" docs/rl_benchmark/v2_curves_wall.png
python -m benchmarks render
