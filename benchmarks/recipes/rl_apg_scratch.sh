#!/usr/bin/env bash
# Analytic policy gradients (APG) from scratch on DWRPointStabilization-v2, five seeds.
# Analytic policy gradients from scratch on DWRPointStabilization-v2 (the benchmark's goal from the reward alone;
# docs/rl-apg.md, 'Gradients through the env (APG)'): `apg-v2` (train/hyperparams/apg.yml: 64 episodes an
# update, a rate of 1e-3 decaying to 0, each episode's state gradient clipped to 4 per step, the best policy on the run's own 256
# validation episodes exported), five seeds of 400 M env steps (about 15 minutes of one core each), JOBS (2) runs side by
# side (about 45 minutes on 2 quiet cores), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes
# docs/rl_benchmark/apg_scratch.json.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-scratch}
dwr-gym benchmark --agents 'apg-v2:total_timesteps=400000000,threads=1' \
  --seeds 5 --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_scratch.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_scratch_curves_steps.png
python -m benchmarks render
