"""Learning curves: of a DAgger run (by round), of behaviour cloning (by epoch) and of a sweep (by env step)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from train.reporting.plotting import ENERGY, HEADING_ERROR, SUCCESS, figure_legend, pyplot, save, style, styles

#: Axis labels of a sweep's metrics.
METRIC_LABELS = {"return_mean": "return per episode, mean [-]", "success_rate": SUCCESS,
                 "energy_mean": "energy, mean [m^2/s + rad^2/s]", "arrival_time_mean": "arrival time, mean [s]",
                 "final_distance_mean": "final distance, mean [m]"}  # fmt: skip


def plot_dagger_curve(
    curve: list[dict[str, Any]],
    T_cons: tuple[float, ...],
    path: Path,
    prefix: str = "",
    title: str = "DAgger on minimum-energy plans: fixed evaluation starts 0.3-3 m away",
) -> Any:
    """Success, final heading error and energy at each evaluation T_con against the DAgger round (the columns
    ``{prefix}success_T{T}`` ...)."""
    try:
        plt = pyplot()
    except ImportError:  # the plots extra is optional
        return None
    rounds = [row["round"] for row in curve]
    fig, axes = plt.subplots(1, 3, figsize=(14.5, 4.2))
    for ax, key, label in zip(axes, ("success", "heading", "energy"), (SUCCESS, HEADING_ERROR, ENERGY), strict=True):
        for i, T in enumerate(T_cons):
            ax.plot(rounds, [float(row[f"{prefix}{key}_T{int(T)}"]) for row in curve], label=f"T_con = {T:g} s",
                    **style(i))  # fmt: skip
        ax.set(xlabel="DAgger round (0: demonstrations only) [-]", ylabel=label)
    figure_legend(fig)
    fig.suptitle(title)
    return save(fig, path, dpi=100)


def plot_imitation_curve(csv_path: Path, path: Path) -> Any:
    """Success, final heading error and energy on the fixed scenario set against the epochs (if matplotlib is there)."""
    try:
        plt = pyplot()
    except ImportError:
        return None
    with csv_path.open() as handle:
        rows = list(csv.DictReader(handle))
    epochs = [int(r["epoch"]) for r in rows]
    fig, axes = plt.subplots(1, 3, figsize=(14.5, 4.2))
    for ax, key, label in zip(axes, ("success_rate", "final_heading_error_mean", "energy_mean"),
                              (SUCCESS, HEADING_ERROR, ENERGY), strict=True):  # fmt: skip
        ax.plot(epochs, [float(r[key]) for r in rows], label="cloned policy", **style(0))
        ax.set(xlabel="epoch of behaviour cloning [-]", ylabel=label)
    figure_legend(fig)
    fig.suptitle("Behaviour cloning of the optimal planner: the fixed evaluation set (T_con in [10, 60] s)")
    return save(fig, path, dpi=100)


def plot_sweep_curves(groups: dict[str, dict[str, Any]], path: Path, metrics: tuple[str, ...]) -> Any:
    """Learning curves: per configuration, the mean over seeds with a +- sd band."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(metrics), figsize=(6 * len(metrics) + 2, 4), squeeze=False)
    labels = {config_id: f"{config_id} ({len(group['runs'])} seeds)" for config_id, group in groups.items()}
    looks = styles(labels.values())
    for config_id, group in groups.items():
        runs = list(group["runs"].values())
        length = min(len(r) for r in runs)
        steps = np.array([r["timesteps"] for r in runs[0][:length]])
        for ax, metric in zip(axes[0], metrics, strict=True):
            values = np.array([[row[metric] for row in r[:length]] for r in runs])
            mean = np.nanmean(values, axis=0)
            sd = np.nanstd(values, axis=0, ddof=1) if len(runs) > 1 else np.zeros_like(mean)
            ax.plot(steps, mean, label=labels[config_id], **looks[labels[config_id]])
            ax.fill_between(steps, mean - sd, mean + sd, color=looks[labels[config_id]]["color"], alpha=0.2)
    for ax, metric in zip(axes[0], metrics, strict=True):
        ax.set(xlabel="environment steps [-]", ylabel=METRIC_LABELS.get(metric, f"{metric} [-]"))
        ax.grid(alpha=0.3)
    figure_legend(fig, title="configuration (mean +- sd over seeds)")
    return save(fig, path)
