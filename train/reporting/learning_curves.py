"""Learning curves: of a DAgger run (by round), of behaviour cloning (by epoch) and of a sweep (by env step)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from train.reporting.plotting import pyplot, save


def plot_dagger_curve(curve: list[dict[str, Any]], T_cons: tuple[float, ...], path: Path) -> None:
    """Success, final heading error and energy at each evaluation T_con against the DAgger round."""
    try:
        plt = pyplot()
    except ImportError:  # the plots extra is optional
        return
    rounds = [row["round"] for row in curve]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    labels = ("success (arrival by T_con)", "final |psi - psi_d| [rad]", "energy [m^2/s + rad^2/s]")
    for ax, key, label in zip(axes, ("success", "heading", "energy"), labels, strict=True):
        for T in T_cons:
            ax.plot(rounds, [row[f"{key}_T{int(T)}"] for row in curve], marker="o", label=f"T_con = {T:g} s")
        ax.set(xlabel="DAgger round (0: demonstrations only)", ylabel=label)
    axes[0].legend(fontsize=8)
    fig.suptitle("DAgger on minimum-energy plans: fixed evaluation starts 0.3-3 m away")
    save(fig, path, dpi=100)


def plot_imitation_curve(csv_path: Path, path: Path) -> None:
    """Success, final heading error and energy on the fixed scenario set against the epochs (if matplotlib is there)."""
    try:
        plt = pyplot()
    except ImportError:
        return
    with csv_path.open() as handle:
        rows = list(csv.DictReader(handle))
    epochs = [int(r["epoch"]) for r in rows]
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    for ax, key, label in zip(axes, ("success_rate", "final_heading_error_mean", "energy_mean"),
                              ("success (arrival by T_con)", "final |psi - psi_d| [rad]", "energy [m^2/s + rad^2/s]"),
                              strict=True):  # fmt: skip
        ax.plot(epochs, [float(r[key]) for r in rows], marker="o")
        ax.set(xlabel="epoch of behaviour cloning", ylabel=label)
    fig.suptitle("Behaviour cloning of the optimal planner: the fixed evaluation set (T_con in [10, 60] s)")
    save(fig, path, dpi=100)


def plot_sweep_curves(groups: dict[str, dict[str, Any]], path: Path, metrics: tuple[str, ...]) -> None:
    """Learning curves: per configuration, the mean over seeds with a +- sd band."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(metrics), figsize=(6 * len(metrics), 4), squeeze=False)
    for config_id, group in groups.items():
        runs = list(group["runs"].values())
        length = min(len(r) for r in runs)
        steps = np.array([r["timesteps"] for r in runs[0][:length]])
        for ax, metric in zip(axes[0], metrics, strict=True):
            values = np.array([[row[metric] for row in r[:length]] for r in runs])
            mean = np.nanmean(values, axis=0)
            sd = np.nanstd(values, axis=0, ddof=1) if len(runs) > 1 else np.zeros_like(mean)
            (line,) = ax.plot(steps, mean, label=f"{config_id} ({len(runs)} seeds)")
            ax.fill_between(steps, mean - sd, mean + sd, color=line.get_color(), alpha=0.2)
    for ax, metric in zip(axes[0], metrics, strict=True):
        ax.set_xlabel("environment steps")
        ax.set_ylabel(metric)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7)
    save(fig, path)
