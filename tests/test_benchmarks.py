"""The benchmarks as one suite: every module is an entry of the registry, listed with one line, runnable by name, and
the docs' blocks render again from the JSON already written without changing a byte."""

from __future__ import annotations

import itertools
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks import recipes, registry
from benchmarks.core import docs

ROOT = Path(__file__).resolve().parents[1]


def test_every_benchmark_module_is_an_entry_and_every_entry_has_a_main() -> None:
    modules = {str(path.relative_to(ROOT).with_suffix("")).replace("/", ".") for path in ROOT.glob("benchmarks/*/*.py")
               if path.name != "__init__.py" and path.parent.name != "core"}  # fmt: skip
    assert modules == {target for target in registry.SUITE.values() if not target.endswith(".sh")}
    for name in registry.SUITE:
        assert callable(registry.load(name).main), name
        assert registry.summary(name), f"{name} has no docstring to list"
    top = {path.name for path in ROOT.glob("benchmarks/*") if path.is_file()}
    assert top == {"__init__.py", "__main__.py", "registry.py"}, "a benchmark belongs in a group, named in registry.py"


def test_each_recipe_script_is_an_entry_in_the_recipes_group() -> None:
    scripts = {str(path.relative_to(ROOT)) for path in ROOT.glob("benchmarks/recipes/*.sh")}
    entries = {name: target for name, target in registry.SUITE.items() if target.endswith(".sh")}
    assert set(entries.values()) == scripts and len(scripts) >= 6  # each shell recipe is an entry, and none is lost
    assert all(registry.group(name) == "recipes" for name in entries)
    assert set(recipes.BLOCKS) <= set(entries), "tables declared for a recipe that is no entry"


def test_list_prints_one_line_per_entry() -> None:
    result = subprocess.run([sys.executable, "-m", "benchmarks", "list"], cwd=ROOT, capture_output=True, text=True)
    lines = result.stdout.splitlines()
    assert result.returncode == 0 and [line.split()[0] for line in lines] == list(registry.SUITE)
    groups = [line.split()[1] for line in lines]
    assert set(groups) == {"speed", "training", "learning", "robustness", "quality", "testing", "datasets", "recipes"}
    assert len(list(itertools.groupby(groups))) == len(set(groups)), "each group's entries are listed together"


def test_an_unknown_entry_is_named_in_one_line() -> None:
    result = subprocess.run([sys.executable, "-m", "benchmarks", "run", "nope"], cwd=ROOT, capture_output=True,
                            text=True)  # fmt: skip
    assert result.returncode != 0 and "benchmark 'nope' is unknown: expected one of throughput" in result.stderr
    assert "Traceback" not in result.stderr


def test_run_gives_its_arguments_to_the_entry(capsys: pytest.CaptureFixture[str]) -> None:
    from benchmarks.__main__ import main

    with pytest.raises(SystemExit) as exit_:
        main(["run", "memory", "--steps", "5"])
    assert exit_.value.code == 2 and "--steps 5 is invalid" in capsys.readouterr().err


def test_render_rewrites_nothing_when_every_block_is_current() -> None:
    before = {path: path.read_text() for path in docs.doc_tables.markdown_files()}
    assert docs.render() == []
    assert {path: path.read_text() for path in before} == before


def test_every_block_is_declared_once_and_every_declared_json_exists_or_is_not_shown() -> None:
    shown = {m.group("name") for path in docs.doc_tables.markdown_files() for m in
             docs.doc_tables.MARKER.finditer(path.read_text())}  # fmt: skip
    for name, (_, block) in docs.producers().items():
        assert (ROOT / block.json).is_file() or name not in shown, name
    assert shown <= set(docs.producers())


