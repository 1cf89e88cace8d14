"""The constraint's log in a run directory, shared by the Lagrangian learners (APG:
:mod:`train.learning.jitted.apg_trainer`; the jitted PPO: :mod:`train.learning.jitted.trainer`): per T_con bin of
:mod:`train.learning.jitted.lagrangian`, the violation rate, the mean final heading error, the energy and the
multipliers."""

from __future__ import annotations

from pathlib import Path
from typing import Any

#: The constraint's log in the run directory: per T_con bin, its violation rate, multipliers and energy.
CONSTRAINT_FILE = "constraint.csv"
#: APG's updates averaged into one row of the constraint's log.
CONSTRAINT_LOG_EVERY = 25


class ConstraintLog:
    """The constraint's log (:data:`CONSTRAINT_FILE`): a row per ``every`` additions (APG: :data:`CONSTRAINT_LOG_EVERY`
    updates; the jitted PPO: one chunk of updates) and T_con bin, the violation rate, the mean final heading error and
    energy over those updates' episodes, and the multipliers at the last of them. A resumed run's rows past its
    checkpoint are dropped first, so the log stays monotonic."""

    FIELDS = ("timesteps", "T_con_low", "T_con_high", "episodes", "violation_rate", "heading", "energy",
              "deadline_multiplier", "heading_multiplier")  # fmt: skip

    def __init__(self, path: Path, T_con_range: Any, steps: int, every: int = CONSTRAINT_LOG_EVERY) -> None:
        import csv

        from train.learning.runs import truncate_log

        self.path, self.every = path, every
        self.low, self.high = (float(bound) for bound in T_con_range)
        truncate_log(path, steps)
        if not path.exists():
            with path.open("w", newline="") as handle:
                csv.writer(handle).writerow(self.FIELDS)
        self.pending: list[dict[str, Any]] = []

    def add(self, metrics: dict[str, Any], steps: int) -> None:
        """One update's (or chunk's) metrics, arrays (bins,): ``episodes`` and the means over them of
        ``violation_rate``, ``heading`` and ``energy``, and the multipliers; every ``every`` additions their summary
        is appended."""
        import numpy as np

        self.pending.append({key: np.asarray(metrics[key]) for key in self.FIELDS[3:]})
        if len(self.pending) >= self.every:
            self.flush(steps)

    def flush(self, steps: int) -> None:
        """Append the summary of the additions not yet logged (none: nothing); APG calls it at the end of each chunk
        of updates (an evaluation, a checkpoint, the run's end), so that a run resumed there logs as one that was not
        stopped."""
        if not self.pending:
            return
        import csv

        import numpy as np

        counts = np.sum([m["episodes"] for m in self.pending], axis=0)
        weight = np.maximum(counts, 1.0)

        def mean(key: str) -> Any:
            return np.sum([m[key] * m["episodes"] for m in self.pending], axis=0) / weight

        rate, heading, energy = mean("violation_rate"), mean("heading"), mean("energy")
        last = self.pending[-1]
        edges = np.linspace(self.low, self.high, len(counts) + 1)
        with self.path.open("a", newline="") as handle:
            writer = csv.writer(handle)
            for b in range(len(counts)):
                writer.writerow([steps, f"{edges[b]:g}", f"{edges[b + 1]:g}", int(counts[b]), f"{rate[b]:.4f}",
                                 f"{heading[b]:.4f}", f"{energy[b]:.4f}", f"{last['deadline_multiplier'][b]:.4f}",
                                 f"{last['heading_multiplier'][b]:.4f}"])  # fmt: skip
        self.pending = []


__all__ = ["CONSTRAINT_FILE", "CONSTRAINT_LOG_EVERY", "ConstraintLog"]
