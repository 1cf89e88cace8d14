"""The RL benchmark's tables and figure as a reader uses them: which goal each agent meets (its boundary included),
'-' where a figure was not measured, every entry and goal listed, and the learning curves' lines and bands."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from train.evaluation.benchmark import SETS
from train.goals import FROM_REWARD, RESIDUAL_ON_PTC
from train.reporting.rl_benchmark import (
    aggregate,
    diagnosis_table,
    disturbed_table,
    goals_table,
    iqm_interval,
    plot_curves,
    residual_table,
    rushing_table,
    sweep_table,
)

pytest.importorskip("rliable")


def seed_result(entry: str, seed: int, in_time: float | None, ratio: float | None, heading: float = 0.05,
                sets: tuple[str, ...] = ("random",)) -> dict[str, Any]:  # fmt: skip
    """One (entry, seed) of dwr-gym benchmark's results, evaluated on ``sets`` with the same metrics on each."""
    metrics = {"in_time": in_time, "energy_ratio": ratio, "final_heading": heading, "energy": 1.0}
    return {"entry": entry, "seed": seed, "sets": dict.fromkeys(sets, metrics), "curve": [], "seconds": 60.0}


def table_rows(text: str) -> dict[str, list[str]]:
    """A markdown table's body: {first cell: the other cells}."""
    rows = [line.strip().strip("|").split(" | ") for line in text.splitlines()[2:] if line.startswith("|")]
    return {row[0].strip(): [cell.strip() for cell in row[1:]] for row in rows}


VERDICT = re.compile(r"(?P<value>-|\d+\.\d+) \((?:goal )?(?P<op>>=|<=) (?P<target>[\d.]+)\): (?P<verdict>.+)")


def verdict(cell: str) -> tuple[str, str, float, str]:
    """A goals-table cell read back: (value, comparison, target, verdict)."""
    match = VERDICT.fullmatch(cell)
    assert match, f"not a verdict cell: {cell!r}"
    return match["value"], match["op"], float(match["target"]), match["verdict"]


def test_a_figure_exactly_at_its_goal_meets_it_and_one_just_past_does_not() -> None:
    """The goals read 'in time >= 99 %', 'E/opt <= 1.5', 'heading <= 0.1 rad': the boundary itself is met."""
    goal = FROM_REWARD
    at = aggregate([seed_result("ppo", 0, goal.in_time, goal.energy_ratio, goal.final_heading)])
    assert at["ppo"]["sets"]["random"]["in_time"]["iqm"] == goal.in_time  # one seed: the IQM is its value
    cells = table_rows(goals_table(at))[goal.name]
    assert cells[:2] == ["ppo", "1"]
    figures = {"in time": (">=", goal.in_time), "E/opt": ("<=", goal.energy_ratio),
               "heading": ("<=", goal.final_heading)}  # fmt: skip
    for cell, (name, (op, target)) in zip(cells[2:5], figures.items(), strict=True):
        assert verdict(cell)[1:] == (op, target, "met"), (name, cell)
    past = aggregate([seed_result("ppo", 0, goal.in_time - 1e-3, goal.energy_ratio + 1e-3, goal.final_heading + 1e-3)])
    for cell, name in zip(table_rows(goals_table(past))[goal.name][2:5], figures, strict=True):
        assert verdict(cell)[3] == "not met", (name, cell)


def test_a_figure_not_measured_is_not_reached_and_still_names_its_goal() -> None:
    """E/opt with no episode in time, or an in-time rate recorded as None, reads '-' and 'not reached' beside the
    goal's own comparison and target, never 'met'."""
    cells = table_rows(goals_table(aggregate([seed_result("sac", 0, 0.0, None)])))[FROM_REWARD.name]
    assert verdict(cells[2]) == ("0.000", ">=", FROM_REWARD.in_time, "not met")
    assert verdict(cells[3]) == ("-", "<=", FROM_REWARD.energy_ratio, "not reached")
    cells = table_rows(goals_table(aggregate([seed_result("sac", 0, None, None)])))[FROM_REWARD.name]
    assert verdict(cells[2]) == ("-", ">=", FROM_REWARD.in_time, "not reached")


