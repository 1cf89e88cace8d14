"""The tables of the RL benchmark's pages (docs/rl-benchmark.md, rl-v2.md, rl-apg.md, what-was-tried.md and
rl-libraries.md, and the README's summary), each from the JSON that ``dwr-gym benchmark`` or a benchmark script
wrote: :data:`RL_TABLES`, which :data:`train.reporting.doc_tables.TABLES` includes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def random_and_per_T_con(name: str, path: str) -> dict[str, tuple[str, Callable[[Any], str]]]:
    """Tables ``name`` (the nominal set) and ``name-per-T_con`` of one benchmark JSON ``path``."""
    return {name: (path, lambda data: rl_table(data, "random")),
            f"{name}-per-T_con": (path, lambda data: rl_table(data, "per-T_con"))}  # fmt: skip


RL_TABLES: dict[str, tuple[str, Callable[[Any], str]]] = {
    "rl-benchmark": ("docs/rl_benchmark/benchmark.json", lambda data: rl_table(data, "random")),
    "rl-residual": ("docs/rl_benchmark/residual.json", lambda data: rl_table(data, "residual")),
    "rl-sweep": ("docs/rl_benchmark/sweep.json", lambda data: rl_table(data, "sweep")),
    "rl-sweep-jax": ("docs/rl_benchmark/sweep_ppo_jax.json", lambda data: rl_table(data, "sweep")),
    "rl-sweep-sac": ("docs/rl_benchmark/sweep_sac.json", lambda data: rl_table(data, "sweep")),
    "rl-sweep-tqc": ("docs/rl_benchmark/sweep_tqc.json", lambda data: rl_table(data, "sweep")),
    "rl-anneal": ("docs/rl_benchmark/anneal.json", lambda data: rl_table(data, "random")),
    "rl-goals": ("docs/rl_benchmark/benchmark.json", lambda data: rl_table(data, "goals")),
    "rl-benchmark-readme": ("docs/rl_benchmark/benchmark.json", lambda data: rl_table(data, "readme")),
    "rl-benchmark-disturbed": ("docs/rl_benchmark/benchmark.json", lambda data: rl_table(data, "disturbed")),
    **random_and_per_T_con("rl-v2", "docs/rl_benchmark/v2.json"),
    "rl-time-scale": ("docs/rl_benchmark/time_scale.json", lambda data: rl_table(data, "random")),
    **random_and_per_T_con("rl-apg", "docs/rl_benchmark/apg.json"),
    **random_and_per_T_con("rl-apg-scratch", "docs/rl_benchmark/apg_scratch.json"),
    "rl-apg-teacher": ("docs/rl_benchmark/apg_teacher.json", lambda data: rl_table(data, "random")),
    **random_and_per_T_con("rl-apg-teacher-30min", "docs/rl_benchmark/apg_teacher_30min.json"),
    **random_and_per_T_con("rl-apg-near-miss", "docs/rl_benchmark/apg_near_miss.json"),
    **random_and_per_T_con("rl-apg-hold", "docs/rl_benchmark/apg_hold.json"),
    **random_and_per_T_con("rl-apg-hold-heading10", "docs/rl_benchmark/apg_hold_heading10.json"),
    "rl-apg-teacher-per-T_con": ("docs/rl_benchmark/apg_teacher.json", lambda data: rl_table(data, "per-T_con")),
    **random_and_per_T_con("rl-apg-teacher-time-scaled", "docs/rl_benchmark/apg_teacher_time_scaled.json"),
    "rl-time-scale-per-T_con": ("docs/rl_benchmark/time_scale.json", lambda data: rl_table(data, "per-T_con")),
    **random_and_per_T_con("rl-time-scale-long", "docs/rl_benchmark/time_scale_long.json"),
    **random_and_per_T_con("rl-time-scale-30min", "docs/rl_benchmark/time_scale_30min.json"),
    "rl-diagnosis": ("docs/rl_benchmark/diagnosis.json", lambda data: rl_table(data, "diagnosis")),
    "rl-levers": ("docs/rl_benchmark/levers.json", lambda data: rl_table(data, "levers")),
    "rl-rushing": ("docs/rl_benchmark/rushing.json", lambda data: rl_table(data, "rushing")),
    "rl-rushing-v2": ("docs/rl_benchmark/rushing_v2.json", lambda data: rl_table(data, "rushing")),
    "sbx-v1": ("docs/rl_benchmark/sbx_v1.json", lambda data: rl_table(data, "random")),
    "sbx-v2": ("docs/rl_benchmark/sbx_v2.json", lambda data: rl_table(data, "random")),
    "sbx-v2-long": ("docs/rl_benchmark/sbx_v2_long.json", lambda data: rl_table(data, "random")),
    "sbx-v2-seeds": ("docs/rl_benchmark/sbx_v2_seeds.json", lambda data: rl_table(data, "random")),
    "sbx-v2-30min": ("docs/rl_benchmark/sbx_v2_30min.json", lambda data: rl_table(data, "random")),
    **random_and_per_T_con("sbx-v2-30min-tqc", "docs/rl_benchmark/sbx_v2_30min_tqc.json"),
    "rl-constrained": ("docs/rl_benchmark/constrained.json", lambda data: rl_table(data, "random")),
    "rl-constrained-per-T_con": (
        "docs/rl_benchmark/constrained.json",
        lambda data: rl_table(data, "per-T_con-heading"),
    ),
    "rl-constrained-30min-per-T_con": (
        "docs/rl_benchmark/constrained_30min.json",
        lambda data: rl_table(data, "per-T_con-heading"),
    ),
    "leaderboard": ("docs/leaderboard.json", lambda data: leaderboard_table(data)),
    "leaderboard-per-T_con": ("docs/leaderboard.json", lambda data: leaderboard_per_T_con(data)),
    "rl-constrained-log": ("docs/rl_benchmark/constrained_log.json", lambda data: constraint_log_table(data)),
}


def leaderboard_table(data: dict[str, Any]) -> str:
    from train.reporting.leaderboard import leaderboard_table as table

    return table(data)


def leaderboard_per_T_con(data: dict[str, Any]) -> str:
    from train.reporting.leaderboard import per_T_con_table

    return per_T_con_table(data)


def constraint_log_table(data: dict[str, Any]) -> str:
    """Each constrained run's last logged violation rate, mean final heading and multipliers, a cell per measure with
    its T_con bins in order, "/" between them (the JSON of ``python -m benchmarks run constraint-log``)."""
    runs = data["runs"]
    bins = " / ".join(f"{row['T_con_low']:g}-{row['T_con_high']:g}" for row in runs[0]["bins"]) if runs else ""
    lines = [f"| run | env steps | violation rate ({bins} s) | final heading [rad] | deadline multiplier | "
             "heading multiplier |", "|---|---:|---|---|---|---|"]  # fmt: skip
    for run in runs:
        cells = [" / ".join(f"{row[key]:{form}}" for row in run["bins"])
                 for key, form in (("violation_rate", ".2f"), ("heading", ".2f"), ("deadline_multiplier", ".0f"),
                                   ("heading_multiplier", ".0f"))]  # fmt: skip
        lines.append(f"| {run['run']} | {run['timesteps']:,} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def rl_table(data: dict[str, Any], kind: str) -> str:
    """The tables of the RL benchmark's pages (train.reporting.rl_benchmark), ending in a newline."""
    text = _rl_table(data, kind)
    return text if text.endswith("\n") else text + "\n"


def _rl_table(data: dict[str, Any], kind: str) -> str:
    from train.reporting import rl_benchmark

    if kind == "diagnosis":
        return rl_benchmark.diagnosis_table(data)
    if kind == "levers":
        return rl_benchmark.levers_table(data)
    if kind == "sweep":
        return rl_benchmark.sweep_table(data)
    if kind == "residual":
        return rl_benchmark.residual_table(data)
    if kind == "rushing":
        return rl_benchmark.rushing_table(data)
    if kind == "goals":
        return rl_benchmark.goals_table(data["summary"])
    if kind == "readme":
        return rl_benchmark.table(
            data["summary"], data["references"], columns=("in_time", "energy_ratio", "final_heading")
        )
    if kind == "disturbed":
        return rl_benchmark.disturbed_table(data["summary"], data["references"])
    if kind in ("per-T_con", "per-T_con-heading"):
        return rl_benchmark.per_T_con_table(data["summary"], data["references"], data.get("references_env"),
                                            heading=kind == "per-T_con-heading")  # fmt: skip
    return rl_benchmark.table(data["summary"], data["references"])
