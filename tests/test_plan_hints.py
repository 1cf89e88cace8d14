"""The shipped plan hints (baselines/plan_hints.py): a plan solved from its winning guess alone is the search's plan,
to the last bit; the shipped file names the search's winners, for this solver; the rows are the same with or
without it."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("casadi")

from baselines import optimal, plan_hints
from baselines.nmpc import clear_memo
from baselines.optimal import solve_minimum_energy

LIMITS = {"dt": 0.05, "u_max": 1.0, "omega_max": 2.0}
#: from behind (four guesses: both turns, forward and reverse), beside and ahead (two)
STARTS = [(-1.2, 0.4, -2.5), (0.8, -0.3, 2.9), (1.5, 1.0, 0.3), (-0.6, -1.4, 1.2)]


@pytest.mark.parametrize("start", STARTS)
def test_a_plan_solved_from_its_winning_guess_alone_is_the_searchs_to_the_last_bit(start: tuple) -> None:
    search = solve_minimum_energy(start, 8.0, **LIMITS)  # type: ignore[arg-type]
    assert search.tried == (4 if abs(start[2]) > np.pi / 2 else 2) and 0 <= search.candidate < search.tried
    alone = solve_minimum_energy(start, 8.0, **LIMITS, only=search.candidate)  # type: ignore[arg-type]
    assert (alone.tried, alone.candidate) == (1, search.candidate)
    np.testing.assert_array_equal(alone.solution, search.solution)
    assert alone.energy == search.energy


def test_a_hinted_guess_that_does_not_converge_falls_back_to_the_whole_search(monkeypatch: pytest.MonkeyPatch) -> None:
    search = solve_minimum_energy(STARTS[0], 8.0, **LIMITS)  # type: ignore[arg-type]
    cheapest = optimal._cheapest

    def failing_alone(candidates: list, *args: Any) -> Any:
        return (None, 7, "forced") if len(candidates) == 1 else cheapest(candidates, *args)

    monkeypatch.setattr(optimal, "_cheapest", failing_alone)
    fallback = solve_minimum_energy(STARTS[0], 8.0, **LIMITS, only=search.candidate)  # type: ignore[arg-type]
    np.testing.assert_array_equal(fallback.solution, search.solution)
    assert fallback.tried == search.tried and fallback.iterations == search.iterations + 7


def test_a_search_named_as_finding_no_plan_returns_its_error_unsolved(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A search whose every guess stops at its iteration limit: recorded with its error, which a hinted planner returns
    without solving, as the same class with the same message."""
    from baselines import nmpc

    job = {"start": STARTS[0], "arrival_time": 8.0, **LIMITS, "max_iter": 2}
    monkeypatch.setenv(plan_hints.RECORD, str(tmp_path))
    searched = nmpc._solve(job)
    assert isinstance(searched, optimal.OptimalControlError)
    (recorded,) = plan_hints.read_recorded(tmp_path).items()
    assert recorded == (nmpc.job_key(job)[: plan_hints.KEY_BYTES], str(searched))  # an error by the job's bits
    monkeypatch.setattr(plan_hints, "_shipped", lambda: dict([recorded]))
    monkeypatch.setattr(nmpc, "solve_minimum_energy", lambda **job: pytest.fail("solved a hinted failure"))
    hinted = nmpc._solve(job)
    assert type(hinted) is type(searched) and str(hinted) == str(searched)


def test_a_winner_is_found_to_10_digits_and_a_search_without_plan_by_its_bits(monkeypatch: pytest.MonkeyPatch) -> None:
    from baselines.nmpc import job_key

    job = {"start": (0.018, -0.025, -0.36), "arrival_time": 2.0, **LIMITS}
    ulps = {**job, "start": tuple(np.nextafter(v, np.inf, dtype=np.float64) for v in job["start"])}
    monkeypatch.setattr(plan_hints, "_shipped", lambda: {plan_hints.hint_key(job): 1})
    assert plan_hints.hint(job, job_key(job)) == 1 and plan_hints.hint(ulps, job_key(ulps)) == 1
    monkeypatch.setattr(plan_hints, "_shipped", lambda: {job_key(job)[: plan_hints.KEY_BYTES]: "no plan"})
    assert plan_hints.hint(job, job_key(job)) == "no plan"
    assert plan_hints.hint(ulps, job_key(ulps)) is None  # a few ulps away it may converge: searched
    monkeypatch.setenv(plan_hints.SWITCH, "0")
    assert plan_hints.hint(job, job_key(job)) is None


