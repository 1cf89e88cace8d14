"""The paper's Figures 5 to 9, the optimum beside PTC, the animation and report.md, from the rollouts of
:func:`train.evaluation.reproduce.measure`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from train.evaluation.reproduce import COMPARED, FIG6_T_CON, FIG8_LAWS, FIG8_T_CON, Claim, PaperRuns
from train.evaluation.scenarios import FIG5_HEADINGS
from train.reporting.plotting import (
    ENERGY,
    TIME,
    figure_legend,
    legend_outside,
    marked,
    pyplot,
    reference_line,
    save,
    style,
    styles,
)

OPTIMUM_LABEL = "optimum (least energy to the pose)"
GOAL_LABEL = "goal (0.8, 0, 0)"


def plot_paper_figures(runs: PaperRuns, out: Path, gif: bool = True) -> list[Path]:
    """Write figure5.png ... figure9.png (optimal_vs_ptc.png with CasADi, figure5.gif if asked); returns the paths."""
    drawn = {"figure5.png": figure5, "figure6.png": figure6, "figure7.png": figure7, "figure8.png": figure8,
             "figure9.png": figure9}  # fmt: skip
    if runs.optimal_fig5 is not None:
        drawn["optimal_vs_ptc.png"] = optimal_vs_ptc
    for name, draw in drawn.items():
        draw(runs, out / name)
    paths = [out / name for name in drawn]
    if gif:
        paths.append(animate_fig5(runs, out / "figure5.gif"))
    return paths


def figure5(runs: PaperRuns, path: Path) -> Any:
    """(a) the eight trajectories and (b) their orientation errors (6) against time."""
    plt = pyplot()
    traj = runs.fig5.trajectory
    assert traj is not None
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(12.5, 4.5))
    for i, heading in enumerate(FIG5_HEADINGS):
        label = f"psi0 = {math.degrees(heading):+.0f} deg"
        look = marked(style(i), len(traj["time"]), i)
        ax_a.plot(traj["x"][:, i], traj["y"][:, i], label=label, **look)
        ax_b.plot(traj["time"][:, i], traj["orientation_error"][:, i], label=label, **look)
    ax_a.plot([0.8], [0.0], "k*", markersize=12, linestyle="none", label=GOAL_LABEL)
    ax_a.set(xlabel="x [m]", ylabel="y [m]", title="(a) motion trajectory", aspect="equal")
    reference_line(ax_b, 20.0, "T_con = 20 s")
    ax_b.set(xlabel=TIME, ylabel="orientation error e_psi [rad]", title="(b) orientation error (6)")
    figure_legend(fig, title="initial heading")
    fig.suptitle("Figure 5: any initial yaw angle, PTC with K1=2, K2=10, T_con=20 s")
    return save(fig, path)


def figure6(runs: PaperRuns, path: Path) -> Any:
    """(a) the distance and (b) the Lyapunov function (21) against time, at each T_con."""
    plt = pyplot()
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(12.5, 4.5))
    for i, T_con in enumerate(FIG6_T_CON):
        tr = runs.fig6[T_con].trajectory
        assert tr is not None
        look = marked(style(i), len(tr["time"]), i)
        ax_a.plot(tr["time"][:, 0], tr["distance"][:, 0], label=f"T_con = {T_con:.0f} s", **look)
        ax_b.semilogy(tr["time"][:, 0], np.maximum(tr["lyapunov"][:, 0], 1e-8), label=f"T_con = {T_con:.0f} s",
                      **look)  # fmt: skip
        for ax in (ax_a, ax_b):
            reference_line(ax, T_con, f"deadline {T_con:.0f} s", color=look["color"], linestyle=":")
    ax_a.set(xlabel=TIME, ylabel="distance d [m]", title="(a) distance (2)")
    ax_b.set(xlabel=TIME, ylabel="Lyapunov function L [m^2 + rad^2]", title="(b) Lyapunov function (21)")
    figure_legend(fig)
    fig.suptitle("Figure 6: different prescribed times, psi0 = pi")
    return save(fig, path)


def figure7(runs: PaperRuns, path: Path) -> Any:
    """Distance, linear and angular velocity of the three laws against time."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(17, 4.2))
    looks = styles(runs.fig7)
    for place, (name, result) in enumerate(runs.fig7.items()):
        tr = result.trajectory
        assert tr is not None
        look = {"label": COMPARED[name], **marked(looks[name], len(tr["time"]), place)}
        axes[0].plot(tr["time"][:, 0], tr["distance"][:, 0], **look)
        axes[1].plot(tr["time"][1:, 0], tr["linear_velocity"][:, 0], **look)
        axes[2].plot(tr["time"][1:, 0], tr["angular_velocity"][:, 0], **look)
    for ax, title, unit in zip(axes, ("(a) distance", "(b) linear velocity", "(c) angular velocity"),
                               ("distance d [m]", "linear velocity u [m/s]", "angular velocity omega [rad/s]"),
                               strict=True):  # fmt: skip
        ax.set(xlabel=TIME, ylabel=unit, title=title)
    figure_legend(fig)
    fig.suptitle("Figure 7: start (-0.4, 0), psi0 = -178 deg, goal (0.8, 0), T_con = 70 s")
    return save(fig, path)


