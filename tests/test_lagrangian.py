"""The deadline as a constraint in APG: multipliers per T_con bin in PID form (train.learning.jitted.lagrangian), what
they weigh in the gradient, their log, and a run with them that resumes bit for bit."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.jitted_runs import assert_resume_is_bit_for_bit
from train.learning.config import ConfigError
from train.learning.jitted import lagrangian
from train.learning.jitted.apg_settings import APGSettings
from train.learning.jitted.lagrangian import LagrangeSettings, Multipliers


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"cost_budget": 0}, r"^cost_budget=0(\.0)? is invalid: expected a finite number in \(0, 1\)$"),
        ({"cost_budget": 1}, r"^cost_budget=1(\.0)? is invalid: expected a finite number in \(0, 1\)$"),
        ({"heading_budget": -0.1}, r"^heading_budget=-0.1 is invalid"),
        ({"pid_ki": -1}, r"^pid_ki=-1(\.0)? is invalid: expected a finite number in \[0, 1e\+06\]$"),
        ({"pid_kp": -1}, r"^pid_kp=-1(\.0)? is invalid"),
        ({"multiplier_bins": 0}, r"^multiplier_bins=0 is invalid: expected an integer in \[1, 100\]$"),
        ({"multiplier_init": -5}, r"^multiplier_init=-5(\.0)? is invalid"),
        ({"multiplier_max": 0}, r"^multiplier_max=0(\.0)? is invalid"),
        ({"pid_average": 1}, r"^pid_average=1(\.0)? is invalid"),
        ({"lagrangian": 2}, r"^lagrangian=2 is invalid"),
        (
            {"lagrangian": 1, "hold_steps": 20, "hold_heading_weight": 10},
            r"^hold_heading_weight=10(\.0)? is invalid with lagrangian=1 \(the multipliers weigh the constraints\)",
        ),
    ],
)
def test_bad_constraint_options_are_refused_in_one_line(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError, match=message) as error:
        APGSettings.from_algo_kwargs(overrides)
    assert "\n" not in str(error.value)


def settings(**kwargs: Any) -> LagrangeSettings:
    return LagrangeSettings(lagrangian=True, multiplier_bins=2, **kwargs)


def run(state: Multipliers, rates: list[float], heading: float, s: LagrangeSettings, times: int) -> Multipliers:
    measured = np.array([rates, [heading] * len(rates)], np.float32)
    for _ in range(times):
        state = lagrangian.pid_update(state, measured, np.ones(len(rates)), s, np)
    return state


def test_a_multiplier_rises_while_violated_and_falls_to_zero_never_below_when_met() -> None:
    s = settings(multiplier_init=1.0, pid_kp=0.0, pid_ki=1.0)
    start = lagrangian.initial_multipliers(s, np)
    assert np.all(start.value == 1.0)
    # bin 0 late on 11 % of its episodes (0.1 above the budget), bin 1 never: the first rises by 0.1 an update
    after = run(start, [0.11, 0.0], 0.08, s, 10)
    np.testing.assert_allclose(after.value[0], [2.0, 0.9], atol=1e-5)
    assert after.value[1, 0] == pytest.approx(1.0, abs=1e-6)  # the heading at its budget: unchanged
    met = run(after, [0.0, 0.0], 0.0, s, 1000)
    assert np.all(met.value == 0.0) and np.all(met.integral >= 0.0)  # held at 0, not below
    again = run(met, [0.51, 0.51], 0.08, s, 1)  # and it rises again at once (no debt below 0 to pay back)
    np.testing.assert_allclose(again.value[0], [0.5, 0.5], atol=1e-5)


def test_a_multiplier_winds_up_no_further_than_its_ceiling_and_comes_down_from_it() -> None:
    """Anti-windup: violated for a long time, the multiplier stops at multiplier_max, and its integral with it, so that
    once the constraint is kept it falls at once rather than after paying back the wound-up sum."""
    s = settings(multiplier_init=1.0, multiplier_max=5.0, pid_kp=0.0, pid_ki=1.0)
    wound = run(lagrangian.initial_multipliers(s, np), [1.0, 1.0], 3.0, s, 1000)
    assert np.all(wound.value == 5.0) and np.all(wound.integral == 5.0)
    eased = run(wound, [0.0, 0.0], 0.0, s, 100)
    np.testing.assert_allclose(eased.value[0], [4.0, 4.0], atol=1e-4)


def test_the_proportional_term_acts_on_the_averaged_violation() -> None:
    s = settings(multiplier_init=0.0, pid_kp=10.0, pid_ki=0.0, pid_average=0.5)
    after = run(lagrangian.initial_multipliers(s, np), [0.21, 0.01], 0.08, s, 1)
    np.testing.assert_allclose(after.value[0], [10.0 * 0.5 * 0.2, 0.0], atol=1e-5)


def test_an_empty_bin_or_a_non_finite_measure_leaves_its_multiplier_as_it_was() -> None:
    s = settings()
    start = lagrangian.initial_multipliers(s, np)
    measured = np.array([[np.nan, 0.5], [np.inf, 0.1]], np.float32)
    after = lagrangian.pid_update(start, measured, np.array([3.0, 0.0]), s, np)
    np.testing.assert_array_equal(after.value, start.value)
    assert np.all(np.isfinite(after.value)) and np.all(np.isfinite(after.integral))


def test_T_con_bins_cover_the_range_ends_included() -> None:
    T_con = np.array([10.0, 19.99, 20.0, 59.9, 60.0])
    np.testing.assert_array_equal(lagrangian.T_con_bin(T_con, (10.0, 60.0), 5, np), [0, 0, 1, 4, 4])
    assert lagrangian.T_con_bin(np.array([20.0]), (20.0, 20.0), 3, np).tolist() == [0]  # a fixed T_con: one bin


def test_violations_are_each_bins_share_late_and_mean_heading() -> None:
    s = settings()
    cost = np.array([1.0, 0.0, 0.0, 1.0, 1.0])
    heading = np.array([0.1, -0.3, 0.2, 0.0, 0.4])
    measured, counts = lagrangian.violations(cost, heading, np.array([0, 0, 0, 1, 1]), s, np)
    np.testing.assert_allclose(measured, [[1 / 3, 1.0], [0.2, 0.2]], atol=1e-6)
    np.testing.assert_array_equal(counts, [3, 2])


jax = pytest.importorskip("jax")


def small_apg(**constraint: Any) -> Any:
    from dwr_gym.jax_env import make_gymnax_env
    from train.learning.jitted.apg import JaxAPG

    env, params = make_gymnax_env("DWRPointStabilization-v2", T_con_range=[1.0, 2.0])
    apg_settings = APGSettings(episodes=8, net_arch=(8,), state_grad_clip=0.0,
                               constraint=LagrangeSettings(lagrangian=True, multiplier_bins=2, **constraint))  # fmt: skip
    return JaxAPG(apg_settings, env, params)


def test_an_update_measures_the_violations_per_bin_and_moves_the_multipliers_by_them() -> None:
    """A fresh policy is late on every short episode: the deadline's multipliers rise where episodes were seen."""
    apg = small_apg(multiplier_init=2.0, pid_kp=0.0, pid_ki=1.0)
    state = apg.init(0)
    after, metrics = apg.update(state)
    counts = np.asarray(metrics["episodes"])
    assert counts.sum() == 8
    rates = np.asarray(metrics["violation_rate"])
    expected = np.where(counts > 0, 2.0 + rates - 0.01, 2.0)
    np.testing.assert_allclose(np.asarray(after.multipliers.value[0]), expected, atol=1e-5)
    np.testing.assert_array_equal(np.asarray(metrics["deadline_multiplier"]), [2.0, 2.0])  # those it used
    assert np.all(np.isfinite(np.asarray(after.multipliers.value))) and np.all(np.asarray(after.multipliers.value) >= 0)


