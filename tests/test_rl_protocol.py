"""The RL benchmark's numbers: the IQM and its bootstrap interval against hand computations, the curves'
band, the seed shipped, E/opt over the in-time episodes only, and each (entry, seed) in its own run on the
benchmark's fixed evaluation set."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from train.env_ids import TASK_ENV_ID, env_keywords
from train.evaluation.benchmark import EVAL_SEED, metrics_of
from train.evaluation.evaluate import evaluate_sets
from train.learning.benchmark import Entry, parse_entry, run_benchmark, train_config
from train.reporting.rl_benchmark import aggregate, best_seed, curve_band, iqm_interval

pytest.importorskip("rliable")


def width(interval: dict[str, Any]) -> float:
    return float(interval["high"] - interval["low"])


@pytest.mark.parametrize(
    ("values", "iqm"),
    [
        ([100.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3.5),  # 8 seeds: the middle four, 2..5; their mean 15.1
        ([0.0, 1.0, 2.0, 3.0, 100.0], 2.0),  # 5 seeds: scipy's trim_mean cuts int(1.25) = 1 each side
        ([-50.0, 0.9, 1.0, 1.1], 0.95),  # 4 seeds: the middle two
        ([7.0], 7.0),
    ],
)
def test_the_iqm_of_skewed_seeds_is_the_mean_of_the_middle_half(values: list[float], iqm: float) -> None:
    """An outlier seed moves the mean but not the IQM: worked out by hand on asymmetric data."""
    result = iqm_interval(values)
    assert result["iqm"] == pytest.approx(iqm) and result["n"] == len(values)
    assert result["low"] <= result["iqm"] <= result["high"]
    with_gaps = iqm_interval([*values, None, float("nan"), float("inf")])  # what is not a number is dropped
    assert with_gaps["iqm"] == pytest.approx(iqm) and with_gaps["n"] == len(values)


def test_the_bootstrap_resamples_all_seeds_so_its_interval_shrinks_like_one_over_root_n() -> None:
    """Each replicate resamples n seeds: the interval of the IQM narrows as 1 / sqrt(n) (four times the seeds, half
    the width) and lies well inside the seeds' spread, while an outlier among 16 seeds (it enters a replicate's
    middle half only if drawn 5 times of 16) barely reaches it."""
    base = np.linspace(0.0, 1.0, 12)
    few, many = iqm_interval(list(base)), iqm_interval(list(np.tile(base, 4)))
    assert 0.35 < width(many) / width(few) < 0.65, (few, many)
    assert width(many) < 0.3  # the seeds span 1.0; the IQM's standard error is ~0.07 at 48 seeds
    skewed = iqm_interval([*np.linspace(0.0, 1.0, 15), 1000.0])
    assert skewed["high"] < 1.0 and skewed["low"] > 0.0


def test_the_bands_of_the_curves_are_the_interval_of_the_seeds_at_each_point() -> None:
    """curve_band at each grid point is iqm_interval of the seeds' curves there (linearly interpolated), on a grid
    that ends at the shortest run."""
    rng = np.random.default_rng(3)
    curves = []
    for end in (10.0, 12.0, 15.0, 10.0, 11.0):
        a, b = rng.uniform(0, 1, 2)
        curves.append([{"env_steps": 0.0, "in_time": a}, {"env_steps": end, "in_time": a + (b - a)}])
    band = curve_band([*curves, []], "env_steps", "in_time")
    assert band["x"][0] == 0.0 and band["x"][-1] == 10.0 and len(band["x"]) > 2
    for k, x in enumerate(band["x"]):
        values = [c[0]["in_time"] + (c[1]["in_time"] - c[0]["in_time"]) * x / c[1]["env_steps"] for c in curves]
        expected = iqm_interval(values)
        for name in ("iqm", "low", "high"):
            assert band[name][k] == pytest.approx(expected[name], abs=1e-12), (name, x)
    assert curve_band([[], []], "env_steps", "in_time") == {"x": [], "iqm": [], "low": [], "high": []}


def result(entry: str, seed: int, in_time: float | None, ratio: float | None) -> dict[str, Any]:
    metrics = {"in_time": in_time, "energy_ratio": ratio, "final_heading": 0.1, "energy": 1.0}
    return {"entry": entry, "seed": seed, "sets": {"random": metrics}, "curve": [], "seconds": 1.0}


def test_the_seed_shipped_is_the_one_most_in_time_then_the_most_frugal() -> None:
    results = [result("a", 0, 0.90, 1.10),  # the lowest E/opt, but fewer in time
               result("a", 1, 0.95, 2.00), result("a", 2, 0.95, 1.50), result("a", 3, 0.95, None),
               result("a", 4, None, 1.0), result("b", 7, 0.5, 3.0)]  # fmt: skip
    assert best_seed(results, "a") == 2
    assert best_seed(results, "b") == 7
    assert best_seed([result("c", 5, 1.0, None), result("c", 6, 1.0, 1.2)], "c") == 6  # E/opt None is worst


def test_the_aggregate_is_per_entry_over_its_own_seeds() -> None:
    results = [result("a", 1, 0.2, 1.5), result("b", 0, 1.0, 1.2), result("a", 0, 0.4, 2.5), result("a", 2, 0.9, 9.0)]
    results[1]["learned_from"] = "demonstrations"
    summary = aggregate(results)
    assert list(summary) == ["a", "b"] and summary["a"]["seeds"] == [0, 1, 2]
    assert summary["b"]["learned_from"] == "demonstrations" and summary["a"]["learned_from"] == "reward"
    assert summary["a"]["per_seed"]["random"]["in_time"] == [0.4, 0.2, 0.9]  # in the order of the seeds
    assert summary["a"]["sets"]["random"]["in_time"]["iqm"] == pytest.approx(0.5)  # 3 seeds: int(0.75) = 0 cut
    assert summary["b"]["sets"]["random"]["energy_ratio"]["iqm"] == pytest.approx(1.2)


def test_e_over_opt_is_the_mean_over_the_episodes_in_time_only() -> None:
    """Three episodes with optima 1, 2, 4: one in time (E = 2), one that arrived late (E = 10) and one that never
    arrived (E = 40): E/opt is 2 / 1 = 2.0, from the first alone."""
    from dwr_gym.params import EnvParams
    from train.evaluation.rollout import RolloutResult

    n = 3
    result = RolloutResult(params=EnvParams(), T_con=np.full(n, 20.0), success=np.array([True, False, False]),
                           arrived=np.array([True, True, False]), arrival_time=np.array([10.0, 30.0, np.nan]),
                           final_distance=np.zeros(n), final_heading_error=np.zeros(n), peak_linear_velocity=np.zeros(n),
                           peak_angular_velocity=np.zeros(n), energy=np.array([2.0, 10.0, 40.0]), path_length=np.zeros(n),
                           command_rate_rms=np.zeros(n), velocity_rate_rms=np.zeros(n), episode_return=np.zeros(n),
                           left_arena=np.zeros(n, bool), optimal_energy=np.array([1.0, 2.0, 4.0]))  # fmt: skip
    summary = result.summary()
    assert summary["energy_ratio_mean"] == 2.0 and summary["energy_ratio_episodes"] == 1.0
    assert summary["success_rate"] == pytest.approx(1 / 3) and summary["arrival_rate"] == pytest.approx(2 / 3)
    assert metrics_of(summary)["energy_ratio"] == 2.0
    none_in_time = RolloutResult(**{**result.__dict__, "success": np.zeros(n, bool)})
    assert metrics_of(none_in_time.summary())["energy_ratio"] is None  # undefined, not NaN, in the JSON


def test_every_seed_of_an_entry_is_evaluated_on_the_benchmarks_fixed_set(tmp_path: Path) -> None:
    """The learning curves of all seeds are measured on the same starts (the benchmark's evaluation seed, which no
    training run uses), so they compare."""
    entry = parse_entry("ppo-rep2:action_repeat=2")
    budget = {"env_steps": 4096, "eval_freq": 1024, "eval_episodes": 7}
    configs = [train_config(entry, seed, tmp_path / f"s{seed}", budget) for seed in (0, 1, EVAL_SEED + 1)]
    assert {(c.eval_seed, c.eval_episodes) for c in configs} == {(EVAL_SEED, 7)}
    assert [c.seed for c in configs] == [0, 1, EVAL_SEED + 1]
    assert {(c.total_timesteps, c.eval_freq) for c in configs} == {(2048, 512)}  # env steps / the action repeat


TINY = "tiny:algo=ppo,num_envs=4,hyperparams={n_steps: 32, batch_size: 64}"


def test_two_seeds_of_one_entry_train_in_their_own_runs_and_their_curves_are_the_fixed_sets_scores(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two seeds of one entry: two run directories, two different networks; a curve's point is the score, on the
    benchmark's nominal set (its seed and size), of the policy it was measured on (best_model.zip, saved then)."""
    import train.learning.benchmark as benchmark
    from train.learning.agents import load_agent

    asked: list[dict[str, Any]] = []
    monkeypatch.setattr(benchmark, "evaluate_policy",
                        lambda policy, **kwargs: asked.append(kwargs) or {"random": {"in_time": 0.0}})  # fmt: skip
    n = 3
    results = run_benchmark([parse_entry(TINY)], [0, 1], tmp_path, {"env_steps": 128, "eval_freq": 128,
                                                                     "eval_episodes": n, "disturbed_episodes": 2,
                                                                     "optimum_episodes": 1})  # fmt: skip
    assert [(a["n"], a["n_disturbed"], a["n_optimum"]) for a in asked] == [(3, 2, 1)] * 2  # the budget's sizes
    assert [r["env_steps"] for r in results] == [128, 128]
    assert all(isinstance(r["seconds"], float) and r["seconds"] > 0 for r in results)
    run_dirs = [Path(r["config"]["run_dir"]) for r in results]
    assert run_dirs[0] != run_dirs[1] and all(d.parent == tmp_path / "runs" for d in run_dirs)
    for r, run_dir in zip(results, run_dirs, strict=True):
        assert yaml.safe_load((run_dir / "config.yaml").read_text())["config"]["seed"] == r["seed"]
        assert [row["env_steps"] for row in r["curve"]] == [0, 128]
        best = json.loads((run_dir / "run_state.json").read_text())["best"]["timesteps"]
        (point,) = [row for row in r["curve"] if row["env_steps"] == best]
        rows = evaluate_sets({"agent": load_agent(run_dir / "best_model.zip")[1]}, ["random"], n, EVAL_SEED,
                             env_keywords(TASK_ENV_ID))  # fmt: skip
        assert point["energy"] == pytest.approx(rows[0]["energy_mean"], rel=1e-6)
        assert point["final_heading"] == pytest.approx(rows[0]["final_heading_error_mean"], rel=1e-6)
    assert results[0]["curve"][0]["energy"] != results[1]["curve"][0]["energy"]  # two networks, not one
    saved = [json.loads((tmp_path / "results" / f"tiny-seed{s}.json").read_text()) for s in (0, 1)]
    assert [s["seed"] for s in saved] == [0, 1]


