"""The deadline as a constraint: Lagrange multipliers per T_con bin, updated in PID form from measured violations.

The task is a constrained MDP (the env's ``info["cost"]``, docs/environment.md): the least energy (v2's return),
subject to a violation rate of at most ``cost_budget`` at every T_con, and a mean final heading error of at most
``heading_budget``. A Lagrangian learner maximises

    return - sum over constraints of lambda_c(T_con) * smooth violation_c

and moves each multiplier by the measured violation of its constraint against its budget: up while violated, down
(to 0, never below) when met. The multipliers are per T_con bin, ``multiplier_bins`` equal bins of the env's T_con
range, because the short deadlines are the hard ones: one multiplier over the range is held low by the long
deadlines, which keep the constraint easily, while the short ones violate it (the per-T_con tables of the learners
without a constraint: docs/rl-constrained.md).

The update is the PID Lagrangian of Stooke, Achiam and Abbeel (ICML 2020): lambda = max(0, K_p e + K_i I + K_d
max(0, de)), with e the measured violation minus the budget, I its sum (held at 0 or above), the proportional and
derivative terms on an exponential average of e; the proportional term damps the integral's oscillation. Everything
here is a pure function of arrays (jax.numpy or numpy), the multipliers' state a pytree that a run saves and resumes
bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

from dwr_gym.validation import as_float, as_int

#: YAML keys of the constraint (beside a learner's own), with their defaults.
LAGRANGE_DEFAULTS: dict[str, Any] = {"lagrangian": 0, "cost_budget": 0.01, "heading_budget": 0.08,
                                     "multiplier_bins": 5, "multiplier_init": 10.0, "multiplier_max": 100.0,
                                     "pid_kp": 10.0, "pid_ki": 0.2, "pid_kd": 0.0, "pid_average": 0.9}  # fmt: skip
#: The constraints, in the order of the multipliers' first axis.
CONSTRAINTS: tuple[str, ...] = ("deadline", "heading")


@dataclass(frozen=True)
class LagrangeSettings:
    """The constraint's options, named as in the hyperparameter files."""

    lagrangian: bool = False
    """On: the deadline and the heading are constraints with multipliers (this module); off: the return alone."""
    cost_budget: float = 0.01
    """The share of episodes allowed to violate the deadline (``info["cost"]`` = 1), per T_con bin, in (0, 1)."""
    heading_budget: float = 0.08
    """[rad] The mean final heading error allowed, per T_con bin (the benchmark's goal is 0.1 rad: a margin)."""
    multiplier_bins: int = 5
    """The T_con bins, each with its own multipliers: equal widths over the env's T_con range (1: one for all)."""
    multiplier_init: float = 10.0
    """Each multiplier's value at the start (per metre of the distance, per radian of the heading error)."""
    multiplier_max: float = 100.0
    """The largest a multiplier gets, its integral held where the law gives this (anti-windup): a budget of 1 % is
    met below it by a margin of 0.01 an update, so an integral wound up while the policy could not keep it would take
    tens of thousands of updates to come down (measured: 1 an update at a violation rate of 0.7 wound a multiplier to
    580 in 300 updates)."""
    pid_kp: float = 10.0
    """The proportional gain on the (averaged) violation minus the budget."""
    pid_ki: float = 0.2
    """The integral gain: the multiplier's rise per update per unit of violation above the budget."""
    pid_kd: float = 0.0
    """The derivative gain on the averaged violation's rise (0: a PI controller)."""
    pid_average: float = 0.9
    """The exponential average's weight of the past for the proportional and derivative terms, in [0, 1)."""

    @classmethod
    def from_values(cls, values: dict[str, Any]) -> LagrangeSettings:
        """The settings of ``values`` (LAGRANGE_DEFAULTS' keys); a bad value is a ValueError naming the key."""
        return cls(
            lagrangian=bool(as_int("lagrangian", values["lagrangian"], 0, 1, text=True)),
            cost_budget=as_float("cost_budget", values["cost_budget"], 0.0, 1.0, low_inclusive=False,
                                 high_inclusive=False, text=True),
            heading_budget=as_float("heading_budget", values["heading_budget"], 0.0, 3.1416, low_inclusive=False,
                                    text=True),
            multiplier_bins=as_int("multiplier_bins", values["multiplier_bins"], 1, 100, text=True),
            multiplier_init=as_float("multiplier_init", values["multiplier_init"], 0.0, 1e6, text=True),
            multiplier_max=as_float("multiplier_max", values["multiplier_max"], 0.0, 1e6, low_inclusive=False,
                                    text=True),
            pid_kp=as_float("pid_kp", values["pid_kp"], 0.0, 1e6, text=True),
            pid_ki=as_float("pid_ki", values["pid_ki"], 0.0, 1e6, text=True),
            pid_kd=as_float("pid_kd", values["pid_kd"], 0.0, 1e6, text=True),
            pid_average=as_float("pid_average", values["pid_average"], 0.0, 1.0, high_inclusive=False, text=True),
        )  # fmt: skip

    def budgets(self, xp: Any) -> Any:
        """The budgets (2, 1) in the order of :data:`CONSTRAINTS`."""
        return xp.asarray([[self.cost_budget], [self.heading_budget]], dtype=xp.float32)


