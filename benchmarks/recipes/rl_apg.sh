#!/usr/bin/env bash
# Analytic policy gradients (APG) on the residual on PTC on DWRPointStabilization-v2, five seeds.
# Analytic policy gradients on the residual on PTC (docs/rl-apg.md, 'Gradients through the env (APG)'):
# `apg-residual-v2` (train/hyperparams/residual_apg.yml: a constant rate of 3e-4, the best policy on the run's own 256
# validation episodes exported), five seeds of 30 M env steps, two runs side by side (about 20 minutes on 2 quiet
# cores), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes docs/rl_benchmark/apg.json and ships the
# best seed as train/pretrained/apg_residual_ptc_v2 (learned_from: reward, its env id, recipe and curve).
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg}
dwr-gym benchmark --agents 'apg-residual-v2:total_timesteps=30000000,eval_freq=5000000,checkpoint_freq=5000000,threads=1' \
  --seeds 5 --jobs 2 --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_curves_steps.png
python -m benchmarks run ship-rl-agents "$OUT"
python -m benchmarks render
