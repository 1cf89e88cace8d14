"""PPO-Lagrangian on the jitted PPO (``--algo ppo --backend jax`` with ``lagrangian=1``): its multipliers move per
T_con bin from the episodes that ended in each rollout and stay finite and non-negative, its loss is PPO's with the
combined advantage and a cost critic, bad options are refused naming them, and a run resumes bit for bit with its
multipliers."""

from __future__ import annotations

import csv
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

from tests.jitted_runs import assert_resume_is_bit_for_bit
from train.learning.config import ConfigError
from train.learning.hyperparams import check_algo_kwargs
from train.learning.jitted.lagrangian import LagrangeSettings
from train.learning.jitted.policy import PPOSettings

#: A short T_con (1-2 s, 20-40 steps): episodes end within a tiny run's rollouts.
SHORT = ("--env-kwargs", "T_con_range=[1.0, 2.0]")
TINY = ("train", "--algo", "ppo", "--backend", "jax", "--env", "DWRPointStabilization-v2", *SHORT, "--num-envs", "8",
        "--eval-episodes", "4", "--no-progress", "--hyperparams", "n_steps=16", "batch_size=64", "n_epochs=1",
        "lagrangian=1", "multiplier_bins=2", "multiplier_init=1.0")  # fmt: skip


def small_ppo(**constraint: Any) -> Any:
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.ppo_lagrangian import JaxPPOLagrangian

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=(1.0, 2.0))
    settings = PPOSettings(n_envs=4, n_steps=8, batch_size=32, n_epochs=1, gamma=1.0,
                           constraint=LagrangeSettings(**{"lagrangian": True, "multiplier_bins": 2, **constraint}))  # fmt: skip
    return JaxPPOLagrangian(settings, env, params)


def synthetic_rollout(ppo: Any, runner: Any, cost: Any, heading: Any, T_con: Any, done: Any) -> Any:
    """A rollout (n_steps 8, n_envs 4) whose steps have these costs, T_con and ends (the rest as collected)."""
    _, transitions, _ = jax.jit(ppo.collect)(runner)
    shape = transitions.reward.shape
    info = {"cost": jnp.broadcast_to(jnp.asarray(cost, jnp.float32), shape),
            "heading_violation": jnp.broadcast_to(jnp.asarray(heading, jnp.float32), shape),
            "T_con": jnp.broadcast_to(jnp.asarray(T_con, jnp.float32), shape),
            "energy": jnp.ones(shape, jnp.float32)}  # fmt: skip
    ended = jnp.broadcast_to(jnp.asarray(done), shape)
    return transitions._replace(info=info, terminated=ended, truncated=jnp.zeros(shape, bool))


def test_each_bins_multipliers_follow_its_own_episodes_and_never_go_negative_or_nan() -> None:
    """Late episodes (cost 1) with T_con 1.2 s (bin 0 of [1, 2] s in two bins) raise bin 0's deadline multiplier;
    bin 1, where no episode ended, keeps its own; episodes in time with no heading error lower the multipliers, to 0
    and not below; a NaN cost moves nothing; each transition is weighed by its bin's multipliers."""
    ppo = small_ppo(multiplier_init=0.05, pid_kp=0.0, pid_ki=1.0, cost_budget=0.1, heading_budget=0.2)
    runner = ppo.init(0)
    prepare = jax.jit(ppo.prepare)
    start = np.asarray(runner.multipliers.value)
    late = synthetic_rollout(ppo, runner, 1.0, 0.0, 1.2, True)
    runner, batch, metrics = prepare(runner, late)
    value = np.asarray(runner.multipliers.value)
    assert value[0, 0] == pytest.approx(0.05 + 0.9)  # + (violation rate 1 - budget 0.1), the integral gain 1
    assert value[1, 0] == pytest.approx(0.0)  # the heading error 0, below its budget: from 0.05 down to 0
    np.testing.assert_array_equal(value[:, 1], start[:, 1])  # no episode of bin 1 ended
    np.testing.assert_array_equal(np.asarray(metrics["bin_episodes"]), [32, 0])
    np.testing.assert_allclose(np.asarray(batch[-1]), np.broadcast_to(value[:, 0], (8, 4, 2)))  # bin 0's weights
    in_time = synthetic_rollout(ppo, runner, 0.0, 0.0, 1.2, True)
    for _ in range(12):  # -0.1 per update: from 0.95 to 0, then held there
        runner, _, _ = prepare(runner, in_time)
        value = np.asarray(runner.multipliers.value)
        assert np.all(np.isfinite(value)) and np.all(value >= 0.0)
    assert value[0, 0] == 0.0
    poisoned = synthetic_rollout(ppo, runner, jnp.nan, jnp.inf, 1.2, True)
    runner, _, _ = prepare(runner, poisoned)
    np.testing.assert_array_equal(np.asarray(runner.multipliers.value), value)


