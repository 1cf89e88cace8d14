"""The figures of ``dwr-gym robustness``: success by T_con and final distance against each disturbance's magnitude."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from train.evaluation.robustness import SUCCESS_LEVEL, SWEEPS
from train.reporting.plotting import SUCCESS, figure_legend, pyplot, reference_line, save, styles


def plot_robustness(rows: list[dict[str, Any]], out_dir: Path) -> list[Path]:
    """One PNG per disturbance: success by T_con and mean final distance against the magnitude."""
    paths = []
    for name in dict.fromkeys(row["disturbance"] for row in rows):
        path = out_dir / f"robustness_{name}.png"
        plot_disturbance([row for row in rows if row["disturbance"] == name], name, path)
        paths.append(path)
    return paths


def plot_disturbance(rows: list[dict[str, Any]], name: str, path: Path) -> Any:
    """Success by T_con and mean final distance of every policy against the magnitude of one disturbance."""
    plt = pyplot()
    fig, (ax_success, ax_error) = plt.subplots(1, 2, figsize=(13, 4.2))
    policies = list(dict.fromkeys(row["policy"] for row in rows))
    looks = styles(policies)
    for policy in policies:
        points = sorted((r["magnitude"], r["success_rate"], r["final_distance_mean"]) for r in rows
                        if r["policy"] == policy)  # fmt: skip
        magnitude, success, error = (np.array(column, dtype=float) for column in zip(*points, strict=True))
        ax_success.plot(magnitude, success, label=policy, **looks[policy])
        ax_error.plot(magnitude, np.maximum(error, 1e-4), label=policy, **looks[policy])
    reference_line(ax_success, SUCCESS_LEVEL, f"{SUCCESS_LEVEL:.0%} success", vertical=False)
    magnitude_label = SWEEPS[name].magnitude if name in SWEEPS else f"{name} [-]"
    ax_success.set(xlabel=magnitude_label, ylabel=SUCCESS, ylim=(-0.02, 1.02), title=f"{name}: arrival by T_con")
    ax_error.set(xlabel=magnitude_label, ylabel="final distance, mean [m]", yscale="log",
                 title=f"{name}: final distance (floored at 0.1 mm)")  # fmt: skip
    figure_legend(fig)
    return save(fig, path)
