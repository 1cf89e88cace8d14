"""Residual agents on the jitted PPO: the analytic laws run on jax arrays as the numpy laws do (one copy, to 1e-12 in
float64), the residual env steps with expert + residual, and ``dwr-gym train --backend jax --residual`` leaves an
agent that ``load_agent`` runs as expert + residual."""

from __future__ import annotations

import functools
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

jax = pytest.importorskip("jax")
pytest.importorskip("flax")
pytest.importorskip("optax")

import jax.numpy as jnp  # noqa: E402

from baselines.base import ControllerInput  # noqa: E402
from baselines.expert import normalized_action  # noqa: E402
from baselines.registry import CONTROLLERS, make_controller  # noqa: E402
from dwr_gym import model  # noqa: E402
from train.learning.config import ConfigError, TrainConfig  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TRACEABLE = [name for name, cls in CONTROLLERS.items() if cls.traceable]
E_MAX = model.MAX_ORIENTATION_ERROR
U_MAX, OMEGA_MAX = 0.5, 2.0  # EnvParams defaults

#: One robot's state as a law sees it: d, alpha, psi, t / T_con, T_con, d0, e_psi0. Distances include the goal
#: itself and the stop distance's neighbourhood; times run past T_con (late robots).
STATE = st.tuples(
    st.one_of(st.floats(0.0, 4.0), st.sampled_from([0.0, 0.004999, 0.005, 0.005001, 1e-7])),
    st.floats(-math.pi, math.pi), st.floats(-math.pi, math.pi), st.floats(0.0, 1.5),
    st.one_of(st.floats(0.5, 90.0), st.sampled_from([10.0, 60.0])), st.floats(0.0, 3.0), st.floats(-E_MAX, E_MAX),
)  # fmt: skip
SETTINGS = {"deadline": None, "suppress_health_check": [HealthCheck.too_slow], "derandomize": True}
ROWS = 16


def pad(states: list[tuple[float, ...]]) -> list[tuple[float, ...]]:
    """The states repeated to ROWS rows: one shape, so one compilation serves every example."""
    return [states[i % len(states)] for i in range(ROWS)]


@functools.cache
def jitted_law(name: str) -> Any:
    controller = make_controller(name)
    return jax.jit(lambda inputs: controller(inputs))


@functools.cache
def jitted_expert(name: str) -> Any:
    controller = make_controller(name)
    return jax.jit(lambda obs: normalized_action(controller, obs, U_MAX, OMEGA_MAX))


def inputs_of(states: list[tuple[float, ...]], xp: Any) -> ControllerInput:
    d, alpha, psi, fraction, T_con, d0, e0 = (
        xp.asarray(column, dtype=xp.float64) for column in zip(*pad(states), strict=True)
    )
    return ControllerInput(d, alpha, psi, fraction * T_con, d0, e0, T_con)


def observations(states: list[tuple[float, ...]]) -> np.ndarray:
    """Observations (N, 10) of the states, as the env writes them (in float64)."""
    d, alpha, psi, fraction, T_con, d0, e0 = (np.asarray(c) for c in zip(*pad(states), strict=True))
    e = model.orientation_error(alpha, psi, d, 1.0 / (2.0 * math.pi))
    return np.stack([d, np.cos(alpha), np.sin(alpha), np.cos(psi), np.sin(psi), e, fraction, T_con, d0, e0], axis=1)


def far_from_branches(states: list[tuple[float, ...]]) -> bool:
    """Whether alpha - psi and -psi - alpha lie away from the +-pi where the laws wrap them and from the +-pi/2 where
    pt-astolfi turns to reversing: the atan2 of numpy and XLA, which decode the observation, differ in the last bit."""
    _, alpha, psi, *_ = (np.asarray(c) for c in zip(*pad(states), strict=True))
    angles = np.concatenate([model.wrap_angle(alpha - psi), model.wrap_angle(-psi - alpha)])
    return bool(np.all(np.abs(np.abs(angles) - math.pi) > 1e-6) and np.all(np.abs(np.abs(angles) - math.pi / 2) > 1e-6))