def test_the_best_agent_for_a_goal_is_the_one_most_in_time() -> None:
    """An agent that never arrives in time (0.0, listed first) or whose rate is unknown is not the best over one
    that arrives half the time."""
    for never in (0.0, None):
        summary = aggregate([seed_result("ppo", 0, never, None), seed_result("sac", 0, 0.5, 3.0)])
        best = table_rows(goals_table(summary))[FROM_REWARD.name][0]
        assert best == "sac", (never, best)


def test_the_goals_table_lists_a_later_goal_when_an_earlier_one_has_no_agent() -> None:
    """A benchmark run of the residual agent alone still shows the residual goal (the first goal has no candidate)."""
    residual = seed_result("residual-ppo", 0, 1.0, 1.2)
    rows = table_rows(goals_table(aggregate([residual])))
    assert list(rows) == [RESIDUAL_ON_PTC.name] and rows[RESIDUAL_ON_PTC.name][0] == "residual-ppo"
    rows = table_rows(goals_table(aggregate([residual, seed_result("td3", 0, 0.9, 2.0)])))
    assert list(rows) == [FROM_REWARD.name, RESIDUAL_ON_PTC.name]


def test_the_disturbed_table_shows_a_dash_for_a_set_an_entry_or_a_law_was_not_evaluated_on() -> None:
    summary = aggregate([seed_result("a", 0, 0.8, 1.2, sets=("random", "delay"))])
    references = {"ptc": {"random": {"in_time": 1.0}, "delay": {"in_time": 0.75}}}
    text = disturbed_table(summary, references)
    names = [s for s in SETS if s != "random"]
    assert text.splitlines()[0].count(": in time") == len(names)
    rows = table_rows(text)
    for row, value in (("a", "0.80 [0.80, 0.80]"), ("ptc (controller)", "0.75")):
        expected = [value if s == "delay" else "-" for s in names]
        assert rows[row] == expected, (row, rows[row], expected)


def test_the_diagnosis_table_of_one_noise_level_shows_a_dash_for_e_over_opt_it_could_not_measure() -> None:
    """A diagnosis of a single sigma renders, its footnote's optimum from that row; E/opt undefined reads '-'."""
    row = {"sigma": 1.0, "in_time": 0.0, "energy": 70.0, "energy_ratio": None, "return": -140.0,
           "optimal_energy": 0.34, "episode_seconds": 30.0, "noise_cost_per_second": 4.0}  # fmt: skip
    data = {"n": 200, "seed": 3232, "energy_weight": 2.0, "arrival_bonus": 10.0, "rows": [row]}
    text = diagnosis_table(data)
    assert table_rows(text)["1.00"][:3] == ["0.000", "70.00", "-"]
    footnote = re.search(r"optimum's mean energy (\S+), i\.e\. a reward of (\S+);", text)
    assert footnote and (float(footnote[1]), float(footnote[2])) == (0.34, -0.68), footnote
    ratio = table_rows(diagnosis_table({**data, "rows": [{**row, "energy_ratio": 200.0}]}))["1.00"][2]
    assert ratio == "200.00"


def test_the_residual_table_shows_a_dash_for_e_over_opt_a_policy_could_not_measure() -> None:
    """No episode in time (E/opt undefined, None in the JSON) reads '-' in the E/opt column, the rest as measured."""
    never = {"in_time": 0.0, "energy_ratio": None, "final_heading": 1.2, "energy": 5.0}
    alone = {"in_time": 1.0, "energy_ratio": 1.8, "final_heading": 0.05, "energy": 0.6}
    data = {"n": 50, "seed": 3232, "agents": {"res": {"expert": "ptc", "agent": never, "expert_alone": alone,
                                                      "by_time_fraction": []}}}  # fmt: skip
    rows = table_rows(residual_table(data))
    assert rows["res (residual)"] == ["0.000", "-", "1.20", "5.000"], rows
    assert rows["ptc alone"][:2] == ["1.000", "1.80"], rows


def test_the_rushing_table_lists_a_policy_without_an_arrival_and_every_policy_after_it() -> None:
    """A policy none of whose episodes arrived in time reads 0 episodes and dashes; the policies after it keep their
    rows; data archived before the env id was recorded are v1's."""
    arrived = {"episodes": 40, "arrival_share": 0.9, "energy_ratio": 1.8, "timing": 1.1, "motion": 1.6}
    data = {"n": 50, "seed": 3232, "policies": {"never": {"episodes": 0}, "ptc": arrived}}
    text = rushing_table(data)
    rows = table_rows(text)
    assert rows["never"] == ["0", "-", "-", "-", "-"] and rows["ptc"][:2] == ["40", "0.90"], rows
    assert "\n*DWRPointStabilization-v1: " in text
    assert "\n*DWRPointStabilization-v2: " in rushing_table({**data, "env_id": "DWRPointStabilization-v2"})


