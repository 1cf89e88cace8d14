#!/usr/bin/env bash
# Analytic policy gradients (APG) from an open-loop teacher on DWRPointStabilization-v2, five seeds.
# APG from an open-loop teacher on DWRPointStabilization-v2 (the RL benchmark's goal from the reward alone; docs/rl-apg.md,
# 'From an open-loop teacher'): `apg-teacher-v2` (train/hyperparams/apg_teacher.yml: apg.yml's v2 recipe, the policy
# first cloned from the best command sequences of 512 fresh episodes) and `apg-teacher-time-scaled-v2` (the same with
# --action-time-scale 10), five seeds each of 400 M env steps (the teacher's 145 M included; about 15 minutes of one
# core a seed alone), JOBS (2) runs side by side (the published tables: 2 for the first, 3 for the second; about 50
# minutes each on 2 cores), on the benchmark's sets and at T_con 10, 20, 40 and 60 s. Writes
# docs/rl_benchmark/apg_teacher.json and apg_teacher_time_scaled.json.
set -euo pipefail
export OMP_NUM_THREADS=1
OUT=${OUT:-results/rl-apg-teacher}
for agent in apg-teacher-v2 apg-teacher-time-scaled-v2; do
  name=${agent%-v2}
  dwr-gym benchmark --agents "$agent:total_timesteps=400000000,threads=1" \
    --seeds 5 --jobs "${JOBS:-2}" --eval-episodes 200 --disturbed-episodes 20 --optimum-episodes 50 --out "$OUT/$name"
  cp "$OUT/$name/benchmark.json" "docs/rl_benchmark/${name//-/_}.json"
  cp "$OUT/$name/curves_steps.png" "docs/rl_benchmark/${name//-/_}_curves_steps.png"
done
python -m benchmarks render
