"""The minimum-energy problem (baselines.optimal), the NMPC controller (baselines.nmpc) and the E/opt ratios."""

from __future__ import annotations

import itertools
import json
import math
import re
import sys
from collections import OrderedDict
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym
from baselines import ExpertPolicy, make_controller
from baselines.optimal import (
    InfeasibleArrivalTimeError,
    OptimalControlError,
    casadi_step_exact,
    solve_minimum_energy,
)
from dwr_gym import model
from tests.solving import energies_one_by_one, plans_one_by_one
from train.evaluation import optimum as optimum_module
from train.evaluation.evaluate import evaluate
from train.evaluation.scenarios import Scenario, make_scenario

ca = pytest.importorskip("casadi")
LIMITS = {"dt": 0.05, "u_max": 0.5, "omega_max": 2.0}


def test_symbolic_step_equals_the_env_step_to_1e_12() -> None:
    rng = np.random.default_rng(0)
    n = 2000
    x, y, psi = rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(-math.pi, math.pi, n)
    u = rng.uniform(-0.5, 0.5, n)
    omega = np.concatenate([rng.uniform(-2, 2, n - 4), [0.0, 1e-9, -1e-7, 1e-5]])  # straight and nearly straight
    for h in (0.01, 0.05, 0.25):
        s, c, hs = ca.SX.sym("s", 3), ca.SX.sym("c", 2), ca.SX.sym("h")
        step = ca.Function("step", [s, c, hs], [casadi_step_exact(s, c, hs)]).map(n)
        symbolic = np.array(step(np.stack([x, y, psi]), np.stack([u, omega]), h))
        exact = model.unicycle_step_exact(x, y, psi, u, omega, h)
        assert np.max(np.abs(symbolic[0] - exact[0])) < 1e-12
        assert np.max(np.abs(symbolic[1] - exact[1])) < 1e-12
        assert np.max(np.abs(model.wrap_angle(symbolic[2] - exact[2]))) < 1e-12


def test_plan_replayed_through_the_env_arrives_with_the_heading_within_the_limits() -> None:
    start, goal = (0.0, 0.0, math.pi / 2), (0.8, 0.0, 0.0)
    local = tuple(float(v) for v in model.to_goal_frame(*start, *goal))
    plan = solve_minimum_energy(local, 20.0, **LIMITS)  # type: ignore[arg-type]
    assert plan.intervals == 400
    env = gym.make("DWRPointStabilization-v1", T_con=20.0, heading_tolerance=0.01)
    env.reset(seed=0, options={"start": start, "goal": goal})
    played = 0.0
    for u, omega in plan.commands:
        played += (u * u + omega * omega) * LIMITS["dt"]
        action = np.array([u / LIMITS["u_max"], omega / LIMITS["omega_max"]])
        assert np.all(np.abs(action) <= 1.0 + 1e-9)  # the limits hold
        _, _, terminated, truncated, info = env.step(action.astype(np.float32))
        if terminated or truncated:
            break
    assert terminated and info["is_success"]
    assert 19.5 <= info["time"] <= 20.0 + 1e-9  # within the tolerances only at the deadline, as planned
    assert info["distance"] <= 0.01 and abs(info["heading_error"]) <= 0.01
    assert info["energy"] == pytest.approx(played, rel=1e-6)  # the env's energy is the plan's objective
    assert played <= plan.energy + 1e-12


@pytest.mark.parametrize("heading", [True, False])
def test_straight_ahead_has_the_closed_form_optimum(heading: bool) -> None:
    length, T_con = 1.2, 10.0
    plan = solve_minimum_energy((-length, 0.0, 0.0), T_con, **LIMITS, heading=heading)  # type: ignore[arg-type]
    assert plan.energy == pytest.approx(length**2 / T_con, abs=1e-8)
    np.testing.assert_allclose(plan.commands[:, 0], length / T_con, atol=1e-6)
    np.testing.assert_allclose(plan.commands[:, 1], 0.0, atol=1e-6)


def test_energy_does_not_increase_with_the_prescribed_time() -> None:
    start = (-0.6, 0.5, 2.5)
    energies = [solve_minimum_energy(start, T, **LIMITS).energy for T in (4.0, 8.0, 16.0, 32.0)]  # type: ignore[arg-type]
    assert all(later <= earlier + 1e-9 for earlier, later in itertools.pairwise(energies))
    assert energies[-1] < energies[0]


