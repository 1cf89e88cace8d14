#!/usr/bin/env bash
# The training runs behind the README's v0 agents: residual PPO on PTC and PPO, seeds 0-2, then compare.
# The training runs behind the README's results: a residual PPO on the PTC expert and a from-scratch PPO,
# the same budget (1.5 M env steps, 16 envs) and env (DWRPointStabilization-v0, heading_weight=5), seeds 0, 1, 2.
# About 4 minutes per run on 2 cores. Seed 0 of each is what ships in train/pretrained/. OLD pins the defaults
# of `dwr-gym train` at the time (before the batch-sized defaults, docs/training.md).
set -euo pipefail
export OMP_NUM_THREADS=1
OLD=(--num-envs 16 --hyperparams n_steps=256 batch_size=512 n_epochs=10 --eval-freq 20000 --checkpoint-freq 50000)
for seed in 0 1 2; do
  dwr-gym train --residual --env DWRPointStabilization-v0 --total-timesteps 1500000 --env-kwargs heading_weight=5 --seed "$seed" \
    "${OLD[@]}" --run-dir "runs/residual_ppo_s$seed" --no-progress
  dwr-gym train --env DWRPointStabilization-v0 --total-timesteps 1500000 --env-kwargs heading_weight=5 --seed "$seed" \
    "${OLD[@]}" --run-dir "runs/ppo_s$seed" --no-progress
done
# The comparison over the three seeds of each:
dwr-gym compare --env DWRPointStabilization-v0 --agents runs/residual_ppo_s{0,1,2} runs/ppo_s{0,1,2} \
  --controllers ptc astolfi --scenarios random --n 1000 --out results/seeds
