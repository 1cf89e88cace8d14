#!/usr/bin/env bash
# Annealing the exploration noise and no discount (docs/rl-benchmark.md, 'Annealing the noise and no discount'): one
# seed each of the jitted PPO with log_std_final and gamma 1, 12 M env steps (ppo-jax-60m: 60 M), and a residual PPO on
# PTC, on the benchmark's sets; about 1.5 minutes per 12 M-step run on 2 cores. Writes docs/rl_benchmark/anneal.json.
set -euo pipefail
export OMP_NUM_THREADS=1
dwr-gym benchmark --agents 'ppo-jax:total_timesteps=12000000' \
  'ppo-jax-60m:backend=jax,total_timesteps=60000000,eval_freq=6000000,checkpoint_freq=12000000' \
  'anneal-3:backend=jax,hyperparams={log_std_final: -3.0}' \
  'g9999-anneal-3:backend=jax,hyperparams={log_std_final: -3.0, gamma: 0.9999}' \
  'g1-anneal-3:backend=jax,hyperparams={log_std_final: -3.0, gamma: 1.0}' \
  'g1-anneal-3-lin:backend=jax,hyperparams={log_std_final: -3.0, gamma: 1.0, learning_rate: lin_3e-4}' \
  'g1-anneal-2.5-lin:backend=jax,hyperparams={log_std_final: -2.5, gamma: 1.0, learning_rate: lin_3e-4}' \
  'residual-ptc-anneal-5:algo=ppo,residual=true,expert=ptc,total_timesteps=1000000,eval_freq=250000,hyperparams={log_std_final: -5.0, gamma: 1.0, learning_rate: lin_3e-4, policy_kwargs: "dict(net_arch=[64, 64], log_std_init=-3.0)"}' \
  --seeds 1 --env-steps 12000000 --eval-freq 2000000 --disturbed-episodes 20 --references --out results/rl-levers
cp results/rl-levers/benchmark.json docs/rl_benchmark/anneal.json
python -m benchmarks render
