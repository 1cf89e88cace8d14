"""One progress bar across every stage of a command, and the time each stage took.

``compare`` and ``evaluate`` run in stages: the optimum of the scenario sets (CasADi solves, cached), then each
policy on each set. :class:`StageClock` shows one bar for all of them, counted in seconds of work, so that its time
left spans every stage to come, and it records the wall time of each stage for the results (``seconds`` and
``optimum_seconds`` of each row) and the closing line (:meth:`summary`).

The bar shows the share of the work done, wall seconds so far against those and the estimate of those to come,
and never goes back (an estimate that grows holds it where it is), beside the time left itself. Each stage to come is
:func:`estimated_seconds`, corrected by the ratio of wall to estimated seconds of the policy's stages that ended (a
planner takes minutes where its plans must be solved and seconds where :mod:`baselines.plan_store` holds them), or of
every policy's until the policy has run (a planner's estimate is measured per set, cold where the plan store is
empty, warm where it holds plans); the stage running here goes at its own pace once a tenth of it is done after
its first step (a planner solves every robot's plan at its first step: a pace measured from the stage's start would
take the plans' minutes for the rate of the seconds of steps that follow). A
set whose stages run in two processes (the costliest planner here, the others also in a second one,
:mod:`train.evaluation.side_process`) takes the longer of this process's stages and half of all; the second
process's stages leave the estimate as they end there.
Where stderr is not a terminal (a redirected log) there is no bar: a plain line every tenth of the work instead,
never a carriage return.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, TextIO

#: Estimated wall seconds of one optimum solved on the two cores of a quiet machine (only the time left uses it).
PLAN_SECONDS = 0.25
#: Wall seconds per episode of each planner on each of compare's sets, measured on 2 cores with the other policies
#: run beside them (``dwr-gym compare``, 1,000 episodes a set, 50 of ``optimal`` on the disturbed ones): where its
#: plans are solved (COLD: no plan store yet, a first run) and where the plan store holds them (WARM). The ratio
#: of a machine's wall to these seconds is learned as the stages end; only the sets' proportions are taken from here.
COLD_EPISODE_SECONDS: dict[str, dict[str, float]] = {
    "robust-pt": {"random": 0.038, "disturbed": 0.020, "fault": 0.098, "delay": 0.024, "noise": 0.047},
    "optimal": {"random": 0.045, "disturbed": 0.50, "fault": 0.48, "delay": 0.23, "noise": 0.28},
    "robust": {"random": 0.014, "disturbed": 0.024, "fault": 0.032, "delay": 0.025, "noise": 0.020},
}
WARM_EPISODE_SECONDS: dict[str, dict[str, float]] = {
    "robust-pt": {"random": 0.0038, "disturbed": 0.0076, "fault": 0.011, "delay": 0.0072, "noise": 0.006},
    "optimal": {"random": 0.0024, "disturbed": 0.005, "fault": 0.005, "delay": 0.003, "noise": 0.003},
    "robust": {"random": 0.0073, "disturbed": 0.0074, "fault": 0.0074, "delay": 0.0074, "noise": 0.0074},
}
DEFAULT_EPISODE_SECONDS = 0.004
#: Estimated wall seconds of one step of a batch, whatever its size (a policy's call, the env's transition).
STEP_SECONDS = 5e-4
#: A redirected log gets a line each time this fraction of the work is done.
LOG_STEP = 0.1
#: The scenario name under which the recorded rollouts of the figures are timed (not a policy's evaluation).
FIGURES = "figures"
#: The estimated seconds of a policy's ended stages from which their ratio to the wall time corrects its stages to come.
CALIBRATE_AFTER = 0.5
#: The fraction of a running stage, after its first step, from which its own pace tells the rest of it.
EXTRAPOLATE_AFTER = 0.1
#: The bar counts the share of the work done in these units (a thousandth: a percentage with a decimal to spare).
BAR_UNITS = 1000
#: Seconds between redraws of a bar whose share done is held (the estimate grew): its clock and time left still move.
REDRAW_HELD = 0.5


def estimated_seconds(policy: str, episodes: int, steps: int, scenario: str = "random", cold: bool = False) -> float:
    """An estimate of the wall seconds of ``policy`` run on ``episodes`` episodes of at most ``steps`` steps of the set
    ``scenario``: a cost per step of the batch, and one per episode (a planner's as measured on that set, solving its
    plans where ``cold``, else taking them from the plan store; on a set not measured, as on ``random``)."""
    by_set = (COLD_EPISODE_SECONDS if cold else WARM_EPISODE_SECONDS).get(policy)
    per_episode = DEFAULT_EPISODE_SECONDS if by_set is None else by_set.get(scenario, by_set["random"])
    return STEP_SECONDS * steps + per_episode * episodes


@dataclass(frozen=True)
class StageTime:
    """The wall time of one stage: the optimum of a scenario set, or a policy on it."""

    scenario: str
    stage: str  # "optimum" or a policy's label
    seconds: float
    size: int  # the plans solved, or the episodes run
    beside: bool = False  # ran in another process at the same time as this one's stages: not in the wall total


class StageClock:
    """One progress bar over stages, in wall seconds, and the wall time of each stage.

    :meth:`plan` adds the estimates of the stages to come (before they run, so that the time left spans them all);
    :meth:`stage` runs one here, reporting its progress as it goes; :meth:`record` counts one that ran in another
    process. The bar shows the wall seconds so far against those and :meth:`left`.
    """

    def __init__(self, progress: bool = True, description: str = "compare", file: TextIO | None = None):
        self.times: list[StageTime] = []
        self.began = time.perf_counter()
        self._file = file or sys.stderr
        self._done = 0.0  # wall seconds since the start, as the bar shows them
        self._waited = 0.0  # for stages of another process, after this one's own
        self._total = 0.0
        self._planned: dict[tuple[str, str], list[float]] = {}  # estimates of the stages to come, by (scenario, name)
        self._unnamed = 0.0  # estimated seconds planned without a stage's name, not run yet
        self._took: dict[tuple[str, str], list[float]] = {}  # by (name, group): [wall s, estimated s] of those ended
        self._groups: dict[str, str] = {}  # scenario -> the group a policy's pace is learned in (plan's groups)
        self._running: _Running | None = None  # the stage running here
        self._ratios: dict[tuple[str, str], float] = {}  # ratio() by (name, group), worked out again as a stage ends
        self._beside: set[str] = set()  # the names of the stages run in a second process (plan's beside)
        self._left_unnamed = 0.0  # the corrected estimates of the stages not run yet: without names,
        self._left_here: dict[str, float] = {}  # by set, of those run here,
        self._left_beside: dict[str, float] = {}  # and of those run in the second process
        self._logged = 0  # tenths of the work already written to a redirected log
        self._shown = 0.0  # the share of the work shown done: never less than before
        self._drawn = 0.0  # when a held bar was last redrawn
        self._description = description
        self._bar: Any = None
        self._log = progress and not self._file.isatty()
        if progress and not self._log:
            from train.progress import Progress

            self._bar = Progress(total=BAR_UNITS, desc=description, file=self._file, fields={"label": "", "left": "?"},
                                 bar_format="{desc}: {percentage:3.0f}%|{bar}| {label} [{elapsed}<{left}]")  # fmt: skip

    @property
    def shown(self) -> bool:
        """Whether the clock shows the progress (a bar, or lines in a redirected log)."""
        return self._bar is not None or self._log

    def plan(
        self,
        weight: float | Iterable[tuple[tuple[str, str], float]],
        beside: Iterable[str] = (),
        groups: Mapping[str, str] | None = None,
    ) -> None:
        """Add stages to come to the bar's total: ((scenario, stage name), estimated seconds) of each, in the order
        they run (each corrected by what its policy's stages took so far), or one estimate for stages without names.
        ``beside``: the names of the stages that run in a second process while this one runs the others of their set
        (the set then takes the longer of this process's stages and half of all). ``groups``: a group for some
        scenarios (e.g. "disturbed"): a policy's pace is learned in each group apart (:meth:`ratio`)."""
        if isinstance(weight, (int, float)):
            self._unnamed += float(weight)
        else:
            for key, seconds in weight:
                self._planned.setdefault(key, []).append(float(seconds))
        self._beside |= set(beside)
        self._groups.update(groups or {})
        self._correct()
        self._move()
        if self._bar is not None:
            self._bar.refresh()

    @contextmanager
    def stage(self, scenario: str, name: str, weight: float, size: int) -> Iterator[Callable[[float], None]]:
        """Run a stage estimated at ``weight`` seconds (planned before under its scenario and name, or not); yields
        ``advance(fraction)``, the fraction of the stage done so far (0 to 1). Its wall time is recorded even when
        it is interrupted."""
        began = time.perf_counter()
        estimate = self._take(scenario, name, weight)
        self._correct()
        running = self._running = _Running(scenario, name, estimate, began)
        self._label(f"{scenario}: {name}")

        def advance(fraction: float) -> None:
            running.fraction = min(max(fraction, 0.0), 1.0)
            if running.first is None and running.fraction > 0.0:  # its first step: a planner's plans in it
                running.first = (time.perf_counter(), running.fraction)
            self._move()

        try:
            yield advance
        finally:
            seconds = time.perf_counter() - began
            self.times.append(StageTime(scenario, name, seconds, size))
            self._running = None
            self._ended(scenario, name, seconds, estimate)
        self._move()

    def record(self, scenario: str, name: str, seconds: float, size: int, weight: float, waited: float = 0.0) -> None:
        """A stage that ran elsewhere (another process, beside this one's), estimated at ``weight`` seconds: its wall
        time, done; ``waited``, the wall seconds this process waited for them after its own stages (a policies'
        time)."""
        self._waited += waited
        self.times.append(StageTime(scenario, name, seconds, size, beside=True))
        self._ended(scenario, name, seconds, self._take(scenario, name, weight))
        self._move()

    def left(self, now: float | None = None) -> float:
        """The wall seconds to come: the stages not run yet, each estimate corrected by :meth:`ratio`, and the rest of
        the stage running here (at its own pace since its first step once a tenth of it is done after that step, else
        its corrected estimate's share); a set whose stages run in two processes takes the longer of this process's and
        half of all."""
        here = dict(self._left_here)
        if self._running is not None:
            stage = self._running
            now = time.perf_counter() if now is None else now
            rest = (1.0 - stage.fraction) * stage.estimate * self.ratio(stage.name, stage.scenario)
            if stage.first is not None and stage.fraction - stage.first[1] >= EXTRAPOLATE_AFTER:
                since, at = stage.first
                rest = (1.0 - stage.fraction) * (now - since) / (stage.fraction - at)
            here[stage.scenario] = here.get(stage.scenario, 0.0) + max(rest, 0.0)
        left = self._left_unnamed
        for scenario in here.keys() | self._left_beside.keys():
            mine, theirs = here.get(scenario, 0.0), self._left_beside.get(scenario, 0.0)
            left += max(mine, (mine + theirs) / 2.0)
        return left

    def ratio(self, name: str, scenario: str = "") -> float:
        """Wall seconds per estimated second of the stages of ``name`` that ended in the group of ``scenario``; until
        they reach :data:`CALIBRATE_AFTER` estimated seconds, the same of ``name``'s stages in every group, then of
        every policy's stages (1 before any)."""
        group = self._groups.get(scenario, "")
        if (name, group) in self._ratios:
            return self._ratios[name, group]
        ratio = 1.0
        for took in (
            [t for (stage, _), t in self._took.items() if stage != "optimum"],
            [t for (stage, _), t in self._took.items() if stage == name],
            [t for (stage, in_group), t in self._took.items() if stage == name and in_group == group],
        ):  # the narrowest with enough estimated seconds
            seconds, estimate = sum(t[0] for t in took), sum(t[1] for t in took)
            if estimate >= CALIBRATE_AFTER:
                ratio = seconds / estimate
        self._ratios[name, group] = ratio
        return ratio

    def _correct(self) -> None:
        """Work out the ratios and the corrected estimates of the stages to come again (a stage ended or was added)."""
        self._ratios.clear()
        self._left_unnamed = self._unnamed * self.ratio("")
        self._left_here, self._left_beside = {}, {}
        for (scenario, name), estimates in self._planned.items():
            lane = self._left_beside if name in self._beside else self._left_here
            lane[scenario] = lane.get(scenario, 0.0) + sum(estimates) * self.ratio(name, scenario)

    def _take(self, scenario: str, name: str, weight: float) -> float:
        """The estimate of a stage that starts (or ended elsewhere): the one planned under its scenario and name, else
        ``weight`` (taken out of the estimates planned without names); :meth:`_correct` follows."""
        planned = self._planned.get((scenario, name))
        if planned:
            estimate = planned.pop(0)
            if not planned:
                del self._planned[(scenario, name)]
        else:
            estimate, self._unnamed = weight, max(self._unnamed - weight, 0.0)
        return estimate

    def _ended(self, scenario: str, name: str, seconds: float, estimate: float) -> None:
        took = self._took.setdefault((name, self._groups.get(scenario, "")), [0.0, 0.0])
        took[0] += seconds
        took[1] += estimate
        self._correct()

    def _label(self, text: str) -> None:
        if self._bar is not None:
            self._bar.fields["label"] = text

    @property
    def fraction(self) -> float:
        """The share of the work the bar shows done: wall seconds so far against those and :meth:`left`, never less
        than it showed before."""
        return self._shown

    def _move(self) -> None:
        """The share of the work done and the time left (:meth:`left`), on the bar or in a redirected log."""
        if not self.shown:
            return
        now = time.perf_counter()
        done = now - self.began
        left = self.left(now)
        self._done, self._total = done, done + left
        if self._total > 0.0:
            self._shown = max(self._shown, min(done / self._total, 1.0))  # an estimate that grows holds the bar
        if self._bar is not None:
            self._bar.fields["left"] = self._bar.format_interval(left)
            step = round(self._shown * BAR_UNITS) - self._bar.n
            if step > 0:
                self._bar.update(step)  # redrawn at most every tenth of a second (tqdm's mininterval)
            elif now - self._drawn >= REDRAW_HELD:  # a bar held where it is: its elapsed and time left still move
                self._bar.refresh()
                self._drawn = now
        tenths = int(self._shown / LOG_STEP + 1e-9)
        if self._log and tenths > self._logged:
            self._logged = tenths
            print(f"{self._description}: {100 * self._shown:.0f}% after {format_seconds(done)}, "
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
        """One line: the total, the optimum (plans, plans/s; "cached" where every one was; nothing where none was
        asked for), the policies (the slowest three named), the rest."""
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
        elif optimum:  # the optimum's stages ran, and found every plan in the cache
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


@dataclass
class _Running:
    """The stage running here: its estimate, its start, the fraction done, and when its first step ended."""

    scenario: str
    name: str
    estimate: float
    began: float
    fraction: float = 0.0
    first: tuple[float, float] | None = None  # (time, fraction) at the end of its first step


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