def test_position_only_optimum_is_cheaper_than_the_pose() -> None:
    start = (-0.8, 0.0, math.pi)
    pose = solve_minimum_energy(start, 20.0, **LIMITS)  # type: ignore[arg-type]
    position = solve_minimum_energy(start, 20.0, **LIMITS, heading=False)  # type: ignore[arg-type]
    assert position.energy == pytest.approx(0.8**2 / 20.0, rel=1e-6)  # straight back, in reverse
    assert pose.energy > position.energy + 0.4  # turning pi around costs at least pi^2 / T_con


def test_an_infeasible_T_con_names_T_con_and_the_smallest_feasible_value() -> None:
    with pytest.raises(InfeasibleArrivalTimeError, match=r"T_con=3 s is infeasible.*expected T_con >= 4"):
        solve_minimum_energy((-2.0, 0.0, 0.0), 3.0, **LIMITS, heading=False)  # type: ignore[arg-type]
    with pytest.raises(
        InfeasibleArrivalTimeError, match=r"T_con=9 s is infeasible: from d_0=5 m .* expected T_con >= 10"
    ):
        solve_minimum_energy((-3.0, 4.0, 0.0), 9.0, **LIMITS, heading=False)  # type: ignore[arg-type]


def test_a_failed_scenario_is_a_failure_in_the_table_not_a_crash(monkeypatch: pytest.MonkeyPatch) -> None:
    import baselines.nmpc as nmpc

    real = solve_minimum_energy

    def failing_for_robot_one(**job: object) -> object:
        if abs(job["start"][1] + 0.3) < 1e-6:  # type: ignore[index]
            raise OptimalControlError("IPOPT found no plan (injected)")
        return real(**job)  # type: ignore[arg-type]

    monkeypatch.setattr(nmpc, "solve_plans", plans_one_by_one(failing_for_robot_one))
    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())  # no plan solved before, none injected kept after
    starts = np.array([[-0.8, 0.0, 0.0], [-0.5, -0.3, 0.0], [-4.0, 0.0, 0.0]])  # the third is infeasible in 5 s
    scenario = Scenario("mixed", starts, np.zeros((3, 3)), {"T_con": 5.0})
    result = evaluate({"optimal": "optimal"}, scenario, optimum="pose")["optimal"]
    assert result.success.tolist() == [True, False, False]
    assert result.planner_failures == 1
    assert np.isnan(result.optimal_energy[2]) and np.isfinite(result.optimal_energy[:2]).all()  # type: ignore[index]
    summary = result.summary()
    assert summary["energy_ratio_mean"] == pytest.approx(result.energy[0] / result.optimal_energy[0])  # type: ignore[index]


def test_a_failed_replan_keeps_the_previous_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    import baselines.nmpc as nmpc

    real = solve_minimum_energy

    def cold_only(**job: object) -> object:
        if job.get("warm_start") is not None:
            raise OptimalControlError("IPOPT found no plan (injected)")
        return real(**job)  # type: ignore[arg-type]

    monkeypatch.setattr(nmpc, "solve_plans", plans_one_by_one(cold_only))
    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())
    scenario = make_scenario("paper-fig5", env_kwargs={"actuation_noise": 0.02})  # noise: re-plans are attempted
    policy = ExpertPolicy(make_controller("optimal", workers=1), 0.5, 2.0)
    result = evaluate({"optimal": policy}, scenario)["optimal"]
    assert result.planner_failures == 0
    assert result.final_distance.max() < 0.1  # it went on open loop on its first plan (from 0.8 m), not stopped