def figure9(runs: PaperRuns, path: Path) -> Any:
    """(a) the three laws' trajectories and (b) their energy against time, with the optimum's."""
    plt = pyplot()
    dt = runs.dt
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(13, 4.5))
    laws = {**runs.fig7, **({"optimal": runs.optimal_fig7} if runs.optimal_fig7 is not None else {})}
    looks = styles(laws)
    for place, (name, result) in enumerate(laws.items()):
        tr = result.trajectory
        assert tr is not None
        # the optimum is the yardstick the paper does not have: the least energy to the pose by T_con
        look = {"label": COMPARED.get(name, OPTIMUM_LABEL), **marked(looks[name], len(tr["time"]), place)}
        u, w = tr["linear_velocity"][:, 0], tr["angular_velocity"][:, 0]
        ax_a.plot(tr["x"][:, 0], tr["y"][:, 0], **look)
        ax_b.plot(tr["time"][1:, 0], np.cumsum((u**2 + w**2) * dt), **look)
    ax_a.plot([0.8], [0.0], "k*", markersize=12, linestyle="none", label=GOAL_LABEL)
    ax_a.set(xlabel="x [m]", ylabel="y [m]", title="(a) trajectories", aspect="equal")
    ax_b.set(xlabel=TIME, ylabel=ENERGY, title="(b) energy: integral of u^2 + omega^2")
    figure_legend(fig)
    fig.suptitle("Figure 9: trajectory and energy consumption")
    return save(fig, path)


def figure8(runs: PaperRuns, path: Path) -> Any:
    """The distance of the fractional and the conventional law against time, one panel per T_con."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.2))
    looks = styles(FIG8_LAWS)
    for ax, T_con in zip(axes, FIG8_T_CON, strict=True):
        for place, (name, label) in enumerate(FIG8_LAWS.items()):
            result = runs.fig8[T_con][name]
            tr = result.trajectory
            assert tr is not None
            ax.plot(tr["time"][:, 0], tr["distance"][:, 0], label=f"{label}: arrives {float(result.arrival_time[0]):.2f} s",
                    **marked(looks[name], len(tr["time"]), place))  # fmt: skip
        reference_line(ax, T_con, f"T_con = {T_con:.0f} s")
        ax.set(xlabel=TIME, ylabel="distance d [m]", title=f"T_con = {T_con:.0f} s")
        legend_outside(ax, below=True)
    fig.suptitle("Figure 8: settling time, fractional against conventional PTC (psi0 = pi)")
    return save(fig, path)


def optimal_vs_ptc(runs: PaperRuns, path: Path) -> Any:
    """Figure 5's eight starts: PTC's trajectories beside the minimum-energy ones to the pose."""
    assert runs.optimal_fig5 is not None
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(13.5, 4.8), sharex=True, sharey=True)
    for ax, result, title in ((axes[0], runs.fig5, "PTC (16)-(19)"), (axes[1], runs.optimal_fig5, OPTIMUM_LABEL)):
        tr = result.trajectory
        assert tr is not None
        for i, heading in enumerate(FIG5_HEADINGS):
            ax.plot(tr["x"][:, i], tr["y"][:, i], label=f"psi0 = {math.degrees(heading):+.0f} deg",
                    **marked(style(i), len(tr["x"]), i))  # fmt: skip
        ax.plot([0.8], [0.0], "k*", markersize=12, linestyle="none", label=GOAL_LABEL)
        ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal",
               title=f"{title}\nenergy {result.energy.mean():.3f}, final |psi| {result.final_heading_error.mean():.3f} rad")  # fmt: skip
    figure_legend(fig, title="initial heading")
    fig.suptitle(
        "Figure 5's starts, T_con = 20 s: the paper's law and the optimum (mean energy, mean final heading error)"
    )
    return save(fig, path)


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
    lines = [ax.plot([], [], linewidth=1.5, color=style(i)["color"])[0] for i in range(len(FIG5_HEADINGS))]
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


def write_claims(claims: list[Claim], path: Path, dt: float, optimum_lines: list[str] | None = None) -> None:
    """The claims as JSON (what the docs' table of verdicts is generated from): the number, the claim, what was
    measured, the verdict; with the control period and the lines on the optimum."""
    import json

    rows = [{"number": i, "claim": c.claim, "measured": c.measured, "verdict": c.verdict, "holds": c.holds}
            for i, c in enumerate(claims, 1)]  # fmt: skip
    data = {"dt": dt, "claims": rows, "optimum": list(optimum_lines or [])}
    path.write_text(json.dumps(data, indent=2) + "\n")


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
