"""The JAX env is the numpy env: from the same starts, T_con and actions, the gymnax adapter's steps (vmapped, jitted,
with auto-reset) agree with the native vector env's (SAME_STEP autoreset) in states, observations, rewards term by
term, termination, truncation and the info of the step that ended, to 1e-12 in float64 and 1e-5 in float32.

In float64 both run free over the whole rollout. In float32 each step starts from the numpy env's state: rounding
in the last bit (numpy's and XLA's float32 atan2 differ by an ulp) moves free trajectories apart by more than 1e-5
where the task is ill-conditioned (the azimuth (3) of a robot 1 cm from the goal turns by 1e-4 rad per um).

Robots are driven four ways, so every example has arrivals (in time and late), arena exits and truncations:
random actions beyond the clip range, a pursuit law that arrives, full speed straight on, and turning on the spot.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

jax = pytest.importorskip("jax")
pytest.importorskip("flax")

import jax.numpy as jnp  # noqa: E402

import dwr_gym  # noqa: E402
import dwr_gym.model  # noqa: E402
from dwr_gym.jax_env import functional_params, make_gymnax_env  # noqa: E402
from dwr_gym.jax_env.func_env import TASK_FIELDS, initial_state, observation_space  # noqa: E402

N = 48
STEPS = 260
TOLERANCE = {"float64": 1e-12, "float32": 1e-5}
STATE_FIELDS = ("x", "y", "psi", "energy", "lyapunov", "T_con", "initial_distance", "initial_orientation_error")
COUNTS = ("step_count", "prescribed_steps", "max_steps")


def draw_episodes(rng: np.random.Generator, n: int, params: dwr_gym.EnvParams, dtype: str) -> tuple[np.ndarray, ...]:
    """Starts (n, 3) in the goal frame and T_con (n,) for robots acting by :func:`actions`' laws: some at or next to
    the goal, some short (late episodes).

    The orientation error (6) wraps alpha - psi at +-pi, where it jumps by 2 pi: two implementations whose last bits
    differ may land on either side. A robot driving straight on along a line through the goal stays there, so the
    straight-on robots start off that line, and start at the goal only those that do not drive straight away from it.
    """
    law = np.arange(n) % 4
    dist = np.where(rng.random(n) < 0.1, rng.uniform(0.0, 0.012, n), rng.uniform(0.0, 0.98 * params.arena_radius, n))
    dist = np.where((law == 1) & (rng.random(n) < 0.4), rng.uniform(0.05, 0.6, n), dist)  # arrivals, some late
    dist[(rng.random(n) < 0.03) & (law % 2 == 1)] = 0.0  # pursuit and turning on the spot
    bearing, heading = rng.uniform(-np.pi, np.pi, (2, n))
    heading = np.where(law == 2, dwr_gym.model.wrap_angle(bearing + np.pi / 2 + rng.uniform(-1.2, 1.2, n)), heading)
    starts = np.stack([dist * np.cos(bearing), dist * np.sin(bearing), heading], axis=1)
    T_con = np.where(rng.random(n) < 0.5, rng.uniform(0.3, 3.0, n), rng.uniform(params.T_con_min, params.T_con_max, n))
    if dtype == "float32":  # both envs get the same float32 numbers, away from where float32 counts a step fewer
        T_con = T_con.astype(np.float32).astype(np.float64)
        near = np.abs(T_con / params.dt - np.round(T_con / params.dt)) < 1e-3
        T_con = np.where(near, T_con + 0.3 * params.dt, T_con).astype(np.float32).astype(np.float64)
    return starts, np.minimum(T_con, params.T_con_max)


def actions(obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Robot i acts by law i % 4: random beyond [-1, 1], pursuit of the goal, straight on, turning on the spot."""
    d, cos_a, sin_a, cos_p, sin_p = obs[:, 0], obs[:, 1], obs[:, 2], obs[:, 3], obs[:, 4]
    cos_b, sin_b = cos_a * cos_p + sin_a * sin_p, sin_a * cos_p - cos_a * sin_p  # bearing alpha - psi
    pursuit = np.stack([np.clip(6.0 * d * cos_b, -1, 1), np.clip(3.0 * sin_b, -1, 1)], axis=1)
    law = np.arange(len(obs)) % 4
    act = np.select(
        [law[:, None] == 0, law[:, None] == 1, law[:, None] == 2],
        [rng.uniform(-1.3, 1.3, (len(obs), 2)), pursuit, np.array([[1.0, 0.0]])],
        np.array([[0.0, 0.4]]),
    )
    return act.astype(np.float32)


#: Each example is a seed: shrinking one would rerun thousands of steps for little (the seed reproduces it).
SETTINGS = {"deadline": None, "database": None, "phases": (Phase.explicit, Phase.generate),
            "suppress_health_check": [HealthCheck.too_slow]}  # fmt: skip
