"""The optima shipped for the default scenario sets: a cache with a check (train.evaluation.shipped_optima).

A fresh clone's `dwr-gym compare` reads them instead of solving some 1,000 plans, so they must be right (a random
sample is solved again here; `dwr-gym optimum verify` solves them all), complete (exactly the keys the commands'
defaults read), read only where the user's cache has none, and never read for another problem."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.solving import energies_one_by_one
from train.cli import main as cli
from train.evaluation import optimum as optimum_module
from train.evaluation import shipped_optima
from train.evaluation.optimum import casadi_available, optimal_energies
from train.evaluation.verify_optima import verify_shipped

needs_casadi = pytest.mark.skipif(not casadi_available(), reason="needs the optimal extra (CasADi)")


@pytest.fixture
def shipped_on(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """The shipped optima read, an empty user cache (a fresh clone); returns the cache directory."""
    monkeypatch.setenv(shipped_optima.SWITCH, "1")
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_the_shipped_files_hold_exactly_the_optima_the_default_sets_read() -> None:
    from benchmarks.quality.ship_optima import default_keys

    wanted = default_keys()
    files = {path.name: shipped_optima.read_shipped(path) for path in shipped_optima.shipped_files()}
    assert set(files) == set(wanted), "a default changed: python -m benchmarks run ship-optima"
    for name, (problem, keys) in wanted.items():
        assert files[name][0] == problem
        assert set(files[name][1]) == keys, f"{name}: python -m benchmarks run ship-optima"


@needs_casadi
def test_a_random_sample_of_the_shipped_optima_solves_again_to_the_same_energy() -> None:
    seed = int(np.random.default_rng().integers(1 << 16))  # a new sample each run: over runs, all of them
    report = verify_shipped(sample=3, seed=seed, workers=1)
    assert report.checked == 3 * len(shipped_optima.shipped_files()) and report.checked > 0
    assert report.ok, f"seed {seed}: {report.mismatches}"
    assert report.largest <= 1e-6


def test_a_fresh_clone_reads_the_default_random_sets_optima_without_solving(
    shipped_on: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from benchmarks.quality.ship_optima import default_scenarios

    monkeypatch.setattr(
        optimum_module, "_solve_energies", energies_one_by_one(lambda job: pytest.fail("solved a shipped optimum"))
    )
    scenario, params, optimum = next(s for s in default_scenarios() if s[0].name == "random")
    energies, failures = optimal_energies(params, scenario.starts, scenario.goals, scenario.T_cons,
                                          heading=optimum == "pose")  # fmt: skip
    name, _, keys = optimum_module.cache_keys(params, scenario.starts, scenario.goals, scenario.T_cons)
    shipped = shipped_optima.read_shipped(shipped_optima.SHIPPED_DIR / name)[1]
    assert failures == [] and len(energies) == scenario.size
    assert energies.tolist() == [shipped[k] for k in keys]
    assert not shipped_on.exists() or not list(
        shipped_on.glob("optimal-energy-*.json")
    )  # nothing solved, so nothing cached


def test_the_users_cache_wins_and_other_episodes_are_solved(shipped_on: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from benchmarks.quality.ship_optima import default_scenarios

    scenario, params, _ = next(s for s in default_scenarios() if s[0].name == "random")
    name, _, keys = optimum_module.cache_keys(params, scenario.starts[:2], scenario.goals[:2], scenario.T_cons[:2])
    shipped_on.mkdir(parents=True)
    (shipped_on / name).write_text(json.dumps({keys[0]: 123.0}))
    solved: list[object] = []
    monkeypatch.setattr(optimum_module, "_solve_energies", energies_one_by_one(lambda job: solved.append(job) or 7.0))
    starts = np.vstack([scenario.starts[:2], [[2.0, 1.0, 0.5]]])  # an episode of no default set
    goals = np.vstack([scenario.goals[:2], [[0.0, 0.0, 0.0]]])
    T_cons = np.append(scenario.T_cons[:2], 17.0)
    energies, _ = optimal_energies(params, starts, goals, T_cons, workers=1)
    shipped = shipped_optima.read_shipped(shipped_optima.SHIPPED_DIR / name)[1]
    assert energies.tolist() == [123.0, shipped[keys[1]], 7.0]
    assert len(solved) == 1
    monkeypatch.setenv(shipped_optima.SWITCH, "0")  # turned off: the shipped one is solved instead
    energies, _ = optimal_energies(params, starts[1:2], goals[1:2], T_cons[1:2], workers=1)
    assert energies.tolist() == [7.0] and len(solved) == 2


def test_a_shipped_file_for_another_problem_or_with_a_bad_energy_is_refused(tmp_path: Path, shipped_on: Path) -> None:
    problem = shipped_optima.problem_record(2, 0.05, 1.0, 2.0, True)
    path = tmp_path / "optimal-energy-0123456789abcdef.json"
    shipped_optima.write_shipped(path, problem, {"1,2,3,10": 0.5})
    assert shipped_optima.read_shipped(path) == (problem, {"1,2,3,10": 0.5})
    for energy in ("NaN", "-1.0", '"failed"'):
        path.write_text(f'{{"problem": {json.dumps(problem)}, "energies": {{"1,2,3,10": {energy}}}}}')
        with pytest.raises(shipped_optima.ShippedOptimaError, match="is not an optimum"):
            shipped_optima.read_shipped(path)
    real = shipped_optima.shipped_files()[0]
    other = {**shipped_optima.read_shipped(real)[0], "u_max": 9.0}
    with pytest.raises(shipped_optima.ShippedOptimaError, match="solved for"):
        shipped_optima.shipped_energies(real.name, other)


@needs_casadi
def test_verify_fails_on_a_planted_wrong_energy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    real = shipped_optima.shipped_files()[0]
    problem, energies = shipped_optima.read_shipped(real)
    key = sorted(energies)[0]
    shipped_optima.write_shipped(tmp_path / real.name, problem, {key: energies[key] * (1 + 1e-4)})
    monkeypatch.setattr(shipped_optima, "SHIPPED_DIR", tmp_path)
    assert cli(["optimum", "verify", "--no-progress", "--workers", "1"]) == 1
    out = capsys.readouterr().out
    assert "verified 1 shipped optima" in out and f"mismatch: {real.name} {key}" in out
    shipped_optima.write_shipped(tmp_path / real.name, problem, {key: energies[key]})
    assert cli(["optimum", "verify", "--no-progress", "--workers", "1"]) == 0


@pytest.mark.parametrize("argv, message", [(["--rtol", "0"], "--rtol=0.0 is invalid"),
                                           (["--rtol", "nan"], "--rtol=nan is invalid")])  # fmt: skip
def test_verify_refuses_a_bad_tolerance(argv: list[str], message: str, capsys) -> None:
    assert cli(["optimum", "verify", *argv]) == 2
    assert message in capsys.readouterr().err


#: A shipped optimum (its key) on which the batched search (the cheapest coarse plan refined) stops 1.5e-6 above the
#: shipped energy, and another of the same fine solver size (800 intervals).
BATCH_STOPS_ABOVE = "-4.999669273158e-01,-4.994638395080e-01,-7.960866141121e-01,3.030800634560e+01"
SAME_SIZE = "-1.088301644463e-01,-7.059883345541e-01,-2.920180176385e-01,3.084763296714e+01"


def _jobs(*keys: str) -> list[optimum_module.EnergyJob]:
    return [((x, y, psi), T_con, 0.05, 0.5, 2.0, True) for x, y, psi, T_con in (map(float, k.split(",")) for k in keys)]


def _in_a_new_thread(jobs: list[optimum_module.EnergyJob], **kwargs: int) -> list[float | str]:
    """``solve_uncached`` on one solving thread that has built no solver yet (its solvers are its own)."""
    import threading

    out: list[list[float | str]] = []
    thread = threading.Thread(target=lambda: out.append(optimum_module.solve_uncached(jobs, 1, **kwargs)))
    thread.start()
    thread.join()
    return out[0]


@needs_casadi
def test_an_optimum_does_not_depend_on_what_its_solver_solved_before(monkeypatch: pytest.MonkeyPatch) -> None:
    """fatrop keeps its tolerance option only until a solver's first success (with a stage per interval, a first search
    of this optimum reaches the shipped energy, a later one stops 1.5e-6 above): each new solver is called once before
    its first search, so an optimum is the same alone, after another of its size, and whatever the threads' timing."""
    monkeypatch.setattr(optimum_module, "STAGE", 1)
    alone = _in_a_new_thread(_jobs(BATCH_STOPS_ABOVE))[0]
    after = _in_a_new_thread(_jobs(SAME_SIZE, BATCH_STOPS_ABOVE))[1]
    assert isinstance(alone, float) and alone == after, f"alone {alone!r}, after another optimum {after!r}"


