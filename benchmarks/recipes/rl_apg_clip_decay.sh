#!/usr/bin/env bash
# APG from an open-loop teacher, time-scaled, with the state's gradient clip decaying from 16 to 4 over the run
# (state_grad_clip_final) on DWRPointStabilization-v2: apg-clip-decay-time-scaled-30min-v2 (train/hyperparams/
# apg_teacher.yml with state_grad_clip 16 and state_grad_clip_final 4, --action-time-scale 10, 560 M env steps: the
# goal's 30 minutes of a core), SEEDS (5) seeds, two runs side by side on one core each (about 30-35 minutes a pair on 2
# cores with the evaluation), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes
# docs/rl_benchmark/apg_clip_decay.json (tables rl-apg-clip-decay and rl-apg-clip-decay-per-T_con in
# docs/rl-apg-levers.md) and its curves.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-clip-decay}
dwr-gym benchmark --agents "apg-clip-decay-time-scaled-30min-v2:threads=1" \
  --seeds "${SEEDS:-5}" --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 \
  --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_clip_decay.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_clip_decay_curves_steps.png
python -m benchmarks render
