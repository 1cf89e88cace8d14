#!/usr/bin/env bash
# The RL benchmark of v1's reward, five seeds of each learner, and the agents it ships.
# The RL benchmark of v1's reward (docs/rl-benchmark.md) and the agents it ships: PPO from v1's reward, residual PPO on
# PTC and on pt-astolfi, SAC and TQC, five seeds each, evaluated on the fixed sets and aggregated with IQM and 95 %
# stratified-bootstrap intervals; then the best seed of ppo-jax and es-arena50 is copied into
# train/pretrained/{ppo_jax_v1,es_v1} (with its learning curve).
# The budgets are those that fitted on 2 shared cores in an hour (about 1 hour with --jobs 4 there); give more with --env-steps and the entries' total_timesteps. Each run's config.yaml records the
# `dwr-gym train` command that trains it alone (`python -m benchmarks run retrain-pretrained` runs it again).
set -euo pipefail
export OMP_NUM_THREADS=1
dwr-gym benchmark --agents ppo residual-ppo:total_timesteps=100000 residual-ppo-astolfi:total_timesteps=100000 \
  sac:total_timesteps=50000,eval_freq=50000 tqc:total_timesteps=50000,eval_freq=50000 --seeds 5 \
  --env-steps 200000 --eval-freq 100000 --disturbed-episodes 100 --jobs 4 --out results/rl-benchmark --docs
# the rows added afterwards (docs/rl-benchmark.md): --docs keeps the rows of the runs above
dwr-gym benchmark --agents 'ppo-jax:total_timesteps=4000000,eval_freq=1000000,checkpoint_freq=4000000' \
  'ppo-jax-tuned:backend=jax,hyperparams=train/hyperparams/ppo_jax_tuned.yml,total_timesteps=4000000,eval_freq=1000000' \
  'ppo-jax-12m:backend=jax,total_timesteps=12000000' \
  'ppo-jax-anneal:backend=jax,hyperparams=train/hyperparams/ppo_jax_anneal.yml' \
  --seeds 5 --eval-freq 2000000 --disturbed-episodes 100 --out results/rl-benchmark --docs
dwr-gym benchmark --agents 'sac-tuned:algo=sac,hyperparams=train/hyperparams/sac_tuned.yml' --seeds 5 \
  --eval-freq 250000 --disturbed-episodes 100 --out results/rl-benchmark --docs
dwr-gym benchmark --agents 'tqc-tuned:algo=tqc,hyperparams=train/hyperparams/tqc_tuned.yml' --seeds 5 \
  --eval-freq 200000 --disturbed-episodes 100 --out results/rl-benchmark --docs
dwr-gym benchmark --agents 'sac-utd8:algo=sac,hyperparams=train/hyperparams/sac_tuned.yml,hyperparam_overrides={gradient_steps: 8}' \
  --seeds 5 --jobs 2 --eval-freq 250000 --disturbed-episodes 100 --out results/rl-benchmark --docs
# evolution strategies: OpenAI-ES on v1's reward with an arena of 50 m (docs/evolution.md), one core each
dwr-gym benchmark --agents 'es-arena50:threads=1,total_timesteps=80000000' --seeds 5 --eval-freq 5000000 \
  --disturbed-episodes 100 --out results/rl-benchmark --docs
python -m benchmarks run ship-rl-agents results/rl-benchmark
python -m benchmarks render