@pytest.mark.parametrize("name", TRACEABLE)
@settings(max_examples=40, **SETTINGS)
@given(states=st.lists(STATE, min_size=1, max_size=ROWS))
def test_the_jax_law_is_the_numpy_law_to_1e_12_in_float64(name: str, states: list[tuple[float, ...]]) -> None:
    controller = make_controller(name)
    expected = controller(inputs_of(states, np))
    with jax.enable_x64(True):
        got = jax.device_get(jitted_law(name)(inputs_of(states, jnp)))
    for want, have in zip(expected, got, strict=True):
        assert have.dtype == np.float64
        np.testing.assert_allclose(have, want, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name", ["ptc", "pt-astolfi"])
@settings(max_examples=30, **SETTINGS)
@given(states=st.lists(STATE, min_size=1, max_size=ROWS))
def test_the_jax_expert_acts_from_observations_as_the_numpy_expert(name: str, states: list[tuple[float, ...]]) -> None:
    from hypothesis import assume

    from baselines.expert import ExpertPolicy

    assume(far_from_branches(states))
    obs = observations(states)
    controller = make_controller(name)
    expected = normalized_action(controller, obs, U_MAX, OMEGA_MAX)
    np.testing.assert_array_equal(ExpertPolicy(controller, U_MAX, OMEGA_MAX).predict(obs)[0],
                                  expected.astype(np.float32))  # fmt: skip
    with jax.enable_x64(True):
        got = jitted_expert(name)(jnp.asarray(obs))
        np.testing.assert_allclose(np.asarray(got), expected, rtol=1e-12, atol=1e-12)


def test_laws_with_state_or_a_planner_are_refused_as_a_jax_residual_expert_in_one_line() -> None:
    from train.learning.jitted.trainer import check_jax_config

    for expert in ("fabregas", "optimal"):
        config = TrainConfig(backend="jax", residual=True, expert=expert, num_envs=8)
        config.validate()
        with pytest.raises(ConfigError, match=rf"^--expert '{expert}' is invalid with --backend jax --residual: .*ptc"):
            check_jax_config(config)
    check_jax_config(TrainConfig(backend="jax", residual=True, expert="pt-astolfi"))


@pytest.mark.slow  # compiles the env's step twice in float64: about 30 s
def test_the_residual_env_steps_with_the_numpy_experts_action_plus_the_scaled_residual() -> None:
    import dwr_gym
    from baselines.expert import ExpertPolicy
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.residual import ResidualGymnaxEnv

    with jax.enable_x64(True):
        env, params = make_gymnax_env(dwr_gym.ENV_ID_V1, dtype="float64")
        expert = ExpertPolicy(make_controller("ptc"), params.env_params.u_max, params.env_params.omega_max)
        residual_env = ResidualGymnaxEnv(env, expert.controller, expert.u_max, expert.omega_max, scale=0.5)
        keys = jax.random.split(jax.random.PRNGKey(3), 64)
        obs, state = jax.vmap(env.reset_env, in_axes=(0, None))(keys, params)
        residual = jax.random.uniform(jax.random.PRNGKey(4), (64, 2), jnp.float64, -1.5, 1.5)
        step = jax.jit(jax.vmap(residual_env.step_env, in_axes=(0, 0, 0, None)))
        got = step(keys, state, residual, params)[0]
        action = np.clip(normalized_action(expert.controller, np.asarray(obs), expert.u_max, expert.omega_max)
                         + 0.5 * np.clip(np.asarray(residual), -1, 1), -1, 1)  # fmt: skip
        want = jax.vmap(env.step_env, in_axes=(0, 0, 0, None))(keys, state, jnp.asarray(action), params)[0]
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-10, atol=1e-10)


@pytest.mark.slow
@pytest.mark.parametrize("expert", ["ptc", "pt-astolfi"])
def test_cli_trains_a_jax_residual_that_evaluate_loads_as_expert_plus_residual(tmp_path: Path, expert: str) -> None:
    import yaml

    from baselines.expert import ExpertPolicy
    from train.learning.agents import load_agent
    from train.learning.residual import ResidualPolicy

    run_dir = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    command = [sys.executable, "-m", "train.cli", "train", "--backend", "jax", "--residual", "--expert", expert,
               "--num-envs", "8", "--eval-episodes", "4", "--no-progress", "--total-timesteps", "128",
               "--eval-freq", "64", "--hyperparams", "n_steps=8", "batch_size=32", "n_epochs=1",
               "--run-dir", str(run_dir)]  # fmt: skip
    done = subprocess.run(command, cwd=ROOT, env=env, text=True, capture_output=True, timeout=600)
    assert done.returncode == 0, done.stderr
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["config"]["residual"] and saved["config"]["expert"] == expert
    assert saved["runtime"] == [f"expert: {expert}"] and saved["config"]["backend"] == "jax"
    _, policy = load_agent(run_dir)
    assert isinstance(policy, ResidualPolicy)
    obs = np.asarray([[1.2, 0.6, 0.8, 1.0, 0.0, 0.9, 0.1, 20.0, 1.5, 0.9]], np.float32)
    expert_action = ExpertPolicy(make_controller(expert), U_MAX, OMEGA_MAX).predict(obs)[0]
    action, _ = policy.predict(obs)
    residual, _ = policy.model.predict(obs, deterministic=True)
    np.testing.assert_allclose(action, np.clip(expert_action + 0.5 * residual, -1, 1), atol=1e-6)
    assert np.max(np.abs(residual)) < 0.1  # 128 steps from a residual started near zero: still near the expert


