"""The benchmark's goals for learned agents, defined once: what an agent must reach on the task to count as solving it.

Each goal is three figures over the benchmark's nominal evaluation set (the IQM over at least five seeds): the share
of episodes in time, the mean energy against the optimum's on the same episode (E/opt), and the final heading error.
The docs' goals tables (``dwr-gym benchmark``, docs/rl-benchmark.md and docs/rl-v2.md) and the measurements that
size a goal (:mod:`train.evaluation.energy_split`, :mod:`train.evaluation.open_loop`) read them from here.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Goal:
    """A goal of the benchmark: in time at least ``in_time``, E/opt at most ``energy_ratio``, the final heading error
    at most ``final_heading`` [rad]."""

    name: str
    in_time: float
    energy_ratio: float
    final_heading: float

    def __str__(self) -> str:
        return (f"{self.name}: in time >= {self.in_time:.1%}, E/opt <= {self.energy_ratio:g}, final heading <= "
                f"{self.final_heading:g} rad")  # fmt: skip


#: A network learned from the reward alone: the task as the optimum solves it, within half its energy again.
FROM_REWARD = Goal("from the reward alone", in_time=0.99, energy_ratio=1.5, final_heading=0.1)
#: A residual learned on PTC: PTC's deadline kept, at less energy than PTC's own.
RESIDUAL_ON_PTC = Goal("residual RL on PTC", in_time=0.995, energy_ratio=1.6, final_heading=0.15)
#: The benchmark's goals, in the order its tables list them.
GOALS: tuple[Goal, ...] = (FROM_REWARD, RESIDUAL_ON_PTC)

__all__ = ["FROM_REWARD", "GOALS", "RESIDUAL_ON_PTC", "Goal"]
