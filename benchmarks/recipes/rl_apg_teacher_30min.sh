#!/usr/bin/env bash
# APG from an open-loop teacher (one round or DAgger), time-scaled, on DWRPointStabilization-v2 at 30 minutes a seed.
# APG from an open-loop teacher with time-scaled actions on DWRPointStabilization-v2, at the goal's budget of 30 minutes
# a seed: apg-teacher-time-scaled-30min-v2 (train/hyperparams/apg_teacher.yml, --action-time-scale 10, 700 M env steps:
# the 400 M runs took about 15 minutes of a core alone and were still climbing), SEEDS (2) seeds, two runs side by side
# on one core each (about 45 minutes a pair on 2 cores with the evaluation), on the benchmark's sets and at T_con 10,
# 20, 40 and 60 s. Writes docs/rl_benchmark/apg_teacher_30min.json (tables rl-apg-teacher-30min and
# rl-apg-teacher-30min-per-T_con; rows of docs/what-was-tried.md).
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-teacher-30min}
dwr-gym benchmark --agents "apg-teacher-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-2}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_teacher_30min.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_teacher_30min_curves_steps.png
python -m benchmarks render