def test_an_interrupted_run_continues_and_its_seconds_count_the_time_before_the_interruption(tmp_path: Path) -> None:
    """A run whose run_state.json is not finished continues from its checkpoint, and its result's ``seconds`` are the
    training's wall time before the interruption and after it (not only the process that finished it)."""
    budget = {"env_steps": 128, "eval_freq": 128, "eval_episodes": 2, "disturbed_episodes": 1, "optimum_episodes": 1}
    (first,) = run_benchmark([parse_entry(TINY)], [0], tmp_path, budget)
    state_path = tmp_path / "runs" / "tiny-seed0" / "run_state.json"
    state = json.loads(state_path.read_text())
    state_path.write_text(json.dumps({**state, "finished": False, "wall_time": 1000.0}))
    (tmp_path / "results" / "tiny-seed0.json").unlink()
    (resumed,) = run_benchmark([parse_entry(TINY)], [0], tmp_path, budget)
    assert resumed["env_steps"] == first["env_steps"] == 128
    assert 1000.0 <= resumed["seconds"] < 1000.0 + 10 * max(first["seconds"], 60.0)  # (the rest may take < 0.05 s)
    assert json.loads(state_path.read_text())["finished"]


def test_a_users_entry_makes_each_seed_in_its_own_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """make(seed, run_dir) gets one directory per seed; a curve it writes there is that seed's result's curve."""
    import train.learning.benchmark as benchmark
    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller

    made = []

    def make(seed: int, run_dir: Path) -> ExpertPolicy:
        made.append((seed, run_dir))
        (run_dir / "evaluations.csv").write_text("timesteps,wall_time,success_rate,final_heading_error_mean,"
                                                 f"energy_mean\n{10 * seed},1.5,0.5,0.25,{seed}.0\n")  # fmt: skip
        return ExpertPolicy(make_controller("ptc"), 0.5, 2.0)

    asked: list[dict[str, Any]] = []
    monkeypatch.setattr(benchmark, "evaluate_policy",
                        lambda policy, **kwargs: asked.append(kwargs) or {"random": {"in_time": 1.0}})  # fmt: skip
    results = run_benchmark([Entry("mine", make=make)], [3, 4], tmp_path, {})
    assert [(a["n"], a["n_disturbed"], a["n_optimum"]) for a in asked] == [(1000, 200, 50)] * 2  # the defaults
    assert [r["env_steps"] for r in results] == [None, None]  # a user's entry reports no env steps
    assert [seed for seed, _ in made] == [3, 4] and made[0][1] != made[1][1]
    assert [r["curve"][0]["energy"] for r in results] == [3.0, 4.0]
    assert [r["curve"][0]["env_steps"] for r in results] == [30, 40]


