"""The optimum cache (train.evaluation.optimum): padded problems, the solvers and the pools that solve the default
sets' optima, what is missing, and where the cache lives."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import dwr_gym
from baselines.optimal import (
    solve_minimum_energy,
)
from tests.solving import energies_one_by_one
from train.evaluation import optimum as optimum_module
from train.evaluation.scenarios import make_scenario

ca = pytest.importorskip("casadi")
LIMITS = {"dt": 0.05, "u_max": 0.5, "omega_max": 2.0}


@pytest.mark.parametrize("start", [(-1.2, 0.7, 2.5), (0.9, -0.4, -0.3)])
def test_the_cache_solves_padded_problems_to_the_same_energy_to_1e_6(start: tuple[float, float, float]) -> None:
    """The optimum cache pads every problem to a multiple of PAD_TO intervals (fewer solvers to build): the energy is
    the unpadded problem's to 1e-6 relative, the goal python -m benchmarks run optimum-speed measures on compare's episodes."""
    plain = solve_minimum_energy(start, 10.37, **LIMITS)  # type: ignore[arg-type]
    padded = solve_minimum_energy(start, 10.37, **LIMITS, pad_to=optimum_module.PAD_TO)  # type: ignore[arg-type]
    assert plain.intervals == padded.intervals == 207  # padded to 400 and cut back
    assert padded.energy == pytest.approx(plain.energy, rel=1e-6)


@pytest.mark.parametrize("start", [(-1.2, 0.7, 2.5), (2.0, 1.0, -3.0), (-0.3, -2.1, 0.4)])
def test_the_coarse_then_fine_search_finds_the_whole_fine_searchs_optimum(start: tuple[float, float, float]) -> None:
    """The optimum is searched on a grid COARSE times coarser, then refined from the cheapest coarse plan alone: the
    energy of IPOPT's whole fine search (every guess) to 1e-6 relative, from one fine solve of a few iterations; the
    plan stays on the fine grid, starts at the start and ends at the goal."""
    plain = solve_minimum_energy(start, 12.0, **LIMITS, pad_to=optimum_module.PAD_TO, solver="ipopt")  # type: ignore[arg-type]
    staged = solve_minimum_energy(start, 12.0, **LIMITS, pad_to=optimum_module.PAD_TO,  # type: ignore[arg-type]
                                  coarse=optimum_module.COARSE)  # fmt: skip
    assert staged.energy == pytest.approx(plain.energy, rel=1e-6)
    assert staged.intervals == plain.intervals == 240 and staged.interval == 0.05
    assert staged.tried == 1 and staged.iterations < plain.iterations / 2  # the warm start converged, no cold guess
    np.testing.assert_allclose(staged.states[0], start, atol=1e-12)
    np.testing.assert_allclose(staged.states[-1][:2], 0.0, atol=1e-8)
    # the coarse grid's commands last at most COARSE_HOLD (1 s): 20 periods of 0.05 s, 4 of 0.25 s, none of 2 s
    assert [optimum_module.coarse_factor(dt) for dt in (0.05, 0.25, 2.0)] == [20, 4, 1] == [optimum_module.COARSE, 4, 1]
    with pytest.raises(ValueError, match=r"^coarse=3 is invalid: expected an integer >= 1 that divides pad_to=20$"):
        solve_minimum_energy(start, 12.0, **LIMITS, pad_to=20, coarse=3)  # type: ignore[arg-type]


@pytest.mark.skipif(not ca.has_nlpsol("fatrop"), reason="this CasADi ships no fatrop")
@pytest.mark.parametrize("stage", [2, optimum_module.STAGE])
def test_fatrop_with_several_intervals_per_stage_solves_the_same_problem(stage: int) -> None:
    """With ``stage`` intervals per fatrop stage (the optimum's, fewer and larger stages), the plan is the one of a stage
    per interval: the energy to 1e-7 relative, each state the exact step of eq. (1) from the one before, from the start
    to the goal pose; a stage that does not divide the intervals, or beside a response, is refused naming it."""
    start = (2.0, 1.0, -3.0)
    one = solve_minimum_energy(start, 12.0, **LIMITS, pad_to=200)  # type: ignore[arg-type]
    staged = solve_minimum_energy(start, 12.0, **LIMITS, pad_to=200, stage=stage)  # type: ignore[arg-type]
    assert staged.energy == pytest.approx(one.energy, rel=1e-7)
    assert staged.intervals == one.intervals == 240
    before, command = staged.states[:-1], staged.commands
    x, y, _ = dwr_gym.model.unicycle_step_exact(*before.T, *command.T, LIMITS["dt"])
    np.testing.assert_allclose(np.stack([x, y], axis=1), staged.states[1:, :2], atol=1e-8)
    np.testing.assert_allclose(np.diff(staged.states[:, 2]), command[:, 1] * LIMITS["dt"], atol=1e-8)
    np.testing.assert_allclose(staged.states[0], start, atol=1e-12)
    np.testing.assert_allclose(staged.states[-1], [0.0, 0.0, one.states[-1, 2]], atol=1e-8)
    np.testing.assert_allclose(staged.states, one.states, atol=1e-6)
    with pytest.raises(ValueError, match=r"^stage=3 is invalid: expected an integer >= 1 that divides the 400 "):
        solve_minimum_energy(start, 12.0, **LIMITS, pad_to=200, stage=3)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^stage=2 is invalid: .*\(1 with response\)$"):
        solve_minimum_energy(start, 9.0, **LIMITS, stage=2, pad_to=2, response=(0, 0, 1, 0))  # type: ignore[arg-type]


@pytest.mark.skipif(not ca.has_nlpsol("fatrop"), reason="this CasADi ships no fatrop")
def test_fatrop_finds_ipopts_plan_in_the_callers_layout() -> None:
    """fatrop sees the unknowns in stage order; the plan it returns is IPOPT's, in the states-then-commands layout."""
    start = (-1.2, 0.7, 2.5)
    ipopt = solve_minimum_energy(start, 10.0, **LIMITS, solver="ipopt")  # type: ignore[arg-type]
    fatrop = solve_minimum_energy(start, 10.0, **LIMITS, solver="fatrop")  # type: ignore[arg-type]
    assert fatrop.energy == pytest.approx(ipopt.energy, rel=1e-8)
    np.testing.assert_allclose(fatrop.states, ipopt.states, atol=1e-5)
    np.testing.assert_allclose(fatrop.commands, ipopt.commands, atol=1e-5)


@pytest.mark.slow
@pytest.mark.own_process
def test_the_optima_solved_as_ray_tasks_on_a_local_cluster_are_the_local_processes(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``--address`` solves the optima as Ray tasks (here a cluster started for the test): the same energies, cached."""
    pytest.importorskip("ray")
    from dwr_gym.params import EnvParams

    monkeypatch.setenv("RAY_raylet_start_wait_time_s", "300")  # a loaded machine starts Ray slowly
    scenario = make_scenario("random", n=4, seed=11, env_kwargs={"T_con": 10.0})
    params = EnvParams(T_con=10.0)
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / "ray"))
    on_ray, _ = optimum_module.optimal_energies(params, scenario.starts, scenario.goals, address="local")
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / "local"))
    local, _ = optimum_module.optimal_energies(params, scenario.starts, scenario.goals, workers=1)
    np.testing.assert_array_equal(on_ray, local)
    (cached,) = (tmp_path / "ray").glob("optimal-energy-*.json")
    assert len(json.loads(cached.read_text())) == 4


def test_missing_optima_are_what_optimal_energies_solves_and_nothing_once_cached(
    monkeypatch: pytest.MonkeyPatch, tmp_path: object
) -> None:
    """A command sums the optima its sets will solve from ``missing_optima``: before solving, every episode (once per
    start and T_con, pose and position apart); after, none; starts given in float32 are the same episodes."""
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    monkeypatch.setattr(optimum_module, "_solve_energies", energies_one_by_one(lambda job: 1.0))
    scenario = make_scenario("random", n=4, seed=8)
    params = dwr_gym.EnvParams(**scenario.env_kwargs)
    goals = np.array([[0.3, -0.7, 1.1], [-1.2, 0.4, -2.5], [0.0, 0.0, 0.0], [2.0, 1.0, 0.3]])
    before = optimum_module.missing_optima(params, scenario.starts, goals)
    assert len(before) == 4
    assert len(optimum_module.missing_optima(params, scenario.starts, goals, heading=False)) == 4
    optimum_module.optimal_energies(params, scenario.starts, goals, workers=1)
    assert optimum_module.missing_optima(params, scenario.starts, goals) == set()
    assert len(optimum_module.missing_optima(params, scenario.starts, goals, heading=False)) == 4
    starts32, goals32 = scenario.starts.astype(np.float32), goals.astype(np.float32)
    optimum_module.optimal_energies(params, starts32.astype(np.float64), goals32.astype(np.float64), workers=1)
    assert optimum_module.missing_optima(params, starts32, goals32) == set()


def test_optima_are_solved_as_batches_on_the_threads_asked_for_with_a_bar_counting_the_plans(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Locally a batch of optima is solved at once on ``workers`` threads; with ``address`` on the Ray cluster's
    workers instead, each an even share; the progress bar names the work and counts its plans."""
    from train.evaluation import ray_pool

    made: list[tuple[object, ...]] = []

    class Pool:  # solves in this process, recording how it was made and used
        workers = 3

        def __init__(self, *args: object, **kwargs: object) -> None:
            made.append(args)

        def map(self, function: object, jobs: object, chunksize: int = 1) -> object:
            made.append(("chunksize", chunksize))
            return map(function, jobs)  # type: ignore[call-overload]

        def shutdown(self, **kwargs: object) -> None:
            pass

    def batch(jobs: list[object], workers: int) -> list[float | str]:
        made.append(("batch", len(jobs), workers))
        return [1.0] * len(jobs)

    monkeypatch.setattr(ray_pool, "RayPool", Pool)
    monkeypatch.setattr(optimum_module, "_solve_energies", batch)
    scenario = make_scenario("random", n=4, seed=9)
    params = dwr_gym.EnvParams(**scenario.env_kwargs)
    for case, kwargs in (("threads", {"workers": 2}), ("ray", {"address": "auto"})):
        monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / case))
        made.clear()
        energies, _ = optimum_module.optimal_energies(params, scenario.starts, scenario.goals, progress=True,
                                                      description=f"optimum ({case})", **kwargs)  # fmt: skip
        assert energies.tolist() == [1.0] * 4
        if case == "ray":  # 4 plans on its 3 workers: 2, 2, each a batch of one
            assert made == [("auto",), ("chunksize", 2), ("batch", 1, 1), ("batch", 1, 1), ("batch", 1, 1),
                            ("batch", 1, 1)]  # fmt: skip
        else:
            assert made == [("batch", 4, 2)]
        err = capsys.readouterr().err
        assert f"optimum ({case})" in err and "/4" in err and "plan" in err


def test_optima_are_cached_in_the_users_cache_folder_unless_dwr_gym_cache_names_another(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.delenv("DWR_GYM_CACHE", raising=False)
    assert optimum_module.cache_dir() == tmp_path / ".cache" / "dwr-gym"
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path / "elsewhere"))
    assert optimum_module.cache_dir() == tmp_path / "elsewhere"
