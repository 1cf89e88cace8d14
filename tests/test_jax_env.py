"""The JAX env's interfaces: Gymnasium's ids and checker, the gymnax adapter, its params and its one-line errors.
(Its equality with the numpy env: tests/test_jax_equivalence.py.)"""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

jax = pytest.importorskip("jax")
pytest.importorskip("flax")

import jax.numpy as jnp  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

import dwr_gym  # noqa: E402
from dwr_gym.disturbances import VelocityBias  # noqa: E402
from dwr_gym.jax_env import DWRFuncEnv, functional_params, make_gymnax_env  # noqa: E402

INFO_KEYS = ("is_success", "energy", "heading_error", "time", "T_con", "terminated", "truncated", "distance",
             "reward_terms", "final_observation")  # fmt: skip


def run(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)


def test_importing_dwr_gym_registers_the_jax_ids_without_importing_jax() -> None:
    result = run("import sys, gymnasium, dwr_gym; print('jax' in sys.modules, 'DWRPointStabilizationJax-v1' in "
                 "gymnasium.registry, gymnasium.spec('DWRPointStabilizationJax-v1').vector_entry_point is not None)")  # fmt: skip
    assert result.stdout.split() == ["False", "True", "True"], result.stderr


def test_without_jax_the_error_is_one_line_naming_the_extra() -> None:
    result = run("import sys; sys.modules['jax'] = None; import dwr_gym.jax_env")
    last = result.stderr.strip().splitlines()[-1]
    assert result.returncode != 0 and last.startswith("ImportError") and 'pip install "dwr-gym[jax]"' in last


@pytest.mark.parametrize("env_id", [dwr_gym.JAX_ENV_ID, dwr_gym.JAX_ENV_ID_V1])
def test_gymnasium_checker_passes_through_the_jax_wrappers(env_id: str) -> None:
    env = gym.make(env_id)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.spec.max_episode_steps == env.unwrapped.params.max_episode_steps


def test_the_jax_vector_env_autoresets_in_the_next_step_as_the_numpy_one() -> None:
    """Standing still, every robot is truncated at the horizon (15 steps at T_con 0.5 s); the step after returns the
    new episode's first observation (time fraction 0), reward 0 and both flags False, in both envs."""
    kwargs = {"T_con": 0.5, "num_envs": 4}
    envs = [gym.make_vec(env_id, **kwargs) for env_id in (dwr_gym.JAX_ENV_ID, dwr_gym.ENV_ID)]
    still = np.zeros((4, 2), np.float32)
    for env in envs:
        env.reset(seed=3)
        for step in range(1, 17):
            obs, reward, terminated, truncated, _info = env.step(still)
            assert not np.any(terminated)
            assert np.all(np.asarray(truncated) == (step == 15)), step
        np.testing.assert_array_equal(np.asarray(reward), 0.0)
        np.testing.assert_array_equal(np.asarray(obs)[:, 6], 0.0)
        assert not np.any(np.asarray(truncated))


def test_the_gymnax_adapter_steps_under_jit_and_vmap_with_autoreset() -> None:
    env, params = make_gymnax_env(dwr_gym.ENV_ID, T_con=0.5)
    keys = jax.random.split(jax.random.PRNGKey(0), 8)
    obs, state = jax.jit(jax.vmap(env.reset, in_axes=(0, None)))(keys, params)
    assert obs.shape == (8, 10) and obs.dtype == jnp.float32
    assert bool(jax.vmap(env.observation_space(params).contains)(obs).all())
    step = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    for _ in range(15):
        obs, state, _reward, done, info = step(keys, state, jnp.zeros((8, 2)), params)
    assert set(INFO_KEYS) <= set(info) and bool(done.all()) and bool(info["truncated"].all())
    np.testing.assert_array_equal(info["time"], 0.75)  # the ended step's info, before the reset
    np.testing.assert_array_equal(state.step_count, 0)  # the state: a new episode's
    np.testing.assert_array_equal(obs, state.observation)
    assert env.action_space(params).sample(keys[0]).shape == (2,)