def test_the_benchmarks_evaluation_measures_e_over_opt_on_its_first_episodes_and_the_rest_on_all() -> None:
    """The nominal set's in-time rate and energy are over its n episodes; E/opt over the set drawn with n_optimum
    (the same seed, so its first episodes); the disturbed sets are n_disturbed episodes, without E/opt unless every
    episode is measured against the optimum (n_optimum None)."""
    pytest.importorskip("casadi")
    from train.evaluation.benchmark import evaluate_policy

    kwargs = env_keywords(TASK_ENV_ID)

    def row(name: str, n: int, optimum: str = "none") -> dict[str, Any]:
        return metrics_of(evaluate_sets({"ptc": "ptc"}, [name], n, EVAL_SEED, kwargs, optimum=optimum)[0])

    sets = evaluate_policy("ptc", n=3, n_disturbed=2, n_optimum=1, sets=("random", "delay"))
    assert {k: v for k, v in sets["random"].items() if k != "energy_ratio"} == {
        k: v for k, v in row("random", 3).items() if k != "energy_ratio"}  # fmt: skip
    assert sets["random"]["energy_ratio"] == pytest.approx(row("random", 1, "pose")["energy_ratio"])
    assert sets["random"]["energy_ratio"] != row("random", 3)["energy"]  # (a ratio, not the energy)
    assert sets["delay"] == row("delay", 2) and sets["delay"]["energy_ratio"] is None
    every = evaluate_policy("ptc", n=1, n_disturbed=1, n_optimum=None, sets=("random", "noise"))
    assert every["random"] == row("random", 1, "pose") and every["noise"] == row("noise", 1, "pose")
    assert every["noise"]["in_time"] == 1.0 and every["noise"]["energy_ratio"] > 1.0  # PTC arrives there
    with pytest.raises(ValueError, match="n=0 and n_disturbed=2 are invalid"):
        evaluate_policy("ptc", n=0, n_disturbed=2)


