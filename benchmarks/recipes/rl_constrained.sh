#!/usr/bin/env bash
# The deadline and the heading as constraints (Lagrangian APG, its residual on PTC, PPO-Lagrangian) on v2, per T_con.
# The deadline and the heading as constraints on DWRPointStabilization-v2: apg-lagrangian-v2 (APG from its open-loop
# teacher, time-scaled, multipliers per T_con bin in PID form; 560 M env steps a seed), apg-lagrangian-averaged-v2 (the
# same, its weights' moving average validated and exported; AVG_SEEDS seeds, 2 by default), apg-lagrangian-residual-ptc-v2
# (the residual on PTC under the same constraints, 30 M env steps a seed), ppo-lagrangian-v2 (the jitted PPO with a
# cost critic and the same multipliers, 8 M env steps a seed) and ppo-lagrangian-30min-v2 (the same for 30 minutes
# of a core: 60 M env steps, stopped at 1,800 s), SEEDS seeds each (APG_SEEDS and PPO30_SEEDS for the two long ones),
# two runs side by side on one core each, on the benchmark's sets and at T_con 10, 20, 40 and 60 s; then the averaged
# recipe in 30 minutes of one core (AVG30_SEEDS seeds, 2 by default). Writes docs/rl_benchmark/constrained.json (tables
# rl-constrained and rl-constrained-per-T_con in docs/rl-constrained.md), constrained_30min.json (rl-constrained-30min),
# the multipliers' log (constrained_log.json, table rl-constrained-log) and its figure. On 2 cores of an Intel Xeon
# about 60 minutes a pair of APG seeds, 4 a pair of residual seeds, 3 a pair of PPO seeds and 32 a pair of 30-minute ones.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-constrained}
BUDGET=(--jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT")
dwr-gym benchmark --agents "apg-lagrangian-v2:threads=1" --seeds "${APG_SEEDS:-${SEEDS:-5}}" "${BUDGET[@]}"
dwr-gym benchmark --agents "apg-lagrangian-averaged-v2:threads=1" --seeds "${AVG_SEEDS:-2}" "${BUDGET[@]}"
dwr-gym benchmark --agents "apg-lagrangian-residual-ptc-v2:threads=1" "ppo-lagrangian-v2:threads=1" \
  --seeds "${SEEDS:-5}" "${BUDGET[@]}"
dwr-gym benchmark --agents "ppo-lagrangian-30min-v2:threads=1" --seeds "${PPO30_SEEDS:-${SEEDS:-5}}" \
  --time-limit 1800 "${BUDGET[@]}"
# the averaged recipe in the goals' 30 minutes of one core a seed: 340 M env steps (its schedules scaled to them; some
# 28 minutes of a core here), stopped at 1,800 s if not done; AVG30_SEEDS seeds (2 by default), $OUT-30min
dwr-gym benchmark --agents "apg-lagrangian-averaged-v2:threads=1,total_timesteps=340000000" \
  --seeds "${AVG30_SEEDS:-2}" --time-limit 1800 --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 \
  --optimum-episodes 50 --out "$OUT-30min"
cp "$OUT-30min/benchmark.json" docs/rl_benchmark/constrained_30min.json
# the four entries' seeds in one table (each JSON of $OUT/results read as it is)
dwr-gym benchmark --agents "apg-lagrangian-v2:threads=1" "apg-lagrangian-averaged-v2:threads=1" \
  "apg-lagrangian-residual-ptc-v2:threads=1" "ppo-lagrangian-v2:threads=1" "ppo-lagrangian-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --report-only "${BUDGET[@]}"
cp "$OUT/benchmark.json" docs/rl_benchmark/constrained.json
python -m benchmarks run constraint-log "$OUT" --json docs/rl_benchmark/constrained_log.json \
  --figure docs/rl_benchmark/constrained_log.png
python -m benchmarks render
