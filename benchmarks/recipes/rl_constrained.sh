#!/usr/bin/env bash
# The deadline and the heading as constraints (Lagrangian APG; the residual on PTC) on v2, per T_con, with multipliers.
# The deadline and the heading as constraints on DWRPointStabilization-v2: apg-lagrangian-v2 (APG from its open-loop
# teacher, time-scaled, multipliers per T_con bin in PID form; 560 M env steps a seed) and apg-lagrangian-residual-ptc-v2
# (the residual on PTC under the same constraints, 30 M env steps a seed), SEEDS seeds each, two runs side by side on
# one core each, on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes docs/rl_benchmark/constrained.json
# (tables rl-constrained and rl-constrained-per-T_con in docs/rl-constrained.md), the multipliers' log
# (constrained_log.json, table rl-constrained-log) and its figure. On 2 quiet cores about 35 minutes a pair of APG
# seeds and 4 a pair of residual seeds.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-constrained}
dwr-gym benchmark --agents "apg-lagrangian-v2:threads=1" "apg-lagrangian-residual-ptc-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/constrained.json
python -m benchmarks run constraint-log "$OUT" --json docs/rl_benchmark/constrained_log.json \
  --figure docs/rl_benchmark/constrained_log.png
python -m benchmarks render
