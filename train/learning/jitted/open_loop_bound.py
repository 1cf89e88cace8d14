"""The open-loop bound on a residual (or on no law): each episode's best command sequence, found on its own.

A residual policy does at most, on each episode, what the best residual *sequence* for that episode does.
:func:`open_loop_bound` searches such sequences with :func:`train.evaluation.open_loop.best_sequences`, through the JAX
env and, for a residual, the law on jax arrays (:class:`train.learning.jitted.residual.ResidualGymnaxEnv`, which is
why it lives with the learners, and the search and its measures with the evaluation).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from train.evaluation.open_loop import best_sequences, episode_fn


def open_loop_bound(
    expert: str | None = "ptc",
    residual_scale: float = 0.5,
    n: int = 32,
    iterations: int = 1000,
    learning_rate: float = 0.02,
    seed: int = 0,
    env_id: str = "DWRPointStabilization-v2",
    progress: bool = False,
    **env_kwargs: Any,
) -> dict[str, Any]:
    """The best action sequence found for each of ``n`` episodes of ``env_id`` (drawn from ``seed``) by ``iterations``
    Adam steps on its return; with ``expert`` the actions are residuals on that law at ``residual_scale`` (the
    training's ``clip(expert + scale * residual)``), else the env's action; ``env_kwargs`` go to the env (the
    optimum's E/opt, :func:`train.evaluation.open_loop.energy_ratios`, assumes none). Returns the per-episode rows of the law
    alone (the zero sequence) and of the best sequences, and the episodes' starts, goals and T_con for the optimum."""
    import jax
    import jax.numpy as jnp

    from dwr_gym.jax_env import make_gymnax_env

    env, env_params = make_gymnax_env(env_id, **env_kwargs)
    if expert is not None:
        from baselines.registry import make_controller
        from train.learning.jitted.residual import ResidualGymnaxEnv

        env = ResidualGymnaxEnv(env, make_controller(expert), env_params.u_max, env_params.omega_max, residual_scale)
    keys = jax.random.split(jax.random.PRNGKey(seed), n)
    _, starts = jax.vmap(env.reset_env, in_axes=(0, None))(keys, env_params)
    batch = jax.jit(jax.vmap(episode_fn(env, env_params)))
    label = f"open loop ({expert or 'no law'})" if progress else None
    best_z, best_played = best_sequences(env, env_params, starts, iterations, learning_rate, label)

    def rows(played: Any) -> list[dict[str, float]]:
        returns, (final, _, _) = played
        in_time = np.asarray(final.is_success, bool)
        return [{"in_time": float(in_time[i]), "energy": float(final.energy[i]),
                 "final_heading": abs(float(final.heading_error[i])), "return": float(returns[i])}
                for i in range(n)]  # fmt: skip

    return {
        "law": rows(batch(jnp.zeros_like(best_z), starts)),
        "best": rows(best_played),
        "starts": np.stack([np.asarray(starts.x), np.asarray(starts.y), np.asarray(starts.psi)], 1).tolist(),
        "goals": np.stack(
            [np.asarray(starts.goal_x), np.asarray(starts.goal_y), np.asarray(starts.goal_psi)], 1
        ).tolist(),
        "T_con": np.asarray(starts.T_con, float).tolist(),
        "settings": {
            "expert": expert,
            "residual_scale": residual_scale,
            "n": n,
            "iterations": iterations,
            "learning_rate": learning_rate,
            "seed": seed,
            "env_id": env_id,
        },
    }


__all__ = ["open_loop_bound"]
