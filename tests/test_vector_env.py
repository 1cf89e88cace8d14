"""The native vector env against N single envs, and the stable-baselines3 adapter."""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import dwr_gym
from dwr_gym import core
from dwr_gym.vector_env import DWRPointStabilizationVectorEnv

ENV_ID = "DWRPointStabilization-v0"
#: This module pins the behaviour of DWRPointStabilization-v0 (fixed T_con, the paper's reward), which Gymnasium
#: rightly calls out of date now that v1 exists; that warning is not what these tests test.
pytestmark = pytest.mark.filterwarnings("ignore:.*DWRPointStabilization-v0 is out of date:DeprecationWarning")
# Short episodes with many arrivals, so autoreset is exercised by both termination and truncation.
KWARGS: dict[str, Any] = {"T_con": 2.0, "dt": 0.1, "goal_tolerance": 0.15, "start_distance": (0.2, 0.5),
                          "heading_weight": 1.0}  # fmt: skip


def test_make_vec_returns_the_native_vector_env() -> None:
    envs = gym.make_vec(ENV_ID, num_envs=8, T_con=25.0)
    assert isinstance(envs, DWRPointStabilizationVectorEnv)
    assert envs.params.T_con == 25.0
    assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP  # as Gymnasium's own vector envs
    assert envs.spec is not None and envs.spec.max_episode_steps == 750  # 1.5 * 25 s / 0.05 s
    assert envs.observation_space.shape == (8, 10) and envs.action_space.shape == (8, 2)


@pytest.mark.parametrize("mode", [*AutoresetMode, "next_step", "SAME_STEP", "Disabled"])
def test_make_vec_takes_the_autoreset_mode_and_reports_it(mode: Any) -> None:
    envs = gym.make_vec(ENV_ID, num_envs=2, autoreset_mode=mode)
    expected = mode if isinstance(mode, AutoresetMode) else {"n": AutoresetMode.NEXT_STEP, "s": AutoresetMode.SAME_STEP,
                                                            "d": AutoresetMode.DISABLED}[mode[0].lower()]  # fmt: skip
    assert envs.metadata["autoreset_mode"] is expected and envs.autoreset_mode is expected
    assert type(envs).metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP  # the class default is untouched
    with pytest.raises(ValueError, match="autoreset_mode='sometimes' is invalid"):
        gym.make_vec(ENV_ID, num_envs=2, autoreset_mode="sometimes")


def test_sync_and_async_vectorization_take_the_autoreset_mode_in_vector_kwargs() -> None:
    envs = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync",
                        vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP})  # fmt: skip
    assert isinstance(envs, SyncVectorEnv) and envs.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    with pytest.raises(ValueError, match="vector_kwargs"):  # a keyword there would reach the single envs
        gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync", autoreset_mode="same_step")


def assert_infos_match(info: dict[str, Any], ref_info: dict[str, Any], rows: Any) -> None:
    """Every info key of the single env, and every reward term, equal on ``rows``."""
    for key in ("distance", "orientation_error", "heading_error", "time", "is_success", "energy", "pose",
                "linear_velocity", "angular_velocity"):  # fmt: skip
        np.testing.assert_allclose(info[key][rows], ref_info[key][rows], rtol=1e-9, atol=1e-12, err_msg=key)
    for term in ("progress", "time", "effort", "arrival", "heading", "late", "arena"):
        np.testing.assert_allclose(info["reward_terms"][term][rows], ref_info["reward_terms"][term][rows], atol=1e-12)


