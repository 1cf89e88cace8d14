#!/usr/bin/env bash
# APG from an open-loop teacher on DWRPointStabilization-v2 (issue 40's goal from the reward alone; docs/rl-benchmark.md,
# 'Gradients through the env (APG)'): `apg-teacher-v2` (train/hyperparams/apg_teacher.yml: apg.yml's v2 recipe, the
# policy first cloned from the best command sequences of 512 fresh episodes), five seeds of 400 M env steps (the
# teacher's 145 M included; about 15 minutes of one core each), JOBS (2) runs side by side (about 50 minutes on 2
# quiet cores), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes docs/rl_benchmark/apg_teacher.json
# and ships the best seed as train/pretrained/apg_teacher_v2.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-teacher}
dwr-gym benchmark --agents 'apg-teacher-v2:total_timesteps=400000000,threads=1' \
  --seeds 5 --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT"
cp "$OUT/benchmark.json" docs/rl_benchmark/apg_teacher.json
cp "$OUT/curves_steps.png" docs/rl_benchmark/apg_teacher_curves_steps.png
python -m benchmarks run ship-rl-agents "$OUT" --also apg-teacher-v2
python -m benchmarks render