def test_the_gymnax_discount_is_zero_only_where_the_episode_terminated() -> None:
    """A value-based learner multiplies the next value by ``discount``: 0 past a termination (leaving the arena or
    arriving), but 1 at a truncation at the horizon, where the episode goes on beyond the cut."""
    from dwr_gym.jax_env.func_env import initial_state, observation_space

    env, params = make_gymnax_env(dwr_gym.ENV_ID, T_con=0.5)
    # robot 0 stands still until the horizon (15 steps); robot 1 starts 2 cm inside the arena, driving outwards
    start = (jnp.array([0.3, params.arena_radius - 0.02]), jnp.zeros(2), jnp.zeros(2))
    state = initial_state(start, jnp.full(2, 0.5), jax.random.PRNGKey(0), params, observation_space(params))
    step = jax.jit(jax.vmap(env.step_env, in_axes=(0, 0, 0, None)))
    action = jnp.array([[0.0, 0.0], [1.0, 0.0]])
    keys = jax.random.split(jax.random.PRNGKey(1), 2)
    seen = {"terminated": 0, "truncated": 0}
    for _ in range(15):
        _, state, _, done, info = step(keys, state, action, params)
        np.testing.assert_array_equal(np.asarray(done), np.asarray(info["terminated"] | info["truncated"]))
        discount = np.asarray(info["discount"])
        np.testing.assert_array_equal(discount, np.where(np.asarray(info["terminated"]), 0.0, 1.0))
        np.testing.assert_array_equal(np.asarray(env.discount(state, params)), discount)
        seen["terminated"] += int(info["terminated"][1])
        seen["truncated"] += int(info["truncated"][0])
        assert not bool(info["terminated"][0])
    assert seen == {"terminated": 15, "truncated": 1}  # robot 1 outside from its first step on; robot 0 cut at 15
    assert np.asarray(info["discount"]).tolist() == [1.0, 0.0]


def test_float64_with_x64_and_a_nan_action_gives_finite_numbers() -> None:
    with jax.enable_x64(True):
        env, params = make_gymnax_env(dtype="float64")
        obs, state = jax.jit(env.reset)(jax.random.PRNGKey(1), params)
        obs, state, reward, _done, info = jax.jit(env.step)(jax.random.PRNGKey(2), state, jnp.array([jnp.nan, 1.0]))
        assert obs.dtype == jnp.float64 and reward.dtype == jnp.float64
        assert bool(jnp.isfinite(obs).all()) and bool(jnp.isfinite(reward))
        assert float(info["linear_velocity"]) == 0.0 and float(info["angular_velocity"]) == params.omega_max


def test_params_vmap_over_robots_of_different_speeds() -> None:
    """Domain randomisation: one compiled step, each robot with its own u_max."""
    func_env = DWRFuncEnv(dwr_gym.ENV_ID)
    params = func_env.default_params
    speeds = jnp.array([0.1, 0.2, 0.4])
    batch = jax.vmap(lambda u: params.replace(u_max=u))(speeds)
    state = jax.jit(jax.vmap(func_env.initial))(jax.random.split(jax.random.PRNGKey(0), 3), batch)
    state = jax.jit(jax.vmap(func_env.transition, in_axes=(0, None, 0, 0)))(
        state, jnp.array([1.0, 0.0]), jax.random.split(jax.random.PRNGKey(1), 3), batch
    )
    np.testing.assert_allclose(state.linear_velocity, speeds)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"dtype": "float16"}, "dtype='float16' is invalid"),
        ({"dtype": "float64"}, "dtype='float64' is invalid while jax_enable_x64 is off"),
        ({"disturbances": [VelocityBias(0.1)]}, "disturbances=[VelocityBias(linear=0.1, angular=0.0)] is invalid"),
        ({"robot": "turtlebot3_burger"}, "robot='turtlebot3_burger' is invalid for the functional (JAX) env"),
        ({"u_max": -1.0}, "u_max=-1.0 is invalid"),
        ({"env_id": "CartPole-v1"}, "env_id='CartPole-v1' is invalid"),
    ],
)
def test_bad_input_is_a_one_line_error_naming_the_parameter(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError) as error:
        functional_params(**kwargs)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_what_the_jax_envs_cannot_do_is_a_one_line_error_naming_it() -> None:
    """Rendering, reset options (the JAX env draws its own starts), a bad robot count, params and keywords at once,
    and parameters that are not EnvParams are refused in one line each, naming the argument."""
    from dwr_gym.jax_env import FunctionalParams
    from dwr_gym.jax_env.wrappers import DWRJaxEnv, DWRJaxVectorEnv

    cases = [
        (lambda: DWRJaxEnv(render_mode="human"), "render_mode='human' is invalid for the JAX env: expected None"),
        (lambda: DWRJaxEnv().reset(options={"start": [1.0, 0.0, 0.0]}), "reset options ['start'] are invalid"),
        (lambda: DWRJaxVectorEnv(2).reset(options={"T_con": 3.0}), "reset options ['T_con'] are invalid"),
        (lambda: DWRJaxVectorEnv(num_envs=0), "num_envs=0 is invalid"),
        (lambda: DWRJaxVectorEnv(num_envs=2**24 + 1), "num_envs=16777217 is invalid"),
        (lambda: DWRFuncEnv(params=functional_params(), u_max=0.2), "env_kwargs=['u_max'] are invalid with params"),
        (lambda: FunctionalParams.from_env_params({"u_max": 0.2}), "is invalid: expected a dwr_gym.params.EnvParams"),
        (
            lambda: functional_params(disturbance_distribution=dwr_gym.randomization.DisturbanceDistribution(seed=1)),
            "disturbance_distribution=DisturbanceDistribution(",
        ),
    ]
    for make, message in cases:
        with pytest.raises(ValueError) as error:
            make()
        assert message in str(error.value) and "\n" not in str(error.value), str(error.value)


