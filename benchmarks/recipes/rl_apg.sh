#!/usr/bin/env bash
# Analytic policy gradients on DWRPointStabilization-v2 (issue 40; docs/rl-benchmark.md, 'Gradients through the env'):
# the residual on PTC (apg-residual-v2), five seeds on the benchmark's sets and at T_con 10, 20, 40 and 60 s, two at a
# time on the 2 cores (one each; 60 M env steps a seed, half of them the replays that check each update, some
# 7 minutes of a core, the evaluations included). Writes
# docs/rl_benchmark/apg.json, ships the best seed as train/pretrained/apg_residual_v2 (learned_from: reward, its env
# id, recipe and curve).
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg}
dwr-gym benchmark --agents 'apg-residual-v2:threads=1,total_timesteps=60000000' \
  --seeds 5 --jobs 2 --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_curves_steps.png
cp "$OUT/curves_wall.png" docs/rl_benchmark/apg_curves_wall.png
python -m benchmarks run ship-rl-agents "$OUT" --also apg-residual-v2
python -m benchmarks render
