"""The open-loop bound (train/learning/jitted/open_loop_bound.py, train/evaluation/open_loop.py): what the best action sequence of each episode reaches."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("jax")
pytest.importorskip("optax")

from train.evaluation.open_loop import MEASURES, summary
from train.learning.jitted.open_loop_bound import open_loop_bound
from train.reporting.energy_tables import open_loop_table

SHORT = {"T_con_range": [2.0, 2.2]}  # 40-44 steps: a quick optimisation


@pytest.fixture(scope="module")
def on_ptc() -> dict:
    return open_loop_bound("ptc", 0.5, n=2, iterations=30, learning_rate=0.05, **SHORT)


def test_the_best_sequence_is_never_worse_than_the_law_and_beats_it_somewhere(on_ptc: dict) -> None:
    """The search starts at the zero residual (the law alone) and keeps each episode's best: its return is at least
    the law's on every episode, and Adam on the return improves it on some."""
    law, best = [np.array([row["return"] for row in on_ptc[k]]) for k in ("law", "best")]
    assert np.all(best >= law - 1e-5) and np.any(best > law + 1e-3)
    for row in on_ptc["law"] + on_ptc["best"]:
        assert set(MEASURES) <= set(row) and all(math.isfinite(row[m]) for m in MEASURES)
    assert len(on_ptc["starts"]) == len(on_ptc["goals"]) == len(on_ptc["T_con"]) == 2
    assert all(2.0 <= t <= 2.2 for t in on_ptc["T_con"])


def test_without_a_law_the_zero_sequence_stands_still_and_the_search_moves_toward_the_goal() -> None:
    result = open_loop_bound(None, n=2, iterations=30, learning_rate=0.05, **SHORT)
    assert all(row["energy"] == 0.0 for row in result["law"])
    assert summary(result["best"])["return"] > summary(result["law"])["return"] + 0.1


def test_the_table_has_the_law_and_the_best_and_marks_a_missing_e_opt(on_ptc: dict) -> None:
    variant = {**on_ptc, "law": [dict(r, energy_ratio=2.5) for r in on_ptc["law"]],
               "best": [dict(r, energy_ratio=None) for r in on_ptc["best"]]}  # fmt: skip
    text = open_loop_table({"variants": [variant], "machine": {}})
    law_line = next(line for line in text.splitlines() if "the law alone" in line)
    best_line = next(line for line in text.splitlines() if "best found per episode" in line)
    assert "residual on ptc (scale 0.5)" in law_line and "| 2.50 |" in law_line
    assert "| - | - |" in best_line and "30 Adam steps" in text
