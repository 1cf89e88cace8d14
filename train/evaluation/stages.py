"""One progress bar across every stage of a command, and the time each stage took.

``compare`` and ``evaluate`` run in stages: the optimum of the scenario sets (CasADi solves, cached), then each
policy on each set. :class:`StageClock` shows one bar for all of them, counted in estimated seconds of work
(:func:`estimated_seconds`), so that its time left spans every stage to come, and it records the wall time of each
stage for the results (``seconds`` and ``optimum_seconds`` of each row) and the closing line (:meth:`summary`).
Where stderr is not a terminal (a redirected log) there is no bar: a plain line every tenth of the work instead,
never a carriage return.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, TextIO

#: Estimated wall seconds of one optimum solved on the two cores of a quiet machine (only the time left uses it).
PLAN_SECONDS = 0.25
#: Estimated wall seconds per episode of each policy (the planners re-plan with CasADi); others: DEFAULT_EPISODE_SECONDS.
EPISODE_SECONDS = {"optimal": 0.6, "robust-pt": 0.08, "robust": 0.02}
DEFAULT_EPISODE_SECONDS = 0.004
#: Estimated wall seconds of one step of a batch, whatever its size (a policy's call, the env's transition).
STEP_SECONDS = 5e-4
#: A redirected log gets a line each time this fraction of the work is done.
LOG_STEP = 0.1
#: The scenario name under which the recorded rollouts of the figures are timed (not a policy's evaluation).
FIGURES = "figures"


def estimated_seconds(policy: str, episodes: int, steps: int) -> float:
    """The share of the bar of ``policy`` run on ``episodes`` episodes of at most ``steps`` steps: an estimate of its
    wall seconds (a cost per step of the batch, and one per episode)."""
    return STEP_SECONDS * steps + EPISODE_SECONDS.get(policy, DEFAULT_EPISODE_SECONDS) * episodes


@dataclass(frozen=True)
class StageTime:
    """The wall time of one stage: the optimum of a scenario set, or a policy on it."""

    scenario: str
    stage: str  # "optimum" or a policy's label
    seconds: float
    size: int  # the plans solved, or the episodes run
    beside: bool = False  # ran in another process at the same time as this one's stages: not in the wall total


class StageClock:
    """One progress bar over stages of estimated weights (seconds), and the wall time of each stage.

    :meth:`plan` adds the weights of the stages to come (before they run, so that the time left spans them all);
    :meth:`stage` runs one and advances the bar by its weight, in parts as the stage reports its progress.
    """

    def __init__(self, progress: bool = True, description: str = "compare", file: TextIO | None = None):
        self.times: list[StageTime] = []
        self.began = time.perf_counter()
        self._file = file or sys.stderr
        self._done = 0.0
        self._waited = 0.0  # for stages of another process, after this one's own
        self._total = 0.0
        self._logged = 0  # tenths of the work already written to a redirected log
        self._description = description
        self._bar: Any = None
        self._log = progress and not self._file.isatty()
        if progress and not self._log:
            from train.progress import Progress

            self._bar = Progress(total=0.0, desc=description, unit="s of work", file=self._file,
                                 bar_format="{desc}: {percentage:3.0f}%|{bar}| {postfix} [{elapsed}<{remaining}]")  # fmt: skip

    @property
    def shown(self) -> bool:
        """Whether the clock shows the progress (a bar, or lines in a redirected log)."""
        return self._bar is not None or self._log

    def plan(self, weight: float) -> None:
        """Add ``weight`` (estimated seconds) of stages to come to the bar's total."""
        self._total += weight
        if self._bar is not None:
            self._bar.total = round(self._total, 1)
            self._bar.refresh()

    @contextmanager
    def stage(self, scenario: str, name: str, weight: float, size: int) -> Iterator[Callable[[float], None]]:
        """Run a stage of ``weight`` (its share of the bar); yields ``advance(fraction)``, the fraction of the stage
        done so far (0 to 1). Its wall time is recorded even when it is interrupted."""
        began, start = time.perf_counter(), self._done
        self._label(f"{scenario}: {name}")

        def advance(fraction: float) -> None:
            self._move(start + weight * min(max(fraction, 0.0), 1.0))

        try:
            yield advance
        finally:
            self.times.append(StageTime(scenario, name, time.perf_counter() - began, size))
        self._move(start + weight)

    def record(self, scenario: str, name: str, seconds: float, size: int, weight: float, waited: float = 0.0) -> None:
        """A stage that ran elsewhere (another process, beside this one's): its wall time, and its share of the bar,
        done; ``waited``, the wall seconds this process waited for it after its own stages (a policies' time)."""
        self._waited += waited
        self.times.append(StageTime(scenario, name, seconds, size, beside=True))
        self._move(self._done + weight)

    def _label(self, text: str) -> None:
        if self._bar is not None:
            self._bar.set_postfix_str(text, refresh=False)

    def _move(self, done: float) -> None:
        done = min(done, self._total)
        if self._total <= 0.0:
            return
        if self._bar is not None and done > self._done:
            self._bar.update(round(done, 1) - round(self._done, 1))
        self._done = max(done, self._done)
        tenths = int(self._done / self._total / LOG_STEP + 1e-9)
        if self._log and tenths > self._logged:
            self._logged = tenths
            elapsed = time.perf_counter() - self.began
            left = elapsed * (self._total - self._done) / self._done if self._done > 0 else float("nan")
            print(f"{self._description}: {100 * self._done / self._total:.0f}% after {format_seconds(elapsed)}, "
                  f"about {format_seconds(left)} left", file=self._file, flush=True)  # fmt: skip

    def close(self) -> None:
        """Remove the bar (the stages' times stay)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def seconds(self, scenario: str, stage: str) -> float:
        """The wall seconds of the stages ``stage`` of ``scenario`` so far."""
        return sum(t.seconds for t in self.times if t.scenario == scenario and t.stage == stage)

    def summary(self) -> str:
        """One line: the total, the optimum (plans, plans/s), the policies (the slowest three named), the rest."""
        total = time.perf_counter() - self.began
        optimum = [t for t in self.times if t.stage == "optimum"]
        policies = [t for t in self.times if t.stage != "optimum" and t.scenario != FIGURES]
        waited = self._waited + sum(t.seconds for t in policies if not t.beside)  # the policies' wall time
        other = total - sum(t.seconds for t in optimum) - waited
        parts = []
        solved = sum(t.size for t in optimum)
        optimum_seconds = sum(t.seconds for t in optimum)
        if solved:
            parts.append(f"optimum {format_seconds(optimum_seconds)} ({solved:,} plans, "
                         f"{solved / max(optimum_seconds, 1e-9):.1f}/s)")  # fmt: skip
        else:
            parts.append("optimum cached")
        by_policy: dict[str, float] = {}
        for t in policies:
            by_policy[t.stage] = by_policy.get(t.stage, 0.0) + t.seconds
        slowest = sorted(by_policy.items(), key=lambda item: -item[1])[:3]
        named = ", ".join(f"{name} {format_seconds(seconds)}" for name, seconds in slowest)
        beside = " each; some in another process" if any(t.beside for t in policies) else ""
        parts.append(f"policies {format_seconds(waited)} ({named}{', ...' if len(by_policy) > 3 else ''}{beside})")
        parts.append(f"the rest (loading, figures, files) {format_seconds(other)}")
        return f"time: {format_seconds(total)}: " + "; ".join(parts)


def format_seconds(seconds: float) -> str:
    """``42 s``, ``3.5 min``, ``1.2 h``; ``?`` when unknown."""
    if seconds != seconds:  # NaN: no work done yet
        return "?"
    if seconds < 100:
        return f"{seconds:.0f} s"
    if seconds < 6000:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


__all__ = ["FIGURES", "StageClock", "StageTime", "estimated_seconds", "format_seconds"]
