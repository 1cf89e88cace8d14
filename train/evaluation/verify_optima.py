"""``dwr-gym optimum verify``: every shipped optimum (:mod:`train.evaluation.shipped_optima`) solved again and
compared, so that the cache a fresh clone reads is a checked one."""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from train.evaluation.optimum import EnergyJob, solve_uncached
from train.evaluation.shipped_optima import read_shipped, shipped_files

#: Shipped and re-solved energies agree to this relative difference by default (a plan's tolerance, docs/controllers.md).
RTOL = 1e-6


@dataclass
class Verification:
    """What ``verify_shipped`` found: the plans solved again, the largest relative difference, the mismatches."""

    checked: int = 0
    largest: float = 0.0
    mismatches: list[str] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    #: The optima the batched search (the cheapest coarse plan refined) missed by more than the tolerance and the whole
    #: fine search (every guess on the fine grid) reproduced: both energies.
    whole_search: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.mismatches


def relative_difference(shipped: float, solved: float | str) -> float:
    """|solved - shipped| / max(|shipped|, 1e-12); inf where the re-solve failed."""
    if not isinstance(solved, float) or not math.isfinite(solved):
        return math.inf
    return abs(solved - shipped) / max(abs(shipped), 1e-12)


def verify_shipped(
    sample: int = 0,
    seed: int = 0,
    rtol: float = RTOL,
    workers: int = 0,
    files: list[Path] | None = None,
    on_solved: Callable[[int, int], None] | None = None,
) -> Verification:
    """Solve the shipped optima again (all, or a seeded random ``sample`` of each file) and compare each energy with
    the shipped one to ``rtol``: as ``dwr-gym compare`` solves an optimum (the batch), and where that misses by more
    than ``rtol``, by the whole fine search, which must then agree. ``report.largest`` is the largest difference of
    the energy that decided. ``on_solved`` receives (solved so far, to solve) for the batch."""
    if sample < 0:
        raise ValueError(f"sample={sample} is invalid: expected an integer >= 0 (0: every shipped optimum)")
    if not (rtol > 0 and math.isfinite(rtol)):
        raise ValueError(f"rtol={rtol} is invalid: expected a finite number > 0")
    report = Verification()
    chosen = []
    for path in shipped_files() if files is None else files:
        problem, energies = read_shipped(path)
        keys = sorted(energies)
        if sample:
            keys = sorted(random.Random(seed).sample(keys, min(sample, len(keys))))
        chosen.append((path, problem, energies, keys))
        report.files.append(path.name)
    total = sum(len(keys) for *_, keys in chosen)
    for path, problem, energies, keys in chosen:
        jobs = []
        for key in keys:
            x, y, psi, T_con = map(float, key.split(","))
            jobs.append(((x, y, psi), T_con, problem["dt"], problem["u_max"], problem["omega_max"], problem["heading"]))
        done = report.checked
        progress = None if on_solved is None else (lambda n, done=done: on_solved(done + n, total))
        missed: dict[str, tuple[EnergyJob, float | str]] = {}
        for key, job, solved in zip(keys, jobs, solve_uncached(jobs, workers, progress), strict=True):
            difference = relative_difference(energies[key], solved)
            if difference > rtol:
                missed[key] = (job, solved)
            else:
                report.largest = max(report.largest, difference)
        # The batched search refines the cheapest coarse plan: on a few optima it stops at fatrop's own tolerance, 1e-6
        # above (docs/results.md); the whole fine search decides whether the shipped energy is right.
        whole = solve_uncached([job for job, _ in missed.values()], workers, coarse=1) if missed else []
        for (key, (_, batched)), solved in zip(missed.items(), whole, strict=True):
            difference = relative_difference(energies[key], solved)
            report.largest = max(report.largest, difference)
            line = f"{path.name} {key}: shipped {energies[key]:.12g}, batched search {batched}, whole search {solved}"
            (report.mismatches if difference > rtol else report.whole_search).append(line)
        report.checked += len(keys)
    return report


__all__ = ["RTOL", "Verification", "relative_difference", "verify_shipped"]
