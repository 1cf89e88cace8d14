"""Evolution strategies on the functional env (``dwr-gym train --algo es --backend jax``), on evosax's strategies.

A generation is one jitted function (:meth:`JaxES.generation`): the strategy's ``ask`` draws ``population_size``
perturbations of the policy's parameters (mirrored pairs with antithetic sampling), every candidate plays the same
``episodes`` episodes (common random numbers: the same starts, T_con and step keys for all), its fitness is the
mean *deterministic* return (the policy's mean action, clipped: no action noise, so no noise energy is paid),
and the strategy's ``tell`` moves the search distribution by the centered ranks of the fitnesses (a NaN return, a
diverged candidate, ranks last). The episodes are stepped under ``vmap`` over candidates and episodes, in
``lax.scan`` chunks of steps inside a ``lax.while_loop`` that stops when every episode has ended; the candidates are
split across the host's XLA devices with ``shard_map`` (one device per core: :func:`train.learning.evolution.trainer.force_host_devices`).

The policy is the actor of the jitted PPO's network (:func:`train.learning.jitted.policy.make_network`): only its
layers ``policy_<i>`` and ``action`` evolve; :meth:`JaxES.mean_params` puts the mean into the whole network so
:class:`train.learning.jitted.export.SB3Exporter` writes it as an SB3 PPO model like any other agent.
"""

from __future__ import annotations

from typing import Any

import evosax.algorithms as algorithms
import flax.struct
import jax
import jax.numpy as jnp
import optax
from evosax.core.optimizer import clipup
from jax.sharding import NamedSharding, PartitionSpec

from train.learning.evolution.settings import STRATEGIES, ESSettings
from train.learning.jitted.policy import make_network
from train.learning.jitted.ppo import ObservationStatistics

#: Steps of one ``lax.scan`` chunk between two checks of whether every episode has ended.
STEPS_PER_CHUNK = 25
#: Observations of fresh episodes the observation statistics start from.
INITIAL_OBSERVATIONS = 1024


def centered_ranks(fitness: Any) -> Any:
    """Ranks of ``fitness`` (lower is better, evosax's convention) scaled to [-0.5, 0.5] (Salimans et al. 2017):
    the best gets -0.5, the worst 0.5; a NaN counts as +inf, the worst (ties share their mean rank)."""
    ranks = jax.scipy.stats.rankdata(jnp.where(jnp.isnan(fitness), jnp.inf, fitness)) - 1.0
    return ranks / (fitness.shape[-1] - 1) - 0.5


def fitness_of(returns: Any) -> Any:
    """evosax's fitness (minimised) of mean returns (maximised): their negative, +inf where a return is NaN."""
    return jnp.where(jnp.isnan(returns), jnp.inf, -returns)


