"""What a policy could reach at best: each episode's whole command sequence optimised on its own (open loop).

A learner's policy maps the observation to one action, the same map for every episode; the best it can do on an
episode is at most what the best *sequence* of actions does on that episode alone. :func:`best_sequences` finds such
sequences (:func:`train.learning.jitted.open_loop_bound.open_loop_bound` on drawn episodes, the APG teacher on its own):
for each of ``n`` v2 episodes it optimises the actions of all its steps (a residual on a law, or the
action itself) by Adam on the episode's own return, differentiated through the JAX env (and the law) as the APG
learner differentiates it, and keeps the best sequence met. What it reaches bounds what a residual on that law, with
that residual scale, can reach (up to the optimiser's own shortfall, which the run without a law measures: there the
bound should come near the optimum, E/opt 1).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from train.goals import RESIDUAL_ON_PTC

#: Per-episode measures of :func:`train.learning.jitted.open_loop_bound.open_loop_bound`, in its rows.
MEASURES = ("in_time", "energy", "final_heading", "return")
#: The residual goal's final heading [rad] (:data:`train.goals.RESIDUAL_ON_PTC`): :func:`summary` gives the share of
#: episodes within it.
HEADING_GOAL = RESIDUAL_ON_PTC.final_heading


def episode_fn(env: Any, env_params: Any) -> Any:
    """(actions (steps, 2) unbounded, start state) -> (return, (final state, observations, alive)), actions squashed by
    tanh; ``observations`` (steps, obs) are those each action was taken on, ``alive`` (steps,) where it was."""
    import jax
    import jax.numpy as jnp

    def run(z: Any, start: Any) -> tuple[Any, Any]:
        def one_step(carry: tuple[Any, Any, Any], action: Any) -> tuple[tuple[Any, Any, Any], tuple[Any, Any]]:
            state, alive, total = carry
            _, after, reward, done, _ = env.step_env(jax.random.PRNGKey(0), state, jnp.tanh(action), env_params)
            total = total + jnp.where(alive, reward, 0.0)
            seen = (state.observation, alive)
            state = jax.tree.map(lambda new, old: jnp.where(alive, new, old), after, state)
            return (state, alive & ~done, total), seen

        carry = (start, jnp.asarray(True), jnp.asarray(0.0, jnp.float32))
        (final, _, total), (observations, alive) = jax.lax.scan(one_step, carry, z)
        return total, (final, observations, alive)

    return run


def best_sequences(
    env: Any, env_params: Any, starts: Any, iterations: int, learning_rate: float, progress: str | None = None
) -> tuple[Any, Any]:
    """The best unbounded action sequences (episodes, steps, 2) met in ``iterations`` Adam steps of ``learning_rate``
    on each episode's own return from ``starts`` (a batch of env states), from zero; and the played sequences'
    rollouts (return, (final state, observations, alive)) of :func:`episode_fn`. ``progress``: a bar's label."""
    import jax
    import jax.numpy as jnp
    import optax

    run = jax.vmap(episode_fn(env, env_params))
    n = int(jnp.shape(starts.T_con)[0])

    def loss(z: Any) -> tuple[Any, Any]:
        returns, _ = run(z, starts)
        return -jnp.sum(returns), returns

    optimizer = optax.adam(learning_rate)

    @jax.jit
    def step(z: Any, opt_state: Any) -> tuple[Any, Any, Any]:
        grads, returns = jax.grad(loss, has_aux=True)(z)
        grads = jnp.where(jnp.isfinite(grads), grads, 0.0)  # a step at 0/0 (the goal) moves nothing there
        updates, opt_state = optimizer.update(grads, opt_state, z)
        return optax.apply_updates(z, updates), opt_state, returns

    z = jnp.zeros((n, int(env_params.max_episode_steps), 2), jnp.float32)
    opt_state = optimizer.init(z)
    best_z, best_return = z, jnp.full((n,), -jnp.inf)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=iterations, desc=progress, unit="it")
    for _ in range(iterations):
        new_z, opt_state, returns = step(z, opt_state)
        better = jnp.isfinite(returns) & (returns > best_return)  # the returns are those of z, before the step
        best_z = jnp.where(better[:, None, None], z, best_z)
        best_return = jnp.where(better, returns, best_return)
        z = new_z
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    return best_z, jax.jit(run)(best_z, starts)


def energy_ratios(result: dict[str, Any], workers: int = 0) -> dict[str, Any]:
    """``result`` of :func:`train.learning.jitted.open_loop_bound.open_loop_bound` with each row's E/opt (its energy
    over the cached optimum of the goal pose, :func:`train.evaluation.optimum.optimal_energies`; None where the
    episode is not in time or has no optimum), as the benchmark's tables compute it."""
    from dwr_gym.params import EnvParams
    from train.env_ids import env_keywords
    from train.evaluation.optimum import optimal_energies

    kwargs = env_keywords(result["settings"]["env_id"], {})
    params = EnvParams.from_kwargs(**{k: v for k, v in kwargs.items() if k in EnvParams.__dataclass_fields__})
    optimum, _ = optimal_energies(params, np.asarray(result["starts"]), np.asarray(result["goals"]),
                                  np.asarray(result["T_con"]), heading=True, workers=workers)  # fmt: skip
    for key in ("law", "best"):
        for row, best in zip(result[key], optimum, strict=True):
            valid = row["in_time"] > 0 and np.isfinite(best) and best > 0
            row["energy_ratio"] = row["energy"] / float(best) if valid else None
    return result


def summary(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Means of the rows' measures, E/opt's mean and median over the episodes in time that have one (NaN where none
    has), and the share of episodes within :data:`HEADING_GOAL`."""
    means = {m: float(np.mean([row[m] for row in rows])) for m in MEASURES}
    ratios = [row["energy_ratio"] for row in rows if row.get("energy_ratio") is not None]
    nan = float("nan")
    return {**means, "energy_ratio": float(np.mean(ratios)) if ratios else nan,
            "energy_ratio_median": float(np.median(ratios)) if ratios else nan,
            "heading_goal_share": float(np.mean([row["final_heading"] <= HEADING_GOAL for row in rows]))}  # fmt: skip


__all__ = ["HEADING_GOAL", "MEASURES", "best_sequences", "energy_ratios", "episode_fn", "summary"]
