"""What the returns pay for (train/evaluation/incentives.py): on v2 the optimum earns the most and arriving later
pays more; on v1 the discount pays for the early arrival (the RL benchmark's diagnosis). Few episodes: the docs'
table has 200 (ranking) and 16 per cell (rushing), from benchmarks/incentives.py."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym

pytest.importorskip("casadi")
from train.evaluation.incentives import (
    CONTROLLERS,
    controller_policy,
    return_ranking,
    rushing_returns,
    training_discount,
)


def test_the_learners_discount_is_1_on_v2_and_0_999_on_v1() -> None:
    assert training_discount(dwr_gym.ENV_ID_V2) == 1.0
    assert training_discount(dwr_gym.ENV_ID_V1) == 0.999


def test_on_v2_the_optimum_earns_the_most_return() -> None:
    params = gym.make(dwr_gym.ENV_ID_V2).unwrapped.params
    ranking = return_ranking(dwr_gym.ENV_ID_V2, {name: controller_policy(name, params) for name in CONTROLLERS}, n=6)
    assert ranking["first"] == "optimal" and ranking["discount"] == 1.0
    means = {row["policy"]: row["return_mean"] for row in ranking["rows"]}
    assert means["optimal"] > max(means["ptc"], means["pt-astolfi"])


def test_without_noise_v2_pays_the_latest_arrival_most_and_v1_pays_an_earlier_one() -> None:
    v2 = rushing_returns(dwr_gym.ENV_ID_V2, fractions=(0.5, 1.0), sigmas=(0.0,), n=4)
    v1 = rushing_returns(dwr_gym.ENV_ID_V1, fractions=(0.5, 1.0), sigmas=(0.0,), n=4)
    assert v2["latest_pays_most"] == {"0.0": True}
    assert v1["latest_pays_most"] == {"0.0": False}  # the bonus, discounted by 0.999 per step, pays for rushing
    for result in (v1, v2):
        assert all(row["in_time"] == 1.0 for row in result["rows"])
        early, late = sorted(result["rows"], key=lambda row: row["fraction"])
        assert early["energy_mean"] > late["energy_mean"]  # the earlier plan costs more energy on both
        assert np.isclose(late["arrival_fraction"], 1.0, atol=0.02)


@pytest.mark.slow
def test_with_action_noise_v2_still_pays_the_latest_arrival_most() -> None:
    v2 = rushing_returns(dwr_gym.ENV_ID_V2, fractions=(0.3, 1.0), sigmas=(0.1,), n=4, workers=2)
    assert v2["latest_pays_most"] == {"0.1": True}