_compiled: dict[tuple[str, str], tuple] = {}


def compiled(env_id: str, dtype: str) -> tuple:
    """(env, params, jitted vmapped step, jitted batched initial_state) for one id and dtype, compiled once."""
    if (env_id, dtype) not in _compiled:
        env, params = make_gymnax_env(env_id, dtype)
        space = observation_space(params)
        step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
        init = jax.jit(lambda start, T_con, key, p: initial_state(start, T_con, key, p, space))
        _compiled[env_id, dtype] = env, params, step, init
    return _compiled[env_id, dtype]


def where(mask: jax.Array, new: object, old: object) -> object:
    """The pytree ``new`` for the robots in ``mask``, ``old`` for the others."""
    return jax.tree.map(lambda a, b: jnp.where(mask.reshape((-1,) + (1,) * (a.ndim - 1)), a, b), new, old)


def close(name: str, jax_value: object, numpy_value: object, atol: float, where: np.ndarray | None = None) -> None:
    a, b = np.asarray(jax_value, np.float64), np.asarray(numpy_value, np.float64)
    if where is not None:
        a, b = a[where], b[where]
    if "observation" in name and a.ndim == 2:  # the azimuth is undefined at the goal, and with it its features 1, 2
        # and the orientation error (5): a robot held there (v2) at a distance of 1e-12 has any azimuth the last bit
        # of its position gives (as the infos' orientation error, compared only away from the goal below)
        undefined = (a[:, 0] < 1e-6) | (b[:, 0] < 1e-6)
        a, b = a.copy(), b.copy()
        a[undefined, 1:3] = b[undefined, 1:3]
        a[undefined, 5] = b[undefined, 5]
    np.testing.assert_allclose(a, b, rtol=0, atol=atol * max(1.0, float(np.max(np.abs(b), initial=0.0))), err_msg=name)


def run_both(env_id: str, dtype: str, seed: int) -> dict[str, int]:
    """Step both envs STEPS times from the same starts with the same actions; assert they agree; count events."""
    atol = TOLERANCE[dtype]
    obs_atol = max(atol, 2e-6)  # the numpy env's observation is float32 (its cos and sin of the heading computed so)
    _, params, step, init = compiled(env_id, dtype)
    native = gym.make_vec(env_id, num_envs=N, vectorization_mode="vector_entry_point", autoreset_mode="same_step",
                          dtype=dtype)  # fmt: skip
    rng = np.random.default_rng(seed)
    key = jax.random.PRNGKey(seed)
    starts, T_con = draw_episodes(rng, N, native.unwrapped.params, dtype)
    obs, _ = native.reset(seed=seed, options={"start": starts, "T_con": T_con})
    state = init(jnp.asarray(starts.T), jnp.asarray(T_con), key, params)
    close("reset observation", state.observation, obs, obs_atol)
    counts = dict.fromkeys(("steps", "arrivals", "late arrivals", "arena exits", "truncations"), 0)
    for _ in range(STEPS):
        action = actions(obs, rng)
        key, step_key, reset_key = jax.random.split(key, 3)
        jax_obs, state, reward, done, info = step(jax.random.split(step_key, N), state, jnp.asarray(action), params)
        obs, native_reward, terminated, truncated, infos = native.step(action)
        ended = terminated | truncated
        final = infos["final_info"] if ended.any() else infos  # the ended step's infos (SAME_STEP)
        np.testing.assert_array_equal(np.asarray(info["terminated"]), terminated)
        np.testing.assert_array_equal(np.asarray(info["truncated"]), truncated)
        np.testing.assert_array_equal(np.asarray(done), ended)
        np.testing.assert_array_equal(np.asarray(info["is_success"]), final["is_success"])
        np.testing.assert_array_equal(np.asarray(info["cost"]), final["cost"], err_msg="cost")
        # the orientation error's azimuth has a condition number of 1/d: rounding differences grow near the goal,
        # where v2 holds robots; there the values that depend on it are compared to 1000 times the tolerance
        away = np.asarray(final["distance"]) > 1e-3
        for near, scale in ((away, 1.0), (~away, 1000.0)):
            close("reward", reward, native_reward, atol * scale, near)
            for term, values in final["reward_terms"].items():
                if not term.startswith("_"):
                    close(f"reward term {term}", info["reward_terms"][term], values, atol * scale, near)
        for key_name in (
            "distance",
            "orientation_error",
            "heading_error",
            "energy",
            "T_con",
            "time",
            "pose",
            "distance_violation",
            "heading_violation",
        ):
            close(
                f"info {key_name}",
                info[key_name],
                final[key_name],
                atol,
                away if key_name == "orientation_error" else None,
            )
        close("final observation", info["final_observation"], infos["final_obs"] if ended.any() else obs, obs_atol)
        going = ~ended
        close("observation", jax_obs, obs, obs_atol, going)
        for name in STATE_FIELDS:
            for near, scale in ((going & away, 1.0), (going & ~away, 1000.0)):
                close(f"state {name}", getattr(state, name), getattr(native.unwrapped._state, name), atol * scale, near)
        for name in COUNTS:
            np.testing.assert_array_equal(np.asarray(getattr(state, name))[going],
                                          getattr(native.unwrapped._state, name)[going], err_msg=name)  # fmt: skip
        # the auto-reset: a new episode's state, whose observation was returned
        assert np.all(np.asarray(state.step_count)[ended] == 0) and np.all(np.asarray(state.energy)[ended] == 0)
        close("reset observation returned", jax_obs, state.observation, 0.0)
        success, late = final["is_success"] & terminated, final["time"] > final["T_con"] + 1e-9
        counts["steps"] += N
        counts["arrivals"] += int(np.sum(success & ~late))
        counts["late arrivals"] += int(np.sum(success & late))
        counts["arena exits"] += int(np.sum(terminated & ~final["is_success"]))
        counts["truncations"] += int(np.sum(truncated))
        if ended.any():  # both restart the ended robots at the same new starts and T_con
            new_starts, new_T_con = draw_episodes(rng, N, native.unwrapped.params, dtype)
            obs, _ = native.reset(options={"reset_mask": ended, "start": new_starts, "T_con": new_T_con})
            fresh = init(jnp.asarray(new_starts.T), jnp.asarray(new_T_con), reset_key, params)
            state = where(jnp.asarray(ended), fresh, state)
            close("restart observation", state.observation, obs, obs_atol)
        if dtype == "float32":  # the next step from the numpy env's state
            task = native.unwrapped._state
            # copies: jax may alias a numpy array's memory, which the numpy env's next step writes into
            state = state.replace(**{name: jnp.asarray(getattr(task, name).copy()) for name in TASK_FIELDS})
    native.close()
    return counts


