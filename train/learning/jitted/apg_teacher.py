"""APG's open-loop teacher (``teacher_episodes`` > 0): before its first update, APG's policy is cloned from the best
command sequences of fresh episodes, each found on its own by gradient ascent on the episode's return.

A policy is one map for all episodes; a sequence is free on each. The search over sequences
(:func:`train.evaluation.open_loop.best_sequences`: Adam on each episode's actions, through the JAX env, as APG
differentiates it) comes within 15 % of the optimum's energy on v2 (docs/rl-apg.md, the open-loop bound),
where APG from scratch stays near twice it. So the teacher plays ``teacher_episodes`` fresh episodes, finds each
one's best sequence in ``teacher_iterations`` Adam steps, and fits the policy's mean action to the sequences'
actions on the observations they were taken on (``clone_steps`` Adam steps of least squares on minibatches); APG's
updates then go on from that policy, on the reward, and correct what cloning alone does not (its drift away from the
sequences' states). This is guided policy search's idea (Levine & Koltun 2013) in its simplest form: the teacher is
computed from the reward and the env's derivative only (no law, no optimal-control solver, nothing at run time), so
the learner stays "from the reward". Its env steps (each iteration plays every episode once) count in the budget.

(Further rounds as DAgger, teaching the states the cloned policy reaches, were measured and removed: they cost their
env steps and changed neither the in-time rate nor the energy, docs/what-was-tried.md.)
"""

from __future__ import annotations

from typing import Any

#: Observation-action pairs per least-squares step of the cloning.
CLONE_BATCH = 4096
#: Adam's step size at the start of the cloning (cosine decay to 0 over ``clone_steps``).
CLONE_LEARNING_RATE = 1e-3


def teacher_steps(settings: Any, mean_episode_steps: float) -> float:
    """The env steps the teacher spends, about: every iteration, and the final rollout, plays each episode once."""
    return float(settings.teacher_episodes * mean_episode_steps * (settings.teacher_iterations + 1))


def clone_from_teacher(apg: Any, state: Any, progress: bool = False) -> tuple[Any, dict[str, float]]:
    """``state`` (an :class:`train.learning.jitted.apg.APGState` before its first update) with its policy cloned from
    the teacher's sequences (and kept as the best so far, with a fresh Adam state); and the teacher's measures: its
    env steps, its first sequences' share in time and mean return, the cloning's last loss."""
    import jax
    import jax.numpy as jnp
    import optax

    from train.evaluation.open_loop import best_sequences

    settings, env, env_params = apg.settings, apg.env, apg.env_params
    rng, key_starts, key_clone = jax.random.split(state.rng, 3)
    optimizer = optax.adam(optax.cosine_decay_schedule(CLONE_LEARNING_RATE, settings.clone_steps))

    def loss(params: Any, x: Any, y: Any) -> Any:
        scaled = state.obs_stats.normalize(x) if settings.normalize_observations else x
        mean, _, _ = apg.network.apply(params, scaled)
        return jnp.mean((mean - y) ** 2)

    @jax.jit
    def fit(params: Any, opt_state: Any, key: Any, x: Any, y: Any) -> tuple[Any, Any, Any]:
        rows = jax.random.randint(key, (CLONE_BATCH,), 0, x.shape[0])  # (the pairs passed in, not baked in)
        value, grads = jax.value_and_grad(loss)(params, x[rows], y[rows])
        updates, opt_state = optimizer.update(grads, opt_state, params)
        return optax.apply_updates(params, updates), opt_state, value

    def fitted(params: Any, key: Any, x: Any, y: Any) -> tuple[Any, Any]:
        opt_state, value = optimizer.init(params), jnp.asarray(jnp.nan)
        for step_key in jax.random.split(key, settings.clone_steps):
            params, opt_state, value = fit(params, opt_state, step_key, x, y)
        return params, value

    def taught(starts: Any, round_: int) -> tuple[Any, Any, Any, Any]:
        """The best sequences from ``starts``, their returns and final states, and the (observations, alive) they
        were played on."""
        label = f"open-loop teacher, round {round_ + 1}" if progress else None
        sequences, (returns, (final, observations, alive)) = best_sequences(
            env, env_params, starts, settings.teacher_iterations, settings.teacher_learning_rate, label
        )
        return sequences, returns, final, (observations, alive)

    keys = jax.random.split(key_starts, settings.teacher_episodes)
    _, starts = jax.vmap(env.reset_env, in_axes=(0, None))(keys, env_params)
    sequences, returns, final, (observations, alive) = taught(starts, 0)
    mask = alive.reshape(-1)
    inputs = observations.reshape(-1, observations.shape[-1])[mask]
    targets = jnp.tanh(sequences).reshape(-1, 2)[mask]
    steps = float(jnp.sum(alive)) * (settings.teacher_iterations + 1)
    params, value = fitted(state.params, key_clone, inputs, targets)
    state = state.replace(
        params=params, opt_state=apg.optimizer.init(params), best_params=params, rng=rng, average_params=params
    )
    measures = {
        "steps": steps,
        "teacher_in_time": float(jnp.mean(final.is_success)),
        "teacher_return": float(jnp.mean(returns)),
        "clone_loss": float(value),
        "pairs": float(inputs.shape[0]),
    }
    return state, measures


__all__ = ["CLONE_BATCH", "CLONE_LEARNING_RATE", "clone_from_teacher", "teacher_steps"]
