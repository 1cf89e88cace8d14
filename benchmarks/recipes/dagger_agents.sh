#!/usr/bin/env bash
# The DAgger hand-over agents, three seeds.
# The hand-over agents of the README's "Prescribed-time agents": minimum-energy plans from random
# starts (0.3-3 m, T_con in [10, 60] s, DWRPointStabilization-v1), four DAgger rounds in which the network
# drives and plans are solved again from the states it reaches, then the choice of the hand-over to the
# pt-astolfi law on the run's own evaluation starts (seed 12345). Seed 0's network is where the shipped `robust`
# starts from (train/pretrained/robust/config.yaml's recipe trains it first, in runs/dagger_handover_s0).
# About 40 minutes per seed on 2 shared cores (planning and fitting on 2 million samples); needs the optimal and
# train extras. (An earlier, smaller recipe: --episodes 250 --dagger-rounds 2 --dagger-episodes 80
# --replans-per-episode 3 --epochs 20, no hand-over.)
set -euo pipefail
export OMP_NUM_THREADS=1
for seed in 0 1 2; do
  python -m train.learning.imitation.dagger --run-dir "runs/dagger_handover_s$seed" --seed "$seed" --episodes 1000 --dagger-rounds 4 \
    --dagger-episodes 300 --replans-per-episode 5 --epochs 30 --workers 2 --near-goal-weight 1 \
    --handover-expert pt-astolfi --eval-episodes 200
done
