"""The figures of ``dwr-gym robustness``: success by T_con and final distance against each disturbance's magnitude."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from train.evaluation.robustness import SUCCESS_LEVEL, SWEEPS
from train.reporting.plotting import pyplot, save


def plot_robustness(rows: list[dict[str, Any]], out_dir: Path) -> list[Path]:
    """One PNG per disturbance: success by T_con and mean final distance against the magnitude."""
    plt = pyplot()
    paths = []
    for name in dict.fromkeys(row["disturbance"] for row in rows):
        fig, (ax_success, ax_error) = plt.subplots(1, 2, figsize=(11, 4))
        for policy in dict.fromkeys(row["policy"] for row in rows):
            points = sorted((r["magnitude"], r["success_rate"], r["final_distance_mean"]) for r in rows
                            if r["disturbance"] == name and r["policy"] == policy)  # fmt: skip
            magnitude, success, error = (np.array(column) for column in zip(*points, strict=True))
            style = "--" if "ppo" in policy else "-"
            ax_success.plot(magnitude, success, style, marker="o", label=policy)
            ax_error.plot(magnitude, np.maximum(error, 1e-4), style, marker="o", label=policy)
        ax_success.axhline(SUCCESS_LEVEL, color="grey", lw=0.8, ls=":")
        ax_success.set(xlabel=SWEEPS[name].magnitude if name in SWEEPS else name, ylabel="success by T_con",
                       ylim=(-0.02, 1.02), title=f"{name}: arrival by T_con")  # fmt: skip
        ax_error.set(xlabel=SWEEPS[name].magnitude if name in SWEEPS else name, ylabel="final distance, mean [m]",
                     yscale="log", title=f"{name}: final distance")  # fmt: skip
        ax_error.legend(fontsize=8)
        path = out_dir / f"robustness_{name}.png"
        save(fig, path)
        paths.append(path)
    return paths
