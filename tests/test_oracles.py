"""Every measure the benchmark publishes against a second, naive computation (tests/oracles.py): each episode's in
time (v0, v1 and v2's rules), arrival, final distance and heading, energy, return and arena exit; v2's reward term by
term; each set's metrics as the benchmark's evaluation writes them, on the nominal set and at each T_con; the IQM
and its interval over seeds; the tables' cells. The sets are small and seeded, played by a scripted policy whose
episodes include the edge cases: a robot that reaches the goal and leaves, one that ends inside the tolerance but
off the goal, a late arrival and an exit from the arena."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests import oracles
from train.env_ids import env_keywords

V0, V1, V2 = "DWRPointStabilization-v0", "DWRPointStabilization-v1", "DWRPointStabilization-v2"
SEED = 11  # the sets' seed: chosen so that every edge case occurs in each (asserted below)


class Scripted:
    """A policy of the observation alone whose episodes take several courses, chosen by the start's distance (the
    observation's 9th feature): mode 0 drives to the goal and stops 8 mm short of it (inside the 1 cm tolerance,
    off the goal); mode 1 drives to the goal, stops there, and at half of T_con drives straight away at full speed
    (reaches the goal and leaves it; far enough to leave the arena when T_con is long); mode 2 drives to the goal and
    stays. ``speed`` (of the normalised action) makes long starts arrive late."""

    def __init__(self, speed: float = 0.3) -> None:
        self.speed = speed

    def predict(self, obs: Any, state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[np.ndarray, None]:  # fmt: skip
        o = np.asarray(obs, dtype=np.float64).reshape(-1, 10)
        d, fraction, start = o[:, 0], o[:, 6], o[:, 8]
        error = np.arctan2(o[:, 2], o[:, 1]) - np.arctan2(o[:, 4], o[:, 3])
        error = (error + np.pi) % (2 * np.pi) - np.pi
        mode = np.floor(start * 997.0) % 3
        ahead = np.cos(error) > 0.0
        u = np.where(ahead, np.minimum(self.speed, 20.0 * d) * np.cos(error), 0.0)  # at most half the way a step
        w = np.where(ahead, np.clip(3.0 * error, -1.0, 1.0), np.sign(error))
        stopped = d <= np.where(mode == 0, 0.008, 0.003)
        u, w = np.where(stopped, 0.0, u), np.where(stopped, 0.0, w)
        leave = (mode == 1) & (fraction > 0.5)
        u, w = np.where(leave, 1.0, u), np.where(leave, 0.0, w)
        return np.stack([u, w], axis=1).astype(np.float32), None


def pipeline_rollout(env_id: str, policy: Any, episodes: list[tuple[tuple[float, ...], float]], fixed: bool) -> Any:
    """The pipeline's batched rollout of a drawn set."""
    from dwr_gym.params import EnvParams
    from train.evaluation.rollout import rollout

    kwargs = env_keywords(env_id)
    if fixed:
        kwargs = {**kwargs, "T_con": episodes[0][1], "T_con_range": None}
    params = EnvParams.from_kwargs(**kwargs)
    starts = np.array([start for start, _ in episodes])
    T_cons = None if fixed or params.T_con_range is None else np.array([T for _, T in episodes])
    return rollout(policy, params, starts, np.zeros_like(starts), T_con=T_cons)


@pytest.mark.parametrize(("env_id", "T_con"), [(V0, None), (V1, None), (V2, None), (V1, 10.0), (V2, 10.0)])
def test_each_episodes_measures_are_the_oracles(env_id: str, T_con: float | None) -> None:
    """Per episode, the rollout's in time, arrival, final distance and heading, energy, return and arena exit are the
    oracle's from the env's own steps, and the env's summed cost is 1 exactly where the oracle is not in time; the
    sets hold the edge cases each rule must get right."""
    policy = oracles.Recorder(Scripted(0.2))
    episodes = oracles.draw_set(env_id, 12, SEED, T_con)
    result = pipeline_rollout(env_id, policy, episodes, fixed=T_con is not None)
    played = oracles.play_set(env_id, policy, 0, episodes, fixed=T_con is not None)
    oracles.assert_same(oracles.rollout_rows(env_id, played, result))
    measures = [oracles.measure(e) for e in played]
    for k, (e, m) in enumerate(zip(played, measures, strict=True)):
        assert e.steps[-1].energy_info == pytest.approx(m.energy, rel=1e-9)  # the env's own: the sum of u^2 + omega^2
        late = 0.0 if m.in_time else 1.0  # the deadline's violation, Safety-Gymnasium's info["cost"] summed
        assert m.cost == late, f"episode {k} ({env_id}, T_con {e.T_con}): the env's summed cost {m.cost}, oracle {late}"
    inside_off_goal = [m.in_time and 1e-3 < m.final_distance <= 0.01 for m in measures]
    assert any(inside_off_goal), "no episode ends inside the tolerance but off the goal"
    assert any(m.in_time for m in measures) and (env_id == V0 or not all(m.in_time for m in measures))
    if env_id == V2:
        assert any(m.reached_and_left for m in measures), "no v2 episode reaches the goal and leaves"
        if T_con is None:
            assert any(m.left_arena for m in measures), "no episode leaves the arena"
    if env_id == V1 and T_con is None:
        assert any(m.late_arrival for m in measures), "no late arrival"


