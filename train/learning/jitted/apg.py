"""``dwr-gym train --algo apg --backend jax``: analytic policy gradients, the return differentiated through the
functional env.

The task's dynamics (the exact step of eq. (1)), its energy and its terminal payment are smooth functions written in
jax (:mod:`dwr_gym.jax_env`), so the gradient of an episode's return with respect to the policy's weights is computed
exactly by ``jax.grad`` through the whole episode (Brax's APG, Freeman et al. 2021; SHAC, Xu et al. 2022, without
its critic). Each update plays ``episodes`` fresh episodes with the deterministic policy (its mean action, clipped:
no exploration noise, so no noise energy is paid, as ES), ``lax.scan`` over the longest episode with the ended ones
held, and takes one Adam step on the mean return's gradient. v2's return (the env's docstring derives it) pays the
distance and heading at T_con linearly and the energy of every command, so its gradient says how to reach the goal
pose with less energy; v2's arrival bonus (a step at 1 cm) has no gradient and is not what the learner follows.

Gradients through 1,200 steps of a closed loop explode: the cotangent of the env state is clipped to a norm of
``state_grad_clip`` at every step on the way back (:func:`clip_gradient`), and the update's gradient to
``max_grad_norm``; with ``near_miss_clip`` the episodes that end just outside the goal tolerance get a wider clip of
their own (:func:`clip_gradient_carried`); with ``hold_steps`` the gradient follows the miss (and with
``hold_heading_weight`` the heading's error) over the last steps before T_con too (the return stays v2's); with
``lagrangian`` the deadline and the heading are constraints whose multipliers per T_con bin weigh those terms
(:mod:`train.learning.jitted.lagrangian`). Other levers were measured and removed (docs/what-was-tried.md). This learns
from the reward alone: what it uses beside the reward is the env's own derivative, which model-free RL does not have
(the docs say so where it is compared).

The policy is the actor of the jitted PPO's network (:func:`train.learning.jitted.policy.make_network`), exported
as an SB3 PPO model (:class:`train.learning.jitted.export.SB3Exporter`) like the ES's; the observations are scaled by
the mean and deviation of 1,024 first observations, fixed, folded into the exported first layer. With ``keep_best``
the run exports the best policy measured on its own validation episodes (:meth:`JaxAPG.validate`), not the last; with
``weight_average`` the policy validated and exported is the weights' moving average (Polyak averaging). With
``teacher_episodes`` the updates start from a policy cloned from open-loop sequences
(:mod:`train.learning.jitted.apg_teacher`).
"""

from __future__ import annotations

import functools
from typing import Any

import flax.struct
import jax
import jax.numpy as jnp
import optax

from train.learning.jitted import lagrangian
from train.learning.jitted.apg_settings import INITIAL_OBSERVATIONS, APGSettings
from train.learning.jitted.policy import make_network
from train.learning.jitted.ppo import ObservationStatistics


class APGState(flax.struct.PyTreeNode):
    """Everything a run continues from: the network, Adam's state, the observation scaling, the key, the updates, for
    ``keep_best`` the best network measured, its mean return and the key of its validation episodes, the constraints'
    multipliers, and for ``weight_average`` the weights' moving average (the network itself without it)."""

    params: Any
    opt_state: Any
    obs_stats: Any
    rng: Any
    updates: Any
    best_params: Any
    best_return: Any
    validation_key: Any
    multipliers: Any
    average_params: Any


def clipped(cotangent: Any, bound: Any) -> Any:
    """``cotangent`` (a tree) scaled so that the norm of its floating leaves together is at most ``bound``."""

    def floating(leaf: Any) -> bool:
        return hasattr(leaf, "dtype") and jnp.issubdtype(leaf.dtype, jnp.floating)

    norm = jnp.sqrt(sum(jnp.sum(leaf**2) for leaf in jax.tree.leaves(cotangent) if floating(leaf)) + 1e-12)
    factor = jnp.minimum(1.0, bound / norm)
    return jax.tree.map(lambda leaf: leaf * factor if floating(leaf) else leaf, cotangent)


