"""The leaderboard: one row per method family's best recipe on the task, from the JSON each row's command wrote.

A row names its shipped agent (if any), the JSON its numbers come from and the command that regenerates that JSON;
:func:`leaderboard` reads them into one document (``python -m benchmarks run leaderboard`` writes it to
docs/leaderboard.json), and :func:`leaderboard_table` and :func:`per_T_con_table` render it. Learners are the IQM
over their seeds (``dwr-gym benchmark``); the controllers, the expert agents and the optimum are one evaluation each.
A cell with no measurement is "-", never a number carried over from another set.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
#: The prescribed times of the per-T_con columns [s].
T_CONS: tuple[int, ...] = (10, 20, 40, 60)
#: The measures of a row: the drawn-T_con set's in time, E/opt and final heading, the disturbed set's in time, and in
#: time at each of T_CONS.
MEASURES: tuple[str, ...] = ("in_time", "energy_ratio", "final_heading", "disturbed_in_time",
                             *(f"in_time_{T_con}" for T_con in T_CONS))  # fmt: skip


@dataclass(frozen=True)
class Row:
    """One line of the leaderboard: where its numbers are and how to regenerate them."""

    method: str
    """The method family, as a reader looks for it."""
    agent: str
    """The shipped agent, a directory of train/pretrained (``--agents train/pretrained/NAME``), or "-" for a
    controller or a learner not shipped."""
    source: str
    """The JSON, relative to the repository, that the numbers come from."""
    entry: str
    """The row's name inside that JSON (a benchmark entry, a controller, a policy)."""
    kind: str
    """How to read it: "benchmark" (an entry of ``dwr-gym benchmark``), "reference" (a controller evaluated beside
    one), "robust-goal" (a policy of ``robust-goal``, its nominal numbers from ``compare``), "compare" (a policy of
    ``dwr-gym compare`` alone)."""
    reproduce: str
    """The command that writes ``source``."""


ROWS: tuple[Row, ...] = (
    Row("APG from the reward (v2)", "apg_v2", "docs/rl_benchmark/apg_hold_heading10.json",
        "apg-hold-heading10-time-scaled-30min-v2", "benchmark", "python -m benchmarks run rl-apg-hold-heading10"),
    Row("APG, the deadline as a constraint (v2, 30 min)", "-", "docs/rl_benchmark/constrained_30min.json",
        "apg-lagrangian-averaged-v2", "benchmark", "python -m benchmarks run rl-constrained"),
    Row("residual on PTC, APG (v2)", "apg_residual_ptc_v2", "docs/rl_benchmark/apg.json", "apg-residual-v2",
        "benchmark", "python -m benchmarks run rl-apg"),
    Row("residual on PTC, constrained (v2)", "-", "docs/rl_benchmark/constrained.json",
        "apg-lagrangian-residual-ptc-v2", "benchmark", "python -m benchmarks run rl-constrained"),
    Row("PPO, jitted (v1)", "ppo_jax_v1", "docs/rl_benchmark/benchmark.json", "ppo-jax", "benchmark",
        "python -m benchmarks run rl-agents"),
    Row("PPO-Lagrangian, jitted (v2, 30 min)", "-", "docs/rl_benchmark/constrained.json", "ppo-lagrangian-30min-v2",
        "benchmark", "python -m benchmarks run rl-constrained"),
    Row("ES (v1, arena 50 m)", "es_v1", "docs/rl_benchmark/benchmark.json", "es-arena50", "benchmark",
        "python -m benchmarks run rl-agents"),
    Row("TQC, sbx (v2, 30 min)", "-", "docs/rl_benchmark/sbx_v2_30min_tqc.json", "tqc-sbx-v2", "benchmark",
        "python -m benchmarks run sbx-tqc-v2"),
    Row("cloned from robust-pt (v1)", "robust", "docs/robust/goal.json", "robust", "robust-goal",
        "python -m benchmarks run robust-goal --n 200 --docs"),
    Row("PTC, the paper's law (16)-(19)", "-", "docs/rl_benchmark/apg_hold_heading10.json", "ptc", "reference",
        "python -m benchmarks run rl-apg-hold-heading10"),
    Row("pt-astolfi", "-", "docs/rl_benchmark/apg_hold_heading10.json", "pt-astolfi", "reference",
        "python -m benchmarks run rl-apg-hold-heading10"),
    Row("robust-pt (re-planning expert)", "-", "docs/robust/goal.json", "robust-pt", "robust-goal",
        "python -m benchmarks run robust-goal --n 200 --docs"),
    Row("the optimum", "-", "docs/compare/comparison.json", "optimal", "compare", "python -m benchmarks run compare"),
)  # fmt: skip
#: The env id of robust-goal's sets (``python -m benchmarks run robust-goal``: v1's episode end and in-time rule).
ROBUST_GOAL_ENV_ID = "DWRPointStabilization-v1"
#: The JSON of ``dwr-gym compare`` (the nominal numbers of the robust-goal rows).
COMPARE_JSON = "docs/compare/comparison.json"


def _iqm(value: Any) -> float | None:
    """A number of a benchmark JSON: the IQM of an aggregate, a plain number, or None."""
    if isinstance(value, dict):
        value = value.get("iqm")
    return None if value is None else float(value)


def _read(path: str, root: Path) -> Any:
    return json.loads((root / path).read_text())


def _compare_rows(root: Path) -> dict[tuple[str, str], dict[str, Any]]:
    return {(row["policy"], row["scenario"]): row for row in _read(COMPARE_JSON, root)}