def test_the_functional_params_are_the_envs_in_the_dtype_asked_for() -> None:
    """A numpy dtype type is read as its name; a fixed T_con is the interval (T_con, T_con); no heading tolerance
    is an infinite one; the spaces and the horizon are the numpy env's."""
    params = functional_params(dwr_gym.ENV_ID, dtype=np.float32, T_con=7.0)
    numpy_env = gym.make(dwr_gym.ENV_ID, T_con=7.0).unwrapped
    assert params.dtype == "float32" and params.T_con_range == (7.0, 7.0) and params.T_con == 7.0
    assert params.heading_tolerance == float("inf") and params.max_episode_steps == numpy_env.params.max_episode_steps
    assert DWRFuncEnv(dwr_gym.ENV_ID, T_con=7.0).observation_space == numpy_env.observation_space
    with jax.enable_x64(True):
        space = DWRFuncEnv(dwr_gym.ENV_ID, dtype="float64", T_con=7.0).observation_space
        assert space.dtype == np.float64
        np.testing.assert_array_equal(space.high, numpy_env.observation_space.high.astype(np.float64))
    assert functional_params(dwr_gym.ENV_ID, heading_tolerance=0.2).heading_tolerance == 0.2


def test_the_gymnax_spaces_are_the_envs_and_contain_exactly_their_bounds() -> None:
    """A gymnax trainer sizes its policy from ``num_actions`` and the spaces, and clips to their bounds: they are
    the numpy env's spaces; ``contains`` holds on the bounds and not past them; ``sample`` draws within them."""
    env, params = make_gymnax_env(dwr_gym.ENV_ID_V1)
    numpy_env = gym.make(dwr_gym.ENV_ID_V1).unwrapped
    assert env.name == gym.spec(dwr_gym.ENV_ID_V1).name
    for space, expected in ((env.observation_space(params), numpy_env.observation_space),
                            (env.action_space(params), numpy_env.action_space)):  # fmt: skip
        np.testing.assert_array_equal(np.broadcast_to(space.low, expected.shape), expected.low)
        np.testing.assert_array_equal(np.broadcast_to(space.high, expected.shape), expected.high)
        assert space.shape == expected.shape and np.dtype(space.dtype) == expected.dtype
        low, high = (jnp.broadcast_to(jnp.asarray(bound), space.shape) for bound in (space.low, space.high))
        assert bool(space.contains(low)) and bool(space.contains(high))
        nudge = jnp.zeros(space.shape).at[0].set(1e-3)
        assert not bool(space.contains(low - nudge)) and not bool(space.contains(high + nudge))
        samples = jax.vmap(space.sample)(jax.random.split(jax.random.PRNGKey(0), 64))
        assert samples.dtype == expected.dtype and bool(jax.vmap(space.contains)(samples).all())
    assert env.num_actions == env.action_space(params).shape[0] == 2