def test_benchmark_entries_train_the_jax_residual_on_each_law_and_v2_with_gamma_1(tmp_path: Path) -> None:
    from train.learning.benchmark import parse_entry, train_config

    for name, expert in (("residual-ppo-jax", "ptc"), ("residual-ppo-jax-astolfi", "pt-astolfi")):
        config = train_config(parse_entry(name), 0, tmp_path / name, {"env_steps": 1000})
        assert (config.backend, config.residual, config.expert) == ("jax", True, expert)
        assert config.algo_kwargs["gamma"] == 0.999 and config.total_timesteps == 1000
    for name, expert in (("residual-ppo-jax-v2", "ptc"), ("residual-ppo-jax-astolfi-v2", "pt-astolfi")):
        v2 = train_config(parse_entry(name), 0, tmp_path / name, {})
        assert (v2.backend, v2.residual, v2.expert, v2.env_id) == ("jax", True, expert, "DWRPointStabilization-v2")
        assert v2.algo_kwargs["gamma"] == 1.0


class _TinyEnv:
    """A gymnax-style env of a few lines (obs of 10 numbers, reward -|action|^2): compiles in seconds."""

    def reset_env(self, key: Any, params: Any) -> tuple[Any, Any]:
        obs = jax.random.normal(key, (10,))
        return obs, obs

    reset = reset_env

    def step_env(self, key: Any, state: Any, action: Any, params: Any) -> tuple[Any, ...]:
        obs = 0.9 * state + 0.1 * jax.random.normal(key, (10,))
        return obs, obs, -jnp.sum(action**2), jnp.asarray(False), {"truncated": jnp.asarray(False)}

    def observation_space(self, params: Any) -> Any:
        from dwr_gym.jax_env.gymnax import Box

        return Box(-10.0, 10.0, (10,), jnp.float32)

    def action_space(self, params: Any) -> Any:
        from dwr_gym.jax_env.gymnax import Box

        return Box(-1.0, 1.0, (2,), jnp.float32)


@pytest.mark.slow  # compiles a PPO update: over a minute on a busy 2-core machine
def test_critic_warmup_keeps_the_actor_as_it_is_while_the_critic_learns() -> None:
    from train.learning.jitted.policy import PPOSettings
    from train.learning.jitted.ppo import JaxPPO

    def changed(before: Any, after: Any) -> dict[str, bool]:
        return {name: not all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(before.params["params"][name]),
                                                                    jax.tree.leaves(after.params["params"][name]),
                                                                    strict=True))
                for name in before.params["params"]}  # fmt: skip

    settings = PPOSettings(n_envs=4, n_steps=8, batch_size=16, n_epochs=2, critic_warmup=32)  # one update of 32 steps
    ppo = JaxPPO(settings, _TinyEnv(), None)
    start = ppo.init(0)
    warm, _ = ppo.run(start, 1, 1e6)
    frozen = changed(start, warm)
    assert frozen["value"] and frozen["value_0"]
    assert not any(frozen[name] for name in ("policy_0", "policy_1", "action", "log_std"))
    assert all(changed(warm, ppo.run(warm, 1, 1e6)[0]).values())  # after the warm-up, the actor learns


def test_critic_warmup_is_an_option_of_residual_agents_too() -> None:
    config = TrainConfig(backend="jax", residual=True, critic_warmup=1000)
    config.validate()
    with pytest.raises(ConfigError, match=r"^--critic-warmup 1000 is invalid: it needs --init-from or --residual, and"):
        TrainConfig(critic_warmup=1000).validate()


