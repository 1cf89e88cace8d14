"""dwr-gym with the standard wrappers and clients, unchanged: Gymnasium's wrappers (single and vector),
stable-baselines3's video recorder and evaluation, CleanRL's PPO wrapper stack, copies after rendering."""

from __future__ import annotations

import copy
import pickle
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import wrappers
from gymnasium.vector import AutoresetMode, SyncVectorEnv
from gymnasium.wrappers import vector

import dwr_gym

ENV_ID = dwr_gym.ENV_ID
#: This module pins the behaviour of DWRPointStabilization-v0 (fixed T_con, the paper's reward), which Gymnasium
#: rightly calls out of date now that v1 exists; that warning is not what these tests test.
pytestmark = pytest.mark.filterwarnings("ignore:.*DWRPointStabilization-v0 is out of date:DeprecationWarning")
# Episodes of at most 30 steps with many arrivals, so that a few dozen steps see episodes end.
SHORT: dict[str, Any] = {"T_con": 2.0, "dt": 0.1, "goal_tolerance": 0.15, "start_distance": (0.2, 0.5)}
DWR_IDS = sorted(env_id for env_id in gym.registry if env_id.startswith("DWRPointStabilization-"))  # Box ids


def wrapper_chain(env: Any) -> list[type]:
    """The classes of ``env`` and everything it wraps, outermost first."""
    chain = [type(env)]
    while hasattr(env, "env"):
        env = env.env
        chain.append(type(env))
    return chain


# -- the horizon where Gymnasium looks for it ------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "steps"),
    [({}, 600), ({"T_con": 3.0, "dt": 0.1}, 45), ({"T_con": 1.0, "dt": 0.03, "horizon_factor": 1.25}, 42)],
)
def test_spec_max_episode_steps_is_the_step_the_env_truncates_at(kwargs: dict[str, Any], steps: int) -> None:
    env = gym.make(ENV_ID, **kwargs)
    assert env.spec is not None and env.spec.max_episode_steps == steps
    assert env.unwrapped.spec is not None and env.unwrapped.spec.max_episode_steps == steps
    env.reset(seed=0, options={"start": (1.0, 0.0, 0.0)})  # standing still 1 m away: only truncation ends it
    count, truncated = 0, False
    while not truncated:
        _, _, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        count += 1
        assert not terminated
    assert count == steps


@pytest.mark.parametrize("env_id", DWR_IDS)
def test_time_aware_observation_works_on_every_registered_id(env_id: str) -> None:
    env = wrappers.TimeAwareObservation(gym.make(env_id, T_con=3.0, T_con_range=None, dt=0.1))
    held = env.unwrapped.params.hold_to_T_con  # v2 ends at T_con (terminated), the others truncate at 1.5 T_con
    steps = 30 if held else 45
    assert env.observation_space.shape == (11,) and env.observation_space.high[-1] == steps
    obs, _ = env.reset(seed=0, options={"start": (1.0, 0.0, 0.0)})
    assert obs[-1] == 0
    for step in range(1, steps + 1):
        obs, _, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        assert obs[-1] == step and (terminated if held else truncated) == (step == steps)
        assert env.observation_space.contains(obs)


@pytest.mark.parametrize("kwargs", [{}, SHORT], ids=["default", "short"])
def test_a_time_limit_at_the_spec_horizon_changes_nothing(kwargs: dict[str, Any]) -> None:
    """gym.make(env.spec) adds TimeLimit(spec.max_episode_steps); it truncates at the very step the env
    already does, so DWRPointStabilization-v0 returns exactly what it returned before the spec said so."""
    plain = gym.make(ENV_ID, **kwargs)
    limited = gym.make(plain.spec)  # type: ignore[arg-type]
    assert wrappers.TimeLimit in wrapper_chain(limited) and wrappers.TimeLimit not in wrapper_chain(plain)
    rng = np.random.default_rng(0)
    results = [env.reset(seed=3) for env in (plain, limited)]
    np.testing.assert_array_equal(results[0][0], results[1][0])
    truncations = 0
    for _ in range(1300):
        action = (0.05 * rng.uniform(-1.0, 1.0, 2)).astype(np.float32)  # slow: most episodes run to the horizon
        (obs_a, rew_a, term_a, trunc_a, info_a), (obs_b, rew_b, term_b, trunc_b, info_b) = (
            plain.step(action), limited.step(action))  # fmt: skip
        np.testing.assert_array_equal(obs_a, obs_b)
        assert (rew_a, term_a, trunc_a, info_a["distance"]) == (rew_b, term_b, trunc_b, info_b["distance"])
        if term_a or trunc_a:
            truncations += int(trunc_a)
            np.testing.assert_array_equal(plain.reset()[0], limited.reset()[0])
    assert truncations >= 2