def test_a_curve_with_an_action_repeat_counts_env_steps(tmp_path: Path) -> None:
    """evaluations.csv counts the agent's decisions; with an action repeat of K the curve's x is K times that."""
    from train.learning.benchmark import read_curve

    (tmp_path / "evaluations.csv").write_text("timesteps,wall_time,success_rate,final_heading_error_mean,energy_mean,"
                                              "return_mean\n0,1.5,0.25,0.5,3.0,-1\n100,9.0,0.75,0.125,2.0,-0.5\n")  # fmt: skip
    assert read_curve(tmp_path, 3) == [
        {"env_steps": 0, "wall_time": 1.5, "in_time": 0.25, "final_heading": 0.5, "energy": 3.0},
        {"env_steps": 300, "wall_time": 9.0, "in_time": 0.75, "final_heading": 0.125, "energy": 2.0},
    ]
    assert read_curve(tmp_path / "none") == []


def test_every_shipped_entry_resolves_to_a_valid_training_configuration(tmp_path: Path) -> None:
    """Each name of ENTRIES is a configuration dwr-gym train accepts: its algorithm, backend and expert exist."""
    from train.learning.benchmark import ENTRIES

    budget = {"env_steps": 1024, "eval_freq": 512, "eval_episodes": 2}
    for name, options in ENTRIES.items():
        config = train_config(parse_entry(name), 0, tmp_path / name, budget)
        assert {key: getattr(config, key) for key in options} == options, name
        assert config.run_dir == str(tmp_path / name) and config.eval_seed == EVAL_SEED