def test_the_sweep_table_shows_whole_and_categorical_hyperparameters_as_drawn() -> None:
    """A sweep's randint and choice draws (a batch size, an activation) read as drawn, the floats to 4 digits."""
    drawn = {"batch_size": 16384, "activation_fn": "tanh", "learning_rate": 0.000312345}
    trial = {"config": "t0", "hyperparams": json.dumps(drawn), "success_rate_mean": "0.5", "return_mean_mean": "1.0",
             "energy_mean_mean": "2.0"}  # fmt: skip
    params = table_rows(sweep_table({"trials": [trial]}))["t0"][0]
    assert params.split(", ") == ["batch_size 16384", "activation_fn tanh", "learning_rate 0.0003123"], params


def test_the_curves_figure_draws_each_entrys_iqm_and_its_translucent_band_side_by_side(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """In time and energy side by side; per entry (those after an entry without a curve too) a line through the
    IQM at the curve's x and a translucent band from the interval's low to its high, in the line's colour."""
    pytest.importorskip("matplotlib")
    from matplotlib.colors import to_rgb
    from matplotlib.figure import Figure

    figures: list[Figure] = []
    real_savefig = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: figures.append(fig) or real_savefig(fig, *a, **k))
    curve = [{"env_steps": 0.0, "wall_time": 0.0, "in_time": 0.0, "energy": 9.0, "final_heading": 1.0},
             {"env_steps": 100.0, "wall_time": 5.0, "in_time": 0.5, "energy": 3.0, "final_heading": 0.5}]  # fmt: skip
    results = [seed_result("empty", 0, 0.1, None)]
    for s in range(3):  # three seeds apart: a band, not a line
        shifted = [{**r, "in_time": r["in_time"] + 0.1 * s, "energy": r["energy"] + s} for r in curve]
        results.append({**seed_result("a", s, 0.5, 1.2), "curve": shifted})
    summary = aggregate(results)
    plot_curves(summary, tmp_path / "curves.png", "env_steps")
    (fig,) = figures
    left, right = fig.axes[:2]
    assert left.get_position().y0 == right.get_position().y0 and left.get_position().x1 < right.get_position().x0
    for ax, y, label in ((left, "in_time", "in time (IQM, 95 % CI)"), (right, "energy", "energy (IQM, 95 % CI)")):
        band = summary["a"]["curves"]["env_steps"][y]
        assert ax.get_ylabel() == label
        (line,) = ax.get_lines()
        np.testing.assert_allclose(line.get_xdata(), band["x"])
        np.testing.assert_allclose(line.get_ydata(), band["iqm"])
        (fill,) = ax.collections
        vertices = {(round(float(px), 9), round(float(py), 9)) for px, py in fill.get_paths()[0].vertices}
        for x, low, high in zip(band["x"], band["low"], band["high"], strict=True):
            assert {(round(x, 9), round(low, 9)), (round(x, 9), round(high, 9))} <= vertices, (y, x, low, high)
        assert band["low"] != band["high"]
        face = fill.get_facecolor()[0]
        assert face[3] < 1.0 and to_rgb(face) == to_rgb(line.get_color()), (face, line.get_color())