# -- every Gymnasium wrapper that applies to a Box env ----------------------------------------------

Factory = Callable[[Any, Path], Any]
#: Each of Gymnasium's single-env wrappers that applies to a Box env, as it is used on this one.
SINGLE_WRAPPERS: dict[str, Factory] = {
    "AddRenderObservation": lambda env, _: wrappers.AddRenderObservation(env),
    "Autoreset": lambda env, _: wrappers.Autoreset(env),
    "ClipAction": lambda env, _: wrappers.ClipAction(env),
    "ClipReward": lambda env, _: wrappers.ClipReward(env, -1.0, 1.0),
    "DelayObservation": lambda env, _: wrappers.DelayObservation(env, 2),
    "DiscretizeAction": lambda env, _: wrappers.DiscretizeAction(env, 3),
    "DiscretizeObservation": lambda env, _: wrappers.DiscretizeObservation(env, 5),
    "DtypeObservation": lambda env, _: wrappers.DtypeObservation(env, np.float64),
    "FlattenObservation": lambda env, _: wrappers.FlattenObservation(env),
    "FrameStackObservation": lambda env, _: wrappers.FrameStackObservation(env, 4),
    "HumanRendering": lambda env, _: wrappers.HumanRendering(env),
    "MaxAndSkipObservation": lambda env, _: wrappers.MaxAndSkipObservation(env, skip=2),
    "NormalizeObservation": lambda env, _: wrappers.NormalizeObservation(env),
    "NormalizeReward": lambda env, _: wrappers.NormalizeReward(env),
    "OrderEnforcing": lambda env, _: wrappers.OrderEnforcing(env),
    "PassiveEnvChecker": lambda env, _: wrappers.PassiveEnvChecker(env),
    "RecordEpisodeStatistics": lambda env, _: wrappers.RecordEpisodeStatistics(env),
    "RecordVideo": lambda env, folder: wrappers.RecordVideo(
        env, str(folder / "videos"), episode_trigger=lambda e: e == 0
    ),
    "RenderCollection": lambda env, _: wrappers.RenderCollection(env),
    "RepeatAction": lambda env, _: wrappers.RepeatAction(env, 2),
    "RescaleAction": lambda env, _: wrappers.RescaleAction(env, np.float32(-2.0), np.float32(2.0)),
    "RescaleObservation": lambda env, _: wrappers.RescaleObservation(env, np.float32(-1.0), np.float32(1.0)),
    "ReshapeObservation": lambda env, _: wrappers.ReshapeObservation(env, (2, 5)),
    "StickyAction": lambda env, _: wrappers.StickyAction(env, 0.25),
    "TimeAwareObservation": lambda env, _: wrappers.TimeAwareObservation(env),
    "TimeLimit": lambda env, _: wrappers.TimeLimit(env, 20),
    "TransformAction": lambda env, _: wrappers.TransformAction(env, lambda a: 0.5 * a, env.action_space),
    "TransformObservation": lambda env, _: wrappers.TransformObservation(
        env, lambda o: np.clip(o, -10.0, 10.0), env.observation_space
    ),
    "TransformReward": lambda env, _: wrappers.TransformReward(env, lambda r: 0.1 * r),
}
#: Gymnasium's vector wrappers that apply to a Box vector env.
VECTOR_WRAPPERS: dict[str, Factory] = {
    "ClipAction": lambda envs, _: vector.ClipAction(envs),
    "ClipReward": lambda envs, _: vector.ClipReward(envs, -1.0, 1.0),
    "DictInfoToList": lambda envs, _: vector.DictInfoToList(envs),
    "DtypeObservation": lambda envs, _: vector.DtypeObservation(envs, np.float64),
    "FlattenObservation": lambda envs, _: vector.FlattenObservation(envs),
    "HumanRendering": lambda envs, _: vector.HumanRendering(envs),
    "NormalizeObservation": lambda envs, _: vector.NormalizeObservation(envs),
    "NormalizeReward": lambda envs, _: vector.NormalizeReward(envs),
    "RecordEpisodeStatistics": lambda envs, _: vector.RecordEpisodeStatistics(envs),
    "RecordVideo": lambda envs, folder: vector.RecordVideo(
        envs, str(folder / "videos"), step_trigger=lambda s: s == 0, video_length=10
    ),
    "RescaleAction": lambda envs, _: vector.RescaleAction(envs, np.float32(-2.0), np.float32(2.0)),
    "RescaleObservation": lambda envs, _: vector.RescaleObservation(envs, np.float32(-1.0), np.float32(1.0)),
    "ReshapeObservation": lambda envs, _: vector.ReshapeObservation(envs, (2, 5)),
    "TransformAction": lambda envs, _: vector.TransformAction(envs, lambda a: 0.5 * a),
    "TransformObservation": lambda envs, _: vector.TransformObservation(envs, lambda o: np.clip(o, -10.0, 10.0)),
    "TransformReward": lambda envs, _: vector.TransformReward(envs, lambda r: 0.1 * r),
    "VectorizeTransformAction": lambda envs, _: vector.VectorizeTransformAction(envs, wrappers.ClipAction),
    "VectorizeTransformObservation": lambda envs, _: vector.VectorizeTransformObservation(
        envs, wrappers.FlattenObservation
    ),
    "VectorizeTransformReward": lambda envs, _: vector.VectorizeTransformReward(
        envs, wrappers.ClipReward, min_reward=-1.0, max_reward=1.0
    ),
}
#: The rest, and why they do not apply.
NOT_APPLICABLE = {
    "AddWhiteNoise": "image observations",
    "ArrayConversion": "needs array-api-compat, not a dependency",
    "AtariPreprocessing": "Atari",
    "FilterObservation": "Dict and Tuple observations",
    "GrayscaleObservation": "image observations",
    "JaxToNumpy": "jax",
    "JaxToTorch": "jax",
    "NumpyToTorch": "needs array-api-compat, not a dependency",
    "ObstructView": "image observations",
    "ResizeObservation": "image observations",
}
RENDERING = {"AddRenderObservation", "HumanRendering", "RecordVideo", "RenderCollection"}