def test_a_plan_met_again_is_the_plan_solved_before_and_the_rollout_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    """The planners' plans are kept by job (compare meets the same first plans on several sets): a rollout run again
    solves nothing and equals the first to the last bit; a job that differs in one bit is solved."""
    import baselines.nmpc as nmpc

    monkeypatch.setattr(nmpc, "_MEMO", OrderedDict())
    solved: list[dict[str, object]] = []
    real = solve_minimum_energy
    monkeypatch.setattr(nmpc, "solve_plans", plans_one_by_one(lambda **job: solved.append(job) or real(**job)))  # type: ignore[func-returns-value]
    scenario = Scenario("two", np.array([[-0.8, 0.2, 0.5], [-1.5, -0.4, 3.0]]), np.zeros((2, 3)), {"T_con": 10.0,
                        "actuation_noise": 0.05})  # fmt: skip
    runs = []
    for _ in range(2):
        policy = ExpertPolicy(make_controller("optimal", T_con=10.0, workers=1), 0.5, 2.0)
        runs.append((evaluate({"optimal": policy}, scenario, seed=3)["optimal"], len(solved)))
        solved.clear()
    (first, solves), (second, again) = runs
    assert solves > 2 and again == 0  # noise: re-plans, all of them met again
    for name in ("energy", "final_distance", "final_heading_error", "episode_return", "command_rate_rms"):
        assert getattr(first, name).tobytes() == getattr(second, name).tobytes()
    pool = nmpc.PlanPool(workers=1)
    job = {"start": (-0.8, 0.0, 0.0), "arrival_time": 5.0, "dt": 0.05, "u_max": 0.5, "omega_max": 2.0, "hold_steps": 5}
    short = {**job, "arrival_time": 2.5}
    plans = pool.map([short, job, short])
    assert [j["arrival_time"] for j in solved] == [2.5, 5.0]  # each once
    assert plans[0] is plans[2] and plans[0].intervals == 10 and plans[1].intervals == 20  # type: ignore[union-attr]
    pool.map([{**job, "start": (-0.8, -0.0, 0.0)}])
    assert len(solved) == 3


def test_optimal_controller_on_paper_fig5_reaches_the_pose_with_less_energy_than_ptc() -> None:
    results = evaluate({"optimal": "optimal", "ptc": "ptc"}, make_scenario("paper-fig5"), optimum="pose")
    optimal, ptc = results["optimal"].summary(), results["ptc"].summary()
    assert optimal["success_rate"] == 1.0 and optimal["final_heading_error_mean"] < 0.05
    assert optimal["energy_mean"] < 0.5 * ptc["energy_mean"]
    assert ptc["energy_ratio_mean"] > 2.0  # PTC spends more than twice the optimum here
    assert 0.9 < optimal["energy_ratio_mean"] <= 1.01  # the env stops at 1 cm, a little before the plan's end


def test_nmpc_replans_under_noise_and_still_arrives() -> None:
    scenario = make_scenario("paper-fig5", env_kwargs={"observation_noise": 0.002, "actuation_noise": 0.05})
    policy = ExpertPolicy(make_controller("optimal", replan_every=20), 0.5, 2.0)
    result = evaluate({"optimal": policy}, scenario)["optimal"]
    assert result.success.all()
    assert policy.controller.solves > 8 * 5  # it re-planned from the measured poses, not once per robot


def test_optimal_energies_are_cached_per_episode(monkeypatch: pytest.MonkeyPatch, tmp_path: object) -> None:
    monkeypatch.setenv("DWR_GYM_CACHE", str(tmp_path))
    scenario = make_scenario("random", n=6, seed=3)
    params = dwr_gym.EnvParams(**scenario.env_kwargs)
    first, failures = optimum_module.optimal_energies(params, scenario.starts, scenario.goals, workers=1)
    assert not failures and np.isfinite(first).all()

    def no_solving(job: object) -> float:
        raise AssertionError("solved again despite the cache")

    monkeypatch.setattr(optimum_module, "_solve_energies", energies_one_by_one(no_solving))
    again, _ = optimum_module.optimal_energies(params, scenario.starts[::-1], scenario.goals[::-1], workers=1)
    np.testing.assert_array_equal(again, first[::-1])


