"""Minari datasets of dwr-gym: collection from the vector env, the round trip, the env spec, safety, the CLI."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym  # noqa: F401
from baselines.expert import ExpertPolicy
from baselines.registry import make_controller
from dwr_gym.disturbances import InputDelay, VelocityBias
from dwr_gym.randomization import DisturbanceDistribution
from dwr_gym.serialization import env_kwargs_from_json, env_kwargs_to_json
from train.datasets.collect import RandomPolicy, collect
from train.env_ids import env_keywords

minari = pytest.importorskip("minari")

from train.datasets.store import (  # noqa: E402  (after the skip: the module needs no minari, its tests do)
    DatasetError,
    episode_metadata,
    load_dataset,
    transitions,
    write_dataset,
)

V1 = "DWRPointStabilization-v1"


@pytest.fixture(autouse=True)
def datasets_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Every test writes its datasets in its own temporary Minari data path."""
    path = tmp_path / "minari"
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(path))
    return path


def ptc() -> ExpertPolicy:
    return ExpertPolicy(make_controller("ptc"), 0.5, 2.0)


def single_env_episode(seed: int, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``index``-th episode of PTC on a single v1 env reset with ``seed`` (then without a seed)."""
    env, policy = gym.make(V1), ptc()
    obs, _ = env.reset(seed=seed)
    for k in range(index + 1):
        if k:
            obs, _ = env.reset()
        observations, actions, rewards, done = [obs], [], [], False
        while not done:
            action, _ = policy.predict(obs)
            obs, reward, terminated, truncated, _ = env.step(action)
            observations.append(obs)
            actions.append(action)
            rewards.append(reward)
            done = terminated or truncated
    return np.array(observations), np.array(actions), np.array(rewards)


def test_collected_episodes_are_the_single_envs_episodes_robot_by_robot() -> None:
    # 10 episodes on 4 robots: episode k is robot k % 4's episode k // 4, robot i reset with seed 7 + i
    episodes = collect(ptc(), env_keywords(V1), 10, seed=7, num_envs=4)
    assert len(episodes.rewards) == 10
    for k in (0, 3, 6, 9):
        observations, actions, rewards = single_env_episode(7 + k % 4, k // 4)
        assert episodes.observations[k].shape == observations.shape  # the last observation included
        np.testing.assert_allclose(episodes.observations[k], observations, atol=1e-5)
        np.testing.assert_allclose(episodes.actions[k], actions, atol=1e-5)
        np.testing.assert_allclose(episodes.rewards[k], rewards, atol=1e-6)
        assert episodes.terminations[k][-1] or episodes.truncations[k][-1]
        assert not (episodes.terminations[k][:-1].any() or episodes.truncations[k][:-1].any())
        meta = episodes.metadata[k]
        assert meta["steps"] == len(rewards) and meta["return"] == pytest.approx(rewards.sum())
        assert meta["T_con"] == pytest.approx(observations[0, 7])  # the observation's T_con feature


def test_each_episodes_outcome_is_the_evaluations_outcome_of_the_same_start() -> None:
    """An episode's metadata (in time, arrived, arrival time, energy, final distance and heading error) is what the
    evaluation's rollout measures from the same start and T_con; short prescribed times make some episodes late."""
    from dwr_gym.params import EnvParams
    from train.evaluation.rollout import rollout

    kwargs = {**env_keywords(V1), "T_con_range": (3.0, 10.0)}
    episodes = collect(ptc(), kwargs, 12, seed=11, num_envs=5)
    meta = episodes.metadata
    starts = np.array([m["start"] for m in meta])
    T_con = np.array([m["T_con"] for m in meta])
    result = rollout(ptc(), EnvParams.from_kwargs(**kwargs), starts, np.zeros_like(starts), T_con=T_con,
                     env_kwargs=kwargs)  # fmt: skip
    assert [m["in_time"] for m in meta] == result.success.tolist()
    assert [m["arrived"] for m in meta] == result.arrived.tolist()
    assert 0 < sum(result.success) and sum(result.success) < sum(result.arrived)  # in time, and late too
    np.testing.assert_allclose([np.nan if m["arrival_time"] is None else m["arrival_time"] for m in meta],
                               result.arrival_time, rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose([m["energy"] for m in meta], result.energy, rtol=1e-5)
    np.testing.assert_allclose([m["final_distance"] for m in meta], result.final_distance, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose([m["heading_error"] for m in meta], result.final_heading_error, rtol=1e-5, atol=1e-7)
    assert [m["steps"] for m in meta] == [len(r) for r in episodes.rewards]


def test_which_episodes_are_kept_does_not_depend_on_the_batch() -> None:
    few = collect(RandomPolicy(0), env_keywords(V1), 3, seed=2, num_envs=3)
    more = collect(RandomPolicy(0), env_keywords(V1), 6, seed=2, num_envs=6)
    for k in range(3):  # robots 0-2 start from the same seeds; the actions differ (one generator), the starts not
        assert few.metadata[k]["start"] == more.metadata[k]["start"]
        assert few.metadata[k]["T_con"] == more.metadata[k]["T_con"]


def written(dataset_id: str = "dwr-gym/test-v0", episodes: int = 5, **kwargs: object) -> tuple[object, object]:
    env_kwargs = {**env_keywords(V1), **kwargs.pop("env_kwargs", {})}  # type: ignore[dict-item]
    data = collect(ptc(), env_kwargs, episodes, seed=1, num_envs=4)
    write_dataset(dataset_id, data, V1, env_kwargs, algorithm_name="ptc", description="test", ref_min_score=-100.0,
                  ref_max_score=12.0, **kwargs)  # type: ignore[arg-type]  # fmt: skip
    return data, load_dataset(dataset_id)


def test_loading_round_trips_the_same_arrays_and_metadata() -> None:
    from minari.namespace import list_local_namespaces

    data, dataset = written()
    assert dataset.total_episodes == 5 and dataset.total_steps == data.steps
    assert list_local_namespaces() == ["dwr-gym"]  # the id's namespace, made for it
    for k, episode in enumerate(dataset.iterate_episodes()):
        np.testing.assert_array_equal(episode.observations, data.observations[k])
        np.testing.assert_array_equal(episode.actions, data.actions[k])
        np.testing.assert_array_equal(episode.rewards, data.rewards[k])
        np.testing.assert_array_equal(episode.terminations, data.terminations[k])
        np.testing.assert_array_equal(episode.truncations, data.truncations[k])
    meta = episode_metadata(dataset)
    assert [m["start"] for m in meta] == [m["start"] for m in data.metadata]
    assert [m["energy"] for m in meta] == [m["energy"] for m in data.metadata]
    flat = transitions(dataset)
    assert flat["observations"].shape == (data.steps, 10) and flat["actions"].shape == (data.steps, 2)
    first = len(data.rewards[0])
    np.testing.assert_array_equal(flat["next_observations"][:first], data.observations[0][1:])


def test_the_normalised_score_is_one_at_the_optimum_and_zero_at_random() -> None:
    _, dataset = written()
    np.testing.assert_allclose(minari.get_normalized_score(dataset, np.array([12.0, -100.0])), [1.0, 0.0])


@pytest.mark.parametrize(
    "imperfection",
    [
        {"disturbances": [VelocityBias(linear=-0.02, angular=0.1), InputDelay(steps=4)]},
        {"disturbance_distribution": DisturbanceDistribution(probability=0.3, seed=4)},
        {"robot": "turtlebot3_burger", "observation_noise": 0.01},
    ],
)
def test_recover_environment_gives_back_the_env_with_its_disturbances(imperfection: dict) -> None:
    _, dataset = written(env_kwargs=imperfection)
    for env in (dataset.recover_environment(), dataset.recover_environment(eval_env=True)):
        original = gym.make(V1, **imperfection)
        assert env.unwrapped.params == original.unwrapped.params
        assert repr(env.unwrapped.perturbation) == repr(original.unwrapped.perturbation)
        obs, _ = env.reset(seed=3)
        expected, _ = original.reset(seed=3)
        np.testing.assert_array_equal(obs, expected)


def test_env_keywords_without_a_json_form_are_a_clear_error() -> None:
    with pytest.raises(ValueError, match=r"env keyword dt=.*no JSON form"):
        env_kwargs_to_json({"dt": object()})
    kwargs = {"disturbances": [VelocityBias(linear=0.1)], "disturbance_distribution": None, "T_con": 20.0}
    assert env_kwargs_from_json(env_kwargs_to_json(kwargs)) == {**kwargs, "disturbances": kwargs["disturbances"]}


def test_an_existing_id_is_refused_and_replaced_only_with_overwrite() -> None:
    written("dwr-gym/same-v0", episodes=2)
    with pytest.raises(DatasetError, match=r"exists.*--overwrite"):
        written("dwr-gym/same-v0", episodes=3)
    assert load_dataset("dwr-gym/same-v0").total_episodes == 2
    written("dwr-gym/same-v0", episodes=3, overwrite=True)
    assert load_dataset("dwr-gym/same-v0").total_episodes == 3


def test_an_interrupted_write_leaves_no_dataset_under_the_id(
    datasets_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from minari.dataset._storages.arrow_storage import ArrowStorage

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(ArrowStorage, "update_episode_metadata", interrupted)
    with pytest.raises(KeyboardInterrupt):
        written("dwr-gym/half-v0")
    assert not (datasets_path / "dwr-gym" / "half-v0").exists()
    assert [p.name for p in datasets_path.iterdir()] == []  # nor a staging directory
    monkeypatch.undo()
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(datasets_path))
    written("dwr-gym/old-v0", episodes=2)
    monkeypatch.setattr(ArrowStorage, "update_episode_metadata", interrupted)
    with pytest.raises(KeyboardInterrupt):
        written("dwr-gym/old-v0", episodes=3, overwrite=True)
    assert load_dataset("dwr-gym/old-v0").total_episodes == 2  # the old one is kept


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["dataset", "ptc-v0", "--policy", "ptc"], "ID 'ptc-v0' is invalid: expected Minari's form namespace/name-vN"),
        (["dataset", "dwr-gym/x-v0", "--policy", "pid"], "--policy 'pid' is invalid: expected any of ptc,"),
        (["dataset", "dwr-gym/x-v0"], "--policy is missing"),
        (["dataset", "dwr-gym/x-v0", "--policy", "ptc", "--scenarios", "paper-fig5"], "--scenarios 'paper-fig5'"),
        (["dataset", "dwr-gym/x-v0", "--policy", "ptc", "--env-kwargs", 'disturbances=[{"type": "Gust"}]'],
         "disturbances item {'type': 'Gust'} is invalid"),
        (["imitate", "--dataset", "dwr-gym/none-v0"], "--dataset 'dwr-gym/none-v0' is invalid: no such dataset"),
    ],
)  # fmt: skip
def test_bad_input_is_a_one_line_error(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    from train.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_minari_missing_is_a_one_line_error_naming_the_extra(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from train.cli import main

    monkeypatch.setitem(sys.modules, "minari", None)  # import minari raises ImportError
    assert main(["dataset", "dwr-gym/x-v0", "--policy", "ptc"]) == 2
    assert 'datasets need Minari: pip install "dwr-gym[minari]"' in capsys.readouterr().err


def test_the_command_writes_a_dataset_that_imitate_clones(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from train import cli
    from train.datasets import build

    pytest.importorskip("casadi")
    monkeypatch.setattr(build, "reference_scores", lambda *args, **kwargs: (-100.0, 12.0))  # the optimum's: slow
    argv = ["dataset", "dwr-gym/cli-v0", "--policy", "pt-astolfi", "--episodes", "6", "--num-envs", "4",
            "--no-optimum", "--no-progress", "--scenarios", "delay"]  # fmt: skip
    assert cli.main(argv) == 0
    dataset = load_dataset("dwr-gym/cli-v0")
    assert dataset.total_episodes == 6
    assert dataset.spec.env_spec.kwargs["disturbances"] == [{"type": "InputDelay", "steps": 4}]
    assert episode_metadata(dataset)[5]["disturbance"] == {"disturbances": [{"type": "InputDelay", "steps": 4}]}
    assert cli.main(argv) == 2  # the id exists now
    run = tmp_path / "bc"
    assert cli.main(["imitate", "--dataset", "dwr-gym/cli-v0", "--epochs", "1", "--eval-episodes", "2",
                     "--run-dir", str(run), "--no-progress"]) == 0  # fmt: skip
    assert (run / "model.zip").is_file()
    assert "steps of 6 episodes from dwr-gym/cli-v0" in capsys.readouterr().out


def test_the_reference_scores_are_random_actions_and_the_optimum_on_the_nominal_robot(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """ref_min_score is the mean return of random actions on the dataset's env, ref_max_score the optimum's on the
    same starts without the robot's noise (here PTC stands in for the CasADi plans); both cached, in that order."""
    from train.datasets import build

    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))  # solved here, not read from another test's cache
    monkeypatch.setattr(build, "controller_policy", lambda name, env_kwargs, seed=0: ptc())
    noisy = {**env_keywords(V1), "observation_noise": 0.05}
    nominal = env_keywords(V1)
    low, high = build.reference_scores(V1, noisy, episodes=3)
    random_returns = collect(RandomPolicy(build.REF_SEED), noisy, 3, seed=build.REF_SEED).returns()
    best_returns = collect(ptc(), nominal, 3, seed=build.REF_SEED).returns()
    assert low == pytest.approx(np.mean(random_returns)) and high == pytest.approx(np.mean(best_returns))
    assert low < high
    monkeypatch.setattr(build, "collect", None)  # the second call reads the cache
    assert build.reference_scores(V1, noisy, episodes=3) == (low, high)
    (cached,) = tmp_path.glob("dataset-reference-*.json")
    assert json.loads(cached.read_text())["ref_min_score"] == low


def test_a_built_dataset_normalises_returns_with_its_reference_scores(monkeypatch: pytest.MonkeyPatch) -> None:
    """``minari.get_normalized_score`` of the written dataset maps the random policy's mean return to 0 and the
    optimum's to 1, and gives the normalised score ``dwr-gym dataset`` reports."""
    from train.datasets import build

    monkeypatch.setattr(build, "reference_scores", lambda *args, **kwargs: (-100.0, 12.0))
    kwargs = {**env_keywords(V1), "observation_noise": 0.01}
    request = build.DatasetRequest("dwr-gym/refs-v0", "ptc", V1, kwargs, 3, seed=2, num_envs=3, optimum=False)
    summary = build.build_dataset(request, ptc())
    dataset = load_dataset("dwr-gym/refs-v0")
    assert {k: summary[k] for k in ("dataset_id", "policy", "env_id", "episodes", "episodes_without_optimum")} == {
        "dataset_id": "dwr-gym/refs-v0",
        "policy": "ptc",
        "env_id": V1,
        "episodes": 3.0,
        "episodes_without_optimum": 3,
    }
    assert Path(summary["path"]) == Path(os.environ["MINARI_DATASETS_PATH"]) / "dwr-gym" / "refs-v0"
    assert summary["collect_seconds"] > 0.0
    assert [m["policy"] for m in episode_metadata(dataset)] == ["ptc"] * 3
    assert [m["disturbance"] for m in episode_metadata(dataset)] == [{"observation_noise": 0.01}] * 3  # the robot
    metadata = dataset.storage.metadata
    assert (metadata["ref_min_score"], metadata["ref_max_score"]) == (-100.0, 12.0)
    assert (summary["ref_min_score"], summary["ref_max_score"]) == (-100.0, 12.0)
    np.testing.assert_allclose(minari.get_normalized_score(dataset, np.array([-100.0, 12.0])), [0.0, 1.0])
    expected = minari.get_normalized_score(dataset, np.array([summary["return_mean"]]))[0]
    assert summary["normalized_score"] == pytest.approx(expected) and 0.0 < expected < 1.5


def test_e_over_opt_of_a_dataset_is_over_its_episodes_in_time_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each episode's energy_ratio is its energy over its optimum where it arrived in time and has an optimum;
    None otherwise (late, or no optimum); the dataset's mean E/opt is over those alone."""
    from train.datasets import build
    from train.datasets.collect import Episodes

    optima, asked = np.array([1.0, 2.0, np.nan, 0.0]), []

    def optimal_energies(params: object, starts: np.ndarray, goals: np.ndarray, T_cons: np.ndarray, **kwargs: object):
        asked.append((params, starts, goals, T_cons))
        return optima, ["no plan"]

    monkeypatch.setattr(build, "optimal_energies", optimal_energies)
    episodes = Episodes(rewards=[np.ones(2)] * 4, metadata=[
        {"start": [0.0, 0.0, 0.0], "goal": [1.0, 0.0, 0.0], "T_con": 20.0, "energy": energy, "in_time": in_time,
         "heading_error": 0.1} for energy, in_time in ((3.0, True), (10.0, False), (4.0, True), (5.0, True))])  # fmt: skip
    assert build.add_optimum(episodes, {**env_keywords(V1), "u_max": 0.3}) == 1
    ((params, starts, goals, T_cons),) = asked  # each episode's own start, goal and T_con, the env's limits
    assert params.u_max == 0.3 and starts.shape == (4, 3) and goals.tolist() == [[1.0, 0.0, 0.0]] * 4
    assert T_cons.tolist() == [20.0] * 4
    assert [m["energy_ratio"] for m in episodes.metadata] == [3.0, None, None, None]
    assert [m["optimal_energy"] for m in episodes.metadata] == [1.0, 2.0, None, 0.0]
    assert build.statistics(episodes)["energy_ratio_mean"] == 3.0


@pytest.mark.parametrize("policy", ["random", "pt-astolfi", "object"])
def test_make_dataset_writes_the_episodes_of_a_controller_or_random_actions_named(
    policy: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``make_dataset`` with a name: the episodes of that controller, scaled to the env's own limits (a slower robot
    here), or of random actions drawn from the dataset's seed; the same as collecting them directly."""
    from baselines.registry import make_controller
    from train.datasets import build, make_dataset

    monkeypatch.setattr(build, "reference_scores", lambda *args, **kwargs: (-100.0, 12.0))
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "new" / "folders"))  # made as needed
    given = ExpertPolicy(make_controller("ptc"), 0.3, 2.0) if policy == "object" else policy  # or any predict()
    summary = make_dataset(f"dwr-gym/{policy}-v0", policy=given, episodes=3, env_kwargs={"u_max": 0.3}, seed=4,
                           num_envs=2, optimum=False)  # fmt: skip
    kwargs = {**env_keywords(V1), "u_max": 0.3}
    name = "ExpertPolicy" if policy == "object" else policy
    acting = (RandomPolicy(4) if policy == "random" else
              ExpertPolicy(make_controller("ptc" if policy == "object" else policy), 0.3, 2.0))  # fmt: skip
    expected = collect(acting, kwargs, 3, seed=4, num_envs=2)
    dataset = load_dataset(f"dwr-gym/{policy}-v0")
    assert summary["policy"] == name and dataset.storage.metadata["algorithm_name"] == name
    assert dataset.spec.env_spec.kwargs["u_max"] == 0.3
    for k, episode in enumerate(dataset.iterate_episodes()):
        np.testing.assert_array_equal(episode.actions, expected.actions[k])
    with pytest.raises(ValueError, match="env_id 'CartPole-v1' is invalid"):
        make_dataset("dwr-gym/x-v0", env_id="CartPole-v1")