def test_the_multipliers_weigh_the_distance_and_heading_at_T_con_in_the_gradient() -> None:
    """The constraint term's gradient: with the deadline's multiplier raised, the episode's objective falls by the
    multiplier times the final distance (d objective / d lambda = -distance), the direction that pays for missing."""
    import jax.numpy as jnp

    apg = small_apg()
    state = apg.init(1)
    key = jax.random.PRNGKey(3)

    def objective(weights: Any) -> Any:
        total, _, final = apg.play(state.params, state.obs_stats, key, multipliers=weights)
        return total, final

    # (the multipliers enter the gradient only: stop_gradient in play; measured here through jax.vjp of the held term)
    weights = jnp.zeros((2, 2), jnp.float32)
    (total_zero, final), _ = objective(weights), None
    total_high, _ = objective(weights.at[0].set(100.0))
    assert float(total_zero) == pytest.approx(float(total_high))  # the value is v2's return whatever the weights

    def held(params: Any, weights: Any) -> Any:
        return apg.play(params, state.obs_stats, key, multipliers=weights)[0]

    grad_low = jax.grad(held)(state.params, weights)
    grad_high = jax.grad(held)(state.params, weights.at[0].set(100.0))
    # the difference of the two gradients is -100 x the gradient of the final distance: a step along it brings the
    # robot nearer the goal at T_con
    diff = jax.tree.map(lambda a, b: b - a, grad_low, grad_high)
    step = jax.tree.map(lambda p, g: p + 1e-3 * g / (optax_norm(diff) + 1e-12), state.params, diff)
    _, _, moved = apg.play(step, state.obs_stats, key)
    assert float(moved.distance) < float(final.distance)


def optax_norm(tree: Any) -> Any:
    import optax

    return optax.tree.norm(tree)


TINY = ("train", "--algo", "apg", "--backend", "jax", "--env", "DWRPointStabilization-v2", "--eval-episodes", "3",
        "--no-progress", "--env-kwargs", "T_con_range=[1,2]", "--hyperparams", "episodes=4", "learning_rate=0.0003",
        "policy_kwargs=dict(net_arch=[16])", "lagrangian=1", "multiplier_bins=2", "keep_best=0",
        "weight_average=0.9")  # fmt: skip


@pytest.mark.slow
def test_a_constrained_run_logs_each_bin_and_resumes_bit_for_bit(tmp_path: Path) -> None:
    """(The multipliers and the weights' average are in the saved state: a resumed run's next updates use the ones it
    stopped with.)"""
    split = assert_resume_is_bit_for_bit(TINY, 4000, 2000, tmp_path)
    for run_dir in (split, tmp_path / "straight"):
        with (run_dir / "constraint.csv").open() as handle:
            rows = list(csv.DictReader(handle))
        assert rows and {row["T_con_low"] for row in rows} == {"1", "1.5"}
        assert all(float(row["deadline_multiplier"]) >= 0 and np.isfinite(float(row["violation_rate"])) for row in rows)
    with (split / "constraint.csv").open() as a, (tmp_path / "straight" / "constraint.csv").open() as b:
        assert a.read() == b.read()  # the resumed log is the uninterrupted one's
