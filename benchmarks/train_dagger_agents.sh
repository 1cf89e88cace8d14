#!/usr/bin/env bash
# The DAgger agents of the README's "Prescribed-time agents by DAgger" (issue 10): minimum-energy plans from
# random starts (0.3-3 m, T_con in [10, 60] s, DWRPointStabilization-v1), then two rounds in which the
# network drives and plans are solved again from the states it reaches. Seed 0 ships in train/pretrained/dagger.
# About 15 minutes per seed on 2 shared cores (most of it planning); needs the optimal and train extras.
set -euo pipefail
export OMP_NUM_THREADS=1
for seed in 0 1 2; do
  python -m train.dagger --run-dir "runs/dagger_s$seed" --seed "$seed" --episodes 250 --dagger-rounds 2 \
    --dagger-episodes 80 --replans-per-episode 3 --epochs 20 --workers 2 --near-goal-weight 1
done
# The goal, measured at T_con in {10, 20, 40, 60} on 500 random starts each, the seeds as mean +- sd:
python benchmarks/prescribed_time_goal.py runs/dagger_s{0,1,2}