def test_the_recorded_actions_are_the_ones_the_env_applied_within_the_action_space() -> None:
    """A policy asking for more than the robot's limits (a scaled agent, a controller past saturation) is clipped to
    [-1, 1] as the env clips it: the dataset holds the actions that drove its observations, inside the action space
    its spec declares, so a cloned policy learns commands the robot can run."""

    class Eager:
        def predict(self, observation: np.ndarray, **kwargs: object) -> tuple[np.ndarray, None]:
            n = np.asarray(observation).shape[0]
            return np.tile(np.array([[1.7, -2.5]], np.float32), (n, 1)), None

    episodes = collect(Eager(), {**env_keywords(V1), "T_con": 0.5}, 3, seed=5, num_envs=3)
    space = gym.make(V1).action_space
    for actions in episodes.actions:
        assert all(space.contains(action) for action in actions)
        np.testing.assert_array_equal(actions, np.tile([[1.0, -1.0]], (len(actions), 1)))


def test_each_episode_records_the_disturbance_its_robot_drew() -> None:
    """Under a DisturbanceDistribution every episode's metadata holds what was drawn for it: robot i's first episode
    (reset with seed + i) drew what a single env reset with that seed draws."""
    distribution = {"disturbance_distribution": DisturbanceDistribution(probability=1.0, seed=4)}
    kwargs = {**env_keywords(V1), "T_con": 0.5, **distribution}
    episodes = collect(RandomPolicy(0), kwargs, 3, seed=9, num_envs=3)
    for k, meta in enumerate(episodes.metadata):
        single = gym.make(V1, T_con=0.5, **distribution).unwrapped
        single.reset(seed=9 + k)
        drawn = {key: np.asarray(value[0]).tolist() for key, value in single.perturbation.episode().items()}
        assert meta["disturbance"] == drawn
    assert episodes.metadata[0]["disturbance"] != episodes.metadata[1]["disturbance"]