@pytest.mark.parametrize(
    ("mode", "num_envs"),
    [(AutoresetMode.NEXT_STEP, 1), (AutoresetMode.NEXT_STEP, 5), (AutoresetMode.SAME_STEP, 5),
     (AutoresetMode.DISABLED, 5)],
)  # fmt: skip
def test_vector_env_matches_sync_vector_env_step_by_step(mode: AutoresetMode, num_envs: int) -> None:
    """Gymnasium's test_cartpole_vector_equiv, for our env and each autoreset mode: same seeds, same
    actions, same everything as SyncVectorEnv of single envs in that mode."""
    vec = gym.make_vec(ENV_ID, num_envs=num_envs, autoreset_mode=mode, **KWARGS)
    ref = SyncVectorEnv([lambda: gym.make(ENV_ID, **KWARGS) for _ in range(num_envs)], autoreset_mode=mode)
    assert vec.metadata["autoreset_mode"] == ref.metadata["autoreset_mode"] == mode
    obs, info = vec.reset(seed=123)
    ref_obs, ref_info = ref.reset(seed=123)
    np.testing.assert_allclose(obs, ref_obs, rtol=1e-6, atol=1e-7)  # float32 features: equal to rounding
    assert_infos_match(info, ref_info, slice(None))
    vec.action_space.seed(0)
    ended = np.zeros(num_envs, dtype=bool)
    dones = 0
    for _ in range(200):
        actions = vec.action_space.sample()
        obs, rewards, terminated, truncated, info = vec.step(actions)
        ref_obs, ref_rewards, ref_terminated, ref_truncated, ref_info = ref.step(actions)
        np.testing.assert_allclose(obs, ref_obs, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(rewards, ref_rewards, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(terminated, ref_terminated)
        np.testing.assert_array_equal(truncated, ref_truncated)
        assert_infos_match(info, ref_info, slice(None))
        if mode == AutoresetMode.NEXT_STEP and ended.any():
            # the step after an episode ends: the reset observation, reward 0, both flags False
            assert np.all(rewards[ended] == 0.0) and not terminated[ended].any() and not truncated[ended].any()
            assert np.all(info["time"][ended] == 0.0) and np.all(obs[ended, 6] == 0.0)
        done = terminated | truncated
        dones += int(done.sum())
        if mode == AutoresetMode.SAME_STEP and done.any():
            np.testing.assert_array_equal(info["_final_obs"], ref_info["_final_obs"])
            ref_final = np.stack(ref_info["final_obs"][done])  # SyncVectorEnv's is an object array
            np.testing.assert_allclose(info["final_obs"][done], ref_final, rtol=1e-6, atol=1e-6)
            assert_infos_match(info["final_info"], ref_info["final_info"], done)
            assert np.all(info["time"][done] == 0.0)  # already the new episodes
        if mode == AutoresetMode.DISABLED and done.any():
            with pytest.raises(gym.error.ResetNeeded, match="reset_mask"):
                vec.step(actions)
            obs, info = vec.reset(options={"reset_mask": done})
            ref_obs, ref_info = ref.reset(options={"reset_mask": done})
            np.testing.assert_allclose(obs[done], ref_obs[done], rtol=1e-6, atol=1e-7)
            assert_infos_match(info, ref_info, done)
            np.testing.assert_array_equal(info["_distance"], done)
        ended = done
    assert dones > 2 * num_envs  # autoreset was exercised
    assert terminated.dtype == bool


@pytest.mark.filterwarnings("ignore:.*out of date")
@pytest.mark.parametrize("env_id", ["DWRPointStabilization-v0", "DWRPointStabilization-v1"])
def test_terminal_reward_terms_are_paid_where_episodes_end_as_in_the_single_env(env_id: str) -> None:
    """The batch computes arrival, heading and arena only for the robots whose episodes end; each robot's
    reward and terms still equal the single env's, and the reward is the sum of the terms."""
    starts = np.array([[0.005, 0.0, 1.0], [4.99, 0.0, 0.0], [1.0, 1.0, 0.5], [0.0, 0.004, -2.0], [-4.98, 0.0, 0.0]])
    # 0 and 3 are within goal_tolerance (arrive), 1 and 4 drive out of the arena, 2 drives on
    actions = np.array([[0.0, 0.0], [1.0, 0.0], [0.3, 0.2], [0.0, 0.5], [-1.0, 0.3]], dtype=np.float32)
    vec = gym.make_vec(env_id, num_envs=len(starts))
    vec.reset(seed=0, options={"start": starts, "T_con": 20.0})
    _, rewards, terminated, _, info = vec.step(actions)
    np.testing.assert_array_equal(terminated, [True, True, False, True, True])
    terms = info["reward_terms"]
    assert np.all(terms["arrival"] == [10.0, 0.0, 0.0, 10.0, 0.0])
    assert np.all(terms["arena"] == [0.0, -10.0, 0.0, 0.0, -10.0])
    assert np.all(terms["heading"][[1, 2, 4]] == 0.0)
    assert terms["heading"][0] == pytest.approx(5.0 * (np.cos(1.0) - 1.0))  # weight 5 x (cos(psi) - 1) on arrival
    assert terms["heading"][3] == pytest.approx(5.0 * (np.cos(-2.0 + 0.5 * 2.0 * 0.05) - 1.0))
    np.testing.assert_allclose(rewards, sum(terms[name] for name in core.REWARD_TERMS), rtol=0, atol=1e-12)
    for i, start in enumerate(starts):
        env = gym.make(env_id)
        env.reset(seed=0, options={"start": tuple(start), "T_con": 20.0})
        _, reward, done, _, ref = env.step(actions[i])
        assert done == terminated[i]
        assert reward == pytest.approx(rewards[i], abs=1e-12)
        for name in core.REWARD_TERMS:
            assert ref["reward_terms"][name] == pytest.approx(terms[name][i], abs=1e-12), name


def test_seeding_is_reproducible_and_per_env() -> None:
    a = gym.make_vec(ENV_ID, num_envs=4)
    b = gym.make_vec(ENV_ID, num_envs=4)
    obs_a, _ = a.reset(seed=9)
    obs_b, _ = b.reset(seed=9)
    np.testing.assert_array_equal(obs_a, obs_b)
    assert len({tuple(row) for row in obs_a}) == 4
    obs_c, _ = b.reset(seed=[9, 10, 11, 12])
    np.testing.assert_array_equal(obs_a, obs_c)


def test_per_env_start_and_goal_options_and_reset_mask() -> None:
    envs = gym.make_vec(ENV_ID, num_envs=3)
    starts = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, np.pi / 2], [1.0, 1.0, 0.0]])
    goals = np.array([[0.8, 0.0, 0.0], [0.0, 0.5, 0.0], [1.0, 2.0, 0.0]])
    _obs, info = envs.reset(options={"start": starts, "goal": goals})
    np.testing.assert_allclose(info["distance"], [0.8, 0.5, 1.0])
    np.testing.assert_allclose(info["pose"], starts)
    envs.step(np.ones((3, 2), dtype=np.float32))
    _obs2, info2 = envs.reset(options={"start": (0.0, 0.0, 0.0), "reset_mask": np.array([True, False, False])})
    assert info2["distance"][0] == pytest.approx(0.0)
    assert info2["time"][1] > 0 and info2["time"][0] == 0
    with pytest.raises(ValueError, match="start"):
        envs.reset(options={"start": np.zeros((2, 3))})
    with pytest.raises(ValueError, match="unknown reset option"):
        envs.reset(options={"stat": np.zeros(3)})
    with pytest.raises(ValueError, match="actions of shape"):
        envs.step(np.zeros((2, 2), dtype=np.float32))
    with pytest.raises(ValueError, match="num_envs"):
        DWRPointStabilizationVectorEnv(num_envs=0)


