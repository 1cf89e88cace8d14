"""OptimisticResetVecEnv: the gymnax adapter's batched step with num_envs // reset_ratio new episodes per step."""

from __future__ import annotations

import numpy as np
import pytest

jax = pytest.importorskip("jax")
pytest.importorskip("flax")

import jax.numpy as jnp  # noqa: E402

import dwr_gym  # noqa: E402
from dwr_gym.jax_env import make_gymnax_env  # noqa: E402
from dwr_gym.jax_env.autoreset import OptimisticResetVecEnv  # noqa: E402

N = 32


def short_episodes() -> tuple:
    """Episodes of 15 to 30 steps (T_con 0.5 to 1 s), so that several end at every few steps."""
    return make_gymnax_env(dwr_gym.ENV_ID, T_con_range=(0.5, 1.0))


def actions(step: int) -> jax.Array:
    return jax.random.uniform(jax.random.PRNGKey(100 + step), (N, 2), minval=-1.0, maxval=1.0)


def test_reset_ratio_1_is_the_vmapped_adapter_step_bit_for_bit() -> None:
    env, params = short_episodes()
    batched = OptimisticResetVecEnv(env, N)  # the default: 1
    vmapped = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    step = jax.jit(batched.step)
    obs, state = jax.jit(batched.reset)(jax.random.PRNGKey(0), params)
    want_obs, expected_state = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(
        jax.random.split(jax.random.PRNGKey(0), N), params
    )
    np.testing.assert_array_equal(np.asarray(obs), np.asarray(want_obs))
    ended = 0
    for t in range(25):
        key = jax.random.PRNGKey(t)
        got = step(key, state, actions(t), params)
        want = vmapped(jax.random.split(key, N), expected_state, actions(t), params)
        for a, b in zip(jax.tree.leaves(got), jax.tree.leaves(want), strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
        state = got[1]
        expected_state = want[1]
        ended += int(got[3].sum())
    assert ended > 0  # the resets were compared too


def test_every_ended_robot_starts_a_valid_new_episode_and_the_others_step_as_the_adapter() -> None:
    env, params = short_episodes()
    batched = OptimisticResetVecEnv(env, N, reset_ratio=4)  # 8 new episodes per step
    step = jax.jit(batched.step)
    step_env = jax.jit(jax.vmap(env.step_env, in_axes=(0, 0, 0, None)))
    obs, state = jax.jit(batched.reset)(jax.random.PRNGKey(0), params)
    ended_total, distinct_checked = 0, 0
    for t in range(60):
        obs, next_state, reward, done, info = step(jax.random.PRNGKey(t), state, actions(t), params)
        # without noise the step draws nothing: the adapter's step without reset, whatever its keys
        want_obs, want_state, want_reward, want_done, want_info = step_env(
            jax.random.split(jax.random.PRNGKey(t), N), state, actions(t), params
        )
        np.testing.assert_array_equal(np.asarray(reward), np.asarray(want_reward))
        np.testing.assert_array_equal(np.asarray(done), np.asarray(want_done))
        np.testing.assert_array_equal(np.asarray(info["final_observation"]), np.asarray(want_obs))
        assert set(info) == set(want_info) | {"final_observation"}
        ended = np.asarray(done)
        kept = ~ended
        for a, b in zip(jax.tree.leaves(next_state), jax.tree.leaves(want_state), strict=True):
            np.testing.assert_array_equal(np.asarray(a)[kept], np.asarray(b)[kept])
        np.testing.assert_array_equal(np.asarray(obs), np.asarray(next_state.observation))
        assert np.isfinite(np.asarray(obs)).all() and np.isfinite(np.asarray(reward)).all()
        if ended.any():
            ended_total += int(ended.sum())
            np.testing.assert_array_equal(np.asarray(next_state.step_count)[ended], 0)
            np.testing.assert_array_equal(np.asarray(next_state.reward)[ended], 0.0)
            assert not np.asarray(next_state.terminated | next_state.truncated)[ended].any()
            T_con = np.asarray(next_state.T_con)[ended]
            assert ((T_con >= 0.5) & (T_con <= 1.0)).all()
            start = np.asarray(next_state.initial_distance)[ended]
            low, high = params.env_params.start_distance
            assert ((start >= low - 1e-6) & (start <= high + 1e-6)).all()
            assert bool(jax.vmap(env.observation_space(params).contains)(obs[ended]).all())
            if ended.sum() <= batched.num_resets:  # as many new episodes as ended robots: no two alike
                distinct_checked += 1
                assert len(np.unique(np.asarray(next_state.x)[ended])) == ended.sum()
        state = next_state
    assert ended_total >= N and distinct_checked > 0  # every robot's first episode ended at least once


def test_more_ended_robots_than_new_episodes_share_them_in_turn() -> None:
    env, params = make_gymnax_env(dwr_gym.ENV_ID, T_con=0.5)  # every episode ends at step 15 together
    batched = OptimisticResetVecEnv(env, N, reset_ratio=8)  # 4 new episodes for 32 ended robots
    _obs, state = batched.reset(jax.random.PRNGKey(0), params)
    step = jax.jit(batched.step)
    for t in range(15):
        _obs, state, _reward, done, _info = step(jax.random.PRNGKey(t), state, jnp.zeros((N, 2)), params)
    assert bool(done.all())
    x = np.asarray(state.x)
    np.testing.assert_array_equal(x, np.tile(x[:4], N // 4))  # robot i starts new episode i mod 4
    assert len(np.unique(x[:4])) == 4


@pytest.mark.parametrize("value", [0, N + 1, 2.5, "4", True])
def test_an_invalid_reset_ratio_is_a_one_line_error_naming_it(value: object) -> None:
    env, _params = make_gymnax_env(dwr_gym.ENV_ID)
    with pytest.raises(ValueError) as error:
        OptimisticResetVecEnv(env, N, reset_ratio=value)  # type: ignore[arg-type]
    message = str(error.value)
    assert "reset_ratio" in message and repr(value) in message and f"[1, {N}]" in message and "\n" not in message


def test_float64_batches_stay_float64_and_finite() -> None:
    with jax.enable_x64(True):
        env, params = make_gymnax_env(dwr_gym.ENV_ID, "float64", T_con=0.5)
        batched = OptimisticResetVecEnv(env, N, reset_ratio=16)
        obs, state = batched.reset(jax.random.PRNGKey(0), params)
        step = jax.jit(batched.step)
        for t in range(20):
            obs, state, reward, _done, _info = step(jax.random.PRNGKey(t), state, actions(t), params)
        assert obs.dtype == jnp.float64 and state.x.dtype == jnp.float64
        assert np.isfinite(np.asarray(obs)).all() and np.isfinite(np.asarray(reward)).all()