def measures(row: Row, root: Path = ROOT) -> dict[str, Any]:
    """The row's measures (:data:`MEASURES`; None where not measured), its seeds and training seconds."""
    data = _read(row.source, root)
    cells: dict[str, Any] = dict.fromkeys(MEASURES)
    cells.update(seeds=None, seconds=None, env=None)
    if row.kind == "benchmark":
        entry = data["summary"][row.entry]
        sets = entry["sets"]
        for key in ("in_time", "energy_ratio", "final_heading"):
            cells[key] = _iqm(sets.get("random", {}).get(key))
        cells["disturbed_in_time"] = _iqm(sets.get("disturbed", {}).get("in_time"))
        for T_con in T_CONS:
            cells[f"in_time_{T_con}"] = _iqm(sets.get(f"T_con={T_con}", {}).get("in_time"))
        cells.update(
            seeds=len(entry["seeds"]),
            seconds=_iqm(entry.get("seconds")),
            env=entry.get("env_id", "DWRPointStabilization-v1"),
        )  # (v1: the entries that predate the key)
    elif row.kind == "reference":
        sets = data["references"][row.entry]
        for key in ("in_time", "energy_ratio", "final_heading"):
            cells[key] = _iqm(sets.get("random", {}).get(key))
        cells["disturbed_in_time"] = _iqm(sets.get("disturbed", {}).get("in_time"))
        for T_con in T_CONS:
            cells[f"in_time_{T_con}"] = _iqm(sets.get(f"T_con={T_con}", {}).get("in_time"))
        cells["env"] = data.get("references_env")
    elif row.kind in ("robust-goal", "compare"):
        compared = _compare_rows(root)
        nominal, disturbed = compared.get((row.entry, "random")), compared.get((row.entry, "disturbed"))
        if nominal is not None:
            cells.update(in_time=nominal["success_rate"], energy_ratio=nominal["energy_ratio_mean"],
                         final_heading=nominal["final_heading_error_mean"], env=nominal.get("env_id"))  # fmt: skip
        if disturbed is not None:
            cells["disturbed_in_time"] = disturbed["success_rate"]
        # robust-goal's sets end as v1's episodes: its in-time cells stand beside compare's only on the same env id
        if row.kind == "robust-goal" and cells["env"] in (None, ROBUST_GOAL_ENV_ID):
            for item in data["rows"]:
                if item["policy"] == row.entry and item["set"] == "random" and int(item["T_con"]) in T_CONS:
                    cells[f"in_time_{int(item['T_con'])}"] = item["success_rate"]
    else:
        raise ValueError(f"kind={row.kind!r} is invalid: expected benchmark, reference, robust-goal or compare")
    return cells


def leaderboard(root: Path = ROOT) -> dict[str, Any]:
    """Every row of :data:`ROWS` with its measures; a row whose JSON or entry is missing is left out, named in
    ``missing``."""
    rows, missing = [], []
    for row in ROWS:
        try:
            cells = measures(row, root)
        except (FileNotFoundError, KeyError) as error:
            missing.append(f"{row.method}: {row.source} ({error})")
            continue
        rows.append({"method": row.method, "agent": row.agent, "source": row.source, "entry": row.entry,
                     "reproduce": row.reproduce, **cells})  # fmt: skip
    return {"rows": rows, "missing": missing, "T_cons": list(T_CONS)}


def _cell(value: Any, digits: int = 2, percent: bool = False) -> str:
    if value is None:
        return "-"
    return f"{100 * value:.1f} %" if percent else f"{value:.{digits}f}"


def leaderboard_table(data: dict[str, Any]) -> str:
    """The leaderboard: in time on the drawn T_con and at T_con 10 s, E/opt, heading, disturbed, cost to train."""
    lines = ["| method | shipped agent | env | in time | in time at T_con 10 s | E/opt | final heading [rad] | "
             "disturbed: in time | seeds | training [min] |", "|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for row in data["rows"]:
        env = str(row["env"] or "-").rsplit("-", 1)[-1]
        agent = "-" if row["agent"] == "-" else f"`{row['agent']}`"
        seconds = "-" if row["seconds"] is None else f"{row['seconds'] / 60:.0f}"
        lines.append(f"| {row['method']} | {agent} | {env} | {_cell(row['in_time'], percent=True)} | "
                     f"{_cell(row['in_time_10'], percent=True)} | {_cell(row['energy_ratio'])} | "
                     f"{_cell(row['final_heading'])} | {_cell(row['disturbed_in_time'], percent=True)} | "
                     f"{row['seeds'] or '-'} | {seconds} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def per_T_con_table(data: dict[str, Any]) -> str:
    """In time at each T_con of :data:`T_CONS`, and the command that regenerates each row."""
    head = " | ".join(f"T_con {T_con} s" for T_con in data["T_cons"])
    lines = [f"| method | {head} | regenerate |", "|---|" + "---:|" * len(data["T_cons"]) + "---|"]
    for row in data["rows"]:
        cells = " | ".join(_cell(row[f"in_time_{T_con}"], percent=True) for T_con in data["T_cons"])
        lines.append(f"| {row['method']} | {cells} | `{row['reproduce']}` |")
    return "\n".join(lines) + "\n"


__all__ = ["MEASURES", "ROWS", "T_CONS", "Row", "leaderboard", "leaderboard_table", "measures", "per_T_con_table"]