def test_vector_env_truncates_itself_at_the_horizon_it_reports() -> None:
    envs = gym.make_vec(ENV_ID, num_envs=2, T_con=1.0, dt=0.1, horizon_factor=2.0)
    assert envs.spec is not None and envs.spec.max_episode_steps == 20
    envs.reset(seed=0)
    for step in range(1, 22):
        _, rewards, terminated, truncated, info = envs.step(np.zeros((2, 2), dtype=np.float32))
        assert not terminated.any()
        assert truncated.all() == (step == 20)
        if step == 20:
            np.testing.assert_allclose(info["time"], 2.0)
    assert np.all(info["time"] == 0.0) and np.all(rewards == 0.0)  # step 21: the new episodes (NEXT_STEP)


def test_vector_env_renders_one_frame_per_sub_env() -> None:
    envs = gym.make_vec(ENV_ID, num_envs=3, render_mode="rgb_array", **KWARGS)
    envs.reset(seed=0)
    for _ in range(25):  # through an autoreset of some sub-envs
        envs.step(np.tile(np.array([[1.0, 0.5]], dtype=np.float32), (3, 1)))
    frames = envs.render()
    assert isinstance(frames, tuple) and len(frames) == 3
    assert all(frame.shape == (480, 480, 3) and frame.dtype == np.uint8 for frame in frames)
    assert not np.array_equal(frames[0], frames[1])  # different robots
    single = gym.make(ENV_ID, render_mode="rgb_array", **KWARGS)
    single.reset(seed=1)
    for _ in range(25):
        _, _, terminated, truncated, _ = single.step(np.array([1.0, 0.5], dtype=np.float32))
        if terminated or truncated:
            single.reset()
    np.testing.assert_array_equal(frames[1], single.render())  # sub-env 1 is drawn as the single env of seed 1


