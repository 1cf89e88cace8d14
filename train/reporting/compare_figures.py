"""The figures of ``dwr-gym compare``: trajectories, time series and learning curves of every policy."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from train.evaluation.rollout import RolloutResult
from train.reporting.plotting import (
    HEADING_ERROR,
    SUCCESS,
    TIME,
    figure_legend,
    marked,
    pyplot,
    reference_line,
    save,
    styles,
)

TIME_SERIES_INDEX = 4  # psi0 = pi in paper-fig5, the hardest start
GOAL = (0.8, 0.0)  # [m] the goal of paper-fig5
T_CON = 20.0  # [s] the prescribed time of paper-fig5


def plot_trajectories(results: dict[str, RolloutResult], labels: tuple[str, ...], path: Path) -> Any:
    """One panel per policy: the eight Figure 5 rollouts, labelled by their initial heading."""
    plt = pyplot()
    n = len(results)
    cols = min(n, 4)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols + 1.6, 3.4 * rows), squeeze=False, sharex=True,
                             sharey=True)  # fmt: skip
    looks = styles(labels)
    for ax, (label, result) in zip(axes.flat, results.items(), strict=False):
        tr = result.trajectory
        assert tr is not None
        for i, start in enumerate(labels):
            ax.plot(tr["x"][:, i], tr["y"][:, i], linewidth=1.2, label=start, **marked(looks[start], len(tr["x"]), i))
        ax.plot(*GOAL, "k*", markersize=10, linestyle="none", label="goal (0.8, 0, 0)")
        ax.set_title(f"{label}: {result.success.mean():.0%} before T_con", fontsize=9)
        ax.set(aspect="equal", xlabel="x [m]", ylabel="y [m]")
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    figure_legend(fig, title="initial heading")
    fig.suptitle(f"Trajectories from the eight Figure 5 headings (T_con = {T_CON:g} s)")
    return save(fig, path, dpi=110)


def plot_time_series(results: dict[str, RolloutResult], path: Path) -> Any:
    """Distance, linear and angular velocity over time from psi0 = pi, every policy on one axis each."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(17, 4.2))
    i = TIME_SERIES_INDEX
    looks = styles(results)
    for place, (label, result) in enumerate(results.items()):
        tr = result.trajectory
        assert tr is not None
        look = marked(looks[label], tr["time"].shape[0], place)
        axes[0].plot(tr["time"][:, i], tr["distance"][:, i], label=label, **look)
        axes[1].plot(tr["time"][1:, i], tr["linear_velocity"][:, i], label=label, **look)
        axes[2].plot(tr["time"][1:, i], tr["angular_velocity"][:, i], label=label, **look)
    for ax, quantity in zip(axes, ("distance d [m]", "linear velocity u [m/s]", "angular velocity omega [rad/s]"),
                            strict=True):  # fmt: skip
        reference_line(ax, T_CON, f"T_con = {T_CON:g} s")
        ax.set(xlabel=TIME, ylabel=quantity)
    figure_legend(fig)
    fig.suptitle(f"Start (0, 0, pi), goal (0.8, 0, 0), T_con = {T_CON:g} s")
    return save(fig, path, dpi=110)


#: What the x axis of a learning curve counts, by the first column of the run's evaluations.csv.
CURVE_KINDS = {"timesteps": "environment steps [-]", "round": "DAgger round (0: demonstrations only) [-]",
               "epoch": "epoch of behaviour cloning [-]"}  # fmt: skip


def curve(rows: list[dict[str, str]]) -> tuple[str, dict[str, list[float]]] | None:
    """(kind, columns) of a run's evaluations.csv: x, success, final heading error and the last panel's quantity
    (return for RL, energy for cloned agents); None for a log of another kind."""
    first = rows[0] if rows else {}
    if "timesteps" in first:
        kind, keys = "timesteps", ("success_rate", "final_heading_error_mean", "return_mean")
    elif "epoch" in first:
        kind, keys = "epoch", ("success_rate", "final_heading_error_mean", "energy_mean")
    elif "round" in first:  # DAgger evaluates at several T_con: the figures' own if it is one of them
        evaluated = [key.removeprefix("success_T") for key in first if key.startswith("success_T")]
        T = f"{T_CON:.0f}" if f"{T_CON:.0f}" in evaluated else evaluated[0]
        kind, keys = "round", (f"success_T{T}", f"heading_T{T}", f"energy_T{T}")
    else:
        return None
    columns = {"x": [float(row[kind]) for row in rows]}
    for name, key in zip(("success", "heading", "last"), keys, strict=True):
        columns[name] = [float(row[key]) for row in rows]
    return kind, columns


def plot_learning_curves(run_dirs: dict[str, Path], path: Path) -> Any:
    """Success, final heading error and return (energy for cloned agents) of each agent's evaluations during
    training, one row per kind of training: RL by env steps, DAgger by round, behaviour cloning by epoch."""
    plt = pyplot()
    curves: dict[str, dict[str, tuple[str, dict[str, list[float]]]]] = {}
    for label, run_dir in run_dirs.items():
        csv_path = run_dir / "evaluations.csv"
        if csv_path.is_file():
            with csv_path.open() as handle:
                found = curve(list(csv.DictReader(handle)))
            if found is not None:
                curves.setdefault(found[0], {})[label] = found
    kinds = [kind for kind in CURVE_KINDS if kind in curves]
    fig, axes = plt.subplots(max(len(kinds), 1), 3, figsize=(17, 3.6 * max(len(kinds), 1)), squeeze=False)
    looks = styles(run_dirs)
    for row, kind in zip(axes, kinds, strict=False):
        last = "return per episode [-]" if kind == "timesteps" else "energy [m^2/s + rad^2/s]"
        for label, (_, columns) in curves[kind].items():
            for ax, key in zip(row, ("success", "heading", "last"), strict=True):
                ax.plot(columns["x"], columns[key], label=label, **looks[label])
        for ax, quantity in zip(row, (SUCCESS, HEADING_ERROR, last), strict=True):
            ax.set(xlabel=CURVE_KINDS[kind], ylabel=quantity)
    if kinds:
        figure_legend(fig)
    dagger = f" (DAgger runs: the network alone, at T_con = {T_CON:g} s)" if "round" in kinds else ""
    fig.suptitle(f"Learning curves on each run's fixed evaluation set{dagger}")
    return save(fig, path, dpi=110)