def test_collecting_with_progress_shows_a_bar_counting_the_episodes(capsys: pytest.CaptureFixture[str]) -> None:
    collect(RandomPolicy(0), {**env_keywords(V1), "T_con": 0.5}, 2, num_envs=2, progress=True,
            description="random: episodes")  # fmt: skip
    err = capsys.readouterr().err
    assert "random: episodes" in err and "/2" in err


def test_make_dataset_and_the_command_share_their_defaults(monkeypatch: pytest.MonkeyPatch) -> None:
    """``make_dataset(id, policy)`` collects what ``dwr-gym dataset ID --policy NAME`` collects: the same number of
    episodes, seed and batch of robots (which robot runs which episode) when neither is given them."""
    from train.cli import build_parser
    from train.datasets import build, make_dataset

    class CollectedError(Exception):
        pass

    asked: dict[str, object] = {}

    def spy(policy: object, env_kwargs: object, episodes: int, **kwargs: object) -> None:
        asked.update(episodes=episodes, **kwargs)
        raise CollectedError

    monkeypatch.setattr(build, "collect", spy)
    with pytest.raises(CollectedError):
        make_dataset("dwr-gym/x-v0", policy="random")
    args = build_parser().parse_args(["dataset", "dwr-gym/x-v0", "--policy", "random"])
    assert {name: asked[name] for name in ("episodes", "seed", "num_envs")} == {
        "episodes": args.episodes, "seed": args.seed, "num_envs": args.num_envs}  # fmt: skip