def test_sb3_adapter_conventions_and_ppo_learns_on_the_native_batch() -> None:
    from stable_baselines3 import PPO

    from dwr_gym.sb3 import make_sb3_vec_env

    venv = make_sb3_vec_env(num_envs=4, seed=0, **KWARGS)
    obs = venv.reset()
    assert obs.shape == (4, 10)
    venv.action_space.seed(0)
    seen_done = False
    for _ in range(60):
        obs, rewards, dones, infos = venv.step(np.stack([venv.action_space.sample() for _ in range(4)]))
        assert isinstance(infos, list) and len(infos) == 4 and rewards.dtype == np.float32
        for i in np.flatnonzero(dones):
            seen_done = True
            assert infos[i]["terminal_observation"].shape == (10,)
            assert isinstance(infos[i]["TimeLimit.truncated"], bool)
            assert not np.array_equal(infos[i]["terminal_observation"], obs[i])
    assert seen_done
    assert venv.get_attr("params")[0].T_con == 2.0

    model = PPO("MlpPolicy", make_sb3_vec_env(num_envs=8, seed=1, **KWARGS), n_steps=32, batch_size=64, seed=0)
    model.learn(total_timesteps=512)
    assert model.num_timesteps >= 512
    # episode statistics without a VecMonitor: SB3 logs rollout/ep_rew_mean and ep_len_mean from them
    assert len(model.ep_info_buffer) > 0 and all(0 < e["l"] <= 30 for e in model.ep_info_buffer)
    assert len(model.ep_success_buffer) == len(model.ep_info_buffer)


def evaluation(model: Any, episodes: int = 64, seed: int = 100) -> tuple[float, float]:
    """(mean return, success rate) of the deterministic policy on a fixed seeded set of episodes."""
    env = gym.make_vec(ENV_ID, num_envs=episodes, **KWARGS)
    obs, _ = env.reset(seed=seed)
    returns, done, success = np.zeros(episodes), np.zeros(episodes, bool), np.zeros(episodes, bool)
    while not done.all():
        obs, rewards, terminated, truncated, info = env.step(model.predict(obs, deterministic=True)[0])
        returns += np.where(done, 0.0, rewards)
        success |= ~done & info["is_success"]
        done |= terminated | truncated
    return float(returns.mean()), float(success.mean())