class Multipliers(NamedTuple):
    """The PID state of every multiplier, arrays (2, bins): constraints (:data:`CONSTRAINTS`) by T_con bins."""

    value: Any
    """The multipliers lambda (>= 0)."""
    integral: Any
    """The summed violation minus budget, held >= 0."""
    average: Any
    """The exponential average of the violation minus budget (the P and D terms' input)."""


def initial_multipliers(settings: LagrangeSettings, xp: Any) -> Multipliers:
    """Every multiplier at ``multiplier_init`` (its integral set so that the PID law gives it), averages at 0."""
    shape = (len(CONSTRAINTS), settings.multiplier_bins)
    value = xp.full(shape, settings.multiplier_init, dtype=xp.float32)
    value = xp.minimum(value, settings.multiplier_max)
    integral = value / settings.pid_ki if settings.pid_ki > 0 else xp.zeros(shape, dtype=xp.float32)
    return Multipliers(value, integral, xp.zeros(shape, dtype=xp.float32))


def T_con_bin(T_con: Any, T_con_range: tuple[Any, Any], bins: int, xp: Any) -> Any:
    """The bin (0 .. bins - 1) of each T_con in equal bins of ``T_con_range`` (the ends included in the outer bins)."""
    low, high = T_con_range
    width = xp.maximum(high - low, 1e-9)  # guard: a fixed T_con (low == high) is one bin
    return xp.clip(xp.floor((T_con - low) / width * bins), 0, bins - 1).astype(xp.int32)


def binned_means(values: Any, bin_index: Any, bins: int, xp: Any) -> tuple[Any, Any]:
    """(the mean of ``values`` (..., N) per bin (..., bins), the episodes per bin (bins,)); an empty bin's mean is 0."""
    one_hot = (bin_index[:, None] == xp.arange(bins)[None, :]).astype(xp.float32)  # (N, bins)
    counts = one_hot.sum(axis=0)
    sums = values @ one_hot
    return sums / xp.maximum(counts, 1.0), counts


def violations(cost: Any, heading: Any, bin_index: Any, settings: LagrangeSettings, xp: Any) -> tuple[Any, Any]:
    """The measured violations (2, bins) of a batch of episodes: each bin's share with a cost of 1 and its mean final
    heading error; and the episodes per bin (bins,)."""
    means, counts = binned_means(xp.stack([cost, xp.abs(heading)]).astype(xp.float32), bin_index,
                                 settings.multiplier_bins, xp)  # fmt: skip
    return means, counts


def pid_update(state: Multipliers, measured: Any, counts: Any, settings: LagrangeSettings, xp: Any) -> Multipliers:
    """The multipliers after one measurement ``measured`` (2, bins) of the violations; a bin with no episode
    (``counts`` 0) keeps its state. Never negative, NaN or inf: a non-finite measurement is ignored."""
    error = measured - settings.budgets(xp)
    seen = (counts > 0)[None, :] & xp.isfinite(error)
    error = xp.where(seen, error, 0.0)
    # anti-windup: the integral alone never asks for more than multiplier_max
    ceiling = settings.multiplier_max / settings.pid_ki if settings.pid_ki > 0 else 0.0
    integral = xp.where(seen, xp.clip(state.integral + error, 0.0, ceiling), state.integral)
    average = xp.where(seen, settings.pid_average * state.average + (1.0 - settings.pid_average) * error,
                       state.average)  # fmt: skip
    rise = xp.maximum(average - state.average, 0.0)
    value = settings.pid_kp * average + settings.pid_ki * integral + settings.pid_kd * rise
    value = xp.clip(xp.nan_to_num(value, nan=0.0, posinf=settings.multiplier_max), 0.0, settings.multiplier_max)
    return Multipliers(value.astype(xp.float32), integral.astype(xp.float32), average.astype(xp.float32))


__all__ = [
    "CONSTRAINTS",
    "LAGRANGE_DEFAULTS",
    "LagrangeSettings",
    "Multipliers",
    "T_con_bin",
    "binned_means",
    "initial_multipliers",
    "pid_update",
    "violations",
]
