"""Where the agents miss on v2 (benchmarks/learning/misses.py): the measure and its table."""

from __future__ import annotations

from typing import Any

import numpy as np

from benchmarks.learning.misses import misses
from train.reporting.energy_tables import misses_table


class StandStill:
    """A policy that never moves: every v2 episode misses where it started, inside the arena."""

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> Any:
        return np.zeros((len(observation), 2), np.float32), None


def test_a_robot_that_stands_still_misses_where_it_started_and_stays_in_the_arena() -> None:
    row = misses(StandStill(), n=6, seed=3, T_con=1.0)
    assert (row["n"], row["misses"], row["in_time"], row["left_arena"]) == (6, 6, 0.0, 0)
    assert row["final_distance_median"] == row["start_distance_median"] >= 0.3  # v2's starts are 0.3-3 m away
    assert row["within_2cm"] == 0.0
    data = {"env_id": "DWRPointStabilization-v2", "seed": 3, "agents": [{"agent": "still", "rows": [row]}]}
    table = misses_table(data)
    assert "| still | 1 | 0.0 % | 6 | 0 |" in table and "6 random episodes" in table