def test_bad_parameters_and_a_missing_casadi_give_clear_errors(monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(ValueError, match=r"replan_every=7 is invalid: expected a multiple of hold_steps=5"):
        make_controller("optimal", replan_every=7)
    with pytest.raises(ValueError, match=r"dt=-1(.0)? is invalid"):
        make_controller("optimal", dt=-1)
    with pytest.raises(ValueError, match=r"unknown parameter\(s\) 'horizon'"):
        make_controller("optimal", horizon=3)
    assert optimum_module.casadi_available()  # what the commands ask before they plan optima
    monkeypatch.setitem(sys.modules, "casadi", None)
    with pytest.raises(ImportError, match=r'the optimal controller needs CasADi: pip install "dwr-gym\[optimal\]"'):
        make_controller("optimal")
    assert not optimum_module.casadi_available()


@pytest.mark.parametrize(
    ("field", "low", "high", "low_excluded"),
    [("T_con", 0.0, 1e6, True), ("dt", 0.0, 1e6, True), ("u_max", 0.0, 1e6, True), ("omega_max", 0.0, 1e6, True),
     ("arrival_time", 0.0, 1e6, True), ("arrival_fraction", 0.0, 1.0, True)],
)  # fmt: skip
def test_each_optimal_parameter_takes_its_range_and_names_itself_outside(
    field: str, low: float, high: float, low_excluded: bool
) -> None:
    from baselines.nmpc import OptimalParams

    assert getattr(OptimalParams.from_kwargs(**{field: high}), field) == high
    assert getattr(OptimalParams.from_kwargs(**{field: 0.5 * high}), field) == 0.5 * high
    for bad in (low if low_excluded else low - 1e-9, high * (1 + 1e-6)):
        with pytest.raises(ValueError, match=re.escape(f"{field}={float(bad)!r} is invalid")):
            OptimalParams.from_kwargs(**{field: bad})
    for name, good, bad in (("workers", 256, 257), ("hold_steps", 10_000, 0)):
        assert getattr(OptimalParams.from_kwargs(**{name: good, "replan_every": 0}), name) == good
        with pytest.raises(ValueError, match=re.escape(f"{name}={bad!r} is invalid")):
            OptimalParams.from_kwargs(**{name: bad, "replan_every": 0})


def test_cli_with_an_infeasible_T_con_reports_it_and_still_writes_the_table(tmp_path: object) -> None:
    import os
    import subprocess

    out = Path(str(tmp_path))
    result = subprocess.run(
        [sys.executable, "-m", "train.cli", "evaluate", "--controllers", "optimal", "ptc", "--scenarios", "paper-fig5",
         "--env-kwargs", "T_con=1", "--out", str(out), "--no-progress"],
        capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"}, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "episode(s) have no optimum" in result.stdout and "T_con=1 s is infeasible" in result.stdout
    assert "Traceback" not in result.stdout + result.stderr and "Ipopt" not in result.stdout + result.stderr
    rows = json.loads((out / "evaluation.json").read_text())
    assert {r["policy"]: r["success_rate"] for r in rows} == {"optimal": 0.0, "ptc": 0.0}


def test_a_second_reset_without_a_step_gets_a_new_plan_and_a_finished_robot_no_more_solves() -> None:
    env = gym.make("DWRPointStabilization-v1")
    controller = make_controller("optimal")
    expert = ExpertPolicy(controller, 0.5, 2.0)
    first, _ = env.reset(seed=0, options={"start": (-1.0, 0.0, 0.0), "T_con": 20.0})
    assert expert.predict(first)[0][0] > 0  # drive forward to the goal ahead
    second, _ = env.reset(seed=0, options={"start": (1.0, 0.0, 0.0), "T_con": 20.0})
    assert expert.predict(second)[0][0] < 0  # a new plan: reverse to the goal behind
    solves = controller.solves
    clipped = second.copy()
    clipped[6] = 1.5  # past the horizon the observed time fraction is clipped: the clock stands still
    for _ in range(5):
        expert.predict(clipped)
    assert controller.solves <= solves + 1  # no re-planning on every call


def test_each_episode_is_measured_against_the_optimum_of_its_own_T_con() -> None:
    """A set with T_con drawn per episode (as v1 draws it): every episode's optimum equals a single solve at
    that episode's T_con, and not the one at the env's nominal T_con."""
    kwargs = {**dwr_gym.V1_DEFAULTS, "T_con_range": (3.0, 12.0), "start_distance": (0.3, 1.0), "dt": 0.25}
    scenario = make_scenario("random", n=4, seed=2, env_kwargs=kwargs)
    assert scenario.T_cons is not None and np.ptp(scenario.T_cons) > 2.0
    result = evaluate({"ptc": "ptc"}, scenario, optimum="position")["ptc"]
    limits = {"dt": 0.25, "u_max": 0.5, "omega_max": 2.0, "heading": False}
    for i, (start, T_con) in enumerate(zip(scenario.starts, scenario.T_cons, strict=True)):  # goals at the origin
        own = solve_minimum_energy(tuple(start), float(T_con), **limits).energy  # type: ignore[arg-type]
        nominal = solve_minimum_energy(tuple(start), 20.0, **limits).energy  # type: ignore[arg-type]
        assert result.optimal_energy[i] == pytest.approx(own, rel=1e-6)  # type: ignore[index]
        assert abs(own - nominal) > 0.2 * own  # so that using the nominal T_con would be seen


def test_the_plan_is_the_cheapest_of_the_guesses_not_the_first_that_converges() -> None:
    """From 1 m straight behind the goal, backing up (u = -1/8 m/s for 8 s, energy 1/8) beats turning round. From
    (0.5, 0.5) facing +x, the forward guess converges to a plan of twice the energy the reverse guess finds: the
    plan kept is the cheaper."""
    plan = solve_minimum_energy((1.0, 0.0, 0.0), 8.0, **LIMITS)  # type: ignore[arg-type]
    assert plan.energy == pytest.approx(1.0 / 8.0, abs=1e-6)
    np.testing.assert_allclose(plan.commands[:, 0], -1.0 / 8.0, atol=1e-5)
    both = solve_minimum_energy((0.5, 0.5, 0.0), 8.0, **LIMITS)  # type: ignore[arg-type]
    forward_only = solve_minimum_energy((0.5, 0.5, 0.0), 8.0, **LIMITS, guesses=1)  # type: ignore[arg-type]
    assert forward_only.energy > 1.5 * both.energy  # measured: 1.069 against 0.503


def test_padding_a_plan_with_a_robot_response_holds_it_still_at_the_goal_and_keeps_the_plan() -> None:
    """pad_to solves a longer problem whose last intervals cancel the robot's drift at the goal: the plan returned
    is the unpadded one (to IPOPT's tolerance), and the robot, with that response, ends at the goal."""
    response = (0.02, 0.1, 0.9, 0.5)
    start = (-0.8, 0.3, 0.4)
    plain = solve_minimum_energy(start, 6.5, **LIMITS, hold_steps=5, response=response)  # type: ignore[arg-type]
    padded = solve_minimum_energy(start, 6.5, **LIMITS, hold_steps=5, response=response, pad_to=8)  # type: ignore[arg-type]
    assert padded.intervals == plain.intervals == 26  # 6.5 s of 0.25 s intervals; padded to 32 and cut back
    assert padded.energy == pytest.approx(plain.energy, rel=1e-4)
    np.testing.assert_allclose(padded.commands, plain.commands, atol=1e-3)
    b_u, b_w, a, g = response
    x, y, psi = start
    for u, w in padded.commands:
        x, y, psi = model.unicycle_step_exact(x, y, psi, a * u + b_u, a * w + g * u + b_w, 0.25)
    np.testing.assert_allclose((x, y, psi), 0.0, atol=1e-6)


def test_the_initial_guess_is_a_straight_line_at_constant_speed_turning_uniformly() -> None:
    from baselines.optimal import initial_guess

    guess = initial_guess((-0.6, 0.8, 1.0), 4, 0.5, 0.0, reverse=False)
    states, commands = guess[:15].reshape(5, 3), guess[15:].reshape(4, 2)
    np.testing.assert_allclose(states[:, 0], -0.6 * np.array([1.0, 0.75, 0.5, 0.25, 0.0]))
    np.testing.assert_allclose(states[:, 1], 0.8 * np.array([1.0, 0.75, 0.5, 0.25, 0.0]))
    np.testing.assert_allclose(states[:, 2], [1.0, 0.75, 0.5, 0.25, 0.0])
    np.testing.assert_allclose(commands, np.tile([1.0 / 2.0, -1.0 / 2.0], (4, 1)))  # 1 m and -1 rad in 2 s
    backwards = initial_guess((-0.6, 0.8, 1.0), 4, 0.5, 0.0, reverse=True)
    np.testing.assert_allclose(backwards[15::2], -0.5)