def test_the_jax_env_draws_starts_and_T_con_as_independent_uniforms_over_the_numpy_envs_ranges() -> None:
    """``initial`` draws what the numpy env's reset draws: distance, bearing, heading and T_con, each uniform over
    its range (v1's start_distance, a full turn, start_heading, T_con_range) and independent of the others."""
    func_env = DWRFuncEnv(dwr_gym.ENV_ID_V1)
    params = func_env.default_params
    n = 4000
    state = jax.jit(jax.vmap(func_env.initial))(jax.random.split(jax.random.PRNGKey(0), n))
    x, y, psi, T_con = (np.asarray(getattr(state, name), np.float64) for name in ("x", "y", "psi", "T_con"))
    draws = {"distance": (np.hypot(x, y), params.start_distance), "bearing": (np.arctan2(y, x), (-np.pi, np.pi)),
             "heading": (psi, params.start_heading), "T_con": (T_con, params.T_con_range)}  # fmt: skip
    uniforms = []
    for name, (values, (low, high)) in draws.items():
        u = (values - low) / (high - low)
        assert u.min() >= -1e-6 and u.max() <= 1 + 1e-6, name
        ks = np.max(np.abs(np.sort(u) - (np.arange(n) + 0.5) / n))  # Kolmogorov-Smirnov distance to U(0, 1)
        assert ks < 0.035, (name, ks)
        uniforms.append(u)
    correlation = np.corrcoef(uniforms) - np.eye(len(uniforms))
    assert np.abs(correlation).max() < 0.06, correlation
    np.testing.assert_allclose(np.asarray(state.initial_distance), np.hypot(x, y), rtol=1e-5)


def test_the_gymnax_adapter_uses_the_params_it_is_given_and_its_own_without() -> None:
    """Domain randomisation through gymnax's interface: reset and step follow the params passed (a start distance
    of exactly 0.5 m, a slower robot), and the env's own when none are; ``is_terminal`` is the step's ``done``."""
    env, params = make_gymnax_env(dwr_gym.ENV_ID, T_con=0.5)
    slow = params.replace(start_distance=(0.5, 0.5), u_max=0.1)
    key = jax.random.PRNGKey(3)
    _, state = env.reset(key, slow)
    assert float(state.initial_distance) == pytest.approx(0.5)
    _, default_state = env.reset(key)
    assert float(default_state.initial_distance) != pytest.approx(0.5)
    _, _, _, _, info = env.step(key, state, jnp.array([1.0, 0.0]), slow)
    assert float(info["linear_velocity"]) == pytest.approx(0.1)
    _, _, _, _, info = env.step(key, state, jnp.array([1.0, 0.0]))
    assert float(info["linear_velocity"]) == pytest.approx(params.u_max)
    for _ in range(15):  # standing still until the horizon (15 steps at T_con 0.5 s)
        _, state, _, done, _ = env.step_env(key, state, jnp.zeros(2), slow)
        assert bool(env.is_terminal(state, slow)) == bool(done)
    assert bool(done)


def test_the_jax_envs_pickle_with_their_keywords_and_accept_an_empty_disturbance_list() -> None:
    """A pickled JAX env (sent to a worker process) comes back with the same parameters and dtype, a vector env with
    its number of robots; ``disturbances=[]``, as a config file writes none, is the nominal robot."""
    import pickle

    from dwr_gym.jax_env.wrappers import DWRJaxEnv, DWRJaxVectorEnv

    env = DWRJaxEnv(T_con=7.0, u_max=0.3)
    copy = pickle.loads(pickle.dumps(env))
    assert copy.params == env.params and copy.params.u_max == 0.3
    assert copy.observation_space == env.observation_space
    vector = pickle.loads(pickle.dumps(DWRJaxVectorEnv(num_envs=3, T_con=7.0)))
    assert vector.num_envs == 3 and vector.params.T_con == 7.0
    assert DWRJaxVectorEnv(num_envs=1).num_envs == 1
    assert functional_params(dwr_gym.ENV_ID, disturbances=[]).env_params == functional_params(dwr_gym.ENV_ID).env_params