def test_the_jitted_trainer_of_a_residual_run_steps_the_residual_env() -> None:
    from train.learning.jitted.residual import ResidualGymnaxEnv
    from train.learning.jitted.trainer import make_jax_env

    config = TrainConfig(backend="jax", residual=True, expert="pt-astolfi", residual_scale=0.3)
    config.validate()
    env, _ = make_jax_env(config)
    assert isinstance(env, ResidualGymnaxEnv) and env.scale == 0.3 and env.controller.name == "pt-astolfi"
    plain = TrainConfig(backend="jax")
    plain.validate()
    assert not isinstance(make_jax_env(plain)[0], ResidualGymnaxEnv)


def test_an_es_residual_starts_its_search_at_the_expert() -> None:
    """``--algo es --residual``: the search mean is a residual near zero (the agent is its expert at generation
    0, as the residual PPO starts), where the same network without ``residual`` acts on its own."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.evolution.settings import ESSettings
    from train.learning.evolution.strategies import JaxES
    from train.learning.jitted.residual import residual_env

    settings = ESSettings(population_size=4, episodes=2, net_arch=(16,))
    config = TrainConfig(
        backend="jax", algo="es", residual=True, expert="pt-astolfi", env_id="DWRPointStabilization-v2"
    )
    env, env_params = make_gymnax_env("DWRPointStabilization-v2")
    obs = jax.random.normal(jax.random.PRNGKey(2), (64, 10), jnp.float32)
    actions = {}
    for residual in (True, False):
        es = JaxES(settings, residual_env(config, env) if residual else env, env_params, devices=1, residual=residual)
        state = es.init(0)
        actions[residual] = np.asarray(es.act(es.mean_params(state), obs, state.obs_stats))
    assert np.max(np.abs(actions[True])) < 1e-2 < np.max(np.abs(actions[False]))


@pytest.mark.slow
def test_cli_trains_an_es_residual_on_v2_that_evaluate_loads_as_expert_plus_residual(tmp_path: Path) -> None:
    import yaml

    from train.learning.agents import load_agent
    from train.learning.residual import ResidualPolicy

    run_dir = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    command = [sys.executable, "-m", "train.cli", "train", "--backend", "jax", "--algo", "es", "--residual",
               "--expert", "ptc", "--env", "DWRPointStabilization-v2", "--env-kwargs", "T_con_range=[10,11]",
               "--eval-episodes", "3", "--no-progress", "--total-timesteps", "3000", "--eval-freq", "2000",
               "--hyperparams", "population_size=4", "episodes=2", "policy_kwargs=dict(net_arch=[16])",
               "--run-dir", str(run_dir)]  # fmt: skip
    done = subprocess.run(command, cwd=ROOT, env=env, text=True, capture_output=True, timeout=600)
    assert done.returncode == 0, done.stderr
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["config"]["residual"] and saved["config"]["algo"] == "es" and saved["learned_from"] == "reward"
    _, policy = load_agent(run_dir)
    assert isinstance(policy, ResidualPolicy) and policy.expert.controller.name == "ptc"


def test_a_gradient_through_the_law_is_kept_where_finite_and_zero_where_its_derivative_is_not() -> None:
    """finite_cotangent: the value unchanged, the cotangent's non-finite entries 0 (sqrt's derivative at 0 is inf)."""
    from train.learning.jitted.residual import finite_cotangent

    x = jnp.asarray([0.0, 4.0])
    np.testing.assert_array_equal(np.asarray(finite_cotangent(x)), [0.0, 4.0])
    grad = jax.grad(lambda v: jnp.sum(jnp.sqrt(finite_cotangent(v))))(x)
    np.testing.assert_allclose(np.asarray(grad), [0.0, 0.25])


def test_apg_updates_of_a_residual_on_ptc_are_not_voided_by_the_laws_gain_at_T_con() -> None:
    """PTC's gain is undefined at T_con (eq. (17)), and a batch's gradient through it was NaN, the update skipped (most
    of them, measured); through the residual env every update of a fresh residual APG on PTC is taken."""
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG
    from train.learning.jitted.apg_settings import APGSettings
    from train.learning.jitted.residual import ResidualGymnaxEnv

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[10.0, 12.0])
    residual = ResidualGymnaxEnv(env, make_controller("ptc"), U_MAX, OMEGA_MAX, scale=0.5)
    apg = JaxAPG(APGSettings(episodes=64, net_arch=(8,), state_grad_clip=64.0), residual, params, residual=True)
    state = apg.init(0)
    update = jax.jit(apg._update)
    skipped = []
    for _ in range(2):
        state, metrics = update(state)
        skipped.append(bool(metrics["skipped"]))
    assert not any(skipped), f"updates skipped for a non-finite gradient: {skipped}"
