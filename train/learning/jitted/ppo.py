"""PPO in the PureJaxRL style (Lu et al. 2022, purejaxrl/ppo_continuous_action.py): the rollout of n_envs robots
of a functional (gymnax-style) env under ``vmap``, GAE and the minibatch epochs, all in one jitted function of a
:class:`Runner`, the whole training state; ``jax.vmap`` of it trains several seeds at once.

It follows stable-baselines3's PPO step for step, so that its hyperparameters mean what they mean in
train/hyperparams/ppo.yml: actions sampled from a diagonal Gaussian and clipped to the action space for the env
(the log-probability is the unclipped sample's), a value bootstrapped from the final observation of a truncated
episode, advantages normalised per minibatch, the clipped surrogate plus ``vf_coef`` times the squared value
error, gradients clipped to ``max_grad_norm``, Adam with eps 1e-5.

>>> import gymnax, jax
>>> from train.learning.jitted.policy import PPOSettings
>>> env, env_params = gymnax.make("Pendulum-v1")
>>> settings = PPOSettings(n_envs=4, n_steps=8, batch_size=16, n_epochs=1)
>>> ppo = JaxPPO(settings, env, env_params)
>>> runner = ppo.init(seed=0)
>>> runner, metrics = ppo.run(runner, 2, total_timesteps=64)
>>> int(runner.updates), metrics["episodes"].shape
(2, ())
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import flax.struct
import jax
import jax.numpy as jnp
import optax

from train.learning.jitted.policy import PPOSettings, gaussian_entropy, gaussian_log_prob, make_network

#: The epsilon of stable-baselines3's VecNormalize: observations are (obs - mean) / sqrt(var + OBS_EPSILON).
OBS_EPSILON = 1e-8


class ObservationStatistics(flax.struct.PyTreeNode):
    """Running mean and variance of the observations (SB3's RunningMeanStd, parallel algorithm)."""

    mean: Any
    var: Any
    count: Any

    @classmethod
    def create(cls, size: int) -> ObservationStatistics:
        return cls(jnp.zeros(size), jnp.ones(size), jnp.asarray(1e-4))

    def update(self, batch: Any) -> ObservationStatistics:
        return self.update_moments(jnp.mean(batch, axis=0), jnp.var(batch, axis=0), batch.shape[0])

    def update_moments(self, batch_mean: Any, batch_var: Any, batch_count: Any) -> ObservationStatistics:
        """The statistics after a batch of ``batch_count`` observations of this mean and variance."""
        delta, total = batch_mean - self.mean, self.count + batch_count
        m2 = self.var * self.count + batch_var * batch_count + delta**2 * self.count * batch_count / total
        return ObservationStatistics(self.mean + delta * batch_count / total, m2 / total, total)

    def normalize(self, obs: Any) -> Any:
        return ((obs - self.mean) / jnp.sqrt(self.var + OBS_EPSILON)).astype(jnp.float32)


class Runner(flax.struct.PyTreeNode):
    """Everything a run continues from: network and optimiser, the n_envs envs, the key, the counters."""

    params: Any
    opt_state: Any
    env_state: Any
    obs: Any  # (n_envs, obs_dim), normalised if the settings say so
    obs_stats: ObservationStatistics
    rng: Any
    updates: Any  # updates done
    episode_return: Any  # (n_envs,) return so far of the running episodes


class Transition(NamedTuple):
    obs: Any
    action: Any
    log_prob: Any
    value: Any
    reward: Any
    terminated: Any
    truncated: Any
    final_obs: Any
    info: Any = None
    """The step's info values a subclass asks for (:attr:`JaxPPO.info_keys`; PPO-Lagrangian's cost), else None."""


def env_step(
    env: Any, env_params: Any, key: Any, state: Any, action: Any, info_keys: tuple[str, ...] = ()
) -> tuple[Any, ...]:
    """One step of a gymnax-style env (``step_env`` and ``reset_env``) with auto-reset: (obs, state, reward,
    terminated, truncated, final_obs, success); ``final_obs`` is the observation the step reached (the one that
    ended the episode, where one ended), which SB3's PPO bootstraps a truncated episode's value from. With
    ``info_keys``, an eighth element: those values of the step's info (of the ended episode where one ended), as
    float32.

    Termination and truncation are ``info["terminated"]`` and ``info["truncated"]`` where the env reports them,
    else ``done`` and gymnax's ``is_truncated``."""
    key_step, key_reset = jax.random.split(key)
    obs_step, state_step, reward, done, info = env.step_env(key_step, state, action, env_params)
    terminated = jnp.asarray(info.get("terminated", done), bool)
    truncated = info["truncated"] if "truncated" in info else env.is_truncated(state_step, env_params)
    truncated = jnp.asarray(truncated, bool) & ~terminated
    obs_reset, state_reset = env.reset_env(key_reset, env_params)
    ended = terminated | truncated
    state = jax.tree.map(lambda r, s: jax.lax.select(ended, r, s), state_reset, state_step)
    obs = jax.lax.select(ended, obs_reset, obs_step)
    success = jnp.asarray(info.get("is_success", False), bool)
    result = (obs, state, jnp.asarray(reward, jnp.float32), terminated, truncated, obs_step, success)
    if info_keys:
        return (*result, {name: jnp.asarray(info[name], jnp.float32) for name in info_keys})
    return result


def gae(rewards: Any, values: Any, terminated: Any, truncated: Any, final_values: Any, last_value: Any,
        gamma: float, lam: float) -> tuple[Any, Any]:  # fmt: skip
    """GAE(gamma, lambda) advantages and returns (advantages + values) of a rollout (arrays (n_steps, n_envs)),
    as SB3's PPO computes them: the reward of a truncated, not terminated, step gets gamma * V(final observation)
    (``final_values``), and an episode's end cuts the recursion; ``last_value`` (n_envs,) bootstraps the last step."""
    rewards = rewards + gamma * jnp.where(truncated & ~terminated, final_values, 0.0)
    alive = 1.0 - (terminated | truncated).astype(jnp.float32)

    def backward(carry: tuple[Any, Any], step: tuple[Any, Any, Any]) -> tuple[tuple[Any, Any], Any]:
        advantage, next_value = carry
        reward, value, not_done = step
        delta = reward + gamma * next_value * not_done - value
        advantage = delta + gamma * lam * not_done * advantage
        return (advantage, value), advantage

    _, advantages = jax.lax.scan(backward, (jnp.zeros_like(last_value), last_value), (rewards, values, alive),
                                 reverse=True)  # fmt: skip
    return advantages, advantages + values


def clipped_surrogate(log_prob: Any, old_log_prob: Any, advantages: Any, clip_range: float) -> Any:
    """PPO's clipped surrogate loss (Schulman et al. 2017, eq. (7), negated): the mean of -min(r A, clip(r) A)."""
    ratio = jnp.exp(log_prob - old_log_prob)
    clipped = jnp.clip(ratio, 1.0 - clip_range, 1.0 + clip_range)
    return -jnp.mean(jnp.minimum(advantages * ratio, advantages * clipped))


def actor_masked_grad(grad: Any, frozen: Any, params: Any, batch: Any) -> Any:
    """``grad(params, batch)`` with the actor's gradients (the policy layers, the mean head, log_std) zero where
    ``frozen``."""
    grads = grad(params, batch)
    actor = {name for name in grads["params"] if name.startswith("policy_") or name in ("action", "log_std")}
    masked = {name: jax.tree.map(lambda g: jnp.where(frozen, 0.0, g), leaf) if name in actor else leaf
              for name, leaf in grads["params"].items()}  # fmt: skip
    return {**grads, "params": masked}


class JaxPPO:
    """The jitted PPO of one configuration on one functional env: :meth:`init` a :class:`Runner`, :meth:`run` it
    for some updates; :meth:`run_seeds` and :meth:`init_seeds` do the same for several seeds under ``vmap``."""

    #: The step's info values each transition keeps (:attr:`Transition.info`): none for PPO.
    info_keys: tuple[str, ...] = ()

    def __init__(self, settings: PPOSettings, env: Any, env_params: Any) -> None:
        settings.check()
        self.settings, self.env, self.env_params = settings, env, env_params
        action_space = env.action_space(env_params)
        self.action_low = jnp.asarray(action_space.low, jnp.float32)
        self.action_high = jnp.asarray(action_space.high, jnp.float32)
        self.action_dim = int(action_space.shape[0])
        self.obs_dim = int(env.observation_space(env_params).shape[0])
        self.network = make_network(settings, self.action_dim)
        self.optimizer = optax.chain(optax.clip_by_global_norm(settings.max_grad_norm), optax.scale_by_adam(eps=1e-5))
        self.run = jax.jit(self._run)
        self.run_seeds = jax.jit(jax.vmap(self._run, in_axes=(0, None, None)))
        self.init_seeds = jax.jit(jax.vmap(self._init))

    def init(self, seed: int) -> Runner:
        """A fresh runner: the network initialised from ``seed``, the envs reset, nothing learned."""
        return jax.jit(self._init)(jax.random.PRNGKey(seed))

    def _init(self, rng: Any) -> Runner:
        rng, key_net, key_env = jax.random.split(rng, 3)
        params = self.network.init(key_net, jnp.zeros((self.obs_dim,), jnp.float32))
        keys = jax.random.split(key_env, self.settings.n_envs)
        obs, env_state = jax.vmap(self.env.reset, in_axes=(0, None))(keys, self.env_params)
        stats = ObservationStatistics.create(self.obs_dim)
        if self.settings.normalize_observations:
            stats = stats.update(obs)
            obs = stats.normalize(obs)
        return Runner(params, self.optimizer.init(params), env_state, jnp.asarray(obs, jnp.float32), stats, rng,
                      jnp.asarray(0, jnp.int32), jnp.zeros(self.settings.n_envs, jnp.float32))  # fmt: skip

    def _run(self, runner: Runner, n_updates: Any, total_timesteps: Any) -> tuple[Runner, dict[str, Any]]:
        """``n_updates`` updates (a traced number: one compilation serves every chunk length); the metrics are
        sums over them (episodes ended, their returns and successes, env steps)."""
        metrics = self.zero_metrics()

        def body(_: Any, carry: tuple[Runner, dict[str, Any]]) -> tuple[Runner, dict[str, Any]]:
            runner, totals = carry
            runner, step = self.update(runner, total_timesteps)
            return runner, {k: totals[k] + step[k] for k in totals}

        return jax.lax.fori_loop(0, n_updates, body, (runner, metrics))

    def zero_metrics(self) -> dict[str, Any]:
        """The metrics :meth:`update` returns, at 0: what :meth:`_run` sums over updates."""
        return {k: jnp.asarray(0.0, jnp.float32) for k in ("episodes", "return_sum", "successes", "reward_sum")}

    def policy(self, params: Any, obs: Any) -> tuple[Any, Any, Any]:
        return self.network.apply(params, obs)

    def collect(self, runner: Runner) -> tuple[Runner, Transition, dict[str, Any]]:
        """n_steps steps of the n_envs envs under the current policy (``lax.scan``)."""
        step = functools.partial(env_step, self.env, self.env_params, info_keys=self.info_keys)

        def one_step(carry: tuple[Runner, dict[str, Any]], _: Any) -> tuple[tuple[Runner, dict[str, Any]], Any]:
            runner, totals = carry
            rng, key_action, key_env = jax.random.split(runner.rng, 3)
            mean, log_std, value = self.policy(runner.params, runner.obs)
            action = mean + jnp.exp(log_std) * jax.random.normal(key_action, mean.shape)
            log_prob = gaussian_log_prob(action, mean, log_std)
            clipped = jnp.clip(action, self.action_low, self.action_high)
            keys = jax.random.split(key_env, self.settings.n_envs)
            stepped = jax.vmap(step, in_axes=(0, 0, 0))(keys, runner.env_state, clipped)
            obs, env_state, reward, terminated, truncated, final_obs, success = stepped[:7]
            info = stepped[7] if self.info_keys else None
            stats = runner.obs_stats
            obs, final_obs = obs.astype(jnp.float32), final_obs.astype(jnp.float32)
            if self.settings.normalize_observations:
                stats = stats.update(obs)
                obs, final_obs = stats.normalize(obs), stats.normalize(final_obs)
            done = terminated | truncated
            episode_return = runner.episode_return + reward
            totals = {
                "episodes": totals["episodes"] + jnp.sum(done),
                "return_sum": totals["return_sum"] + jnp.sum(jnp.where(done, episode_return, 0.0)),
                "successes": totals["successes"] + jnp.sum(done & success),
                "reward_sum": totals["reward_sum"] + jnp.sum(reward),
            }
            transition = Transition(runner.obs, action, log_prob, value, reward, terminated, truncated, final_obs,
                                    info)  # fmt: skip
            runner = runner.replace(env_state=env_state, obs=obs, obs_stats=stats, rng=rng,
                                    episode_return=jnp.where(done, 0.0, episode_return))  # fmt: skip
            return (runner, totals), transition

        zero = {k: jnp.asarray(0.0, jnp.float32) for k in ("episodes", "return_sum", "successes", "reward_sum")}
        (runner, totals), transitions = jax.lax.scan(one_step, (runner, zero), None, self.settings.n_steps)
        return runner, transitions, totals

    def advantages(self, params: Any, transitions: Transition, last_obs: Any) -> tuple[Any, Any]:
        """:func:`gae` of a rollout, with the values of its final and its last observations."""
        final_values = self.policy(params, transitions.final_obs)[2]
        last_value = self.policy(params, last_obs)[2]
        return gae(transitions.reward, transitions.value, transitions.terminated, transitions.truncated, final_values,
                   last_value, self.settings.gamma, self.settings.gae_lambda)  # fmt: skip

    def prepare(self, runner: Runner, transitions: Transition) -> tuple[Runner, tuple[Any, ...], dict[str, Any]]:
        """What the epochs learn from, arrays (n_steps, n_envs, ...) in :meth:`loss`'s order (observations, actions,
        log-probabilities, advantages, returns), the runner to learn on and metrics beside :meth:`collect`'s."""
        advantages, returns = self.advantages(runner.params, transitions, runner.obs)
        return runner, (transitions.obs, transitions.action, transitions.log_prob, advantages, returns), {}

    def loss(self, params: Any, batch: tuple[Any, ...]) -> Any:
        """SB3's PPO loss on one minibatch: clipped surrogate + ent_coef * (-entropy) + vf_coef * MSE(returns)."""
        s = self.settings
        obs, actions, old_log_prob, advantages, returns = batch
        mean, log_std, values = self.policy(params, obs)
        if s.normalize_advantage and advantages.shape[0] > 1:
            advantages = (advantages - advantages.mean()) / (jnp.std(advantages, ddof=1) + 1e-8)
        policy_loss = clipped_surrogate(gaussian_log_prob(actions, mean, log_std), old_log_prob, advantages,
                                        s.clip_range)  # fmt: skip
        value_loss = jnp.mean((returns - values) ** 2)
        entropy_loss = -jnp.mean(gaussian_entropy(log_std) * jnp.ones_like(values))
        return policy_loss + s.ent_coef * entropy_loss + s.vf_coef * value_loss

    def update(self, runner: Runner, total_timesteps: Any) -> tuple[Runner, dict[str, Any]]:
        """One PPO update: a rollout, its advantages, then n_epochs passes of shuffled minibatches."""
        s = self.settings
        runner, transitions, totals = self.collect(runner)
        runner, batch, extra = self.prepare(runner, transitions)
        totals = {**totals, **extra}
        flat = jax.tree.map(lambda x: x.reshape((s.steps_per_update, *x.shape[2:])), batch)
        done_after = (runner.updates + 1).astype(jnp.float32) * s.steps_per_update
        progress_remaining = 1.0 - done_after / jnp.asarray(total_timesteps, jnp.float32)
        rate = s.learning_rate * (jnp.maximum(progress_remaining, 0.0) if s.linear_schedule else 1.0)
        grad = jax.grad(self.loss)
        if s.critic_warmup:  # the actor frozen (its gradients zero) until critic_warmup env steps are done
            grad = functools.partial(actor_masked_grad, grad, runner.updates * s.steps_per_update < s.critic_warmup)

        def minibatch_step(carry: tuple[Any, Any], batch: tuple[Any, ...]) -> tuple[tuple[Any, Any], None]:
            params, opt_state = carry
            updates, opt_state = self.optimizer.update(grad(params, batch), opt_state, params)
            params = jax.tree.map(lambda p, u: p - rate * u, params, updates)
            return (params, opt_state), None

        def epoch(carry: tuple[Any, Any, Any], _: Any) -> tuple[tuple[Any, Any, Any], None]:
            params, opt_state, rng = carry
            rng, key = jax.random.split(rng)
            order = jax.random.permutation(key, s.steps_per_update)
            batches = jax.tree.map(lambda x: x[order].reshape((s.minibatches, s.minibatch_size, *x.shape[1:])), flat)
            (params, opt_state), _ = jax.lax.scan(minibatch_step, (params, opt_state), batches)
            return (params, opt_state, rng), None

        (params, opt_state, rng), _ = jax.lax.scan(
            epoch, (runner.params, runner.opt_state, runner.rng), None, s.n_epochs
        )
        if s.log_std_final is not None or s.log_std_fixed:  # the exploration noise capped by (or set to) its schedule
            cap = s.log_std_cap(jnp.clip(1.0 - progress_remaining, 0.0, 1.0))
            inner = params["params"]
            log_std = jnp.full_like(inner["log_std"], cap) if s.log_std_fixed else jnp.minimum(inner["log_std"], cap)
            params = {**params, "params": {**inner, "log_std": log_std}}
        runner = runner.replace(params=params, opt_state=opt_state, rng=rng, updates=runner.updates + 1)
        return runner, totals
