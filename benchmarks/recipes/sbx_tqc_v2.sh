#!/usr/bin/env bash
# What sbx's TQC learns on v2 at the goal's budget: five seeds of 30 minutes, with the references.
# TQC (sbx, JAX) on DWRPointStabilization-v2, five seeds of 1800 s each (the time limit, not the env steps, ends a
# run), two runs side by side on one core each: about 2.5 hours on 2 cores. A run already finished under OUT is only
# aggregated again. Writes docs/rl_benchmark/sbx_v2_30min_tqc.json (tables sbx-v2-30min-tqc and its per-T_con table
# in docs/rl-libraries.md; the leaderboard's TQC row). The briefer runs of SAC, TQC and CrossQ on v1 and v2 answered
# their question (none learns the task): their JSONs are rows of docs/what-was-tried.md, as are the seeds' curves.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/sbx-v2-30min-tqc}
dwr-gym benchmark --agents tqc-sbx-v2 --seeds 5 --jobs 2 --time-limit 1800 --env-steps 50000000 --eval-freq 1000000 \
  --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --references --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/sbx_v2_30min_tqc.json
python -m benchmarks render