@pytest.mark.parametrize("T_con", [None, 10.0])
def test_v2s_reward_is_its_definition_term_by_term(T_con: float | None) -> None:
    """Each step's v2 reward is the progress, the energy and, where the episode ends, the miss (inside the tolerance
    too), the heading, the arrival bonus at T_con and the arena's penalty: v2's definition, step by step."""
    episodes = oracles.draw_set(V2, 12, SEED, T_con)
    policy = oracles.Recorder(Scripted(0.2))
    pipeline_rollout(V2, policy, episodes, fixed=T_con is not None)
    played = oracles.play_set(V2, policy, 0, episodes, fixed=T_con is not None)
    rows = []
    for i, episode in enumerate(played):
        for k, (step, expected) in enumerate(zip(episode.steps, oracles.v2_rewards(episode), strict=True)):
            rows.append((f"v2 episode {i} step {k + 1}", "reward", expected, step.reward))
    oracles.assert_same(rows)
    ends = [oracles.measure(e) for e in played]
    assert any(m.in_time and m.final_distance > 1e-3 for m in ends)  # the miss inside the tolerance is paid


def oracle_sets(env_id: str, recorder: oracles.Recorder, n: int, seed: int, n_optimum: int,
                per_T_con: tuple[float, ...]) -> dict[str, dict[str, Any]]:  # fmt: skip
    """{set: the oracle's metrics} of the benchmark's nominal set (E/opt on the set drawn with ``n_optimum``
    episodes: the same starts first, their T_cons drawn after them) and per-T_con sets (``n`` each), against the
    stand-in pose optimum, from the actions of the recorder's rollouts (the nominal set, the disturbed sets' ``n_disturbed``
    each, the set of ``n_optimum`` when smaller than ``n``, then one per T_con)."""
    sizes = [len(r[0]) for r in recorder.rollouts]
    nominal = oracles.play_set(env_id, recorder, 0, oracles.draw_set(env_id, n, seed), fixed=False)
    sets = {"random": oracles.set_metrics(nominal, oracles.pose_optimum)}
    if n_optimum < n:
        rollout = sizes.index(n_optimum, 1)
        first = oracles.play_set(env_id, recorder, rollout, oracles.draw_set(env_id, n_optimum, seed), fixed=False)
        sets["random"]["energy_ratio"] = oracles.set_metrics(first, oracles.pose_optimum)["energy_ratio"]
    for index, T_con in enumerate(per_T_con):
        rollout = len(sizes) - len(per_T_con) + index
        played = oracles.play_set(env_id, recorder, rollout, oracles.draw_set(env_id, n, seed, T_con), fixed=True)
        sets[f"T_con={T_con:g}"] = oracles.set_metrics(played, oracles.pose_optimum)
    return sets


