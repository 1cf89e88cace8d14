"""Stand-ins for the batch solvers that tests monkeypatch: a function of one job run over a batch, in order."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from baselines.optimal import InfeasibleArrivalTimeError, OptimalControlError, Plan


def plans_one_by_one(solve: Callable[..., Plan]) -> Callable[..., list[Plan | Exception]]:
    """A stand-in of :func:`baselines.optimal.solve_plans` (as ``baselines.nmpc.solve_plans``) that calls
    ``solve(**job)`` for each job, its planning error returned as the batch returns it."""

    def solve_plans(jobs: list[dict[str, Any]], workers: int = 1) -> list[Plan | Exception]:
        results: list[Plan | Exception] = []
        for job in jobs:
            try:
                results.append(solve(**job))
            except (OptimalControlError, InfeasibleArrivalTimeError) as error:
                results.append(error)
        return results

    return solve_plans


def energies_one_by_one(solve: Callable[[Any], float | str]) -> Callable[..., list[float | str]]:
    """A stand-in of ``train.evaluation.optimum._solve_energies`` that calls ``solve(job)`` for each job."""

    def solve_energies(jobs: list[Any], workers: int = 1) -> list[float | str]:
        return [solve(job) for job in jobs]

    return solve_energies
