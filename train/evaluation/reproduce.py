"""``dwr-gym reproduce``'s measurements: the rollouts behind the paper's Figures 5 to 9 and its claims, measured.

All rollouts go through :func:`train.evaluation.rollout.rollout`, the same batched env code as everything else,
with a control period ``dt`` (0.01 s by default, close to the paper's continuous-time simulation). The figures
and report.md are drawn from them by :mod:`train.reporting.paper`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from baselines.controllers import PTCParams
from dwr_gym import model
from train.evaluation.evaluate import evaluate
from train.evaluation.optimum import casadi_available
from train.evaluation.rollout import RolloutResult
from train.evaluation.scenarios import Scenario, make_scenario

FIG6_T_CON = (20.0, 25.0, 30.0, 35.0)
FIG8_T_CON = (25.0, 50.0)
COMPARED = {"ptc": "PTC (this paper)", "fabregas": "Fabregas [9]", "fixed-time": "fixed-time [23]"}
FIG8_LAWS = {"ptc": "fractional PTC (17)", "conventional-ptc": "conventional PTC (12)"}


@dataclass
class Claim:
    """One claim of the paper with the number measured here and a verdict."""

    claim: str
    measured: str
    holds: bool

    @property
    def verdict(self) -> str:
        return "holds" if self.holds else "does not hold"


@dataclass
class PaperRuns:
    """The recorded rollouts of the paper's figures (each a :class:`RolloutResult` with its trajectory)."""

    dt: float
    fig5: RolloutResult
    """PTC from Figure 5's eight headings, T_con = 20 s."""
    fig6: dict[float, RolloutResult]
    """PTC from psi0 = pi at each T_con of :data:`FIG6_T_CON`."""
    fig7: dict[str, RolloutResult]
    """The three laws of :data:`COMPARED` from Figure 7's start, T_con = 70 s."""
    fig8: dict[float, dict[str, RolloutResult]]
    """The fractional and the conventional law from psi0 = pi at each T_con of :data:`FIG8_T_CON`."""
    fabregas_at_pi: RolloutResult
    """Fabregas [9] from psi0 = pi, T_con = 20 s: its balance point."""
    optimal_fig5: RolloutResult | None = None
    """The ``optimal`` controller on Figure 5's starts (None without CasADi)."""
    optimal_fig7: RolloutResult | None = None
    """The ``optimal`` controller on Figure 7's start (None without CasADi)."""


def _run(name: str, policies: dict[str, Any], dt: float) -> dict[str, RolloutResult]:
    return evaluate(policies, make_scenario(name, env_kwargs={"dt": dt}), record=True)


def _single_start(start: tuple[float, float, float], T_con: float, dt: float, policy: str) -> RolloutResult:
    """A rollout of one controller from one start to the goal (0.8, 0, 0)."""
    scenario = Scenario("custom", np.array([start]), np.array([[0.8, 0.0, 0.0]]), {"T_con": T_con, "dt": dt})
    return evaluate({policy: policy}, scenario, record=True)[policy]


def measure(dt: float = 0.01, log: Callable[[str], None] | None = None) -> PaperRuns:
    """Run every rollout of the paper's figures at control period ``dt``; ``log`` hears each stage as it starts."""
    say = log or (lambda text: None)
    optimum = casadi_available()
    say("Figure 5: PTC from eight initial headings")
    fig5 = _run("paper-fig5", {"ptc": "ptc"}, dt)["ptc"]
    say("Figure 6: PTC at four prescribed times")
    fig6 = {T_con: _single_start((0.0, 0.0, math.pi), T_con, dt, "ptc") for T_con in FIG6_T_CON}
    say("Figures 7 and 9: PTC, Fabregas [9] and fixed-time [23] from Figure 7's start")
    fig7 = _run("paper-fig7", {name: name for name in COMPARED}, dt)
    optimal7 = None
    if optimum:
        say("Figures 7 and 9: the optimum from Figure 7's start")
        optimal7 = _run("paper-fig7", {"optimal": "optimal"}, dt)["optimal"]
    say("Figure 8: fractional against conventional PTC")
    fig8 = {T_con: {name: _single_start((0.0, 0.0, math.pi), T_con, dt, name) for name in FIG8_LAWS}
            for T_con in FIG8_T_CON}  # fmt: skip
    say("Fabregas [9] at its balance point")
    stuck = _single_start((0.0, 0.0, math.pi), 20.0, dt, "fabregas")
    optimal5 = None
    if optimum:
        say("the optimum from Figure 5's eight headings")
        optimal5 = _run("paper-fig5", {"optimal": "optimal"}, dt)["optimal"]
    return PaperRuns(dt, fig5, fig6, fig7, fig8, stuck, optimal5, optimal7)


