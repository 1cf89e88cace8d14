#!/usr/bin/env bash
# The agents cloned from the optimal controller (`dwr-gym imitate`), three seeds, then their goal.
# The prescribed-time agents behind the README's results (issue: one policy for any T_con).
# `dwr-gym imitate` records the optimal controller on DWRPointStabilization-v1's task (T_con in [10, 60] s,
# starts 0.3-3 m) with noise on the executed actions, and clones it into a PPO MlpPolicy.
# About 10 minutes per seed on 2 cores (most of it planning). Seed 0 is what ships in train/pretrained/bc_optimal.
set -euo pipefail
for seed in 0 1 2; do
  dwr-gym imitate --episodes 400 --seed "$seed" --run-dir "runs/bc_optimal_s$seed" --no-progress
done
# The goal, measured at T_con in {10, 20, 40, 60} on 500 random starts each, the three seeds as mean +- sd:
python -m benchmarks run prescribed-time-goal runs/bc_optimal_s{0,1,2}
