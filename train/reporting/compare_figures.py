"""The figures of ``dwr-gym compare``: trajectories, time series and learning curves of every policy."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from train.evaluation.rollout import RolloutResult
from train.reporting.plotting import legend_outside, pyplot, save

TIME_SERIES_INDEX = 4  # psi0 = pi in paper-fig5, the hardest start


def plot_trajectories(results: dict[str, RolloutResult], labels: tuple[str, ...], path: Path) -> None:
    """One panel per policy: the eight Figure 5 rollouts, labelled by their initial heading."""
    plt = pyplot()
    n = len(results)
    cols = min(n, 4)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.4 * rows), squeeze=False, sharex=True, sharey=True)
    for ax, (label, result) in zip(axes.flat, results.items(), strict=False):
        tr = result.trajectory
        assert tr is not None
        for i, start in enumerate(labels):
            ax.plot(tr["x"][:, i], tr["y"][:, i], linewidth=1.2, label=start)
        ax.plot([0.8], [0.0], "k*", markersize=10)
        ax.set_title(f"{label}: {result.success.mean():.0%} before T_con", fontsize=9)
        ax.set(aspect="equal", xlabel="x [m]", ylabel="y [m]")
    legend_outside(axes.flat[n - 1], title="initial heading", fontsize=7)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.suptitle("Trajectories from the eight Figure 5 headings (T_con = 20 s)")
    save(fig, path, dpi=110)


def plot_time_series(results: dict[str, RolloutResult], path: Path) -> None:
    """Distance, linear and angular velocity over time from psi0 = pi, every policy on one axis each."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    i = TIME_SERIES_INDEX
    for label, result in results.items():
        tr = result.trajectory
        assert tr is not None
        axes[0].plot(tr["time"][:, i], tr["distance"][:, i], label=label)
        axes[1].plot(tr["time"][1:, i], tr["linear_velocity"][:, i], label=label)
        axes[2].plot(tr["time"][1:, i], tr["angular_velocity"][:, i], label=label)
    for ax, unit in zip(axes, ("d [m]", "u [m/s]", "omega [rad/s]"), strict=True):
        ax.axvline(20.0, color="k", linestyle="--", linewidth=1)
        ax.set(xlabel="t [s]", ylabel=unit)
    legend_outside(axes[-1])
    fig.suptitle("Start (0, 0, pi), goal (0.8, 0, 0), T_con = 20 s")
    save(fig, path, dpi=110)


def plot_learning_curves(run_dirs: dict[str, Path], path: Path) -> None:
    """Success rate, final heading error and return on the fixed evaluation set against training steps."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for label, run_dir in run_dirs.items():
        csv_path = run_dir / "evaluations.csv"
        if not csv_path.is_file():
            continue
        with csv_path.open() as handle:
            rows = list(csv.DictReader(handle))
        if not rows or "timesteps" not in rows[0]:  # a cloned agent's curve is over epochs: its own learning_curve.png
            continue
        steps = [float(r["timesteps"]) for r in rows]
        for ax, key in zip(axes, ("success_rate", "final_heading_error_mean", "return_mean"), strict=True):
            ax.plot(steps, [float(r[key]) for r in rows], marker="o", markersize=3, label=label)
    for ax, title, unit in zip(axes, ("success rate (arrival before T_con)", "final |psi - psi_d|", "return"),
                               ("fraction of episodes", "[rad]", "return per episode [-]"), strict=True):  # fmt: skip
        ax.set(xlabel="env steps", ylabel=unit, title=title)
    legend_outside(axes[-1])
    save(fig, path, dpi=110)
