#!/usr/bin/env bash
# The `robust` agent's network fine-tuned by PPO under disturbances, five seeds, and its goal.
# The RL benchmark's stretch goal (docs/rl-benchmark.md, 'Robust RL'): the `robust` agent's network, cloned by robust DAgger,
# fine-tuned by PPO from v1's reward under randomised disturbances (the distribution it was cloned under), five
# seeds; then the network alone before and after, on the nominal and the four disturbed sets at T_con 20 and 40 s.
# About 5 minutes of one core per seed; a finished seed is skipped, so the script continues an interrupted run.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/robust-rl}
for seed in 0 1 2 3 4; do
  [ -f "$OUT/seed$seed/run_state.json" ] && grep -q '"finished": true' "$OUT/seed$seed/run_state.json" && continue
  dwr-gym train --init-from train/pretrained/robust --critic-warmup 300000 \
    --env-kwargs disturbance_distribution='{}' --hyperparams learning_rate=1e-4 --total-timesteps 1500000 \
    --eval-freq 300000 --seed "$seed" --run-dir "$OUT/seed$seed" --overwrite --no-progress
done
python -m benchmarks run robust-goal 'train/pretrained/robust#network' "$OUT"/seed{0,1,2,3,4} --controllers --n 100 \
  --T-con 20 40 --workers 2 --json docs/rl_benchmark/robust_finetune.json
python -m benchmarks render