def test_ppo_learns_on_the_native_batch() -> None:
    """4096 steps of PPO on the short task raise the evaluation return and success, for each of three seeds.

    Measured (seeds 0, 1, 2): return -5.72 -> 7.30, -5.76 -> -3.68, -5.79 -> -3.86; success 0 -> 0.86, 0.31, 0.16."""
    from stable_baselines3 import PPO

    from dwr_gym.sb3 import make_sb3_vec_env

    rises = []
    for seed in range(3):
        model = PPO("MlpPolicy", make_sb3_vec_env(num_envs=8, seed=1, **KWARGS), n_steps=32, batch_size=64,
                    seed=seed, device="cpu")  # fmt: skip
        before, success_before = evaluation(model)
        model.learn(total_timesteps=4096)
        after, success_after = evaluation(model)
        assert success_before == 0.0 and success_after > 0.05, (seed, success_after)
        rises.append(after - before)
    assert min(rises) > 1.0 and np.mean(rises) > 3.0, rises


def test_float32_mode_tracks_float64_and_keeps_its_dtype() -> None:
    fast = gym.make_vec(ENV_ID, num_envs=64, dtype="float32")
    exact = gym.make_vec(ENV_ID, num_envs=64)
    obs_f, _ = fast.reset(seed=4)
    obs_e, _ = exact.reset(seed=4)
    np.testing.assert_allclose(obs_f, obs_e, atol=1e-6)
    actions = np.tile(np.array([[0.3, 0.4]], dtype=np.float32), (64, 1))
    for _ in range(100):
        obs_f, rew_f, _term_f, _, info_f = fast.step(actions)
        obs_e, rew_e, term_e, _, _info_e = exact.step(actions)
        assert not term_e.any()
        np.testing.assert_allclose(obs_f, obs_e, atol=2e-4)
        np.testing.assert_allclose(rew_f, rew_e, atol=2e-4)
    assert fast.unwrapped._state.x.dtype == np.float32 and info_f["distance"].dtype == np.float32
    with pytest.raises(ValueError, match="dtype"):
        DWRPointStabilizationVectorEnv(num_envs=2, dtype="float16")


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_an_autoreset_episode_starts_as_a_reset_at_its_start_pose_does(dtype: str) -> None:
    # T_con = 1 s and dt = 0.1 s: every episode ends within 15 steps, so most robots restart in 40 steps.
    kwargs = {"num_envs": 16, "dtype": dtype, "T_con": 1.0, "dt": 0.1}
    envs, fresh = gym.make_vec(ENV_ID, **kwargs), gym.make_vec(ENV_ID, **kwargs)
    envs.reset(seed=3)
    fresh.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (16, 2)).astype(np.float32)
    restarted = 0
    for _ in range(40):
        ended = envs.unwrapped._needs_reset.copy()  # the robots whose new episodes this step starts
        obs, rewards, _, _, info = envs.step(actions)
        if not ended.any():
            continue
        restarted += int(ended.sum())
        expected, expected_info = fresh.reset(options={"start": info["pose"], "reset_mask": ended})
        # the features of the pose match exactly; the last two are computed from the unrounded start in float32
        np.testing.assert_array_equal(obs[ended, :8], expected[ended, :8])
        np.testing.assert_allclose(obs[ended, 8:], expected[ended, 8:], rtol=0, atol=0 if dtype == "float64" else 1e-6)
        for key in ("distance", "orientation_error", "energy", "time", "T_con"):
            np.testing.assert_array_equal(info[key][ended], expected_info[key][ended])
        assert not rewards[ended].any()
    assert restarted >= 16


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_fresh_state_is_n_robots_at_the_goal_in_its_dtype_with_integer_counters(dtype: type) -> None:
    state = core.TaskState.zeros(3, dtype)
    for name in ("step_count", "prescribed_steps", "max_steps"):
        value = getattr(state, name)
        assert value.dtype == np.int64 and value.shape == (3,) and not value.any(), name
    for name in ("x", "y", "psi", "goal_x", "goal_y", "goal_psi", "energy", "initial_distance",
                 "initial_orientation_error", "lyapunov", "goal_sin", "T_con"):  # fmt: skip
        value = getattr(state, name)
        assert value.dtype == dtype and value.shape == (3,) and not value.any(), name
    np.testing.assert_array_equal(state.goal_cos, np.ones(3, dtype))  # the goal heading 0: cos 1, sin 0
    np.testing.assert_array_equal(np.array(state.world_pose()), np.zeros((3, 3)))