def test_the_wrapper_tables_cover_every_gymnasium_wrapper() -> None:
    """A Gymnasium release with a new wrapper fails here until the tables say whether it applies."""
    assert set(wrappers.__all__) - {"vector"} == set(SINGLE_WRAPPERS) | set(NOT_APPLICABLE)
    assert set(vector.__all__) == set(VECTOR_WRAPPERS) | (set(NOT_APPLICABLE) & set(vector.__all__))


# DtypeObservation(float64): Gymnasium's Box compares our float32 bounds with float64's limits in float32 and
# numpy warns about that comparison, inside Gymnasium; it says nothing about our env.
@pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning:gymnasium.spaces.box")
@pytest.mark.parametrize("name", sorted(SINGLE_WRAPPERS))
def test_gymnasium_wrapper_on_the_single_env(name: str, tmp_path: Path) -> None:
    env = SINGLE_WRAPPERS[name](gym.make(ENV_ID, render_mode="rgb_array" if name in RENDERING else None, **SHORT),
                                tmp_path)  # fmt: skip
    env.reset(seed=0)
    env.action_space.seed(0)
    ends = 0
    for _ in range(40):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
        assert np.isfinite(reward)
        if terminated or truncated:
            ends += 1
            env.reset()
    assert ends >= 1
    env.close()
    if name == "RecordVideo":
        assert list((tmp_path / "videos").glob("*.mp4"))


# DtypeObservation(float64): Gymnasium's Box compares our float32 bounds with float64's limits in float32 and
# numpy warns about that comparison, inside Gymnasium; it says nothing about our env.
@pytest.mark.filterwarnings("ignore:overflow encountered in cast:RuntimeWarning:gymnasium.spaces.box")
@pytest.mark.parametrize("name", sorted(VECTOR_WRAPPERS))
def test_gymnasium_vector_wrapper_on_make_vec(name: str, tmp_path: Path) -> None:
    """On the native vector env with its default autoreset mode."""
    envs = gym.make_vec(ENV_ID, num_envs=3, render_mode="rgb_array" if name in RENDERING else None, **SHORT)
    wrapped = VECTOR_WRAPPERS[name](envs, tmp_path)
    wrapped.reset(seed=0)
    wrapped.action_space.seed(0)
    ends = 0
    for _ in range(40):
        obs, rewards, terminated, truncated, _ = wrapped.step(wrapped.action_space.sample())
        assert wrapped.observation_space.contains(obs)
        assert np.all(np.isfinite(rewards)) and rewards.shape == (3,)
        ends += int(np.sum(terminated | truncated))
    assert ends >= 3
    wrapped.close()
    if name == "RecordVideo":
        assert list((tmp_path / "videos").glob("*.mp4"))