@pytest.mark.parametrize("name", list(registry.SUITE))
def test_each_entry_says_how_to_run_it(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    try:
        code = registry.load(name).main(["--help"])
    except SystemExit as exit_:
        code = exit_.code
    assert code in (0, None) and capsys.readouterr().out.strip(), name


def test_compare_time_says_where_the_time_went_and_keeps_a_run_per_cache_state() -> None:
    from benchmarks.speed.compare_time import merged, render, stage_seconds

    nan = float("nan")
    rows = [  # two sets; each set's rows repeat its optima's seconds
        {"scenario": "random", "T_con": nan, "policy": "ptc", "seconds": 2.0, "optimum_seconds": 30.0},
        {"scenario": "random", "T_con": nan, "policy": "optimal", "seconds": 50.0, "optimum_seconds": 30.0},
        {"scenario": "fault", "T_con": nan, "policy": "ptc", "seconds": 3.0, "optimum_seconds": 0.0},
        {"scenario": "fault", "T_con": nan, "policy": "optimal", "seconds": 20.0, "optimum_seconds": 0.0},
    ]
    assert stage_seconds(rows) == {"optimal": 70.0, "optimum": 30.0, "ptc": 5.0}
    assert list(stage_seconds(rows)) == ["optimal", "optimum", "ptc"]  # slowest first
    run = {"machine": "m", "cpu": "Intel Xeon", "busy_processes": 0, "wall_seconds": 600.0, "cpu_seconds": 900.0,
           "load_average_1min_at_end": 1.5, "cache": "cold", "optima_solved": 0, "stages": stage_seconds(rows)}  # fmt: skip
    unshipped = {**run, "shipped_optima": False, "optima_solved": 1009}
    runs = merged(merged(merged(None, unshipped), {**run, "shipped_optima": True}), {**run, "shipped_optima": True})
    assert len(runs["runs"]) == 2  # one per (cache, shipped, busy): the same again replaces it
    table = render(runs)
    assert "no shipped optima (1,009 optima solved)" in table and "the shipped optima read (0 solved)" in table
    assert "optimal 1.2, optimum 0.5, ptc 0.1" in table
    elsewhere = merged(runs, {**run, "shipped_optima": True, "cpu": "AMD EPYC", "wall_seconds": 120.0})
    assert len(elsewhere["runs"]) == 2  # another CPU's run of a case replaces it: one row per case, not per machine
    assert render(elsewhere).count("| AMD EPYC |") == 1 and "| AMD EPYC | a fresh clone" in render(elsewhere)
    busy = merged(elsewhere, {**run, "shipped_optima": True, "busy_processes": 2})
    assert len(busy["runs"]) == 3  # the busy case beside the quiet one


def test_compare_time_reads_the_bars_time_left_from_a_redirected_log() -> None:
    from benchmarks.speed.compare_time import PROGRESS_LINE, as_seconds, said_left

    match = PROGRESS_LINE.match("compare: 40% after 1.2 min, about 2.5 min left\n")
    assert match is not None and (match[1], as_seconds(match[2])) == ("40", 150.0)
    assert as_seconds("42 s") == 42.0 and as_seconds("1.5 h") == 5400.0
    assert PROGRESS_LINE.match("compare: 10% after 3 s, about ? left") is not None
    run = {"time_left": [[10, 10.0, 120.0, 100.0], [20, 20.0, 90.0, 90.0], [50, 60.0, 60.0, 50.0]]}
    assert said_left(run) == "1.5 (1.5) / 1.0 (0.8) / -"
    assert said_left({}) == "-"


def test_apg_speed_refuses_a_count_below_one_naming_it(capsys: pytest.CaptureFixture[str]) -> None:
    for argv, named in ((["--repeats", "0"], "--repeats 0"), (["--episodes", "64", "0"], "--episodes [64, 0]")):
        with pytest.raises(SystemExit) as exit_:
            registry.load("apg-speed").main(argv)
        assert exit_.value.code == 2 and named in capsys.readouterr().err


def test_compare_cpu_paths_names_the_cells_that_differ_as_printed() -> None:
    """Two runs differ where a cell differs as the docs print it: 99 % against 98.9 % does, an energy that differs
    in the 5th decimal does not; a row only one run has is named too."""
    from benchmarks.quality.cpu_paths import differences

    row = {"scenario": "fault", "T_con": None, "policy": "robust", "success_rate": 0.99, "energy_mean": 1.00001,
           "final_heading_error_mean": 0.3912, "energy_ratio_mean": 1.234, "energy_ratio_max": 2.04}  # fmt: skip
    other = {**row, "success_rate": 0.989, "energy_mean": 1.00002}
    assert differences([row], [other]) == {"fault / None / robust / success_rate": ["99 %", "98.9 %"]}
    assert differences([row], [row]) == {}
    extra = {**row, "policy": "ptc"}
    assert differences([row], [row, extra])["fault / None / ptc / energy_mean"] == ["absent", "1.000"]


def test_every_planted_slip_names_code_that_is_in_its_file_once() -> None:
    """The planted-bugs table (docs/testing.md) is only as current as its catalogue: each slip replaces text that must
    still be in the tree, once, or the benchmark stops at that slip."""
    from benchmarks.testing.planted_bugs import BUGS

    root = Path(__file__).resolve().parents[1]
    stale = {bug: slip["file"] for bug, slip in BUGS.items()
             if bug != "additive_before_saturation" and (root / slip["file"]).read_text().count(slip["old"]) != 1}  # fmt: skip
    assert not stale, f"planted slips whose code moved (benchmarks/testing/planted_bugs.json): {stale}"


def test_the_misses_are_sorted_by_where_they_end_and_the_goals_side() -> None:
    """constraint-misses: far (over 2 cm, and of those the ones still closing in), beside the goal, goal ahead."""
    from types import SimpleNamespace

    import numpy as np

    from benchmarks.learning.misses import kinds_of_misses

    # four robots at heading 0, 21 recorded distances each (the last second at 20 steps a second)
    end = np.array([0.005, 0.10, 0.015, 0.015])  # in time; far; 1.5 cm with the goal to its left; 1.5 cm ahead
    distance = np.tile(end, (21, 1))
    distance[0, 1] = 0.30  # the far one came 20 cm nearer in the last second
    x = np.array([0.0, -0.10, 0.0, -0.015])
    y = np.array([0.0, 0.0, -0.015, 0.0])
    trajectory = {"distance": distance, "x": x[None], "y": y[None], "psi": np.zeros((1, 4))}
    result = SimpleNamespace(trajectory=trajectory, success=end <= 0.01, final_distance=end)
    kinds = kinds_of_misses(result, np.zeros((4, 3)), steps_per_second=20)
    assert (kinds["misses"], kinds["far"], kinds["closing_in"], kinds["beside"], kinds["ahead"]) == (3, 1, 1, 1, 1)
    assert kinds["in_time"] == 0.25 and kinds["beside_distance"] == 0.015