def check(env_id: str, dtype: str, seed: int) -> int:
    """Compare the two envs over one draw; returns its count of late arrivals."""
    counts = run_both(env_id, dtype, seed)
    if env_id == dwr_gym.ENV_ID_V2:  # held to T_con: nothing is late and nothing truncates
        assert counts.pop("late arrivals") == counts.pop("truncations") == 0, counts
    # every kind of episode end happened, and was compared; late arrivals (a short T_con, the pursuit law arriving
    # between T_con and 1.5 T_con) do not happen in every draw of 48 robots (seed 44627 on v0 has none)
    late = counts.pop("late arrivals", 1)
    assert all(counts.values()), counts
    return late


@settings(max_examples=2, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1), env_id=st.sampled_from([dwr_gym.ENV_ID, dwr_gym.ENV_ID_V1]))
def test_float32_steps_equal_the_numpy_env_to_1e_5(seed: int, env_id: str) -> None:
    check(env_id, "float32", seed)


@settings(max_examples=2, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1), env_id=st.sampled_from([dwr_gym.ENV_ID, dwr_gym.ENV_ID_V1]))
def test_float64_steps_equal_the_numpy_env_to_1e_12(seed: int, env_id: str) -> None:
    with jax.enable_x64(True):
        check(env_id, "float64", seed)


@settings(max_examples=1, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1))
def test_v2_steps_equal_the_numpy_env_in_float64_and_float32(seed: int) -> None:
    """v2 (held to T_con) to the same tolerances as v0 and v1, but for what the azimuth decides within 1 mm of
    the goal, where v2 holds robots (1000 times the tolerance there)."""
    with jax.enable_x64(True):
        check(dwr_gym.ENV_ID_V2, "float64", seed)
    check(dwr_gym.ENV_ID_V2, "float32", seed)


def test_late_arrivals_are_compared_too() -> None:
    """A fixed draw with late arrivals (7 of them), where the random draws above may have none."""
    assert check(dwr_gym.ENV_ID_V1, "float32", 0) > 0


@pytest.mark.slow
@settings(max_examples=25, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1), env_id=st.sampled_from([dwr_gym.ENV_ID, dwr_gym.ENV_ID_V1, dwr_gym.ENV_ID_V2]),
       dtype=st.sampled_from(["float32", "float64"]))  # fmt: skip
def test_many_more_steps_equal_the_numpy_env(seed: int, env_id: str, dtype: str) -> None:
    with jax.enable_x64(dtype == "float64"):
        check(env_id, dtype, seed)


def test_functional_params_are_the_numpy_envs() -> None:
    params = functional_params(dwr_gym.ENV_ID_V1)
    assert params.env_params == gym.make(dwr_gym.ENV_ID_V1).unwrapped.params
    assert params.T_con_range == (10.0, 60.0) and params.zero_terminal_potential