def test_the_single_jax_env_terminates_where_its_robot_leaves_the_arena() -> None:
    """gym.make's JAX env returns the step's flags: driving straight on at full speed, the robot leaves the 5 m arena
    before v0's 30 s horizon, and that step is terminated (not truncated), with the arena's penalty."""
    env = gym.make(dwr_gym.JAX_ENV_ID)
    env.reset(seed=2)
    for _ in range(env.spec.max_episode_steps):
        _, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
        assert terminated == bool(info["terminated"]) and truncated == bool(info["truncated"])
        if terminated or truncated:
            break
    assert terminated and not truncated and float(info["distance"]) > env.unwrapped.params.arena_radius
    assert float(info["reward_terms"]["arena"]) == -env.unwrapped.params.arena_penalty and reward < 0


def test_a_seeded_reset_of_the_jax_vector_env_is_reproducible() -> None:
    env = gym.make_vec(dwr_gym.JAX_ENV_ID, num_envs=3)
    first, _ = env.reset(seed=5)
    env.step(np.ones((3, 2), np.float32))
    again, _ = env.reset(seed=5)
    other, _ = env.reset(seed=6)
    np.testing.assert_array_equal(np.asarray(first), np.asarray(again))
    assert not np.array_equal(np.asarray(first), np.asarray(other))


def test_the_observation_noise_at_reset_has_its_sigma_and_is_drawn_apart_from_the_start() -> None:
    """The reset's measured heading is the drawn heading plus noise of standard deviation ``observation_noise``,
    independent of it (noise drawn with the start's own key would be a function of the heading drawn)."""
    func_env = DWRFuncEnv(dwr_gym.ENV_ID_V1, observation_noise=0.05)
    state = jax.jit(jax.vmap(func_env.initial))(jax.random.split(jax.random.PRNGKey(1), 2000))
    obs, psi = np.asarray(state.observation, np.float64), np.asarray(state.psi, np.float64)
    noise = np.angle(np.exp(1j * (np.arctan2(obs[:, 4], obs[:, 3]) - psi)))
    assert abs(np.std(noise) - 0.05) < 0.005
    assert abs(np.corrcoef(noise, psi)[0, 1]) < 0.1
    # a step standing still measures the same heading with fresh noise of the same sigma
    step = jax.jit(jax.vmap(func_env.transition, in_axes=(0, None, 0)))
    state = step(state, jnp.zeros(2), jax.random.split(jax.random.PRNGKey(2), 2000))
    obs = np.asarray(state.observation, np.float64)
    fresh = np.angle(np.exp(1j * (np.arctan2(obs[:, 4], obs[:, 3]) - psi)))
    assert abs(np.std(fresh) - 0.05) < 0.005 and abs(np.corrcoef(fresh, noise)[0, 1]) < 0.1


def test_a_float32_jax_env_keeps_float32_states_when_x64_is_on() -> None:
    """A session that enables jax_enable_x64 for other work still gets the float32 env it asked for: float64 starts
    placed with initial_state become float32 states, and a step keeps them so (no float64 creeps in)."""
    from dwr_gym.jax_env.func_env import initial_state, observation_space, transition_state

    with jax.enable_x64(True):
        params = functional_params(dwr_gym.ENV_ID, dtype="float32")
        start = (np.array([1.0, -0.5]), np.array([0.5, 2.0]), np.array([0.2, 3.0]))
        space = observation_space(params)
        state = initial_state(start, np.array([5.0, 8.0]), jax.random.PRNGKey(0), params, space)
        state = transition_state(state, jnp.ones((2, 2), jnp.float32), jax.random.PRNGKey(1), params, space)
        floats = {name: leaf.dtype for name, leaf in vars(state).items()
                  if hasattr(leaf, "dtype") and jnp.issubdtype(leaf.dtype, jnp.floating)}  # fmt: skip
        assert set(floats.values()) == {jnp.dtype("float32")}, floats


