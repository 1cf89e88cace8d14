"""The recipes: the trainings behind the shipped agents and the docs' tables, each a shell script run as it is (hours
on 2 cores). A script is an entry of the suite by its path in ``registry.SUITE``; the first line of its header is what
``list`` prints, the rest says its steps and their times. The tables each one's JSON renders are named here."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from benchmarks.core.commands import recipe_main
from benchmarks.core.docs import BENCHMARK, NUMBER, Block, Schema, table


def _tables(*names: str) -> tuple[Block, ...]:
    return tuple(table(name, BENCHMARK) for name in names)


def _and_per_t_con(*names: str) -> tuple[Block, ...]:
    """Each table on the benchmark's sets, then the same entries at each T_con."""
    return _tables(*(f"{name}{tail}" for name in names for tail in ("", "-per-T_con")))


#: Entry -> the tables its JSON renders (the recipes not named render none).
BLOCKS: dict[str, tuple[Block, ...]] = {
    "rl-agents": _tables("rl-benchmark", "rl-goals", "rl-benchmark-readme", "rl-benchmark-disturbed"),
    "rl-time-scale": _and_per_t_con("rl-time-scale", "rl-time-scale-long"),
    "rl-apg-teacher": _and_per_t_con("rl-apg-teacher", "rl-apg-teacher-time-scaled"),
    **{
        name: _and_per_t_con(name)
        for name in (
            "rl-v2",
            "rl-apg",
            "rl-apg-scratch",
            "rl-apg-teacher-30min",
            "rl-apg-near-miss",
            "rl-apg-hold",
            "rl-apg-hold-heading10",
        )
    },
    "rl-constrained": (*_and_per_t_con("rl-constrained"), *_tables("rl-constrained-30min-per-T_con")),
    "sbx-tqc-v2": _and_per_t_con("sbx-v2-30min-tqc"),
    "robust-rl": (table("rl-robust", Schema({"rows": list, "seed": int, "n": int, "seconds": NUMBER})),),
}


def entry(name: str, script: Path) -> SimpleNamespace:
    """Entry ``name`` as the suite runs it: ``main`` runs ``script``; ``BLOCKS`` are the tables its JSON renders."""
    return SimpleNamespace(main=recipe_main(script), BLOCKS=BLOCKS.get(name, ()))