def claims(runs: PaperRuns) -> list[Claim]:
    """The paper's claims, each with the numbers measured in ``runs`` and a verdict."""
    fig5, fig7 = runs.fig5, runs.fig7
    found: list[Claim] = []
    worst = float(np.nanmax(fig5.arrival_time))
    found.append(Claim(
        "The robot reaches the target before T_con = 20 s from any initial yaw angle (Fig. 5).",
        f"{int(fig5.success.sum())}/8 headings arrive within 1 cm before T_con; latest arrival {worst:.2f} s "
        f"({worst / 20.0:.3f} T_con)", bool(fig5.success.all()),
    ))  # fmt: skip
    final_yaw = fig5.final_heading_error
    found.append(Claim(
        "The yaw angle at the target goes to zero (Theorem 8, Remark 1).",
        f"final abs(psi) at 1 cm over Fig. 5's headings: mean {np.mean(final_yaw):.3f} rad, max {np.max(final_yaw):.3f} rad "
        f"({math.degrees(np.max(final_yaw)):.1f} deg)", bool(np.max(final_yaw) < math.radians(2.0)),
    ))  # fmt: skip
    arr = np.array([float(runs.fig6[T].arrival_time[0]) for T in FIG6_T_CON])
    ratios = arr / np.array(FIG6_T_CON)
    found.append(Claim(
        "The arrival time is set by T_con: every run arrives before its T_con, later for a larger T_con (Fig. 6).",
        "arrival times " + ", ".join(f"{a:.2f} s (T_con {t:.0f})" for a, t in zip(arr, FIG6_T_CON, strict=True))
        + f"; t_arr / T_con from {ratios.min():.3f} to {ratios.max():.3f}",
        bool(np.all(ratios < 1.0) and np.all(np.diff(arr) > 0)),
    ))  # fmt: skip
    peaks = {name: float(r.peak_linear_velocity[0]) for name, r in fig7.items()}
    energies = {name: float(r.energy[0]) for name, r in fig7.items()}
    settle = {name: float(r.arrival_time[0]) for name, r in fig7.items()}
    found.append(Claim(
        "The PTC law has the lowest peak linear velocity of the three laws, for similar settling times (Fig. 7(b)).",
        ", ".join(f"{COMPARED[n]}: peak u {peaks[n]:.3f} m/s, arrival {settle[n]:.1f} s" for n in COMPARED)
        + " (the paper gives no gains for [23]; ours settle faster, so the settling times are not similar)",
        peaks["ptc"] < min(peaks["fabregas"], peaks["fixed-time"]),
    ))  # fmt: skip
    found.append(Claim(
        "The PTC law uses less energy (integral of u^2 + omega^2) than the other two laws (Fig. 9(b)).",
        ", ".join(f"{COMPARED[n]}: {energies[n]:.3f}" for n in COMPARED),
        energies["ptc"] < min(energies["fabregas"], energies["fixed-time"]),
    ))  # fmt: skip
    earlier = [{name: float(result.arrival_time[0]) for name, result in runs.fig8[T].items()} for T in FIG8_T_CON]
    found.append(Claim(
        "The fractional law settles before the conventional one (Fig. 8).",
        "; ".join(f"T_con {T:.0f}: fractional {t['ptc']:.2f} s, conventional {t['conventional-ptc']:.2f} s"
                  for T, t in zip(FIG8_T_CON, earlier, strict=True)),
        all(t["ptc"] < t["conventional-ptc"] for t in earlier),
    ))  # fmt: skip
    paper = PTCParams.paper_fig5()
    t_v = float(model.switching_time(0.8, math.pi, 20.0, paper.beta, paper.K, paper.p_min))
    exponent = (0.8**2 + math.pi**2) ** (1 - paper.beta) / ((1 - paper.beta) * 2 * paper.K * paper.p_min)
    found.append(Claim(
        "The scaling function (17) avoids the infinite gain of conventional PTC (Remark 5, Remark 9).",
        f"for the paper's parameters the exponent in t_v is -{exponent:.0f}, so t_v = {t_v!r} s equals T_con = 20 s "
        "in double precision and mu* = 1/(T_con - t) grows without bound exactly like (12); the gain stays "
        f"bounded here only through the cap max_gain = {paper.max_gain} 1/s",
        t_v < 20.0,
    ))  # fmt: skip
    stuck, ptc_pi = runs.fabregas_at_pi, runs.fig6[20.0]
    found.append(Claim(
        "With p of eq. (9), ref. [9]'s law stalls when abs(alpha - psi) = pi; p* of eq. (10) does not.",
        f"from psi0 = pi, Fabregas [9] ends {float(stuck.final_distance[0]):.3f} m from the goal; "
        f"the PTC law arrives at {float(ptc_pi.arrival_time[0]):.2f} s",
        bool(stuck.final_distance[0] > 0.5 and ptc_pi.success[0]),
    ))  # fmt: skip
    return found


def optimum_lines(runs: PaperRuns) -> list[str]:
    """How far the laws are from the optimum on the paper's starts (not a claim of the paper); empty without CasADi."""
    lines = []
    if runs.optimal_fig5 is not None:
        ptc, optimal = runs.fig5, runs.optimal_fig5
        lines.append(
            f"Figure 5's eight starts (T_con = 20 s): the optimum spends {optimal.energy.mean():.3f} on average with "
            f"a final heading error of {optimal.final_heading_error.mean():.3f} rad; PTC {ptc.energy.mean():.3f} "
            f"({ptc.energy.mean() / optimal.energy.mean():.2f}x) with {ptc.final_heading_error.mean():.3f} rad "
            "(optimal_vs_ptc.png)"
        )
    if runs.optimal_fig7 is not None:
        best = float(runs.optimal_fig7.energy[0])
        lines.append(
            f"Figure 7/9's start (T_con = 70 s): the optimum spends {best:.3f}; "
            + ", ".join(f"{COMPARED[n]} {float(runs.fig7[n].energy[0]) / best:.1f}x" for n in COMPARED)
        )
    return lines