# -- CleanRL's PPO (continuous) -----------------------------------------------------------------------


def cleanrl_ppo_continuous_stack(env: gym.Env[Any, Any], gamma: float) -> gym.Env[Any, Any]:
    """The single-env wrappers of CleanRL's ppo_continuous_action.py, in its order."""
    env = wrappers.FlattenObservation(env)
    env = wrappers.RecordEpisodeStatistics(env)
    env = wrappers.ClipAction(env)
    env = wrappers.NormalizeObservation(env)
    env = wrappers.TransformObservation(env, lambda obs: np.clip(obs, -10, 10), None)
    env = wrappers.NormalizeReward(env, gamma=gamma)
    return wrappers.TransformReward(env, lambda reward: np.clip(reward, -10, 10))


def cleanrl_ppo_continuous_vector_stack(envs: Any, gamma: float) -> Any:
    """The same stack of Gymnasium's vector wrappers, for the native vector env."""
    envs = vector.FlattenObservation(envs)
    envs = vector.RecordEpisodeStatistics(envs)
    envs = vector.ClipAction(envs)
    envs = vector.NormalizeObservation(envs)
    envs = vector.TransformObservation(envs, lambda obs: np.clip(obs, -10, 10))
    envs = vector.NormalizeReward(envs, gamma=gamma)
    return vector.TransformReward(envs, lambda reward: np.clip(reward, -10, 10))


def test_cleanrl_ppo_continuous_stack_over_sync_and_native_vector_envs() -> None:
    """CleanRL's env id form, wrappers and episode logging; the first episode of each robot has the same
    return through SyncVectorEnv (CleanRL's SAME_STEP) and the native vector env (NEXT_STEP)."""
    n, env_id = 4, f"dwr_gym:{ENV_ID}"
    sync = SyncVectorEnv([lambda: cleanrl_ppo_continuous_stack(gym.make(env_id, **SHORT), 0.99) for _ in range(n)],
                         autoreset_mode=AutoresetMode.SAME_STEP)  # fmt: skip
    native = cleanrl_ppo_continuous_vector_stack(gym.make_vec(env_id, num_envs=n, **SHORT), 0.99)
    sync.reset(seed=1)
    native.reset(seed=1)
    returns: dict[str, list[list[float]]] = {"sync": [[] for _ in range(n)], "native": [[] for _ in range(n)]}
    rng = np.random.default_rng(0)
    for _ in range(80):
        actions = rng.uniform(-1.5, 1.5, (n, 2)).astype(np.float32)  # out of range: ClipAction has work to do
        for name, envs in (("sync", sync), ("native", native)):
            obs, rewards, _, _, infos = envs.step(actions)
            assert obs.shape == (n, 10) and np.all(np.abs(obs) <= 10) and np.all(np.abs(rewards) <= 10)
            episodes = infos["final_info"] if name == "sync" and "final_info" in infos else infos  # as CleanRL reads
            for i in np.flatnonzero(episodes.get("_episode", np.zeros(n, dtype=bool))):
                returns[name][i].append(float(episodes["episode"]["r"][i]))
    assert all(returns["sync"]) and all(returns["native"])
    np.testing.assert_allclose([r[0] for r in returns["native"]], [r[0] for r in returns["sync"]], rtol=1e-6)


# -- stable-baselines3: video, Monitor semantics -------------------------------------------------------