def test_a_job_keeps_its_hint_key_on_a_cpu_whose_numbers_differ_in_the_last_bits() -> None:
    """The key of a hint is the job's to 10 significant digits: a start that another CPU's numpy reached a few ulps away
    (or a numpy float for a float) has the same key; a start 1e-6 away, another deadline or limit, does not; a
    warm-started re-plan has none."""
    from baselines.nmpc import job_key

    job = {"start": (-1.2, 0.4, -2.5), "arrival_time": 8.0, **LIMITS, "response": (0.01, -0.02, 0.9, 0.1)}
    key = plan_hints.hint_key(job)
    assert key is not None and len(key) == plan_hints.KEY_BYTES
    ulps = {**job, "start": tuple(np.nextafter(v, np.inf, dtype=np.float64) for v in job["start"])}
    assert job_key(ulps) != job_key(job) and plan_hints.hint_key(ulps) == key  # the plan store's key is exact
    assert plan_hints.hint_key({**job, "arrival_time": np.float64(8.0)}) == key
    for other in ({"start": (-1.2 + 1e-6, 0.4, -2.5)}, {"arrival_time": 8.25}, {"u_max": 0.5}, {"heading": False},
                  {"response": (0.01, -0.02, 0.9, 0.1 + 1e-6)}):  # fmt: skip
        assert plan_hints.hint_key({**job, **other}) != key, other
    assert plan_hints.hint_key({**job, "warm_start": np.zeros(10)}) is None


def test_the_hint_file_reads_back_what_was_written(tmp_path: Path) -> None:
    hints: dict[bytes, plan_hints.Hint] = {bytes([i] * 16): i % 4 for i in range(5)} | {bytes([9] * 16): "no plan"}
    plan_hints.write_hints(tmp_path / "h.npz", "abc", "3.8.2", hints)
    assert plan_hints.read_hints(tmp_path / "h.npz") == ("abc", "3.8.2", hints)


def shipped_hints() -> plan_hints.HintFile:
    """The shipped hint file; the test is skipped under another CasADi than theirs (they are not read there)."""
    import casadi

    shipped = plan_hints.read_hints(plan_hints.HINTS_PATH)
    if shipped.casadi != casadi.__version__:
        pytest.skip(f"the plan hints were recorded with CasADi {shipped.casadi}, this is {casadi.__version__}")
    return shipped


def test_the_shipped_hints_are_for_this_solver() -> None:
    """Fails where baselines/optimal.py changed since the hints were recorded: run ``python -m benchmarks run
    ship-plan-hints`` (until then every plan searches all its guesses: slower, not wrong)."""
    solver, _, winners = shipped_hints()
    assert solver == plan_hints.solver_digest(), "the solver changed: python -m benchmarks run ship-plan-hints"
    guesses = {w for w in winners.values() if isinstance(w, int)}
    assert len(winners) > 1000 and guesses <= {0, 1, 2, 3}


def compare_head(name: str, episodes: int) -> Any:
    """The first ``episodes`` of ``dwr-gym compare``'s default set ``name``, as compare makes it."""
    from train.cli import build_parser
    from train.commands.shared import checked_env
    from train.evaluation.scenarios import make_scenario

    args = build_parser().parse_args(["compare"])
    scenario = make_scenario(name, n=args.n, seed=args.seed, env_kwargs=checked_env(args)[1])
    return replace(scenario, starts=scenario.starts[:episodes], goals=scenario.goals[:episodes],
                   labels=scenario.labels[:episodes],
                   T_cons=None if scenario.T_cons is None else scenario.T_cons[:episodes])  # fmt: skip


def rows(policies: dict[str, str], scenario: Any) -> str:
    from train.evaluation.evaluate import evaluate

    clear_memo()  # every plan solved here, none taken from an earlier test's
    results = evaluate(policies, scenario, seed=0)  # type: ignore[arg-type]
    return json.dumps({label: result.summary() for label, result in results.items()}, sort_keys=True, default=str)


def test_the_shipped_hints_name_the_searchs_winners_and_give_the_same_rows(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``robust-pt`` and ``optimal`` on the first episodes of compare's disturbed set (few robots: solved in this
    process): every search they solve is named by the shipped file with the winner it keeps, and the rows with the
    hints equal those without to the last digit, with no search solved (each hinted plan one guess)."""
    policies = {"robust-pt": "robust-pt", "optimal": "optimal"}
    scenario = compare_head("disturbed", 3)
    monkeypatch.setenv(plan_hints.RECORD, str(tmp_path))
    monkeypatch.setenv(plan_hints.SWITCH, "0")
    searched = rows(policies, scenario)
    recorded = plan_hints.read_recorded(tmp_path)
    shipped = shipped_hints().hints
    assert len(recorded) >= 3 and recorded.keys() <= shipped.keys()
    assert recorded == {key: shipped[key] for key in recorded}
    for path in tmp_path.glob("*.txt"):
        path.unlink()
    monkeypatch.setenv(plan_hints.SWITCH, "1")
    assert rows(policies, scenario) == searched
    assert plan_hints.read_recorded(tmp_path) == {}  # every search was one guess: the hints were read