def clip_gradient(tree: Any, limit: float) -> Any:
    """``tree`` unchanged on the way forward; on the way back its cotangent (the floating leaves together) clipped to
    the norm ``limit`` (a number, or a jax scalar)."""

    @jax.custom_vjp
    def identity(x: Any, bound: Any) -> Any:
        return x

    def forward(x: Any, bound: Any) -> tuple[Any, Any]:
        return x, bound

    def backward(bound: Any, cotangent: Any) -> tuple[Any, Any]:
        return clipped(cotangent, bound), jnp.zeros_like(bound)

    identity.defvjp(forward, backward)
    # (the limit an argument, not a closure: a traced one, the decaying clip's, is then allowed)
    return identity(tree, jnp.asarray(limit, jnp.float32))


def clip_gradient_carried(tree: Any, carrier: Any) -> tuple[Any, Any]:
    """``(tree, carrier)`` unchanged on the way forward; on the way back ``tree``'s cotangent clipped to the norm of
    ``carrier``'s (a scalar, passed back unchanged). An episode adds ``bound * carrier`` (0: the carrier is 0) to its
    return once it knows ``bound`` (at its end: :attr:`APGSettings.near_miss_clip`), and the bound then travels back
    with the cotangent to every step: a clip chosen after the forward pass, without playing the episode twice. (The
    bound arrives as it was added when the return's own cotangent is -1 or 1: the update differentiates the sum of
    the returns, not their mean.)"""

    @jax.custom_vjp
    def identity(x: Any, c: Any) -> tuple[Any, Any]:
        return x, c

    def forward(x: Any, c: Any) -> tuple[tuple[Any, Any], None]:
        return (x, c), None

    def backward(_: None, cotangents: tuple[Any, Any]) -> tuple[Any, Any]:
        cotangent, bound = cotangents
        return clipped(cotangent, jnp.abs(bound)), bound

    identity.defvjp(forward, backward)
    return identity(tree, carrier)  # type: ignore[no-any-return]


def all_finite(tree: Any) -> Any:
    """True (a jax bool) where every number of ``tree`` is finite."""
    return jnp.all(jnp.stack([jnp.all(jnp.isfinite(leaf)) for leaf in jax.tree.leaves(tree)]))