def test_sb3_adapter_renders_every_robot_and_vec_video_recorder_records(tmp_path: Path) -> None:
    from stable_baselines3.common.vec_env import VecVideoRecorder

    from dwr_gym.sb3 import make_sb3_vec_env

    venv = make_sb3_vec_env(num_envs=4, seed=0, render_mode="rgb_array", **SHORT)
    venv.reset()
    frames = venv.get_images()
    assert len(frames) == 4 and all(f is not None and f.shape == (480, 480, 3) for f in frames)
    assert venv.render().shape == (960, 960, 3)  # tiled 2 x 2
    recorder = VecVideoRecorder(venv, str(tmp_path), record_video_trigger=lambda step: step == 0, video_length=5)
    recorder.reset()
    for _ in range(8):
        recorder.step(np.full((4, 2), 0.5, dtype=np.float32))
    recorder.close()
    videos = list(tmp_path.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 0


def test_evaluate_policy_reports_true_returns_without_a_monitor_warning() -> None:
    """Behind VecNormalize the rewards SB3's loop sees are scaled; the Monitor statistics are the env's own."""
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.vec_env import VecNormalize

    from baselines import ExpertPolicy, PTCController
    from dwr_gym.sb3 import make_sb3_vec_env

    venv = VecNormalize(make_sb3_vec_env(num_envs=4, seed=5, **SHORT), norm_obs=False, norm_reward=True)
    expert = ExpertPolicy(PTCController(), u_max=0.5, omega_max=2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        returns, lengths = evaluate_policy(expert, venv, n_eval_episodes=4, return_episode_rewards=True)  # type: ignore[arg-type]
    expected = []
    for i in range(4):  # sub-env i is the single env seeded with 5 + i
        env = gym.make(ENV_ID, **SHORT)
        obs, _ = env.reset(seed=5 + i)
        total, steps, done = 0.0, 0, False
        while not done:
            obs, reward, terminated, truncated, _ = env.step(expert.predict(obs)[0])
            total, steps, done = total + float(reward), steps + 1, terminated or truncated
        expected.append((round(total, 6), steps))
    got = sorted(zip(returns, lengths, strict=True))
    expected.sort()
    assert [length for _, length in got] == [length for _, length in expected]
    np.testing.assert_allclose([r for r, _ in got], [r for r, _ in expected], atol=1e-5)


def test_dwr_gym_train_env_logs_episode_statistics_without_vec_monitor(tmp_path: Path) -> None:
    """What makes SB3 log rollout/ep_rew_mean, ep_len_mean and success_rate during `dwr-gym train`."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import VecMonitor
    from stable_baselines3.common.vec_env.base_vec_env import VecEnvWrapper

    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams
    from train.learning.training_env import make_training_env

    config = TrainConfig(
        env_id="DWRPointStabilization-v1", residual=True, num_envs=4, run_dir=str(tmp_path), env_kwargs=dict(SHORT)
    )  # (v1: its short episodes end on arrival, within the 128 steps)
    resolve_hyperparams(config, set())
    venv = make_training_env(config)
    assert venv.env_is_wrapped(Monitor) == [True] * 4
    layer = venv
    while isinstance(layer, VecEnvWrapper):
        assert not isinstance(layer, VecMonitor)  # no second set of statistics, no "overwritten" warning
        layer = layer.venv
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=64, seed=0)
    model.learn(total_timesteps=128)
    assert len(model.ep_info_buffer) > 0 and len(model.ep_success_buffer) == len(model.ep_info_buffer)
    assert all(set(e) == {"r", "l", "t"} and 1 <= e["l"] <= 30 for e in model.ep_info_buffer)


# -- copies after rendering ------------------------------------------------------------------------------


def make_rendered(kind: str) -> Any:
    """An env of ``kind`` that has rendered a frame."""
    if kind == "single":
        env: Any = gym.make(ENV_ID, render_mode="rgb_array", **SHORT)
        env.reset(seed=0)
    elif kind == "vector":
        env = gym.make_vec(ENV_ID, num_envs=2, render_mode="rgb_array", **SHORT)
        env.reset(seed=0)
    else:
        from dwr_gym.sb3 import make_sb3_vec_env

        env = make_sb3_vec_env(num_envs=2, seed=0, render_mode="rgb_array", **SHORT)
        env.reset()
    env.render()
    return env


@pytest.mark.parametrize("kind", ["single", "vector", "sb3"])
def test_envs_stay_deep_copyable_and_picklable_after_render(kind: str) -> None:
    env = make_rendered(kind)
    action = np.full((2,) if kind == "single" else (2, 2), 0.5, dtype=np.float32)
    for clone in (copy.deepcopy(env), pickle.loads(pickle.dumps(env))):
        np.testing.assert_array_equal(np.asarray(clone.render()), np.asarray(env.render()))
        twin = copy.deepcopy(env)
        np.testing.assert_array_equal(clone.step(action)[0], twin.step(action)[0])  # the same episode goes on
        np.testing.assert_array_equal(np.asarray(clone.render()), np.asarray(twin.render()))
