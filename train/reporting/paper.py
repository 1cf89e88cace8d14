"""The paper's Figures 5 to 9, the optimum beside PTC, the animation and report.md, from the rollouts of
:func:`train.evaluation.reproduce.measure`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from train.evaluation.reproduce import COMPARED, FIG6_T_CON, FIG8_LAWS, FIG8_T_CON, Claim, PaperRuns
from train.evaluation.scenarios import FIG5_HEADINGS
from train.reporting.plotting import legend_outside, pyplot, save

OPTIMUM_LABEL = "optimum (least energy to the pose)"


def plot_paper_figures(runs: PaperRuns, out: Path, gif: bool = True) -> list[Path]:
    """Write figure5.png ... figure9.png (optimal_vs_ptc.png with CasADi, figure5.gif if asked); returns the paths."""
    paths = [figure5(runs, out / "figure5.png"), figure6(runs, out / "figure6.png"),
             figure7(runs, out / "figure7.png"), figure9(runs, out / "figure9.png"),
             figure8(runs, out / "figure8.png")]  # fmt: skip
    if runs.optimal_fig5 is not None:
        paths.append(optimal_vs_ptc(runs, out / "optimal_vs_ptc.png"))
    if gif:
        paths.append(animate_fig5(runs, out / "figure5.gif"))
    return paths


def figure5(runs: PaperRuns, path: Path) -> Path:
    """(a) the eight trajectories and (b) their orientation errors (6) against time."""
    plt = pyplot()
    traj = runs.fig5.trajectory
    assert traj is not None
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.5))
    for i, heading in enumerate(FIG5_HEADINGS):
        label = f"psi0 = {math.degrees(heading):+.0f} deg"
        ax_a.plot(traj["x"][:, i], traj["y"][:, i], label=label)
        ax_b.plot(traj["time"][:, i], traj["orientation_error"][:, i], label=label)
    ax_a.plot([0.8], [0.0], "k*", markersize=12)
    ax_a.set(xlabel="x [m]", ylabel="y [m]", title="(a) motion trajectory", aspect="equal")
    ax_b.axvline(20.0, color="k", linestyle="--", linewidth=1)
    ax_b.set(xlabel="t [s]", ylabel="e_psi [rad]", title="(b) orientation error (6)")
    legend_outside(ax_b, fontsize=7)
    fig.suptitle("Figure 5: any initial yaw angle, PTC with K1=2, K2=10, T_con=20 s")
    save(fig, path)
    return path


def figure6(runs: PaperRuns, path: Path) -> Path:
    """(a) the distance and (b) the Lyapunov function (21) against time, at each T_con."""
    plt = pyplot()
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.5))
    for T_con in FIG6_T_CON:
        tr = runs.fig6[T_con].trajectory
        assert tr is not None
        line = ax_a.plot(tr["time"][:, 0], tr["distance"][:, 0], label=f"T_con = {T_con:.0f} s")[0]
        ax_b.semilogy(
            tr["time"][:, 0], np.maximum(tr["lyapunov"][:, 0], 1e-8), color=line.get_color(), label=line.get_label()
        )
        for ax in (ax_a, ax_b):
            ax.axvline(T_con, color=line.get_color(), linestyle="--", linewidth=1)
    ax_a.set(xlabel="t [s]", ylabel="d [m]", title="(a) distance (2)")
    ax_b.set(xlabel="t [s]", ylabel="L [m^2, rad^2]", title="(b) Lyapunov function (21)")
    legend_outside(ax_b)
    fig.suptitle("Figure 6: different prescribed times, psi0 = pi")
    save(fig, path)
    return path


def figure7(runs: PaperRuns, path: Path) -> Path:
    """Distance, linear and angular velocity of the three laws against time."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    for name, result in runs.fig7.items():
        tr = result.trajectory
        assert tr is not None
        axes[0].plot(tr["time"][:, 0], tr["distance"][:, 0], label=COMPARED[name])
        axes[1].plot(tr["time"][1:, 0], tr["linear_velocity"][:, 0], label=COMPARED[name])
        axes[2].plot(tr["time"][1:, 0], tr["angular_velocity"][:, 0], label=COMPARED[name])
    for ax, title, unit in zip(axes, ("(a) distance", "(b) linear velocity", "(c) angular velocity"),
                               ("d [m]", "u [m/s]", "omega [rad/s]"), strict=True):  # fmt: skip
        ax.set(xlabel="t [s]", ylabel=unit, title=title)
    legend_outside(axes[-1])
    fig.suptitle("Figure 7: start (-0.4, 0), psi0 = -178 deg, goal (0.8, 0), T_con = 70 s")
    save(fig, path)
    return path


def figure9(runs: PaperRuns, path: Path) -> Path:
    """(a) the three laws' trajectories and (b) their energy against time, with the optimum's."""
    plt = pyplot()
    dt = runs.dt
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.5))
    for name, result in runs.fig7.items():
        tr = result.trajectory
        assert tr is not None
        ax_a.plot(tr["x"][:, 0], tr["y"][:, 0], label=COMPARED[name])
        u, w = tr["linear_velocity"][:, 0], tr["angular_velocity"][:, 0]
        ax_b.plot(tr["time"][1:, 0], np.cumsum((u**2 + w**2) * dt), label=COMPARED[name])
    if runs.optimal_fig7 is not None:  # the yardstick the paper does not have: the least energy to the pose by T_con
        tr = runs.optimal_fig7.trajectory
        assert tr is not None
        u, w = tr["linear_velocity"][:, 0], tr["angular_velocity"][:, 0]
        style = {"color": "k", "linestyle": ":", "linewidth": 2, "label": OPTIMUM_LABEL}
        ax_a.plot(tr["x"][:, 0], tr["y"][:, 0], **style)
        ax_b.plot(tr["time"][1:, 0], np.cumsum((u**2 + w**2) * dt), **style)
    ax_a.plot([0.8], [0.0], "k*", markersize=12)
    ax_a.set(xlabel="x [m]", ylabel="y [m]", title="(a) trajectories", aspect="equal")
    ax_b.set(xlabel="t [s]", ylabel="integral of u^2 + omega^2 dt [m^2/s, rad^2/s]", title="(b) energy")
    legend_outside(ax_b)
    fig.suptitle("Figure 9: trajectory and energy consumption")
    save(fig, path)
    return path


