"""The robust headline of ``dwr-gym compare``: every policy on the nominal set and the four disturbed sets, as a
table (in time, final heading error, energy, E/opt nominal, command-rate RMS) and as a Pareto figure (energy over
the optimum's against the worst in-time rate over the disturbed sets)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

DISTURBED = ("disturbed", "fault", "delay", "noise")
NOMINAL = "random"


def percent(value: Any) -> str:
    return "-" if value is None or value != value else f"{100 * value:.3g}"


def number(value: Any, fmt: str) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else format(value, fmt)


def headline(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One summary per policy that ran on the nominal set: its figures there and on each disturbed set present."""
    by = {(r["scenario"], r["policy"]): r for r in rows}
    sets = [name for name in DISTURBED if any(r["scenario"] == name for r in rows)]
    out = []
    for policy in dict.fromkeys(r["policy"] for r in rows if r["scenario"] == NOMINAL):
        nominal = by[(NOMINAL, policy)]
        disturbed = {name: by[(name, policy)] for name in sets if (name, policy) in by}
        out.append({
            "policy": policy,
            "in_time": {NOMINAL: nominal["success_rate"], **{k: v["success_rate"] for k, v in disturbed.items()}},
            "heading": {NOMINAL: nominal["final_heading_error_mean"],
                        **{k: v["final_heading_error_mean"] for k, v in disturbed.items()}},
            "energy": {NOMINAL: nominal["energy_mean"], **{k: v["energy_mean"] for k, v in disturbed.items()}},
            "energy_ratio": nominal.get("energy_ratio_mean"),
            "command_rate": {NOMINAL: nominal["command_rate_rms_mean"],
                             **{k: v["command_rate_rms_mean"] for k, v in disturbed.items()}},
            "worst_in_time": min((v["success_rate"] for v in disturbed.values()), default=float("nan")),
        })  # fmt: skip
    return out


def headline_table(rows: list[dict[str, Any]], names: dict[str, str] | None = None, energy_ratio: bool = True) -> str:
    """The headline as Markdown: a row per policy, the sets side by side; without ``energy_ratio`` (no optimum asked
    for) no E/opt column."""
    summary = headline(rows)
    sets = [NOMINAL, *[s for s in DISTURBED if any(s in h["in_time"] for h in summary)]]
    names = names or {}
    header = ["policy", "in time [%]: " + " / ".join(sets), "\\|psi_end\\| [rad]: " + " / ".join(sets),
              "energy: " + " / ".join(sets), *(["E/opt nominal"] if energy_ratio else []),
              "command rate RMS: nominal / noise"]  # fmt: skip
    lines = ["| " + " | ".join(header) + " |", "|---" * len(header) + "|"]
    for h in summary:
        cells = [
            names.get(h["policy"], f"`{h['policy']}`"),
            " / ".join(percent(h["in_time"].get(s)) for s in sets),
            " / ".join(number(h["heading"].get(s), ".2f") for s in sets),
            " / ".join(number(h["energy"].get(s), ".2f") for s in sets),
            *([number(h["energy_ratio"], ".2f")] if energy_ratio else []),
            f"{number(h['command_rate'].get(NOMINAL), '.2f')} / {number(h['command_rate'].get('noise'), '.2f')}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot_pareto(rows: list[dict[str, Any]], path: Path, names: dict[str, str] | None = None) -> Any:
    """Energy / optimum (nominal) against the worst in-time rate over the disturbed sets, one point per policy."""
    from train.reporting.plotting import figure_legend, pyplot, reference_line, save, styles

    plt = pyplot()
    summary = [h for h in headline(rows) if h["energy_ratio"] is not None and h["energy_ratio"] == h["energy_ratio"]]
    looks = styles([h["policy"] for h in summary])
    fig, ax = plt.subplots(figsize=(8.6, 4.8))
    for h in summary:
        look = {k: v for k, v in looks[h["policy"]].items() if k in ("color", "marker")}
        label = (names or {}).get(h["policy"], h["policy"]).strip("`*")
        ax.plot(h["energy_ratio"], 100 * h["worst_in_time"], linestyle="none", markersize=9, label=label, **look)
        ax.annotate(
            h["policy"],
            (h["energy_ratio"], 100 * h["worst_in_time"]),
            textcoords="offset points",
            xytext=(7, -3 if h["policy"] == "ptc" else 4),
            fontsize=8,
        )  # the name beside its point: colours repeat
    reference_line(ax, 97.0, "97 %: the goal on each disturbed set", vertical=False)
    reference_line(ax, 1.3, "1.3 x the optimum: the stretch goal", vertical=True)
    ax.set(xlabel="energy / the optimum's, nominal (mean over episodes) [-]",
           ylabel="worst in-time rate over disturbed, fault, delay, noise [%]")  # fmt: skip
    ax.set_xscale("log")
    figure_legend(fig)
    ax.set_title("Deadline under disturbances against energy: up and left is better", loc="left")
    return save(fig, path)