def test_the_loss_is_ppos_with_the_combined_advantage_and_the_cost_critics_error() -> None:
    """With every multiplier 0 the loss is PPO's plus vf_coef times the cost critic's squared error; with a multiplier
    lambda on the deadline it is the loss of the advantage (A_r - lambda A_c) / (1 + lambda) (standardisation off)."""
    import dataclasses

    from train.learning.jitted.ppo import JaxPPO

    ppo = small_ppo()
    runner = ppo.init(1)
    _, transitions, _ = jax.jit(ppo.collect)(runner)
    runner, batch, _ = jax.jit(ppo.prepare)(runner, transitions)
    flat = jax.tree.map(lambda x: x.reshape((32, *x.shape[2:])), batch)
    obs, params = flat[0], runner.params
    cost_error = jnp.mean(jnp.sum((flat[6] - ppo.cost_values(params, obs)) ** 2, axis=-1))
    assert float(jnp.abs(flat[5]).sum()) > 0.0  # (the cost advantages are not all 0: the identity below bites)
    free = (*flat[:7], jnp.zeros_like(flat[7]))
    plain = JaxPPO.loss(ppo, params, flat[:5])  # (PPO's loss; ppo.policy reads the network's part of params)
    assert float(ppo.loss(params, free)) == pytest.approx(float(plain + ppo.settings.vf_coef * cost_error), rel=1e-5)
    ppo.settings = dataclasses.replace(ppo.settings, normalize_advantage=False)
    lam = 3.0
    weighed = (*flat[:7], jnp.zeros_like(flat[7]).at[:, 0].set(lam))
    combined = (flat[3] - lam * flat[5][:, 0]) / (1.0 + lam)
    as_reward = (*flat[:3], combined, *flat[4:7], jnp.zeros_like(flat[7]))
    assert float(ppo.loss(params, weighed)) == pytest.approx(float(ppo.loss(params, as_reward)), rel=1e-5)
    assert float(ppo.loss(params, weighed)) != pytest.approx(float(ppo.loss(params, free)), rel=1e-3)


@pytest.mark.parametrize(
    ("item", "name"),
    [("lagrangian=2", "lagrangian"), ("cost_budget=1.5", "cost_budget"), ("cost_budget=0", "cost_budget"),
     ("heading_budget=-0.1", "heading_budget"), ("multiplier_bins=0", "multiplier_bins"),
     ("multiplier_init=-1", "multiplier_init"), ("pid_kp=-1", "pid_kp"), ("pid_ki=nan", "pid_ki"),
     ("pid_average=1", "pid_average")],
)  # fmt: skip
def test_bad_constraint_options_are_refused_naming_the_option(item: str, name: str) -> None:
    from train.learning.hyperparams import parse_overrides

    values = {"n_steps": 8, **parse_overrides([item])}
    with pytest.raises(ConfigError, match=rf"^{name}=\S+ is invalid"):
        check_algo_kwargs("ppo", values, "jax")
    with pytest.raises(ConfigError, match=rf"^{name}=\S+ is invalid"):
        PPOSettings.from_algo_kwargs(values, 8)


def test_the_constraint_options_are_the_jitted_ppos_only() -> None:
    with pytest.raises(ConfigError, match=r"\['lagrangian'\] are options of --algo ppo --backend jax"):
        check_algo_kwargs("ppo", {"lagrangian": 1}, "sb3")
    assert PPOSettings.from_algo_kwargs(check_algo_kwargs("ppo", {"lagrangian": 1, "pid_kd": 0.5}, "jax"),
                                        8).constraint == LagrangeSettings(lagrangian=True, pid_kd=0.5)  # fmt: skip
    assert "lagrangian" not in PPOSettings().as_dict()  # (the plain PPO's settings as they were)


def test_an_env_without_a_T_con_is_refused_in_one_line() -> None:
    from types import SimpleNamespace

    from train.learning.jitted.ppo_lagrangian import JaxPPOLagrangian

    env, params = SimpleNamespace(), SimpleNamespace(max_steps_in_episode=200)  # (a gymnax env's params: no T_con)
    settings = PPOSettings(n_envs=4, n_steps=8, batch_size=32, constraint=LagrangeSettings(lagrangian=True))
    with pytest.raises(ConfigError, match="lagrangian=1 is invalid for this env"):
        JaxPPOLagrangian(settings, env, params)


def read_log(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


@pytest.mark.slow
def test_a_tiny_run_logs_each_bin_and_resumes_bit_for_bit_with_its_multipliers(tmp_path: Path) -> None:
    """The run stopped halfway and resumed ends with the uninterrupted run's weights and writes its constraint log
    row for row (the multipliers, saved in the run's state, are the same); every multiplier logged is finite and >= 0,
    and the late episodes of the untrained policy raise them."""
    split = assert_resume_is_bit_for_bit(TINY, 2048, 1024, tmp_path)
    straight = read_log(tmp_path / "straight" / "constraint.csv")
    assert read_log(split / "constraint.csv") == straight
    # a row per bin and chunk: two chunks of 8 updates (128 steps each) up to each evaluation at 1024 and 2048 steps
    assert [row["T_con_low"] for row in straight[:2]] == ["1", "1.5"] and len(straight) == 2 * 2
    multipliers = np.array([[float(row["deadline_multiplier"]), float(row["heading_multiplier"])] for row in straight])
    assert np.all(np.isfinite(multipliers)) and np.all(multipliers >= 0.0)
    assert sum(int(row["episodes"]) for row in straight) > 0
    assert multipliers[:, 0].max() > 1.0  # (from multiplier_init 1: the untrained policy is late)


def test_the_benchmark_entry_is_the_v2_recipe_with_the_constraint(tmp_path: Path) -> None:
    from train.learning.benchmark import parse_entry, train_config

    config = train_config(parse_entry("ppo-lagrangian-v2"), 0, tmp_path, {"env_steps": 1024})
    settings = PPOSettings.from_algo_kwargs(config.algo_kwargs, int(config.num_envs or 0))
    assert config.env_id == "DWRPointStabilization-v2" and config.backend == "jax"
    assert settings.gamma == 1.0 and settings.log_std_fixed and settings.normalize_observations
    assert settings.constraint == LagrangeSettings(lagrangian=True)