def test_no_seeds_nothing_finite_and_a_missing_rliable_are_said_plainly(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    assert iqm_interval([]) == {"iqm": None, "low": None, "high": None, "n": 0}
    assert iqm_interval([None, float("nan")]) == {"iqm": None, "low": None, "high": None, "n": 0}
    summary = aggregate([{**result("a", 0, 0.5, None), "env_steps": None}])
    assert summary["a"]["learned_from"] == "reward" and summary["a"]["env_steps"]["iqm"] is None
    assert summary["a"]["sets"]["random"]["energy_ratio"]["iqm"] is None
    assert set(summary["a"]["curves"]) == {"env_steps", "wall_time"}
    assert set(summary["a"]["curves"]["wall_time"]) == {"in_time", "energy", "final_heading"}
    monkeypatch.setitem(sys.modules, "rliable", None)
    with pytest.raises(
        ImportError, match=r'^the RL benchmark aggregates with rliable: pip install "dwr-gym\[benchmark\]"$'
    ):
        iqm_interval([1.0])


def test_the_learning_curves_figure_draws_each_entry_and_its_band(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("matplotlib")
    from matplotlib import image as mpimg
    from matplotlib.figure import Figure

    from train.reporting.rl_benchmark import plot_curves

    saved: list[Figure] = []
    real_savefig = Figure.savefig
    monkeypatch.setattr(
        Figure, "savefig", lambda fig, *args, **kwargs: saved.append(fig) or real_savefig(fig, *args, **kwargs)
    )

    curve = [{"env_steps": 0.0, "wall_time": 0.0, "in_time": 0.0, "energy": 9.0, "final_heading": 1.0},
             {"env_steps": 100.0, "wall_time": 5.0, "in_time": 0.5, "energy": 3.0, "final_heading": 0.5}]  # fmt: skip
    results = [{**result("a", s, 0.5, 1.2), "curve": curve} for s in (0, 1)] + [result("empty", 0, 0.1, None)]
    summary = aggregate(results)
    for x in ("env_steps", "wall_time"):  # both figures into one folder, as dwr-gym benchmark writes them
        path = tmp_path / "figures" / f"curves_{x}.png"
        plot_curves(summary, path, x)
        image = mpimg.imread(path)
        assert image.shape[:2] == (324, 900)  # 10 x 3.6 inches at 90 dpi: the docs' width
        assert len(np.unique(image.reshape(-1, image.shape[2]), axis=0)) > 20  # lines and a translucent band
        legend = saved[-1].axes[0].get_legend()
        assert [text.get_text() for text in legend.get_texts()] == ["a (2 seeds)"]  # which line is whose, from how many


def test_the_table_shows_every_entry_evaluated_on_the_set_asked_for() -> None:
    """An entry without the set (say, evaluated on the nominal set only) is left out of that set's table, not the
    entries after it."""
    from train.reporting.rl_benchmark import table

    disturbed = {**result("b", 0, 0.5, 1.5), "sets": {"delay": result("b", 0, 0.5, 1.5)["sets"]["random"]}}
    summary = aggregate([result("a", 0, 0.9, 1.2), disturbed, result("c", 0, 0.7, 1.4)])
    rows = table(summary, set_name="delay").splitlines()
    assert [row.split(" | ")[0] for row in rows[2:]] == ["| b"]
    rows = table(summary).splitlines()
    assert [row.split(" | ")[0] for row in rows[2:]] == ["| a", "| c"]
    metrics = result("x", 0, 1.0, 2.0)["sets"]["random"]
    references = {"pt-astolfi": {"delay": metrics}, "ptc": {"random": metrics}}  # the first without the set
    assert table(summary, references).splitlines()[-1].startswith("| ptc (controller) | - | - | - | 1.000 | 2.00 |")


def test_the_tables_show_each_entrys_env_and_a_dash_for_what_is_missing() -> None:
    """Each entry on its own env (a v2 agent is not shown as v1); a prescribed time an entry was not evaluated at, a
    law without an optimum there (E/opt None) and an entry recorded without its env steps (an earlier run's, kept
    from the docs) read '-', not a crash."""
    from train.reporting.rl_benchmark import per_T_con_table, table

    metrics = result("x", 0, 0.9, 1.2)["sets"]["random"]
    agent = {**result("v2-agent", 0, 0.9, 1.2), "env_id": "DWRPointStabilization-v2"}
    agent["sets"] = {"random": metrics, "T_con=10": metrics}
    summary = aggregate([agent])
    law = {"ptc": {"T_con=20": {**metrics, "energy_ratio": None}}}
    rows = [row.split(" | ") for row in per_T_con_table(summary, law).splitlines()[2:]]
    assert rows[0][:2] == ["| v2-agent", "v2"] and rows[0][2].startswith("0.90") and rows[0][3:] == ["-", "-", "- |"]
    assert rows[1] == ["| ptc (controller)", "v1", "-", "0.90, -", "-", "- |"]
    del summary["v2-agent"]["env_steps"]
    assert table(summary).splitlines()[2].split(" | ")[:3] == ["| v2-agent", "1", "-"]


def test_parallel_seeds_train_in_fresh_worker_processes_and_come_back_in_order(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """jobs > 1 trains the (entry, seed) runs in processes started by spawn (a forked process of torch's or JAX's
    threads can deadlock), and returns their results in the order of the entries, then the seeds."""
    import concurrent.futures

    import train.learning.benchmark as benchmark

    pools: list[tuple[int, str]] = []

    class InProcess:
        def __init__(self, workers: int, mp_context: Any) -> None:
            pools.append((workers, mp_context.get_start_method()))

        def __enter__(self) -> InProcess:
            return self

        def __exit__(self, *error: object) -> None:
            return None

        def submit(self, function: Any, *args: Any) -> concurrent.futures.Future:
            future: concurrent.futures.Future = concurrent.futures.Future()
            future.set_result(function(*args))
            return future

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", InProcess)
    monkeypatch.setattr(benchmark, "run_one", lambda entry, seed, out, budget: {"entry": entry.name, "seed": seed})
    results = run_benchmark([Entry("a"), Entry("b")], [3, 1], tmp_path, {}, jobs=2)
    assert pools == [(2, "spawn")]
    assert [(r["entry"], r["seed"]) for r in results] == [("a", 3), ("a", 1), ("b", 3), ("b", 1)]


def test_an_entrys_own_budget_and_a_repeats_share_of_the_evaluations_are_whole_numbers_kept(tmp_path: Path) -> None:
    """An entry's own total_timesteps beats its YAML's n_timesteps (1e6 for sac_tuned.yml) as it beats the benchmark's;
    with an action repeat of 3 the evaluations come every 2048 // 3 = 682 agent decisions, a whole number."""
    own = parse_entry("sac-own:algo=sac,hyperparams=train/hyperparams/sac_tuned.yml,total_timesteps=3000")
    assert train_config(own, 0, tmp_path / "own", {}).total_timesteps == 3000
    repeat = parse_entry("ppo-rep3:action_repeat=3")
    config = train_config(repeat, 0, tmp_path / "rep", {"env_steps": 6144, "eval_freq": 2048})
    assert (config.total_timesteps, config.eval_freq, config.checkpoint_freq) == (2048, 682, 682)
    assert all(type(v) is int for v in (config.eval_freq, config.checkpoint_freq))


def test_an_entrys_own_time_limit_beats_the_benchmarks(tmp_path: Path) -> None:
    """``--agents 'NAME:time_limit=S'`` stops that entry's runs after S seconds whatever the benchmark's --time-limit
    (a run of the v2's 30-minute measure trained on past it when the budget's None replaced the entry's 1800)."""
    own = parse_entry("ppo-30min:time_limit=1800")
    assert train_config(own, 0, tmp_path / "own", {}).time_limit == 1800
    assert train_config(own, 0, tmp_path / "both", {"time_limit": 60.0}).time_limit == 1800
    assert train_config(parse_entry("ppo"), 0, tmp_path / "budget", {"time_limit": 60.0}).time_limit == 60.0
    assert train_config(parse_entry("ppo"), 0, tmp_path / "none", {}).time_limit is None