def test_the_curves_figure_names_its_axes_and_is_written_into_a_folder_not_yet_made(tmp_path: Path) -> None:
    """The x axis says env steps or wall-clock seconds as asked; the grid is faint, the legend's text smaller than
    the axes' labels; the file goes into a folder made for it, however deep; no figure is left open."""
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    curve = [{"env_steps": 0.0, "wall_time": 0.0, "in_time": 0.0, "energy": 9.0, "final_heading": 1.0},
             {"env_steps": 100.0, "wall_time": 5.0, "in_time": 0.5, "energy": 3.0, "final_heading": 0.5}]  # fmt: skip
    summary = aggregate([{**seed_result("a", s, 0.5, 1.2), "curve": curve} for s in (0, 1)])
    figures: list[Figure] = []
    real_savefig = Figure.savefig
    open_before = plt.get_fignums()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Figure, "savefig", lambda fig, *a, **k: figures.append(fig) or real_savefig(fig, *a, **k))
        for x in ("env_steps", "wall_time"):
            path = tmp_path / "new" / "deeper" / f"curves_{x}.png"
            plot_curves(summary, path, x)
            assert path.is_file()
    assert plt.get_fignums() == open_before
    for fig, words in zip(figures, ("env steps", "wall-clock seconds"), strict=True):
        for ax in fig.axes:
            assert ax.get_xlabel().startswith(words), (words, ax.get_xlabel())
            grid = ax.get_xgridlines() + ax.get_ygridlines()
            assert all(line.get_visible() and (line.get_alpha() or 1.0) < 1.0 for line in grid)
        legend = fig.axes[0].get_legend()
        assert legend.get_texts()[0].get_fontsize() < fig.axes[0].yaxis.label.get_fontsize()


def test_the_curves_band_spans_the_shortest_run_on_its_grid_and_a_run_of_one_evaluation_is_one_point() -> None:
    """The grid runs from 0 to the last evaluation of the shortest run (not its second) in CURVE_POINTS points, for
    an extent under 1 too; runs evaluated only at 0 give one point, the seeds' IQM there."""
    from train.reporting.rl_benchmark import CURVE_POINTS, curve_band

    def run(*xs: float) -> list[dict[str, float]]:
        return [{"wall_time": x, "in_time": x / 10.0} for x in xs]

    band = curve_band([run(0.0, 2.0, 5.0), run(0.0, 1.0, 4.0, 8.0)], "wall_time", "in_time")
    assert len(band["x"]) == CURVE_POINTS and band["x"][0] == 0.0 and band["x"][-1] == 5.0, band["x"]
    short = curve_band([run(0.0, 0.25, 0.5), run(0.0, 0.5)], "wall_time", "in_time")
    assert len(short["x"]) == CURVE_POINTS and short["x"][-1] == 0.5, short["x"]
    start = [[{"wall_time": 0.0, "in_time": v}] for v in (0.2, 0.4, 0.9)]
    band = curve_band(start, "wall_time", "in_time")
    assert band["x"] == [0.0] and band["iqm"] == pytest.approx([iqm_interval([0.2, 0.4, 0.9])["iqm"]]), band


def test_the_aggregate_counts_env_steps_and_reads_a_result_without_its_env_as_v1() -> None:
    """The env steps' IQM over seeds (a result without them: none); a result recorded before its env id was (an
    earlier run's) is v1's, the task's env."""
    from train.env_ids import TASK_ENV_ID

    results = [{**seed_result("a", s, 0.5, 1.2), "env_steps": steps} for s, steps in enumerate((1000, 2000, 3000))]
    summary = aggregate([*results, seed_result("b", 0, 0.5, 1.2)])
    assert summary["a"]["env_steps"]["iqm"] == pytest.approx(2000.0) and summary["b"]["env_steps"]["iqm"] is None
    assert summary["a"]["env_id"] == summary["b"]["env_id"] == TASK_ENV_ID == "DWRPointStabilization-v1"


def test_the_tables_show_a_dash_for_a_laws_missing_figure_and_list_entries_after_one_without_per_T_con_sets() -> None:
    """A law without E/opt on the nominal set reads '-' there; an entry evaluated on the nominal set alone is left out
    of the per-T_con table, not the entries after it; an entry kept from an earlier run's docs without its env id
    reads v1."""
    from train.reporting.rl_benchmark import per_T_con_table, table

    summary = aggregate([seed_result("nominal-only", 0, 0.9, 1.2), seed_result("a", 0, 0.8, 1.3, sets=("T_con=10",))])
    law = {"ptc": {"random": {"in_time": 1.0, "energy_ratio": None, "final_heading": 0.02, "energy": 0.7}}}
    assert table_rows(table(summary, law))["ptc (controller)"][3:] == ["1.000", "-", "0.02", "0.70"]
    rows = table_rows(per_T_con_table(summary))
    assert list(rows) == ["a"] and rows["a"][0] == "v1", rows
    del summary["a"]["env_id"]
    assert table_rows(per_T_con_table(summary))["a"][0] == "v1"