def figure8(runs: PaperRuns, path: Path) -> Path:
    """The distance of the fractional and the conventional law against time, one panel per T_con."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, T_con in zip(axes, FIG8_T_CON, strict=True):
        for name, label in FIG8_LAWS.items():
            result = runs.fig8[T_con][name]
            tr = result.trajectory
            assert tr is not None
            ax.plot(
                tr["time"][:, 0], tr["distance"][:, 0], label=f"{label}: arrives {float(result.arrival_time[0]):.2f} s"
            )
        ax.axvline(T_con, color="k", linestyle="--", linewidth=1)
        ax.set(xlabel="t [s]", ylabel="d [m]", title=f"T_con = {T_con:.0f} s")
        legend_outside(ax, below=True)
    fig.suptitle("Figure 8: settling time, fractional against conventional PTC (psi0 = pi)")
    save(fig, path)
    return path


def optimal_vs_ptc(runs: PaperRuns, path: Path) -> Path:
    """Figure 5's eight starts: PTC's trajectories beside the minimum-energy ones to the pose."""
    assert runs.optimal_fig5 is not None
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharex=True, sharey=True)
    for ax, result, title in ((axes[0], runs.fig5, "PTC (16)-(19)"), (axes[1], runs.optimal_fig5, OPTIMUM_LABEL)):
        tr = result.trajectory
        assert tr is not None
        for i, heading in enumerate(FIG5_HEADINGS):
            ax.plot(tr["x"][:, i], tr["y"][:, i], label=f"psi0 = {math.degrees(heading):+.0f} deg")
        ax.plot([0.8], [0.0], "k*", markersize=12)
        ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal",
               title=f"{title}\nenergy {result.energy.mean():.3f}, final |psi| {result.final_heading_error.mean():.3f} rad")  # fmt: skip
    axes[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.suptitle(
        "Figure 5's starts, T_con = 20 s: the paper's law and the optimum (mean energy, mean final heading error)"
    )
    save(fig, path)
    return path


def animate_fig5(runs: PaperRuns, path: Path, fps: int = 12) -> Path:
    """An animated GIF of the Figure 5 rollouts, one frame every 0.5 s of simulated time."""
    plt = pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    tr = runs.fig5.trajectory
    assert tr is not None
    t = tr["time"][:, 0]
    frames = np.searchsorted(t, np.arange(0.0, t[-1] + 1e-9, 0.5))
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.set(xlim=(-0.35, 1.0), ylim=(-0.45, 0.45), aspect="equal", xlabel="x [m]", ylabel="y [m]")
    ax.plot([0.8], [0.0], "k*", markersize=12)
    lines = [ax.plot([], [], linewidth=1.5)[0] for _ in FIG5_HEADINGS]
    heads = [ax.plot([], [], "o", color=line.get_color(), markersize=5)[0] for line in lines]
    title = ax.set_title("")

    def draw(k: int) -> list[Any]:
        for i, (line, head) in enumerate(zip(lines, heads, strict=True)):
            line.set_data(tr["x"][: k + 1, i], tr["y"][: k + 1, i])
            head.set_data([tr["x"][k, i]], [tr["y"][k, i]])
        title.set_text(f"PTC, T_con = 20 s: t = {t[k]:4.1f} s")
        return [*lines, *heads, title]

    FuncAnimation(fig, draw, frames=frames, blit=False).save(str(path), writer=PillowWriter(fps=fps))
    plt.close(fig)
    return path


def write_report(claims: list[Claim], path: Path, dt: float, optimum_lines: list[str] | None = None) -> None:
    """The Markdown report: each claim, the number measured here and the verdict."""
    lines = [
        "# The paper's claims, measured",
        "",
        f"Regenerated by `dwr-gym reproduce` (control period dt = {dt} s, exact zero-order-hold integration,",
        "arrival = within 1 cm of the goal; the PTC law's guards: stop within 5 mm, gain cap 10 1/s).",
        "",
        "| # | claim | measured here | verdict |",
        "|---|-------|---------------|---------|",
    ]
    for i, claim in enumerate(claims, 1):
        lines.append(f"| {i} | {claim.claim} | {claim.measured} | **{claim.verdict}** |")
    if optimum_lines:
        lines += ["", "## How far from optimal (not a claim of the paper)", "",
                  "The `optimal` controller: minimum energy to the goal pose (heading 0 included) by T_con, "
                  "planned with CasADi/IPOPT.", ""]  # fmt: skip
        lines += [f"- {line}" for line in optimum_lines]
    lines += ["", "Figures: figure5.png ... figure9.png, optimal_vs_ptc.png; animation: figure5.gif.", ""]
    path.write_text("\n".join(lines))