class MirroredSNES(algorithms.SNES):  # type: ignore[misc]
    """SNES sampling mirrored pairs mean +- std * z (antithetic sampling)."""

    def _ask(self, key: Any, state: Any, params: Any) -> tuple[Any, Any]:
        z = jax.random.normal(key, (self.population_size // 2, self.num_dims))
        return state.mean + state.std * jnp.concatenate([z, -z]), state


def _shaping(population: Any, fitness: Any, state: Any, params: Any) -> Any:
    return centered_ranks(fitness)


def make_strategy(settings: ESSettings, solution: Any) -> tuple[Any, Any]:
    """The evosax strategy of ``settings`` over pytrees shaped as ``solution``, and its params."""
    size, name, rate = settings.population_size, settings.strategy, settings.learning_rate
    if name == "open_es":
        strategy = algorithms.Open_ES(size, solution, use_antithetic_sampling=settings.antithetic,
                                      optimizer=optax.adam(rate), std_schedule=optax.constant_schedule(settings.sigma),
                                      fitness_shaping_fn=_shaping)  # fmt: skip
        return strategy, strategy.default_params
    if name == "pgpe":
        strategy = algorithms.PGPE(size, solution, optimizer=clipup(rate, max_velocity=2 * rate),
                                   fitness_shaping_fn=_shaping)  # fmt: skip
    elif name == "snes":
        strategy = (MirroredSNES if settings.antithetic else algorithms.SNES)(size, solution, optax.sgd(rate))
    else:
        strategy = getattr(algorithms, STRATEGIES[name])(size, solution)
    return strategy, strategy.default_params.replace(std_init=settings.sigma)


class ESState(flax.struct.PyTreeNode):
    """Everything a run continues from: the network (its critic and log_std unused, but exported), the
    strategy's state (mean, step sizes, optimiser), the observation statistics, the key, the generations."""

    params: Any
    strategy: Any
    obs_stats: ObservationStatistics
    rng: Any
    generations: Any


class JaxES:
    """ES of one configuration on one gymnax-style env: :meth:`init` an :class:`ESState`, :meth:`generation` it."""

    def __init__(
        self,
        settings: ESSettings,
        env: Any,
        env_params: Any,
        devices: int | None = None,
        residual: bool = False,
        initial_actor: Any = None,
        initial_source: str = "the saved network",
    ) -> None:
        self.settings, self.env, self.env_params, self.residual = settings, env, env_params, residual
        #: a saved actor's layers the search starts from (train.learning.evolution.init_from), or None
        self.initial_actor, self.initial_source = initial_actor, initial_source
        space = env.action_space(env_params)
        self.action_low = jnp.asarray(space.low, jnp.float32)
        self.action_high = jnp.asarray(space.high, jnp.float32)
        self.obs_dim = int(env.observation_space(env_params).shape[0])
        self.network = make_network(settings.ppo_settings(), int(space.shape[0]))
        self.max_steps = int(getattr(env_params, "max_episode_steps", 0) or env_params.max_steps_in_episode)
        available = len(jax.devices()) if devices is None else min(devices, len(jax.devices()))
        #: devices the candidates are split over: the most that divide the population
        self.devices = max(d for d in range(1, available + 1) if settings.population_size % d == 0)
        shapes = jax.eval_shape(self.network.init, jax.random.PRNGKey(0), jnp.zeros((self.obs_dim,), jnp.float32))
        solution = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), self.actor(shapes))
        self.strategy, self.strategy_params = make_strategy(settings, solution)
        self.mesh = jax.make_mesh((self.devices,), ("c",), (jax.sharding.AxisType.Auto,),
                                  devices=jax.devices()[: self.devices])  # fmt: skip
        # the state is replicated on the mesh before and after a generation (else the second compiles again)
        self.replicated = NamedSharding(self.mesh, PartitionSpec())
        self.generation = jax.jit(self._generation, out_shardings=self.replicated)

    def actor(self, params: Any) -> dict[str, Any]:
        """The layers of ``params`` (the whole network's) that the ES evolves: the hidden layers and the mean head."""
        return {k: v for k, v in params["params"].items() if k.startswith("policy_") or k == "action"}

    def init(self, seed: int) -> Any:
        """A fresh state: the network initialised from ``seed`` as the jitted PPO's (its actor the saved one with
        ``initial_actor``), the search centred on it."""
        return jax.jit(self._init, out_shardings=self.replicated)(jax.random.PRNGKey(seed))

    def _init(self, rng: Any) -> Any:
        rng, key_net, key_strategy, key_obs = jax.random.split(rng, 4)
        params = self.network.init(key_net, jnp.zeros((self.obs_dim,), jnp.float32))
        if self.residual:  # the search starts at the expert: a residual near zero (train.learning.jitted.residual)
            from train.learning.jitted.residual import near_zero_head

            params = near_zero_head(params)
        if self.initial_actor is not None:  # --init-from: the search starts at a saved network
            from train.learning.evolution.init_from import centred_on

            params = centred_on(params, self.initial_actor, self.initial_source)
        stats = ObservationStatistics.create(self.obs_dim)
        if self.settings.normalize_observations:
            keys = jax.random.split(key_obs, INITIAL_OBSERVATIONS)
            obs, _ = jax.vmap(self.env.reset_env, in_axes=(0, None))(keys, self.env_params)
            stats = stats.update(jnp.asarray(obs, jnp.float32))
        state = ESState(params=params, strategy=self.strategy.init(key_strategy, self.actor(params), self.strategy_params),
                        obs_stats=stats, rng=rng, generations=jnp.asarray(0, jnp.int32))  # fmt: skip
        return _strongly_typed(state)

    def mean_params(self, state: Any) -> Any:
        """The whole network's parameters with the search mean as its actor: the policy the run stands for."""
        return {"params": {**state.params["params"], **self.strategy.get_mean(state.strategy)}}

    def act(self, params: Any, obs: Any, stats: Any) -> Any:
        """The deterministic action: the network's mean on the (normalised) observation, clipped as SB3 clips it."""
        if self.settings.normalize_observations:
            obs = stats.normalize(obs)
        mean, _, _ = self.network.apply(params, jnp.asarray(obs, jnp.float32))
        return jnp.clip(mean, self.action_low, self.action_high)

    def _generation(self, state: Any) -> tuple[Any, dict[str, Any]]:
        """One generation: ask, every candidate's episodes, tell; the metrics count the env steps it took."""
        strategy, strategy_params = self.strategy, self.strategy_params
        rng, key_ask, key_episodes, key_tell = jax.random.split(state.rng, 4)
        population, strategy_state = strategy.ask(key_ask, state.strategy, strategy_params)
        returns, steps, moments = self.play(population, state, key_episodes)
        mean_returns = jnp.mean(returns, axis=1)
        strategy_state, _ = strategy.tell(key_tell, population, fitness_of(mean_returns), strategy_state,
                                          strategy_params)  # fmt: skip
        stats = state.obs_stats
        if self.settings.normalize_observations:
            count, total, squares = moments
            mean = total / count
            stats = stats.update_moments(mean, jnp.maximum(squares / count - mean**2, 0.0), count)
        metrics = {"steps": steps, "return_mean": jnp.nanmean(mean_returns), "return_max": jnp.nanmax(mean_returns),
                   "diverged": jnp.sum(jnp.isnan(mean_returns))}  # fmt: skip
        state = state.replace(strategy=strategy_state, obs_stats=stats, rng=rng, generations=state.generations + 1)
        return _strongly_typed(state), metrics

    def play(self, population: Any, state: Any, key: Any) -> tuple[Any, Any, Any]:
        """Returns (population_size, episodes) of every candidate on the same episodes, the env steps they took,
        and the moments (count, sum, sum of squares) of the observations they saw; candidates split over devices."""
        key_reset, key_steps = jax.random.split(key)
        keys = jax.random.split(key_reset, self.settings.episodes)
        _, starts = jax.vmap(self.env.reset_env, in_axes=(0, None))(keys, self.env_params)
        step_keys = jax.random.split(key_steps, self.settings.episodes)
        fixed = {k: v for k, v in state.params["params"].items() if k not in self.actor(state.params)}

        def shard(actors: Any) -> tuple[Any, Any, Any]:
            returns, steps, moments = self.play_on_one_device(actors, fixed, state.obs_stats, starts, step_keys)
            if self.devices == 1:
                return returns, steps, moments
            return returns, jax.lax.psum(steps, "c"), jax.tree.map(lambda m: jax.lax.psum(m, "c"), moments)

        if self.devices == 1:
            return shard(population)
        split = jax.shard_map(shard, mesh=self.mesh, in_specs=PartitionSpec("c"),
                              out_specs=(PartitionSpec("c"), PartitionSpec(), PartitionSpec()), check_vma=False)  # fmt: skip
        return split(population)

    def play_on_one_device(self, actors: Any, fixed: Any, stats: Any, starts: Any, step_keys: Any) -> tuple[Any, ...]:
        """The episodes of a batch of candidates ``actors`` (leading axis): ``lax.scan`` chunks of steps under a
        ``lax.while_loop`` until every episode has ended; an ended episode's state is held and pays nothing."""
        candidates = jax.tree.leaves(actors)[0].shape[0]
        states = jax.tree.map(lambda x: jnp.broadcast_to(x, (candidates, *x.shape)), starts)
        obs = jnp.asarray(states.observation, jnp.float32)
        alive = jnp.ones(obs.shape[:2], bool)
        returns = jnp.zeros(obs.shape[:2], jnp.float32)
        zeros = jnp.zeros(self.obs_dim, jnp.float32)
        moments = (jnp.asarray(0.0, jnp.float32), zeros, zeros)
        act = jax.vmap(lambda actor, o: self.act({"params": {**fixed, **actor}}, o, stats))  # over candidates
        step = jax.vmap(jax.vmap(self.env.step_env, in_axes=(0, 0, 0, None)), in_axes=(None, 0, 0, None))

        def one_step(carry: tuple[Any, ...], _: Any) -> tuple[tuple[Any, ...], None]:
            t, states, obs, alive, returns, steps, moments = carry
            keys = jax.vmap(jax.random.fold_in, in_axes=(0, None))(step_keys, t)  # common to all candidates
            next_obs, next_states, reward, done, _ = step(keys, states, act(actors, obs), self.env_params)
            weight = alive.astype(jnp.float32)
            count, total, squares = moments
            moments = (count + jnp.sum(weight), total + jnp.einsum("ce,ceo->o", weight, obs),
                       squares + jnp.einsum("ce,ceo->o", weight, obs**2))  # fmt: skip
            returns = returns + jnp.where(alive, reward, 0.0)
            states = jax.tree.map(lambda new, old: jnp.where(_expand(alive, new), new, old), next_states, states)
            obs = jnp.where(alive[..., None], jnp.asarray(next_obs, jnp.float32), obs)
            steps = steps + jnp.sum(alive, dtype=jnp.int32)
            return (t + 1, states, obs, alive & ~done, returns, steps, moments), None

        def chunk(carry: tuple[Any, ...]) -> tuple[Any, ...]:
            return jax.lax.scan(one_step, carry, None, STEPS_PER_CHUNK)[0]

        def running(carry: tuple[Any, ...]) -> Any:
            return jnp.any(carry[3]) & (carry[0] < self.max_steps)

        carry = (jnp.asarray(0, jnp.int32), states, obs, alive, returns, jnp.asarray(0, jnp.int32), moments)
        _, _, _, _, returns, steps, moments = jax.lax.while_loop(running, chunk, carry)
        return returns, steps, moments


def _expand(mask: Any, value: Any) -> Any:
    """``mask`` (candidates, episodes) broadcastable against ``value`` (candidates, episodes, ...)."""
    return mask.reshape(mask.shape + (1,) * (value.ndim - mask.ndim))


def _strongly_typed(state: ESState) -> ESState:
    """``state`` without weak types (evosax leaves some), so that a generation takes and returns the same types
    and compiles once."""
    return jax.tree.map(lambda x: jnp.asarray(x, x.dtype), state)
