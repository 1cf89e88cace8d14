"""The leaderboard: each row's numbers are its source JSON's, read again here by hand; a missing source is named."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from train.reporting import leaderboard as board

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("row", [row for row in board.ROWS if (ROOT / row.source).is_file()], ids=lambda r: r.method)
def test_each_rows_cells_are_its_sources_numbers(row: board.Row) -> None:
    cells = board.measures(row, ROOT)
    data = json.loads((ROOT / row.source).read_text())
    if row.kind == "benchmark":
        sets = data["summary"][row.entry]["sets"]
        assert cells["in_time"] == sets["random"]["in_time"]["iqm"], (row.method, "in_time")
        assert cells["energy_ratio"] == sets["random"]["energy_ratio"]["iqm"], (row.method, "energy_ratio")
        assert cells["final_heading"] == sets["random"]["final_heading"]["iqm"], (row.method, "final_heading")
        if "T_con=10" in sets:  # the shortest deadline's own set, not the nominal one's
            assert cells["in_time_10"] == sets["T_con=10"]["in_time"]["iqm"], (row.method, "in_time_10")
        assert cells["seeds"] == len(data["summary"][row.entry]["seeds"])
    elif row.kind == "reference":
        assert cells["in_time"] == data["references"][row.entry]["random"]["in_time"]
        assert cells["in_time_60"] == data["references"][row.entry]["T_con=60"]["in_time"]
    else:
        compared = json.loads((ROOT / board.COMPARE_JSON).read_text())
        nominal = next(r for r in compared if r["policy"] == row.entry and r["scenario"] == "random")
        assert cells["in_time"] == nominal["success_rate"] and cells["energy_ratio"] == nominal["energy_ratio_mean"]
        if row.kind == "robust-goal" and nominal.get("env_id") == board.ROBUST_GOAL_ENV_ID:
            at_10 = next(
                r for r in data["rows"] if r["policy"] == row.entry and r["set"] == "random" and r["T_con"] == 10
            )
            assert cells["in_time_10"] == at_10["success_rate"]
        elif row.kind == "robust-goal":  # robust-goal's v1 cells are not set beside another env id's
            assert all(cells[f"in_time_{T_con}"] is None for T_con in board.T_CONS), row.method


def test_a_row_whose_json_is_missing_is_named_not_filled(tmp_path: Path) -> None:
    for row in board.ROWS:
        if (ROOT / row.source).is_file():
            (tmp_path / row.source).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / row.source, tmp_path / row.source)
    shutil.copy(ROOT / board.COMPARE_JSON, tmp_path / board.COMPARE_JSON)
    gone = board.ROWS[0]
    (tmp_path / gone.source).unlink()
    data = board.leaderboard(tmp_path)
    assert gone.method not in [row["method"] for row in data["rows"]]
    assert any(gone.method in missing for missing in data["missing"])
    table = board.leaderboard_table(data)
    assert "nan" not in table and len(table.strip().splitlines()) == 2 + len(data["rows"])


def test_the_shipped_agents_are_the_leaderboards_each_on_the_env_its_row_names() -> None:
    """One shipped agent per row that names one, and those are what ``dwr-gym compare`` runs by default; the paper's
    reward's record (v0) is shipped beside them, compared only when named."""
    from train.learning.agents import PAPER_AGENTS, PRETRAINED, PRETRAINED_DIR, default_agents, trained_env_id

    rows = [row for row in board.ROWS if row.agent != "-"]
    assert sorted(path.name for path in default_agents().values()) == sorted(row.agent for row in rows)
    assert set(PRETRAINED) == {row.agent.replace("_", "-") for row in rows} | set(PAPER_AGENTS)
    for row in rows:
        trained = trained_env_id(PRETRAINED_DIR / row.agent)
        assert f"({trained.rsplit('-', 1)[-1]}" in row.method, (row.method, trained)
        env = board.measures(row, ROOT)["env"]
        assert env in (None, trained), (row.method, env, trained)
    for name in PAPER_AGENTS:
        assert trained_env_id(PRETRAINED[name]) == "DWRPointStabilization-v0"