@pytest.mark.parametrize("env_id", [V1, V2])
def test_the_benchmarks_sets_are_the_oracles_on_the_nominal_set_and_each_T_con(
    env_id: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """What the benchmark's evaluation writes (each set's in time, E/opt against the pose optimum of each episode's own
    T_con, final heading, energy) is the oracle's, on the nominal set (E/opt on its first episodes) and at each T_con;
    and at T_con 10 s the numbers differ from the nominal set's."""
    from train.evaluation.benchmark import PER_T_CON, evaluate_policy

    oracles.use_stand_in_optimum(monkeypatch)
    policy = oracles.Recorder(Scripted())
    n, n_optimum = 8, 5
    got = evaluate_policy(policy, env_id, n=n, n_disturbed=1, seed=SEED, n_optimum=n_optimum, sets=("random",),
                          n_per_T_con=n)  # fmt: skip
    expected = oracle_sets(env_id, policy, n, SEED, n_optimum, PER_T_CON)
    assert set(got) == set(expected)
    oracles.assert_same([row for name in expected for row in oracles.metric_rows(f"{env_id} {name}", expected[name],
                                                                                 got[name])])  # fmt: skip
    short, nominal = expected["T_con=10"], expected["random"]
    assert short["in_time"] != nominal["in_time"] and short["energy_ratio"] != nominal["energy_ratio"]


def test_the_iqm_and_its_interval_are_the_oracles() -> None:
    """The IQM (the middle half's mean) and the 2.5-97.5 percentiles of the bootstrapped IQMs, over 1 to 9 seeds and
    with values the aggregate drops (None, NaN)."""
    from train.reporting.rl_benchmark import iqm_interval

    rng = np.random.default_rng(5)
    rows = []
    for n in range(1, 10):
        values: list[Any] = [*rng.lognormal(0.0, 1.0, n).tolist(), None, math.nan]
        got, expected = iqm_interval(values, reps=300), oracles.iqm_interval(values, reps=300)
        rows += [(f"{n} seeds", key, expected[key], got[key]) for key in ("iqm", "low", "high", "n")]
    oracles.assert_same(rows)


RECORDED: dict[int, oracles.Recorder] = {}


def scripted_entry(seed: int, run_dir: Path) -> oracles.Recorder:
    """A benchmark entry whose seeds differ (seed s drives at 0.25 + 0.1 s), its actions recorded."""
    RECORDED[seed] = oracles.Recorder(Scripted(0.25 + 0.1 * seed))
    return RECORDED[seed]


def test_the_results_json_aggregate_and_tables_are_the_oracles(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A benchmark of one entry over three seeds: each seed's result JSON holds the oracle's metrics of each set, the
    aggregate the oracle's IQM and interval of them, and the nominal set's and per-T_con tables those cells."""
    from train.evaluation.benchmark import EVAL_SEED, PER_T_CON
    from train.learning.benchmark import Entry, run_benchmark
    from train.reporting.rl_benchmark import aggregate, per_T_con_table, table

    pytest.importorskip("rliable")
    oracles.use_stand_in_optimum(monkeypatch)
    n, n_optimum, seeds = 5, 3, [0, 1, 2]
    budget = {"eval_episodes": n, "disturbed_episodes": 1, "optimum_episodes": n_optimum}
    run_benchmark([Entry("scripted", make=scripted_entry)], seeds, tmp_path, budget)
    expected = {s: oracle_sets(V1, RECORDED[s], n, EVAL_SEED, n_optimum, PER_T_CON) for s in seeds}
    results = [json.loads((tmp_path / "results" / f"scripted-seed{s}.json").read_text()) for s in seeds]
    rows = []
    for s, result in zip(seeds, results, strict=True):
        assert result["env_id"] == V1
        for name, metrics in expected[s].items():
            rows += oracles.metric_rows(f"seed {s} {name}", metrics, result["sets"][name])
    oracles.assert_same(rows)
    summary = aggregate(results)
    rows, cells = [], {}
    for name in expected[0]:
        for metric in ("in_time", "energy_ratio", "final_heading", "energy"):
            want = oracles.iqm_interval([expected[s][name][metric] for s in seeds])
            got = summary["scripted"]["sets"][name][metric]
            rows += [(f"IQM over seeds of {name}", f"{metric} {key}", want[key], got[key]) for key in want]
            cells[name, metric] = want
    oracles.assert_same(rows)
    assert cells["T_con=10", "in_time"]["iqm"] != cells["random", "in_time"]["iqm"]
    # the tables, cell by cell
    (line,) = table(summary).splitlines()[2:]
    digits = {"in_time": 3, "energy_ratio": 2, "final_heading": 2, "energy": 2}
    want_cells = [oracles.cell(cells["random", m], d) for m, d in digits.items()]
    oracles.assert_same([("nominal table", f"column {i}", w, g)
                         for i, (w, g) in enumerate(zip(want_cells, line.strip(" |").split(" | ")[4:], strict=True))])  # fmt: skip
    (line,) = per_T_con_table(summary).splitlines()[2:]
    got_cells = line.strip(" |").split(" | ")
    assert got_cells[:2] == ["scripted", "v1"]
    rows = []
    for T_con, got_cell in zip(PER_T_CON, got_cells[2:], strict=True):
        name = f"T_con={T_con:g}"
        want = f"{oracles.cell(cells[name, 'in_time'], 2)}, {oracles.cell(cells[name, 'energy_ratio'], 2)}"
        rows.append(("per-T_con table", name, want, got_cell))
    oracles.assert_same(rows)


def test_a_trained_entry_is_evaluated_on_its_own_env_id_and_its_json_holds_the_oracles_metrics(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An entry of ``dwr-gym train`` options on v2 (its training stood in for, its agent a recorded scripted policy):
    its result JSON says v2 and holds the oracle's metrics of v2's episodes on the nominal set and at each T_con."""
    import train.learning.agents as agents
    import train.learning.training as training
    from train.evaluation.benchmark import EVAL_SEED, PER_T_CON
    from train.learning.benchmark import parse_entry, run_benchmark

    oracles.use_stand_in_optimum(monkeypatch)
    recorder = oracles.Recorder(Scripted())
    monkeypatch.setattr(training, "train", lambda config, command=None: None)
    monkeypatch.setattr(agents, "load_agent", lambda path, part="whole": ("agent", recorder))
    n = 4
    budget = {"eval_episodes": n, "disturbed_episodes": 1, "optimum_episodes": n}
    run_benchmark([parse_entry(f"held:algo=ppo,env_id={V2}")], [0], tmp_path, budget)
    result = json.loads((tmp_path / "results" / "held-seed0.json").read_text())
    assert result["env_id"] == V2
    expected = oracle_sets(V2, recorder, n, EVAL_SEED, n, PER_T_CON)
    assert set(result["sets"]) >= set(expected)
    oracles.assert_same([row for name, metrics in expected.items()
                         for row in oracles.metric_rows(f"held {name}", metrics, result["sets"][name])])  # fmt: skip


@pytest.mark.slow  # trains four tiny runs: ~1 min on a free core, 3 on a busy one
def test_a_tiny_benchmark_of_a_v1_and_a_v2_entry_prints_the_oracles_per_T_con_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``dwr-gym benchmark`` with a v1 and a v2 entry (residual PPO on PTC, two seeds, a few env steps): each entry is
    evaluated on its own env id, and the per-T_con table it prints is, cell by cell, the oracle's IQM and interval
    over the seeds of the in-time rate and E/opt of each seed's agent on each T_con set of that env."""
    import train.learning.agents as agents
    from train.cli import main
    from train.evaluation.benchmark import EVAL_SEED, PER_T_CON

    pytest.importorskip("rliable")
    oracles.use_stand_in_optimum(monkeypatch)
    recorded: dict[str, oracles.Recorder] = {}
    load_agent = agents.load_agent

    def recording(path: Any, part: str = "whole") -> tuple[str, Any]:  # the agent each run is evaluated with
        label, policy = load_agent(path, part)
        recorded[Path(path).name] = oracles.Recorder(policy)
        return label, recorded[Path(path).name]

    monkeypatch.setattr(agents, "load_agent", recording)
    tiny = "algo=ppo,residual=true,expert=ptc,num_envs=2,hyperparams={n_steps: 32, batch_size: 32}"
    entries = {"res-v1": V1, "res-v2": V2}
    n, seeds = 3, (0, 1)
    argv = ["benchmark", "--agents", f"res-v1:{tiny}", f"res-v2:{tiny},env_id={V2}", "--seeds", str(len(seeds)),
            "--env-steps", "64", "--eval-freq", "64", "--eval-episodes", str(n), "--disturbed-episodes", "1",
            "--optimum-episodes", str(n), "--references", "--out", str(tmp_path)]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out.splitlines()
    head = next(i for i, line in enumerate(printed) if line.startswith("| agent | env |"))
    rows = {line.split(" | ")[0].strip("| "): line.strip(" |").split(" | ") for line in printed[head + 2 :]
            if line.startswith("| res-")}  # fmt: skip
    saved = json.loads((tmp_path / "benchmark.json").read_text())["summary"]
    checks = []
    for entry, env_id in entries.items():
        assert saved[entry]["env_id"] == env_id
        per_seed = [oracle_sets(env_id, recorded[f"{entry}-seed{s}"], n, EVAL_SEED, n, PER_T_CON) for s in seeds]
        checks.append((entry, "env", env_id.rsplit("-", 1)[-1], rows[entry][1]))
        for T_con, got in zip(PER_T_CON, rows[entry][2:], strict=True):
            name = f"T_con={T_con:g}"
            in_time = oracles.iqm_interval([metrics[name]["in_time"] for metrics in per_seed])
            ratio = oracles.iqm_interval([metrics[name]["energy_ratio"] for metrics in per_seed])
            checks.append((entry, name, f"{oracles.cell(in_time, 2)}, {oracles.cell(ratio, 2)}", got))
    oracles.assert_same(checks)
    assert rows["res-v1"][2:] != rows["res-v2"][2:]  # v1's and v2's episode ends measure differently
