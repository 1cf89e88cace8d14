"""The tables printed by ``evaluate``, ``compare``, ``robustness`` and ``sweep``, with the notes under them."""

from __future__ import annotations

import json
import math
from typing import Any

from train.evaluation.robustness import SUCCESS_LEVEL, SWEEPS, tolerated


def format_table(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]]) -> str:
    """Rows as an aligned text table; ``columns`` are (key, header, format)."""
    cells = [[header for _, header, _ in columns]]
    for row in rows:
        cells.append([cell(row, key, fmt) for key, _, fmt in columns])
    widths = [max(len(r[i]) for r in cells) for i in range(len(columns))]
    lines = [
        "  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=True)))
        for r in cells
    ]
    lines.insert(1, "-" * len(lines[0]))
    return "\n".join(lines)


def cell(row: dict[str, Any], key: str, fmt: str) -> str:
    """One cell: a T_con drawn per episode as its range; a mean E/opt over fewer episodes than the row's with how
    many stand behind it (an agent in time on 3 of 200 would otherwise look better than a law in time on all)."""
    value = row[key]
    if key == "T_con" and isinstance(value, float) and math.isnan(value) and row.get("T_con_range"):
        low, high = row["T_con_range"]
        return f"drawn in [{low:g}, {high:g}]"
    text = format(value, fmt) if isinstance(value, float) else str(value)
    behind = row.get("energy_ratio_episodes")
    if key == "energy_ratio_mean" and isinstance(value, float) and math.isfinite(value) and behind is not None:
        if behind < row["n"]:
            return f"{text} ({behind:.0f}/{row['n']:.0f})"
    return text


EVAL_COLUMNS = [
    ("scenario", "scenario", ""),
    ("T_con", "T_con", "g"),
    ("policy", "policy", ""),
    ("n", "n", ".0f"),
    ("success_rate", "success", ".3f"),
    ("arrival_time_mean", "t_arr mean", ".2f"),
    ("arrival_time_max", "t_arr max", ".2f"),
    ("arrival_fraction_max", "t_arr/T max", ".3f"),
    ("final_distance_max", "d_end max", ".4f"),
    ("final_heading_error_mean", "|psi_end| mean", ".3f"),
    ("peak_u_max", "peak u", ".3f"),
    ("peak_omega_max", "peak w", ".3f"),
    ("energy_mean", "energy", ".3f"),
    ("energy_ratio_mean", "E/opt mean", ".2f"),
    ("energy_ratio_max", "E/opt max", ".2f"),
    ("path_length_mean", "path", ".3f"),
    ("command_rate_rms_mean", "rate rms", ".3f"),
]

#: The columns of the E/opt measure, there only when an optimum was asked for (``--optimum pose`` or ``position``).
OPTIMUM_COLUMNS = frozenset({"energy_ratio_mean", "energy_ratio_max"})


def asked_columns(columns: list[tuple[str, str, str]], optimum: str) -> list[tuple[str, str, str]]:
    """``columns`` less those of a measure that was not asked for: E/opt's with ``optimum`` "none" (a column of nan
    says nothing the user does not know)."""
    return [column for column in columns if optimum != "none" or column[0] not in OPTIMUM_COLUMNS]


FAILS_BY_DESIGN = {
    "fabregas": "fabregas is the slow law of ref. [9] (u = K0 d p, not prescribed-time): the paper compares it at "
    "T_con = 70 s (paper-fig7); it is not designed to arrive by a shorter T_con, so its low success there is by design",
}


def table_notes(rows: list[dict[str, Any]]) -> str:
    """One line per policy whose low success rate the table alone would not explain."""
    failing = {row["policy"] for row in rows if row["policy"] in FAILS_BY_DESIGN and row["success_rate"] < 0.5}
    return "\n".join(f"note: {FAILS_BY_DESIGN[name]}" for name in sorted(failing))


def print_blocks(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]]) -> None:
    """The table, one block per (scenario, T_con), with notes on the optimum (policies that fail by design are
    explained once, by :func:`table_notes`)."""

    def block_of(row: dict[str, Any]) -> str:
        T_con = row["T_con"]
        if T_con == T_con:
            return f"{row['scenario']}, T_con = {T_con:g} s"
        drawn = " in [{:g}, {:g}] s".format(*row["T_con_range"]) if row.get("T_con_range") else ""
        return f"{row['scenario']}, T_con drawn per episode{drawn}"

    blocks: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        blocks.setdefault(block_of(row), []).append(row)
    for title, block in blocks.items():
        print(f"\n{title}")
        print(format_table(block, columns))
    noted = {block_of(r): r for r in rows if r.get("optimum_failures")}
    for title, row in noted.items():
        print(f"note: {title}: {row['optimum_failures']:.0f} episode(s) have no optimum (E/opt is nan there); "
              f"the first: {row['optimum_note']}")  # fmt: skip
    if any(row.get("planner_failures") for row in rows):
        print("note: the optimal controller found no plan for some robots (planner_failures in the JSON); "
              "they stood still and count as failures")  # fmt: skip
    if any(row["optimal_energy_mean"] == row["optimal_energy_mean"] for row in rows):  # not NaN
        print("E/opt: energy / minimum energy to the goal pose by T_con, over the episodes that succeeded")


def tolerance_markdown(rows: list[dict[str, Any]], level: float = SUCCESS_LEVEL) -> str:
    """The tolerance table of ``dwr-gym robustness`` as Markdown: one row per disturbance, one column per policy.

    A cell "0.2" means success >= level at every swept magnitude up to 0.2; a trailing "+" that the
    policy held up to the largest magnitude swept; "-" that it is below the level even undisturbed;
    an empty cell that it was not run on that disturbance.
    """
    table = tolerated(rows, level)
    policies = list(dict.fromkeys(row["policy"] for row in rows))
    disturbances = list(dict.fromkeys(row["disturbance"] for row in rows))
    sizes = {row["policy"]: int(row["n"]) for row in rows}
    header = " | ".join(f"{policy} (n={sizes[policy]})" for policy in policies)
    lines = [f"| disturbance (magnitude) | {header} |", "|---" * (len(policies) + 1) + "|"]
    for name in disturbances:
        largest = max(row["magnitude"] for row in rows if row["disturbance"] == name)
        cells = []
        for policy in policies:
            value = table.get((name, policy), math.inf)  # inf: not run on this disturbance
            cells.append(
                "" if value == math.inf else "-" if value is None else f"{value:g}" + ("+" if value == largest else "")
            )
        lines.append(f"| {name} ({SWEEPS[name].magnitude if name in SWEEPS else ''}) | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def format_trials(table: list[dict[str, Any]], columns: tuple[str, ...]) -> str:
    """The trials of ``dwr-gym sweep``: mean +- sd over seeds of each of ``columns``, one line per configuration."""
    lines = [f"{'config':<10} {'seeds':>5} " + " ".join(f"{c:>22}" for c in columns) + "  hyperparameters"]
    for row in table:
        cells = " ".join(f"{row[c + '_mean']:>12.3f} +- {row[c + '_sd']:<6.3f}" for c in columns)
        lines.append(f"{row['config']:<10} {row['seeds']:>5} {cells}  {json.dumps(row['hyperparams'])}")
    return "\n".join(lines)