class JaxAPG:
    """APG of one configuration on one gymnax-style env: :meth:`init` a state, :meth:`update` it (jitted)."""

    def __init__(
        self, settings: APGSettings, env: Any, env_params: Any, residual: bool = False, total_timesteps: float = 0.0
    ) -> None:
        self.settings, self.env, self.env_params, self.residual = settings, env, env_params, residual
        self.obs_dim = int(env.observation_space(env_params).shape[0])
        self.network = make_network(settings.ppo_settings(), int(env.action_space(env_params).shape[0]))
        self.max_steps = int(getattr(env_params, "max_episode_steps", 0) or env_params.max_steps_in_episode)
        rate: Any = settings.learning_rate
        self.decay_updates = 0
        if settings.linear_schedule:
            # to 0 after the updates the budget buys (episodes of the mean T_con)
            from train.learning.jitted.apg_teacher import teacher_steps

            mean_steps = self.mean_episode_steps()
            budget = max(0.0, total_timesteps - teacher_steps(settings, mean_steps))  # (0 without a teacher)
            self.decay_updates = max(1, round(budget / (settings.episodes * mean_steps)))
            rate = optax.linear_schedule(settings.learning_rate, 0.0, self.decay_updates)
        self.optimizer = optax.chain(optax.clip_by_global_norm(settings.max_grad_norm), optax.adam(rate))
        self.update = jax.jit(self._update)
        self.validate = jax.jit(self._validate)

    def mean_episode_steps(self) -> float:
        """The mean length of an episode, in env steps, over :data:`INITIAL_OBSERVATIONS` fresh ones (those of v2 end
        at T_con; an earlier end makes the schedule's updates more)."""
        keys = jax.random.split(jax.random.PRNGKey(0), INITIAL_OBSERVATIONS)

        _, states = jax.vmap(self.env.reset_env, in_axes=(0, None))(keys, self.env_params)
        return float(jnp.mean(jnp.minimum(states.prescribed_steps, self.max_steps)))

    def init(self, seed: int) -> Any:
        """A fresh state: the network initialised from ``seed`` as the jitted PPO's (a residual's near zero), the
        observation scaling of fresh episodes."""
        rng, key_net, key_obs, key_val = jax.random.split(jax.random.PRNGKey(seed), 4)
        params = self.network.init(key_net, jnp.zeros((self.obs_dim,), jnp.float32))
        if self.residual:  # the search starts at the expert (train.learning.jitted.residual)
            from train.learning.jitted.residual import near_zero_head

            params = near_zero_head(params)
        stats = ObservationStatistics.create(self.obs_dim)
        if self.settings.normalize_observations:
            keys = jax.random.split(key_obs, INITIAL_OBSERVATIONS)
            obs, _ = jax.vmap(self.env.reset_env, in_axes=(0, None))(keys, self.env_params)
            stats = stats.update(jnp.asarray(obs, jnp.float32))
        state = APGState(params=params, opt_state=self.optimizer.init(params), obs_stats=stats, rng=rng,
                         updates=jnp.asarray(0, jnp.int32), best_params=params,
                         best_return=jnp.asarray(-jnp.inf, jnp.float32), validation_key=key_val,
                         multipliers=lagrangian.initial_multipliers(self.settings.constraint, jnp),
                         average_params=params)  # fmt: skip
        return jax.tree.map(lambda x: jnp.asarray(x, x.dtype), state)  # no weak types: one compilation

    def act(self, params: Any, obs: Any, stats: Any) -> Any:
        """The deterministic action: the network's mean on the (scaled) observation, clipped as SB3 clips it."""
        if self.settings.normalize_observations:
            obs = stats.normalize(obs)
        mean, _, _ = self.network.apply(params, jnp.asarray(obs, jnp.float32))
        return jnp.clip(mean, -1.0, 1.0)

    def episode(self, params: Any, stats: Any, key: Any, limit: Any = None) -> tuple[Any, Any]:
        """One episode's return (differentiable in ``params``, the state's gradient clipped to ``limit``, by default
        ``state_grad_clip``) and its env steps."""
        total, steps, _ = self.play(params, stats, key, limit)
        return total, steps

    def play(
        self, params: Any, stats: Any, key: Any, limit: Any = None, multipliers: Any = None
    ) -> tuple[Any, Any, Any]:
        """:meth:`episode`'s return and env steps, and the episode's last state. With ``multipliers`` (the
        constraint's, (2, bins)), the gradient also follows the constraints' smooth violations over the window before
        T_con, each weighed by its multiplier at this episode's T_con (:mod:`train.learning.jitted.lagrangian`)."""
        key_reset, key_steps = jax.random.split(key)
        _, start = self.env.reset_env(key_reset, self.env_params)
        limit = self.settings.state_grad_clip if limit is None else limit

        near_miss = self.settings.near_miss_clip is not None
        hold: Any = self.settings.hold_steps
        holding = bool(self.settings.hold_steps)
        weights = None
        if multipliers is not None:  # this episode's multipliers, constants of its gradient
            constraint = self.settings.constraint
            bin_index = lagrangian.T_con_bin(start.T_con, self.env_params.T_con_range, constraint.multiplier_bins, jnp)
            weights = jax.lax.stop_gradient(multipliers[:, bin_index])
            if not holding:  # the constraints at T_con alone: a window of one step
                hold, holding = 1, True

        def one_step(carry: tuple[Any, ...], t: Any) -> tuple[tuple[Any, ...], None]:
            state, carrier, alive, total, held, steps = carry
            if near_miss:  # the clip is chosen at the end and comes back with the carrier's cotangent
                state, carrier = clip_gradient_carried(state, carrier)
            elif self.settings.state_grad_clip > 0:
                state = clip_gradient(state, limit)
            action = self.act(params, state.observation, stats)
            _, after, reward, done, _ = self.env.step_env(jax.random.fold_in(key_steps, t), state, action,
                                                          self.env_params)  # fmt: skip
            total = total + jnp.where(alive, reward, 0.0)
            if holding:  # the miss over the last `hold` steps up to T_con (hold_steps): the gradient
                last = after.step_count > after.prescribed_steps - hold
                if weights is not None:  # the multipliers weigh the smooth violations (distance, heading error)
                    miss = weights[0] * after.distance + weights[1] * 2.0 * jnp.abs(jnp.sin(0.5 * after.psi))
                else:
                    miss = self.settings.hold_weight * after.distance
                if (
                    weights is None and self.settings.hold_heading_weight
                ):  # the heading's error, linear near 0 (2 |sin(psi / 2)|)
                    miss = miss + self.settings.hold_heading_weight * 2.0 * jnp.abs(jnp.sin(0.5 * after.psi))
                held = held - jnp.where(alive & last, miss / hold, 0.0)
            state = jax.tree.map(lambda new, old: jnp.where(alive, new, old), after, state)
            return (state, carrier, alive & ~done, total, held, steps + alive.astype(jnp.int32)), None

        zero = jnp.asarray(0.0, jnp.float32)
        # (the carrier from the episode's own start: under vmap a constant would be one for all episodes, and its
        # cotangent the sum of their bounds)
        carrier = (start.distance * 0.0).astype(jnp.float32)
        carry = (start, carrier, jnp.asarray(True), zero, zero, jnp.asarray(0, jnp.int32))
        (final, carrier, _, total, held, steps), _ = jax.lax.scan(one_step, carry, jnp.arange(self.max_steps))
        if holding:  # + 0: the return as it is, the held miss's gradient in it
            total = total + (held - jax.lax.stop_gradient(held))
        if near_miss:  # + bound * 0: the return as it is, the episode's clip into the carrier's cotangent
            total = total + jax.lax.stop_gradient(self.episode_clip(final, limit)) * carrier
        return total, steps, final

    def near_miss(self, final: Any) -> Any:
        """True where an episode's last state ``final`` is a near miss: the goal tolerance < its distance <=
        ``near_miss_distance`` (:attr:`APGSettings.near_miss_clip`)."""
        distance = final.distance
        return (distance > self.env_params.goal_tolerance) & (distance <= self.settings.near_miss_distance)

    def episode_clip(self, final: Any, limit: Any) -> Any:
        """The state's gradient clip of the episode whose last state is ``final``: ``near_miss_clip`` (if set) for a
        near miss, else ``limit`` (``state_grad_clip`` or its decay)."""
        limit = jnp.asarray(limit, jnp.float32)
        if self.settings.near_miss_clip is None:
            return limit
        return jnp.where(self.near_miss(final), self.settings.near_miss_clip, limit)

    def exported_params(self, state: Any) -> Any:
        """The network a run exports: with ``keep_best`` the best measured (:meth:`validate`), else the last (with
        ``weight_average``, the weights' moving average)."""
        return state.best_params if self.settings.keep_best else self.policy_params(state)

    def policy_params(self, state: Any) -> Any:
        """The network that is validated and exported: the weights' moving average with ``weight_average``, else the
        last network."""
        return state.average_params if self.settings.weight_average else state.params

    def _validate(self, state: Any) -> tuple[Any, dict[str, Any]]:
        """The policy's mean return on the run's ``validation_episodes`` fixed episodes; kept as the best when higher
        than the best so far (a network with a non-finite weight, or its non-finite return, never is: the env holds a
        NaN action's robot still, so such a network can score above a poor one)."""
        keys = jax.random.split(state.validation_key, self.settings.validation_episodes)
        candidate = self.policy_params(state)
        returns, steps = jax.vmap(self.episode, in_axes=(None, None, 0))(candidate, state.obs_stats, keys)
        mean = jnp.mean(returns)
        better = all_finite(candidate) & jnp.isfinite(mean) & (mean > state.best_return)
        state = state.replace(best_params=jax.tree.map(lambda new, old: jnp.where(better, new, old), candidate,
                                                       state.best_params),
                              best_return=jnp.where(better, mean, state.best_return))  # fmt: skip
        return state, {"steps": jnp.sum(steps), "validation_return": mean, "kept": better}

    def _update(self, state: Any) -> tuple[Any, dict[str, Any]]:
        rng, key = jax.random.split(state.rng)
        keys = jax.random.split(key, self.settings.episodes)

        limit = self.settings.state_grad_clip

        constrained = self.settings.constraint.lagrangian

        def loss(params: Any) -> tuple[Any, tuple[Any, Any, Any]]:
            if constrained:
                play = functools.partial(self.play, multipliers=state.multipliers.value)
                returns, steps, final = jax.vmap(play, in_axes=(None, None, 0, None))(params, state.obs_stats, keys,
                                                                                     limit)  # fmt: skip
            else:
                returns, steps = jax.vmap(self.episode, in_axes=(None, None, 0, None))(params, state.obs_stats, keys,
                                                                                       limit)  # fmt: skip
                final = None
            return -jnp.sum(returns), (returns, steps, final)

        # The sum's gradient, then divided: each episode's state cotangent enters the backward pass at the scale of
        # its own return, so state_grad_clip clips each episode's as that episode's gradient alone would be clipped
        # (the mean's would be 1/episodes of it, and the clip's effect would change with the batch's size)
        grads, (returns, steps, final) = jax.grad(loss, has_aux=True)(state.params)
        grads = jax.tree.map(lambda g: g / self.settings.episodes, grads)
        # Guard: an episode whose derivative is undefined somewhere (0/0 at the goal, the law's gain at T_con) makes the
        # batch's gradient NaN; that update is skipped (a zero gradient; Adam's moments carry on) rather than poisoning
        # the weights. (Leaving such episodes out of the mean instead, a per-episode gradient, was measured to break the
        # residual on PTC, with its clip then 64 times tighter than this update's: docs/rl-apg.md.)
        finite = all_finite(grads)
        grads = jax.tree.map(lambda g: jnp.where(finite, g, 0.0), grads)
        updates, opt_state = self.optimizer.update(grads, state.opt_state, state.params)
        params = optax.apply_updates(state.params, updates)
        average = params
        if self.settings.weight_average:  # Polyak averaging: the average moves (1 - decay) of the way to the network
            decay = self.settings.weight_average
            average = jax.tree.map(lambda a, p: decay * a + (1.0 - decay) * p, state.average_params, params)
        multipliers, constraint_metrics = state.multipliers, {}
        if constrained:  # the multipliers from this update's fresh episodes' violations, per T_con bin
            multipliers, constraint_metrics = self.constraint_step(state.multipliers, final)
        state = state.replace(params=params, opt_state=opt_state, rng=rng, updates=state.updates + 1,
                              multipliers=multipliers, average_params=average)  # fmt: skip
        metrics = {"steps": jnp.sum(steps), "return_mean": jnp.mean(returns), "grad_norm": optax.tree.norm(grads),
                   "skipped": ~finite, **constraint_metrics}  # fmt: skip
        return state, metrics

    def constraint_step(self, multipliers: Any, final: Any) -> tuple[Any, dict[str, Any]]:
        """The multipliers after the violations of the episodes whose last states are ``final``, and per T_con bin
        (arrays (bins,)) the violation rate, the mean final heading error, the mean energy, the episodes and the
        multipliers used."""
        constraint = self.settings.constraint
        bins = constraint.multiplier_bins
        cost, _, _ = self.final_cost(final)
        bin_index = lagrangian.T_con_bin(final.T_con, self.env_params.T_con_range, bins, jnp)
        measured, counts = lagrangian.violations(cost, final.heading_error, bin_index, constraint, jnp)
        energy, _ = lagrangian.binned_means(final.energy[None, :].astype(jnp.float32), bin_index, bins, jnp)
        updated = lagrangian.pid_update(multipliers, measured, counts, constraint, jnp)
        return updated, {"violation_rate": measured[0], "heading": measured[1], "energy": energy[0],
                         "episodes": counts, "deadline_multiplier": multipliers.value[0],
                         "heading_multiplier": multipliers.value[1]}  # fmt: skip

    def final_cost(self, final: Any) -> tuple[Any, Any, Any]:
        """The env's cost and smooth violations (:func:`dwr_gym.core.deadline_cost`) of episodes' last states: an
        episode that ended (at T_con, or leaving the arena) not in time costs 1."""
        from dwr_gym.core import deadline_cost

        p = self.env_params
        heading_tolerance = jnp.where(jnp.isinf(p.heading_tolerance), 0.0, p.heading_tolerance)
        return deadline_cost(jnp.ones_like(final.is_success), final.is_success, final.step_count,  # type: ignore[no-any-return]
                             final.prescribed_steps, final.distance, final.heading_error, p.goal_tolerance,
                             heading_tolerance, jnp)  # fmt: skip
