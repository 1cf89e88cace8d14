"""Where the energy goes (train/evaluation/energy_split.py): the split adds up to the env's energy, PTC spends its
energy early and mostly turning, and the gain grid finds what its rows hold. Few episodes: the docs' tables have 100
each, from the archived docs/rl_benchmark/energy_split.json (``python -m benchmarks run archive --docs``)."""

from __future__ import annotations

import numpy as np
import pytest

from train.evaluation.energy_split import energy_split, gain_settings, law_gains
from train.reporting.energy_tables import gains_table, split_table


def test_the_split_adds_up_to_the_energy_the_env_counts_and_its_shares_to_one() -> None:
    result = energy_split({"ptc": "ptc", "pt-astolfi": "pt-astolfi"}, n=6, parts=4)
    assert [row["policy"] for row in result["rows"]] == ["ptc", "pt-astolfi"]
    for row in result["rows"]:
        assert row["in_time"] == 1.0 and len(row["shares"]) == 4
        assert row["linear_mean"] + row["turning_mean"] == pytest.approx(row["energy_mean"], rel=1e-9)
        assert sum(row["shares"]) == pytest.approx(1.0, abs=1e-9)
        assert all(np.isfinite(v) for v in (row["energy_mean"], row["final_heading_mean"], *row["shares"]))


def test_ptc_spends_its_energy_early_and_mostly_turning_while_pt_astolfi_ends_at_the_goal_heading() -> None:
    rows = {row["policy"]: row for row in energy_split({"ptc": "ptc", "pt-astolfi": "pt-astolfi"}, n=8)["rows"]}
    ptc, astolfi = rows["ptc"], rows["pt-astolfi"]
    assert sum(ptc["shares"][:2]) > 0.7  # the first two fifths of T_con: eq. (17)'s 1 / (T_con - t) gain, K2 = 10
    assert ptc["turning_mean"] > ptc["linear_mean"]
    assert sum(astolfi["shares"][:2]) < sum(ptc["shares"][:2])
    assert astolfi["final_heading_mean"] < 0.05 < ptc["final_heading_mean"]


def test_gain_settings_span_the_grid_in_order_and_refuse_an_empty_axis() -> None:
    assert gain_settings({"a": (1, 2), "b": (3.0,)}) == [{"a": 1.0, "b": 3.0}, {"a": 2.0, "b": 3.0}]
    with pytest.raises(ValueError, match=r"grid\['b'\]=\(\) is invalid"):
        gain_settings({"a": (1,), "b": ()})
    with pytest.raises(ValueError, match="n=0 is invalid"):
        law_gains(n=0)
    with pytest.raises(ValueError, match="n=0 and parts=5 are invalid"):
        energy_split({"ptc": "ptc"}, n=0)


def test_law_gains_leaves_out_what_a_law_refuses_and_names_its_lowest_e_opt_in_time() -> None:
    pytest.importorskip("casadi")
    grids = {"pt-astolfi": {"k_rho": (1.5, 5.0), "k_alpha": (4.7,), "k_beta": (-1.7, -0.5)}}
    result = law_gains(grids, n=4)
    # k_alpha must exceed k_rho: the settings with k_rho 5 are left out
    assert [row["gains"]["k_rho"] for row in result["rows"]] == [1.5, 1.5]
    in_time = [row for row in result["rows"] if row["in_time"] >= result["in_time_goal"]]
    best = result["best"]["pt-astolfi"]["any_heading"]
    assert best is not None and best["energy_ratio"] == min(row["energy_ratio"] for row in in_time)
    heading = result["best"]["pt-astolfi"]["heading_goal"]
    assert heading is None or heading["final_heading"] <= result["heading_goal"]
    assert all(row["energy_ratio"] is None or row["energy_ratio"] >= 1.0 - 1e-6 for row in result["rows"])
    data = {"gains": result, "defaults": {"pt-astolfi": {"k_rho": 1.5, "k_alpha": 4.7, "k_beta": -1.7}}}
    table = gains_table(data)
    assert "k_rho 1.5, k_alpha 4.7, k_beta -1.7 | default |" in table


def test_the_split_table_has_a_column_per_part_of_t_con() -> None:
    row = {"policy": "p", "in_time": 1.0, "energy_mean": 1.0, "linear_mean": 0.4, "turning_mean": 0.6,
           "shares": [0.5, 0.5], "final_heading_mean": 0.1}  # fmt: skip
    table = split_table({"split": {"parts": 2, "rows": [row], "episodes": 3, "env_id": "v2", "seed": 0}})
    assert (
        "| 0/2-1/2 T_con | 1/2-2/2 T_con |" in table and "| p | 1.00 | 1.000 | 0.400 | 0.600 | 50 % | 50 % |" in table
    )