def test_a_robot_on_its_goal_observes_the_azimuth_as_1_0_without_warnings() -> None:
    """At d = 0, eq. (3)'s (cos, sin) of the azimuth are 0 / 0; the observation holds (1, 0) there."""
    envs = gym.make_vec(ENV_ID, num_envs=3)
    starts = np.array([[0.5, 0.5, 0.0], [1.0, 0.0, 0.3], [0.2, -0.1, 0.0]])
    goals = np.array([[0.5, 0.5, 0.0], [0.0, 0.0, 0.0], [0.2, -0.1, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        obs, _ = envs.reset(seed=0, options={"start": starts, "goal": goals})
    np.testing.assert_array_equal(obs[[0, 2], 0], 0.0)
    np.testing.assert_array_equal(obs[[0, 2], 1:3], [[1.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(obs[1, 1:3], [-1.0, 0.0], atol=1e-7)  # the goal lies behind robot 1


def test_new_states_keep_integer_counters() -> None:
    params = dwr_gym.EnvParams()
    state = core.new_state((np.array([1.0, 2.0]), np.zeros(2), np.zeros(2)), (np.zeros(2),) * 3, params,
                           T_con=np.array([10.0, 20.0]))  # fmt: skip
    for name in ("step_count", "prescribed_steps", "max_steps"):
        assert getattr(state, name).dtype == np.int64, name
    np.testing.assert_array_equal(state.prescribed_steps, [200, 400])
    np.testing.assert_array_equal(state.max_steps, [300, 600])


@pytest.mark.parametrize("goal", [(0.8, 0.0, 0.0), (0.0, -0.5, 0.0), (0.0, 0.0, 1.2)])
def test_the_pose_in_the_info_is_the_world_pose_whatever_the_goal(goal: tuple[float, float, float]) -> None:
    """info["pose"] is the robot's pose in the world frame, also for a goal off the origin along one axis only."""
    env = DWRPointStabilizationVectorEnv(num_envs=2)
    starts = np.array([[0.3, 0.2, 0.1], [-0.4, 0.5, -2.0]])
    _, info = env.reset(seed=0, options={"start": starts, "goal": np.tile(goal, (2, 1))})
    np.testing.assert_allclose(info["pose"], starts, atol=1e-12)


def test_float32_mode_ends_an_episode_at_the_step_float64_counts() -> None:
    """An episode's step counts come from its float64 T_con, as EnvParams counts them, whatever the state's dtype: a
    T_con of 26.400000537472387 s is truncated at step ceil(1.5 T_con / dt) = 793 in float32 mode too (its float32
    rounding would give 792)."""
    T_con = 26.400000537472387
    for dtype in ("float64", "float32"):
        envs = gym.make_vec(ENV_ID, num_envs=1, dtype=dtype, T_con=T_con, T_con_range=None)
        envs.reset(seed=0)
        steps, ended = 0, False
        while not ended and steps < 800:
            _, _, terminated, truncated, _ = envs.step(np.zeros((1, 2), np.float32))  # standing still: no arrival
            steps, ended = steps + 1, bool(terminated[0] or truncated[0])
        assert (steps, bool(truncated[0])) == (793, True), dtype
        envs.close()


def test_the_world_pose_of_a_state_is_a_copy_unless_asked_otherwise() -> None:
    """TaskState.world_pose() returns copies: an autoreset that writes into the state's arrays in place leaves a pose
    taken before it as it was; copy=False may hand out the state's own arrays."""
    envs = gym.make_vec(ENV_ID, num_envs=2)
    envs.reset(seed=0)
    state = envs.unwrapped._state
    x, y, psi = state.world_pose()
    before = (x.copy(), y.copy(), psi.copy())
    state.x[:], state.y[:], state.psi[:] = 5.0, 5.0, 1.0
    for taken, kept in zip((x, y, psi), before, strict=True):
        np.testing.assert_array_equal(taken, kept)
    assert state.world_pose(copy=False)[0] is state.x
