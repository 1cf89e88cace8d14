"""The jitted PPO of ``dwr-gym train --backend jax``: its policy is SB3's once exported, its advantages are SB3's,
and every seed's curve is measured on one set (its command line, resume and Ctrl-C: test_jax_training_cli.py)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("jax")
pytest.importorskip("flax")
pytest.importorskip("optax")
pytest.importorskip("stable_baselines3")

import jax
import jax.numpy as jnp

from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import resolve_hyperparams
from train.learning.jitted.policy import PPOSettings, gaussian_entropy, gaussian_log_prob, make_network

ROOT = Path(__file__).resolve().parent.parent


def resolved(**kwargs: Any) -> TrainConfig:
    config = TrainConfig(num_envs=8, **kwargs)
    config.validate()
    return resolve_hyperparams(config, set())


def random_params(settings: PPOSettings, seed: int) -> Any:
    """Network parameters far from the initialisation (biases and log_std included), so every tensor matters."""
    params = make_network(settings, 2).init(jax.random.PRNGKey(seed), jnp.zeros(10))
    leaves, tree = jax.tree.flatten(params)
    keys = jax.random.split(jax.random.PRNGKey(seed + 1), len(leaves))
    return jax.tree.unflatten(
        tree, [leaf + 0.4 * jax.random.normal(k, leaf.shape) for leaf, k in zip(leaves, keys, strict=True)]
    )


@pytest.mark.parametrize("normalize", [False, True])
def test_exported_sb3_policy_acts_as_the_jax_policy(normalize: bool) -> None:
    import torch

    from train.learning.jitted.export import SB3Exporter
    from train.learning.training_env import make_training_env

    config = resolved()
    settings = PPOSettings.from_algo_kwargs(config.algo_kwargs, 8)
    network = make_network(settings, 2)
    params = random_params(settings, 0)
    rng = np.random.default_rng(0)
    mean, var = (rng.uniform(-2, 2, 10), rng.uniform(0.1, 30, 10)) if normalize else (None, None)
    model = SB3Exporter(make_training_env(config), config.algo_kwargs).load(params, mean, var, timesteps=7)
    obs = (rng.normal(size=(400, 10)) * 3).astype(np.float32)
    scaled = ((obs - mean) / np.sqrt(var + 1e-8)).astype(np.float32) if normalize else obs
    action_mean, log_std, value = (np.asarray(x) for x in network.apply(params, scaled))
    expected = np.clip(action_mean, -1.0, 1.0)
    assert 0.05 < np.mean(np.abs(expected) == 1.0) < 0.95  # some actions clipped, some not
    actions, _ = model.predict(obs, deterministic=True)
    np.testing.assert_allclose(actions, expected, atol=1e-5)
    samples = rng.normal(size=(400, 2)).astype(np.float32)
    with torch.no_grad():
        values, log_prob, entropy = model.policy.evaluate_actions(torch.as_tensor(obs), torch.as_tensor(samples))
    np.testing.assert_allclose(values.numpy()[:, 0], value, atol=1e-4)
    np.testing.assert_allclose(log_prob.numpy(), gaussian_log_prob(samples, action_mean, log_std), atol=1e-4)
    np.testing.assert_allclose(entropy.numpy(), np.full(400, gaussian_entropy(log_std)), atol=1e-5)
    assert model.num_timesteps == 7


def test_advantages_are_sb3s_with_the_truncation_bootstrap() -> None:
    import torch
    from gymnasium import spaces
    from stable_baselines3.common.buffers import RolloutBuffer

    from train.learning.jitted.ppo import gae

    steps, envs, gamma, lam = 24, 5, 0.97, 0.9
    rng = np.random.default_rng(1)
    rewards, values, final_values = (rng.normal(size=(steps, envs)).astype(np.float32) for _ in range(3))
    terminated, truncated = rng.random((steps, envs)) < 0.1, rng.random((steps, envs)) < 0.1
    truncated &= ~terminated
    last_value = rng.normal(size=envs).astype(np.float32)
    buffer = RolloutBuffer(steps, spaces.Box(-1, 1, (1,)), spaces.Box(-1, 1, (1,)), gae_lambda=lam, gamma=gamma,
                           n_envs=envs)  # fmt: skip
    episode_start = np.zeros(envs, bool)
    for t in range(steps):  # what PPO.collect_rollouts adds for a truncated episode, then the buffer's GAE
        reward = rewards[t] + gamma * np.where(truncated[t], final_values[t], 0.0)
        buffer.add(np.zeros((envs, 1)), np.zeros((envs, 1)), reward, episode_start, torch.as_tensor(values[t]),
                   torch.zeros(envs))  # fmt: skip
        episode_start = terminated[t] | truncated[t]
    buffer.compute_returns_and_advantage(torch.as_tensor(last_value), episode_start)
    advantages, returns = gae(jnp.asarray(rewards), jnp.asarray(values), jnp.asarray(terminated),
                              jnp.asarray(truncated), jnp.asarray(final_values), jnp.asarray(last_value), gamma, lam)  # fmt: skip
    np.testing.assert_allclose(np.asarray(advantages), buffer.advantages, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(np.asarray(returns), buffer.returns, rtol=1e-5, atol=1e-5)


def test_observation_statistics_are_sb3s_running_mean_and_variance() -> None:
    """The running statistics of --normalize-observations merge batches of any size as SB3's RunningMeanStd (the
    parallel algorithm), so the exported model's folded scaling is VecNormalize's."""
    from stable_baselines3.common.running_mean_std import RunningMeanStd

    from train.learning.jitted.ppo import OBS_EPSILON, ObservationStatistics

    rng = np.random.default_rng(4)
    ours, theirs = ObservationStatistics.create(3), RunningMeanStd(shape=(3,))
    for size, scale in ((5, 1.0), (17, 4.0), (2, 0.1)):
        batch = rng.normal(2.0, scale, (size, 3))
        ours, _ = ours.update(jnp.asarray(batch)), theirs.update(batch)
        np.testing.assert_allclose(np.asarray(ours.mean), theirs.mean, rtol=1e-5)
        np.testing.assert_allclose(np.asarray(ours.var), theirs.var, rtol=1e-5)
        assert float(ours.count) == pytest.approx(theirs.count)
    obs = rng.normal(size=(4, 3))
    expected = (obs - theirs.mean) / np.sqrt(theirs.var + OBS_EPSILON)
    np.testing.assert_allclose(np.asarray(ours.normalize(jnp.asarray(obs))), expected, rtol=1e-4, atol=1e-5)


def test_the_loss_is_the_clipped_surrogate_plus_the_value_and_entropy_terms() -> None:
    """JaxPPO.loss on a minibatch against the PPO loss written out in numpy (SB3's: advantages normalised with
    ddof 1, the pessimistic min of the clipped and unclipped surrogates, vf_coef * MSE, ent_coef * -entropy)."""
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.jitted.ppo import JaxPPO

    env, env_params = make_gymnax_env("DWRPointStabilization-v1")
    settings = PPOSettings(n_envs=2, n_steps=4, batch_size=8, ent_coef=0.03, vf_coef=0.7, clip_range=0.1)
    ppo = JaxPPO(settings, env, env_params)
    params = random_params(settings, 3)
    rng = np.random.default_rng(5)
    obs, actions = rng.normal(size=(8, 10)).astype(np.float32), rng.normal(size=(8, 2)).astype(np.float32)
    advantages, returns = rng.normal(1.0, 2.0, 8), rng.normal(size=8)
    mean, log_std, values = (np.asarray(x, np.float64) for x in ppo.network.apply(params, obs))
    log_prob = np.asarray(gaussian_log_prob(actions, mean, log_std), np.float64)
    old_log_prob = log_prob + rng.uniform(-0.3, 0.3, 8)  # ratios on both sides of the clip range
    ratio = np.exp(log_prob - old_log_prob)
    assert np.any(ratio > 1.1) and np.any(ratio < 0.9) and np.any(np.abs(ratio - 1) < 0.1)
    a = (advantages - advantages.mean()) / (advantages.std(ddof=1) + 1e-8)
    surrogate = -np.mean(np.minimum(a * ratio, a * np.clip(ratio, 0.9, 1.1)))
    entropy = np.sum(log_std + 0.5 * (1.0 + np.log(2.0 * np.pi)))
    expected = surrogate + 0.03 * -entropy + 0.7 * np.mean((returns - values) ** 2)
    batch = tuple(jnp.asarray(x, jnp.float32) for x in (obs, actions, old_log_prob, advantages, returns))
    assert float(ppo.loss(params, batch)) == pytest.approx(expected, rel=1e-4)


def test_a_rollout_records_what_the_policy_did_and_the_updates_follow_the_schedule() -> None:
    """collect: each transition's log-probability and value are the policy's at its observation, the totals are
    the rollout's sums. update: n_epochs x minibatches Adam steps each; with lin_ the rate reaches 0 at the end of
    the budget, so the last update leaves the weights as they were."""
    import dwr_gym
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.jitted.ppo import JaxPPO

    env, env_params = make_gymnax_env(dwr_gym.ENV_ID, T_con=0.5)
    settings = PPOSettings(n_envs=2, n_steps=16, batch_size=8, n_epochs=2, learning_rate=1e-2, linear_schedule=True)
    ppo = JaxPPO(settings, env, env_params)
    runner = ppo.init(seed=1)
    after, transitions, totals = jax.jit(ppo.collect)(runner)
    np.testing.assert_array_equal(transitions.obs[0], runner.obs)
    mean, log_std, value = ppo.policy(runner.params, transitions.obs)
    np.testing.assert_allclose(transitions.log_prob, gaussian_log_prob(transitions.action, mean, log_std), atol=1e-5)
    z = np.asarray((transitions.action - mean) / np.exp(log_std))  # the sampled actions: mean + std * N(0, 1)
    assert abs(z.mean()) < 0.5 and abs(z.std() - 1.0) < 0.35, (z.mean(), z.std())
    np.testing.assert_allclose(transitions.value, value, atol=1e-6)
    ended = np.asarray(transitions.terminated | transitions.truncated)
    assert float(totals["episodes"]) == ended.sum() >= 2  # each robot truncated at 15 steps at the latest
    assert float(totals["reward_sum"]) == pytest.approx(float(np.sum(transitions.reward)), rel=1e-5)
    # return_sum: the returns of the episodes that ended (from the runner's start: every robot's first episode);
    # successes: those that ended at the goal (an arrival ends a v0 episode; the final observation's distance)
    rewards, returns, running = np.asarray(transitions.reward, np.float64), 0.0, np.zeros(settings.n_envs)
    for t in range(settings.n_steps):
        running += rewards[t]
        returns += float(np.sum(np.where(ended[t], running, 0.0)))
        running = np.where(ended[t], 0.0, running)
    assert float(totals["return_sum"]) == pytest.approx(returns, rel=1e-5, abs=1e-4)
    arrived = np.asarray(transitions.terminated) & (np.asarray(transitions.final_obs)[..., 0] <= params_tolerance(env))
    assert float(totals["successes"]) == arrived.sum()
    np.testing.assert_allclose(after.episode_return, running, rtol=1e-5, atol=1e-5)  # restarted at 0 at each end
    assert int(after.updates) == 0 and not np.array_equal(after.obs, runner.obs)

    budget = 2 * settings.steps_per_update
    first, metrics = ppo.run(runner, 1, total_timesteps=budget)
    second, _ = ppo.run(first, 1, total_timesteps=budget)
    changed = [not np.array_equal(a, b) for a, b in zip(jax.tree.leaves(runner.params), jax.tree.leaves(first.params),
                                                         strict=True)]  # fmt: skip
    assert all(changed)  # half the rate: every tensor moved
    for a, b in zip(jax.tree.leaves(first.params), jax.tree.leaves(second.params), strict=True):
        np.testing.assert_array_equal(a, b)  # the rate at the end of the budget is 0
    assert int(second.updates) == 2 and int(second.opt_state[1].count) == 2 * 2 * 4
    assert float(metrics["episodes"]) == float(totals["episodes"])  # the same first rollout, the same key


def params_tolerance(env: Any) -> float:
    return float(env.default_params.goal_tolerance)


def test_log_std_fixed_sets_the_noise_to_its_schedule_whatever_the_gradient() -> None:
    """With log_std_fixed the log standard deviation is the schedule's value after every update (from log_std_init
    to log_std_final over the budget), not a cap the gradient may stay below (a large rate would move it)."""
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.jitted.ppo import JaxPPO

    env, env_params = make_gymnax_env("DWRPointStabilization-v1")
    settings = PPOSettings(n_envs=4, n_steps=8, batch_size=16, n_epochs=1, learning_rate=0.5, log_std_init=0.5,
                           log_std_final=-1.5, log_std_fixed=True)  # fmt: skip
    ppo = JaxPPO(settings, env, env_params)
    runner = ppo.init(seed=0)
    for update in (1, 2, 3, 4):  # a budget of 4 updates of 32 steps: from 0.5 down by 0.5 per update
        runner, _ = ppo.run(runner, 1, total_timesteps=128)
        np.testing.assert_allclose(np.asarray(runner.params["params"]["log_std"]), 0.5 - 0.5 * update, atol=1e-6)


def test_env_step_reads_an_env_that_reports_only_done_and_restarts_it() -> None:
    """A gymnax env without the terminated and truncated flags in its info (gymnax's own envs): ``done`` is the
    termination, the step that ends returns the new episode's observation, and ``final_obs`` the ended one's."""
    from train.learning.jitted.ppo import env_step

    class Counter:  # the observation counts the steps; the episode is done at the third
        def step_env(self, key: Any, state: Any, action: Any, params: Any) -> tuple[Any, ...]:
            state = state + 1
            return jnp.full(1, state, jnp.float32), state, jnp.float32(1.0), state >= 3, {}

        def reset_env(self, key: Any, params: Any) -> tuple[Any, Any]:
            return jnp.zeros(1, jnp.float32), jnp.asarray(0)

        def is_truncated(self, state: Any, params: Any) -> Any:
            return jnp.asarray(False)

    step = jax.jit(lambda state: env_step(Counter(), None, jax.random.PRNGKey(0), state, jnp.zeros(1)))
    obs, state, reward, terminated, truncated, final_obs, success = step(jnp.asarray(1))
    assert (float(obs[0]), int(state), bool(terminated), bool(truncated)) == (2.0, 2, False, False)
    obs, state, reward, terminated, truncated, final_obs, success = step(state)
    assert (float(obs[0]), int(state), bool(terminated), bool(truncated)) == (0.0, 0, True, False)
    assert float(final_obs[0]) == 3.0 and float(reward) == 1.0 and not bool(success)


def test_each_epoch_passes_over_the_whole_rollout_in_a_new_random_order_and_a_warm_up_trains_the_critic_alone() -> None:
    """As SB3's PPO, every epoch splits the rollout into minibatches afresh: each transition once per epoch, in an
    order that differs from epoch to epoch (consecutive steps of one robot would otherwise share a minibatch).
    Within --critic-warmup's steps (the first update here) only the critic's weights move."""
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.jitted.ppo import JaxPPO

    env, env_params = make_gymnax_env("DWRPointStabilization-v1")
    settings = PPOSettings(n_envs=2, n_steps=8, batch_size=8, n_epochs=2, critic_warmup=16)
    ppo = JaxPPO(settings, env, env_params)
    seen: list[np.ndarray] = []
    loss = ppo.loss

    def watched(params: Any, batch: tuple[Any, ...]) -> Any:
        jax.debug.callback(lambda obs: seen.append(np.asarray(obs)), batch[0], ordered=True)
        return loss(params, batch)

    ppo.loss = watched  # type: ignore[method-assign]
    start = ppo.init(seed=2)
    after, _ = ppo.run(start, 1, total_timesteps=10_000)
    jax.effects_barrier()
    assert len(seen) == 4 and all(batch.shape == (8, 10) for batch in seen)  # 2 epochs of 2 minibatches
    first, second = np.concatenate(seen[:2]), np.concatenate(seen[2:])
    rows = lambda a: sorted(map(tuple, a))  # noqa: E731
    assert rows(first) == rows(second) and len(set(map(tuple, first))) == 16  # the same 16 transitions, once each
    assert not np.array_equal(first, second)
    for name, leaf in start.params["params"].items():
        moved = not all(np.array_equal(x, y) for x, y in zip(jax.tree.leaves(leaf),
                                                            jax.tree.leaves(after.params["params"][name]), strict=True))  # fmt: skip
        assert moved == name.startswith("value"), name


def test_the_critic_warm_up_zeroes_the_actors_gradients_only_while_frozen() -> None:
    """--critic-warmup: while frozen, the gradients of the actor (its hidden layers, mean head and log_std) are 0 and
    the critic's untouched; once not frozen, every gradient is the loss's."""
    from train.learning.jitted.ppo import actor_masked_grad

    names = ("policy_0", "policy_1", "action", "log_std", "value_0", "value_1", "value")
    params = {"params": {name: {"kernel": jnp.full((2, 2), float(k + 1))} for k, name in enumerate(names)}}
    grad = jax.grad(lambda p, batch: sum(jnp.sum(leaf * batch) for leaf in jax.tree.leaves(p)))
    for frozen in (True, False):
        masked = actor_masked_grad(grad, jnp.asarray(frozen), params, jnp.asarray(3.0))["params"]
        for name in names:
            actor = not name.startswith("value")
            np.testing.assert_array_equal(masked[name]["kernel"], 0.0 if frozen and actor else 3.0, err_msg=name)


def test_each_activation_is_the_one_the_exported_sb3_model_computes() -> None:
    """The exported model runs torch's activation of the name in policy_kwargs: the jitted network's, for every
    activation it accepts, computes the same function."""
    import torch

    from train.learning.jitted.policy import ACTIVATIONS, activation_function

    torch_names = {"tanh": "Tanh", "relu": "ReLU", "elu": "ELU", "leakyrelu": "LeakyReLU", "silu": "SiLU",
                   "gelu": "GELU", "sigmoid": "Sigmoid"}  # fmt: skip
    assert set(ACTIVATIONS) == set(torch_names)
    x = np.linspace(-4.0, 4.0, 33, dtype=np.float32)
    for name, torch_name in torch_names.items():
        settings = PPOSettings.from_algo_kwargs({"policy_kwargs": {"activation_fn": f"nn.{torch_name}"}}, 64)
        assert settings.activation == name
        expected = getattr(torch.nn, torch_name)()(torch.as_tensor(x)).numpy()
        np.testing.assert_allclose(np.asarray(activation_function(name)(jnp.asarray(x))), expected, atol=1e-6)


def test_settings_read_the_yaml_and_refuse_what_they_do_not_implement() -> None:
    config = resolved()
    settings = PPOSettings.from_algo_kwargs(config.algo_kwargs, 256)
    assert (settings.n_steps, settings.batch_size, settings.n_epochs, settings.gamma) == (64, 1024, 4, 1.0)  # v2's
    assert settings.net_arch == (64, 64) and settings.activation == "tanh" and settings.minibatches == 16
    with pytest.raises(ConfigError, match=r"\['use_sde'\] are not implemented by --backend jax"):
        PPOSettings.from_algo_kwargs({**config.algo_kwargs, "use_sde": True}, 256)
    with pytest.raises(ConfigError, match="batch_size=1000 is invalid for --backend jax"):
        PPOSettings.from_algo_kwargs({**config.algo_kwargs, "batch_size": 1000}, 256)
    with pytest.raises(ConfigError, match=r"^policy_kwargs activation_fn='nn.Swish' is invalid for --backend jax: "
                                          r"expected one of nn.Tanh, nn.Relu"):  # fmt: skip
        PPOSettings.from_algo_kwargs({**config.algo_kwargs, "policy_kwargs": {"activation_fn": "nn.Swish"}}, 256)
    linear = PPOSettings.from_algo_kwargs({**config.algo_kwargs, "learning_rate": "lin_1e-3"}, 256)
    assert linear.linear_schedule and linear.learning_rate == 1e-3


def test_log_std_final_caps_the_noise_along_the_budget_and_ends_at_its_value() -> None:
    from dwr_gym.jax_env.gymnax import make_gymnax_env
    from train.learning.jitted.ppo import JaxPPO

    config = resolved(hyperparam_overrides={"log_std_final": -3.0})
    settings = PPOSettings.from_algo_kwargs({**config.algo_kwargs, "n_steps": 8, "batch_size": 16, "n_epochs": 1}, 4)
    assert settings.log_std_final == -3.0 and settings.log_std_init == 0.0
    env, env_params = make_gymnax_env("DWRPointStabilization-v1")
    ppo = JaxPPO(settings, env, env_params)
    runner = ppo.init(seed=0)
    for update in (1, 2, 3, 4):  # a budget of 4 updates of 32 steps: the cap falls by 0.75 per update
        runner, _ = ppo.run(runner, 1, total_timesteps=128)
        log_std = np.asarray(runner.params["params"]["log_std"])
        assert np.all(log_std <= -0.75 * update + 1e-6), (update, log_std)
    np.testing.assert_allclose(log_std, -3.0, atol=1e-6)


def test_every_seeds_learning_curve_is_measured_on_the_same_evaluation_set(tmp_path: Path) -> None:
    """The jitted trainer evaluates on the starts drawn with --eval-seed, whatever the training seed: the curves of
    two seeds compare episode for episode (and differ from the starts the training seed would draw)."""
    from train.evaluation.scenarios import make_scenario
    from train.learning.jitted.run import JaxRun

    runs = [JaxRun(resolved(backend="jax", seed=seed, eval_seed=777, eval_episodes=5), tmp_path, None, {}, None)
            for seed in (0, 5)]  # fmt: skip
    expected = make_scenario("random", n=5, seed=777, env_kwargs=runs[0].config.env_keywords())
    for run in runs:
        np.testing.assert_array_equal(run.scenario.starts, expected.starts)
        np.testing.assert_array_equal(run.scenario.T_cons, expected.T_cons)
    own = make_scenario("random", n=5, seed=0, env_kwargs=runs[0].config.env_keywords())
    assert not np.array_equal(own.starts, expected.starts)


def test_a_missing_jax_extra_is_one_line_naming_it(monkeypatch: pytest.MonkeyPatch) -> None:
    from train.learning.jitted.trainer import make_jax_env

    monkeypatch.setitem(sys.modules, "optax", None)  # as if optax were not installed
    with pytest.raises(ConfigError, match=r"optax is missing\): pip install \"dwr-gym\[jax\]\"$"):
        make_jax_env(resolved(backend="jax"))


def test_each_docs_block_is_what_the_benchmark_renders_from_its_json() -> None:
    from benchmarks.core import docs
    from benchmarks.training import jax_training

    for block in jax_training.BLOCKS:
        if (ROOT / block.json).is_file():
            assert docs.written(block.name) == docs.rendered(block.name), block.name