def test_v2_on_jax_ends_at_T_con_and_pays_the_heading_and_the_miss_as_the_numpy_env() -> None:
    """v2 held to T_con on JAX: a robot standing 1 m from the goal, turned 0.5 rad, ends at the step floor(T_con / dt)
    (terminated, not truncated) with the numpy v2 env's reward terms: no arrival, the heading's cost and the miss."""
    from dwr_gym.jax_env.func_env import initial_state, observation_space, transition_state

    with jax.enable_x64(True):
        params = functional_params(dwr_gym.ENV_ID_V2, dtype="float64", T_con_range=None, T_con=0.5)
        space = observation_space(params)
        start = (np.array([1.0]), np.array([0.0]), np.array([0.5]))
        state = initial_state(start, np.array([0.5]), jax.random.PRNGKey(0), params, space)
        numpy_env = gym.make(dwr_gym.ENV_ID_V2, T_con_range=None, T_con=0.5).unwrapped
        numpy_env.reset(options={"start": (1.0, 0.0, 0.5), "goal": (0.0, 0.0, 0.0)})
        for step in range(1, 11):  # v2 steps 0.05 s: T_con is its 10th step
            state = transition_state(state, jnp.zeros((1, 2)), jax.random.PRNGKey(step), params, space)
            _, reward, terminated, truncated, info = numpy_env.step(np.zeros(2, np.float32))
            assert bool(state.terminated[0]) == terminated == (step == 10) and not (
                bool(state.truncated[0]) or truncated
            )
            assert float(state.reward[0]) == pytest.approx(reward, abs=1e-12)
            for term, value in info["reward_terms"].items():
                assert float(state.reward_terms[term][0]) == pytest.approx(value, abs=1e-12), term
        assert info["reward_terms"]["heading"] < 0 and info["reward_terms"]["late"] < 0
        assert info["reward_terms"]["arrival"] == 0


def test_actuation_noise_on_jax_steps_under_jit_and_moves_a_robot_told_to_stand_still() -> None:
    """v1's actuation noise on JAX, jitted: the command is the action plus sigma x a standard-normal draw (the numpy
    env's one place, core.transition), so a robot told to stand still moves, within the limits; the same key, the
    same move."""
    env, params = make_gymnax_env(dwr_gym.ENV_ID, T_con=5.0, actuation_noise=0.2)
    _, state = jax.jit(env.reset)(jax.random.PRNGKey(0), params)
    step = jax.jit(env.step)
    _, _, _, _, info = step(jax.random.PRNGKey(1), state, jnp.zeros(2), params)
    _, _, _, _, again = step(jax.random.PRNGKey(1), state, jnp.zeros(2), params)
    u, omega = float(info["linear_velocity"]), float(info["angular_velocity"])
    assert 0.0 < abs(u) < params.u_max and 0.0 < abs(omega) < params.omega_max
    assert (u, omega) == (float(again["linear_velocity"]), float(again["angular_velocity"]))


def test_the_jax_observation_at_the_goal_and_at_one_metre_is_the_numpy_envs() -> None:
    """The bearing features -x/d and -y/d hold at every distance, exactly 1 m included (straight below the goal: (0, 1)),
    and at the goal itself, where the division is guarded, they are the numpy env's (1, 0): no NaN."""
    from dwr_gym.jax_env.func_env import initial_state, observation_space

    with jax.enable_x64(True):
        params = functional_params(dwr_gym.ENV_ID, dtype="float64")
        start = (np.array([0.0, 0.0]), np.array([-1.0, 0.0]), np.array([0.3, 0.3]))
        state = initial_state(start, np.array([10.0, 10.0]), jax.random.PRNGKey(0), params, observation_space(params))
        observed = np.asarray(state.observation)
    numpy_env = gym.make(dwr_gym.ENV_ID).unwrapped
    for robot, pose in enumerate([(0.0, -1.0, 0.3), (0.0, 0.0, 0.3)]):
        reference, _ = numpy_env.reset(options={"start": pose, "goal": (0.0, 0.0, 0.0), "T_con": 10.0})
        np.testing.assert_allclose(observed[robot], reference, rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(observed[:, 1:3], [[0.0, 1.0], [1.0, 0.0]])