@needs_casadi
def test_verify_decides_by_the_whole_search_where_the_batch_lands_above(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    """With a stage per interval, the batch stops 1.5e-6 above this optimum, and verify re-solves it by the whole
    search, which reaches the shipped energy."""
    monkeypatch.setattr(optimum_module, "STAGE", 1)
    real = shipped_optima.shipped_files()[0]
    problem, energies = shipped_optima.read_shipped(real)
    shipped = energies[BATCH_STOPS_ABOVE]
    batched = _in_a_new_thread(_jobs(BATCH_STOPS_ABOVE))[0]
    whole = _in_a_new_thread(_jobs(BATCH_STOPS_ABOVE), coarse=1)[0]
    assert isinstance(batched, float) and isinstance(whole, float)
    assert 1e-6 < (batched - shipped) / shipped < 2e-6, f"batched {batched!r}, shipped {shipped!r}"
    assert abs(whole - shipped) / shipped < 1e-9, f"whole search {whole!r}, shipped {shipped!r}"
    shipped_optima.write_shipped(tmp_path / real.name, problem, {BATCH_STOPS_ABOVE: shipped})
    monkeypatch.setattr(shipped_optima, "SHIPPED_DIR", tmp_path)
    assert cli(["optimum", "verify", "--no-progress", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "1 optima reproduced by the whole fine search" in out and BATCH_STOPS_ABOVE in out
