"""The robust prescribed-time expert ``robust-pt`` (baselines/robust.py): its arrival under each kind of
disturbance, its margin and its energy against the paper's law, its guards."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from baselines.base import ControllerInput
from baselines.registry import CONTROLLER_NAMES, make_controller
from dwr_gym.disturbances import (
    ActuatorFault,
    InputDelay,
    MeasurementDropout,
    VelocityBias,
    VelocityRandomWalk,
    VelocitySinusoid,
    WheelSlip,
)
from dwr_gym.randomization import DEFAULT_GEOMETRY

pytest.importorskip("casadi")
T_CON = 20.0
START_DISTANCE = (0.3, 3.0)

#: One moderate magnitude of each kind: the shipped sets' and the sweep's second step.
KINDS = {
    "bias": {"disturbances": [VelocityBias(linear=-0.03, angular=0.3)]},
    "sinusoid": {"disturbances": [VelocitySinusoid(0.05, 0.2, period=4.0)]},  # the `disturbed` set's (0.1: 88 %)
    "random-walk": {"disturbances": [VelocityRandomWalk(0.02, 0.1)]},
    "slip": {"robot": DEFAULT_GEOMETRY, "disturbances": [WheelSlip(0.7, 0.8)]},
    "fault": {"robot": DEFAULT_GEOMETRY, "disturbances": [ActuatorFault("left", 0.5, start_time=T_CON / 4)]},
    "delay": {"disturbances": [InputDelay(6)]},
    "dropout": {"disturbances": [MeasurementDropout(0.5)]},
    "noise": {"observation_noise": 0.01, "actuation_noise": 0.05},
}


def run(policies: dict, env_kwargs: dict, n: int = 12, seed: int = 5) -> dict:
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario

    scenario = make_scenario("random", n=n, seed=seed,
                             env_kwargs={"T_con": T_CON, "start_distance": START_DISTANCE, **env_kwargs})  # fmt: skip
    return evaluate(policies, scenario, seed=seed)


def test_nominally_it_arrives_with_its_margin_and_the_heading_for_less_energy_than_ptc() -> None:
    results = run({"robust-pt": "robust-pt", "ptc": "ptc"}, {})
    robust, ptc = results["robust-pt"], results["ptc"]
    assert robust.success.all()
    assert np.nanmax(robust.arrival_time) <= 0.81 * T_CON  # plan_arrival = 0.8: the rest is the margin
    assert np.mean(robust.final_heading_error) < 0.1  # PTC ends about 1.4 rad off the goal heading
    assert robust.energy.mean() < 0.8 * ptc.energy.mean()


@pytest.mark.parametrize("kind", list(KINDS))
def test_it_keeps_the_deadline_under_each_kind_of_disturbance(kind: str) -> None:
    result = run({"robust-pt": "robust-pt"}, KINDS[kind])["robust-pt"]
    assert result.success.mean() >= 11 / 12, kind
    assert np.mean(result.final_heading_error[result.success]) < 0.25, kind  # of those in time: a late one may be off


def test_without_its_estimate_the_same_bias_makes_it_late_or_off() -> None:
    """The disturbance observer is what keeps the deadline: the same law on the raw measurement does worse."""
    results = run({"with": "robust-pt"}, KINDS["fault"])
    without = run({"without": make_controller_policy(estimator=None)}, KINDS["fault"])
    assert results["with"].success.mean() > without["without"].success.mean()


def make_controller_policy(**kwargs: object) -> object:
    from baselines import ExpertPolicy

    return ExpertPolicy(make_controller("robust-pt", T_con=T_CON, **kwargs), 0.5, 2.0)


def test_it_is_a_controller_like_the_others_and_bad_parameters_are_named() -> None:
    assert "robust-pt" in CONTROLLER_NAMES
    with pytest.raises(ValueError, match="plan_arrival"):
        make_controller("robust-pt", plan_arrival=1.2)
    with pytest.raises(ValueError, match="finish_arrival"):
        make_controller("robust-pt", plan_arrival=0.9, finish_arrival=0.85)
    with pytest.raises(ValueError, match="estimator"):
        make_controller("robust-pt", estimator={"position_noise": 0.01})


@pytest.mark.parametrize("plan", [True, False])
def test_no_nan_or_inf_leaves_it_whatever_the_state(plan: bool) -> None:
    controller = make_controller("robust-pt", plan=plan, workers=1)
    d = np.array([0.0, 1e-12, 0.005, 2.0, 50.0, 1e6])
    n = d.size
    inputs = ControllerInput(d, np.array([0.0, np.pi, -np.pi, 1.0, -2.0, 3.0]), np.array([np.pi, 0.0, -1.0, 2.0, 0.5, -3.0]),
                             np.full(n, 0.0), d, np.zeros(n), np.full(n, T_CON))  # fmt: skip
    for time in (0.0, 0.05, T_CON - 0.05, T_CON, 2 * T_CON):
        u, omega = controller(inputs._replace(time=np.full(n, time)))
        assert np.isfinite(u).all() and np.isfinite(omega).all()
        assert np.all(np.abs(u) <= 0.5) and np.all(np.abs(omega) <= 2.0)


def test_the_evaluate_command_takes_it(tmp_path: object) -> None:
    from train.cli import main

    out = str(tmp_path)
    assert main(["evaluate", "--controllers", "robust-pt", "--scenarios", "random", "--n", "3", "--optimum", "none",
                 "--no-progress", "--out", out]) == 0  # fmt: skip


def test_the_optimal_controller_runs_on_the_first_n_optimal_episodes_of_a_disturbed_set(tmp_path: Path) -> None:
    """It re-plans with CasADi whenever pushed off its plan: on the disturbed sets it runs on a head of the set."""
    from train.cli import main

    assert main(["evaluate", "--controllers", "optimal", "ptc", "--scenarios", "delay", "random", "--n", "4",
                 "--n-optimal", "2", "--optimum", "none", "--no-progress", "--out", str(tmp_path)]) == 0  # fmt: skip
    rows = {(r["scenario"], r["policy"]): r["n"] for r in json.loads((tmp_path / "evaluation.json").read_text())}
    assert rows == {("delay", "optimal"): 2, ("delay", "ptc"): 4, ("random", "optimal"): 4, ("random", "ptc"): 4}


@pytest.mark.parametrize("name", ["random", "disturbed", "fault", "delay", "noise"])
def test_the_shipped_robust_agent_keeps_the_deadline_for_less_energy_than_ptc(name: str) -> None:
    """The claim of docs/robust.md on a small set (24 starts 0.3-3 m, T_con 20 s, a seed the benchmark does not use)."""
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario
    from train.learning.agents import PRETRAINED, load_agent

    _, agent = load_agent(PRETRAINED["robust"])
    scenario = make_scenario(name, n=24, seed=31, env_kwargs={"T_con": T_CON, "start_distance": START_DISTANCE})
    results = evaluate({"agent": agent, "ptc": "ptc"}, scenario, seed=31)
    robust, ptc = results["agent"], results["ptc"]
    assert robust.success.mean() >= 23 / 24
    assert np.mean(robust.final_heading_error) <= (0.1 if name == "random" else 0.2)
    assert robust.energy.mean() < ptc.energy.mean()


def drive_on_its_plan(controller: object, start: tuple[float, float, float], steps: int,
                      push: tuple[int, float] | None = None) -> list[int]:  # fmt: skip
    """Step one nominal robot (the exact arc of eq. (1)) under ``controller``; ``push`` = (step, metres) moves it
    sideways (in its own frame) before that step. Returns the controller's plan solves after each step."""
    from dwr_gym import model

    x, y, psi = start
    initial = (float(np.hypot(x, y)), 0.0)
    solves = []
    for k in range(steps):
        if push is not None and k == push[0]:
            x, y = x - push[1] * np.sin(psi), y + push[1] * np.cos(psi)
        inputs = ControllerInput.from_pose(x, y, psi, k * 0.05, initial)._replace(prescribed_time=np.array([T_CON]))
        u, omega = controller(inputs)  # type: ignore[operator]
        x, y, psi = model.unicycle_step_exact(x, y, psi, float(u[0]), float(omega[0]), 0.05)
        solves.append(controller.solves)  # type: ignore[attr-defined]
    return solves


@pytest.mark.parametrize(("push", "replans"), [(None, 0), (0.03, 0), (0.12, 1)], ids=["none", "in-tube", "out"])
def test_a_robot_pushed_out_of_the_tube_re_plans_once_one_inside_it_does_not(push: float | None, replans: int) -> None:
    """robust-pt on the raw measurement (no filter to smooth the push): a nominal robot tracks its plan without
    re-planning; a push of 3 cm (tube 5 cm) is tracked back; one of 12 cm re-plans from where the robot is, once."""
    controller = make_controller("robust-pt", T_con=T_CON, estimator=None, workers=1)
    solves = drive_on_its_plan(controller, (-1.0, 0.4, 0.3), 40, None if push is None else (20, push))
    assert solves[0] == 1  # the first plan, at the first step
    assert solves[-1] == 1 + replans
    if replans:
        assert solves[19] == 1 and solves[20] == 2  # at the very step it left the tube


def finish_by_hand(x: float, y: float, psi: float, t: float, direction: float, p: object) -> tuple[float, float]:
    """Astolfi's law (rho, alpha, beta) driving ``direction``, times min(1 / (T - t), max_gain), T = 0.92 T_con."""
    from dwr_gym import model

    alpha = float(model.wrap_angle(np.arctan2(-y, -x) - psi))
    if direction < 0:
        alpha = float(model.wrap_angle(alpha + np.pi))
    beta = float(model.wrap_angle(-psi - alpha))
    T = p.finish_arrival * T_CON  # type: ignore[attr-defined]
    rate = min(1.0 / (T - t), p.max_gain) if t < T else p.max_gain  # type: ignore[attr-defined]
    return (direction * p.k_rho * np.hypot(x, y) * rate,  # type: ignore[attr-defined]
            (p.k_alpha * alpha + p.k_beta * beta) * rate)  # type: ignore[attr-defined]  # fmt: skip


def test_the_finish_is_astolfis_law_on_the_deadlines_time_scale_and_reverses_with_hysteresis() -> None:
    """plan=False: the finish law from the start. A goal behind (bearing pi) is approached in reverse, and stays so
    while the bearing is within reverse_hysteresis (0.3 rad) of pi/2; past it the robot drives forward."""
    controller = make_controller("robust-pt", T_con=T_CON, plan=False, estimator=None, cancel_disturbance=False)
    p = controller.params
    # the goal 1 m north of the robot: bearing = pi/2 - psi
    for t, psi, direction in ((0.0, -np.pi / 2, -1.0), (0.05, -0.1, -1.0), (0.1, 0.1, -1.0), (0.15, 0.4, 1.0),
                              (0.2, -0.1, 1.0), (17.0, -0.1, 1.0), (18.3, 0.0, 1.0), (19.0, 0.0, 1.0)):  # fmt: skip
        inputs = ControllerInput.from_pose(0.0, -1.0, psi, t, (1.0, 0.0))._replace(prescribed_time=np.array([T_CON]))
        u, omega = controller(inputs)
        expected = finish_by_hand(0.0, -1.0, psi, t, direction, p)
        np.testing.assert_allclose((u[0], omega[0]), np.clip(expected, [-0.5, -2.0], [0.5, 2.0]), atol=1e-12,
                                   err_msg=f"t={t}, psi={psi}")  # fmt: skip
    ptc = make_controller("robust-pt", T_con=T_CON, plan=False, estimator=None, finish="ptc")
    inputs = ControllerInput.from_pose([0.3, -1.0], [0.2, 0.5], [1.0, -2.0], 3.0, ([0.5, 1.2], [0.1, -0.4]))
    inputs = inputs._replace(prescribed_time=np.full(2, T_CON))
    np.testing.assert_allclose(ptc(inputs), np.clip(make_controller("ptc", T_con=T_CON)(inputs),
                                                    [[-0.5], [-2.0]], [[0.5], [2.0]]), atol=1e-12)  # fmt: skip


def one_step(controller: object, x: float, y: float, psi: float, t: float, T_con: float = T_CON) -> np.ndarray:
    inputs = ControllerInput.from_pose(x, y, psi, t, (float(np.hypot(x, y)), 0.0))
    return np.array(controller(inputs._replace(prescribed_time=np.array([T_con]))))[:, 0]  # type: ignore[operator]


def test_past_its_re_plans_or_too_far_to_plan_the_robot_is_handed_to_the_finish_law() -> None:
    """max_replans = 0: a robot pushed out of the tube is not re-planned, the finish law drives it; a plan longer than
    MAX_PLAN_INTERVALS (T_con 400 s) is not even tried."""
    controller = make_controller("robust-pt", T_con=T_CON, estimator=None, workers=1, max_replans=0)
    solves = drive_on_its_plan(controller, (-1.0, 0.4, 0.3), 21, (20, 0.12))
    assert solves[-1] == 1
    p = controller.params
    x, y, psi = -0.5, 0.9, 0.2
    u, omega = one_step(controller, x, y, psi, 21 * 0.05)
    assert (u, omega) == pytest.approx(finish_by_hand(x, y, psi, 21 * 0.05, 1.0, p), abs=1e-12)
    far = make_controller("robust-pt", T_con=400.0, estimator=None, workers=1)
    u, omega = one_step(far, -1.0, 0.4, 0.3, 0.0, T_con=400.0)
    assert far.solves == 0
    T = p.finish_arrival * 400.0
    assert u == pytest.approx(p.k_rho * np.hypot(-1.0, 0.4) / T, rel=1e-12)


def test_a_robot_too_slow_for_a_plan_of_two_T_con_gets_the_finish_law_without_a_search(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A failing wheel that leaves the robot 1 cm/s: the plan would take 1.1 x 108 s, over LONGEST_PLAN = 2 T_con
    (the episode ends at 1.5 T_con), so no search is started (one of hundreds of intervals rarely converges) and the
    finish law drives; at 0.4 m/s the same robot is planned."""
    slow = make_controller("robust-pt", T_con=T_CON, estimator=None, workers=1)
    monkeypatch.setattr(slow, "_responses", lambda index: np.tile([0.0, 0.0, 0.02, 0.0], (index.size, 1)))
    one_step(slow, -1.0, 0.4, 0.3, 0.0)
    assert slow.solves == 0 and not slow.failures  # type: ignore[attr-defined]
    able = make_controller("robust-pt", T_con=T_CON, estimator=None, workers=1)
    monkeypatch.setattr(able, "_responses", lambda index: np.tile([0.0, 0.0, 0.8, 0.0], (index.size, 1)))
    one_step(able, -1.0, 0.4, 0.3, 0.0)
    assert able.solves == 1  # type: ignore[attr-defined]


class Cruise:
    """A learned cruise whose mean action is (0.5, -0.25); a sampled one (deterministic=False) is 0.1 off: the cruise
    must drive on the mean, as a deployed agent does (reproducible, no sampling noise in the commands)."""

    def predict(self, obs, state=None, episode_start=None, deterministic=True):  # type: ignore[no-untyped-def]
        return np.tile(np.float32([0.5, -0.25]) + (0.0 if deterministic else 0.1), (len(obs), 1)), state


def test_a_learned_cruise_drives_until_handover_time_or_until_the_robot_falls_behind() -> None:
    from baselines.robust import RobustPTController, RobustPTParams

    params = RobustPTParams(T_con=T_CON, estimator=None, cancel_disturbance=False, workers=1)
    early = RobustPTController(params, cruise=Cruise())
    assert one_step(early, -1.0, 0.4, 0.3, 0.0) == pytest.approx([0.25, -0.5])  # the network's (0.5, -0.25) x limits
    assert early.solves == 0
    late = RobustPTController(params, cruise=Cruise())  # past handover_time (0.7) x T_con: the planner takes over
    one_step(late, -1.0, 0.4, 0.3, 0.71 * T_CON)
    assert late.solves >= 1
    behind = RobustPTController(params, cruise=Cruise())  # 3 s left for 1.08 m: less than 1.5 x the 2.2 s it takes
    one_step(behind, -1.0, 0.4, 0.3, T_CON - 3.0)
    assert behind.solves >= 1
    in_time = RobustPTController(params, cruise=Cruise())  # 10 s left at 0.5 T_con: on schedule, the network drives
    assert one_step(in_time, -1.0, 0.4, 0.3, 0.5 * T_CON) == pytest.approx([0.25, -0.5])


def test_frozen_robots_get_no_command_and_no_plan_until_their_reset() -> None:
    controller = make_controller("robust-pt", T_con=T_CON, estimator=None, workers=1)
    inputs = ControllerInput.from_pose([-1.0, 0.8], [0.4, -0.6], [0.3, 2.0], 0.0, ([1.08, 1.0], [0.0, 0.0]))
    inputs = inputs._replace(prescribed_time=np.full(2, T_CON))
    controller(inputs)
    assert controller.solves == 2
    controller.freeze(np.array([False, True]))
    controller.freeze(np.array([True, True, True]))  # a mask of another batch size is ignored
    pushed = ControllerInput.from_pose([-1.0, 0.3], [0.4, -0.6], [0.3, 2.0], 0.05, ([1.08, 1.0], [0.0, 0.0]))
    u, omega = controller(pushed._replace(prescribed_time=np.full(2, T_CON)))  # robot 1 is 0.5 m out of its tube
    assert controller.solves == 2 and u[1] == omega[1] == 0.0 and u[0] != 0.0
    controller.reset(np.array([False, True]))
    controller(pushed._replace(time=np.full(2, 0.1), prescribed_time=np.full(2, T_CON)))
    assert controller.solves == 3  # robot 1 planned anew once it was reset


def test_the_first_finish_decision_inside_the_hysteresis_band_goes_the_shorter_way() -> None:
    """Undecided, a bearing of pi/2 + 0.1 (within reverse_hysteresis of pi/2) reverses, pi/2 - 0.1 drives forward."""
    p = make_controller("robust-pt", T_con=T_CON, plan=False).params
    for psi, direction in ((-0.1, -1.0), (0.1, 1.0)):  # the goal 1 m north: bearing pi/2 - psi
        controller = make_controller("robust-pt", T_con=T_CON, plan=False, estimator=None, cancel_disturbance=False)
        inputs = ControllerInput.from_pose(0.0, -1.0, psi, 0.0, (1.0, 0.0))._replace(prescribed_time=np.array([T_CON]))
        u, omega = controller(inputs)
        assert (u[0], omega[0]) == pytest.approx(finish_by_hand(0.0, -1.0, psi, 0.0, direction, p), abs=1e-12)


def test_the_cruise_tracks_its_reference_with_kanayamas_law_by_hand() -> None:
    """u = u_r cos e_psi + k_along e_x, omega = omega_r + k_lateral u_r e_y + k_heading |u_r| sin e_psi, the errors in
    the robot's frame; and the position error it reports."""
    from baselines.robust import RobustPTParams, tracking_commands

    p = RobustPTParams(k_along=1.3, k_lateral=3.0, k_heading=2.5)
    pose = np.array([[0.2, -0.1, 0.4], [-1.0, 0.5, -2.0]])
    reference = np.array([[0.25, -0.05, 0.3], [-0.9, 0.45, -2.2]])
    command = np.array([[0.3, 0.5], [-0.2, -1.0]])
    u, omega, error = tracking_commands(pose, reference, command, p)
    for i in range(2):
        dx, dy = reference[i, :2] - pose[i, :2]
        c, s = np.cos(pose[i, 2]), np.sin(pose[i, 2])
        e_x, e_y, e_psi = c * dx + s * dy, -s * dx + c * dy, reference[i, 2] - pose[i, 2]
        u_r, omega_r = command[i]
        assert u[i] == pytest.approx(u_r * np.cos(e_psi) + 1.3 * e_x, abs=1e-12)
        assert omega[i] == pytest.approx(omega_r + 3.0 * u_r * e_y + 2.5 * abs(u_r) * np.sin(e_psi), abs=1e-12)
        assert error[i] == pytest.approx(np.hypot(dx, dy), abs=1e-12)


@pytest.mark.parametrize("bias", [-0.1, 0.1])
def test_behind_schedule_the_plan_takes_the_least_time_at_the_speed_the_robot_keeps_at_least(
    bias: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With 0.5 s left of its 0.8 T_con for 1.08 m, the robot is planned to arrive in 1.1 x the least time at the
    speed its estimated response keeps whichever way it turns: a u_max - |b_u| = 0.5 - 0.1 = 0.4 m/s, for a bias
    forward as for one backward (a bias that helps in one direction hinders in the other)."""
    controller = make_controller("robust-pt", T_con=T_CON, estimator=None, workers=1)
    monkeypatch.setattr(controller, "_responses", lambda index: np.tile([bias, 0.0, 1.0, 0.0], (index.size, 1)))
    jobs: list[dict] = []
    real = controller._pool.map  # type: ignore[attr-defined]
    monkeypatch.setattr(controller._pool, "map", lambda batch: jobs.extend(batch) or real(batch))  # type: ignore[attr-defined]
    one_step(controller, -1.0, 0.4, 0.3, 0.8 * T_CON - 0.5)
    assert jobs[0]["arrival_time"] == pytest.approx(1.1 * np.hypot(-1.0, 0.4) / 0.4, rel=1e-12)
    assert jobs[0]["response"] == (bias, 0.0, 1.0, 0.0)


class WeakActuators:
    """A pose filter that estimates the measured pose and a robot whose actuators give half the commanded velocities."""

    response = np.array([[0.0, 0.0, 0.5, 0.0]])

    def update(self, measured: np.ndarray, command: np.ndarray) -> np.ndarray:
        return measured

    def reset(self, index: object = None) -> None:
        pass


class TightTurn:
    """A learned cruise asking for (0.25 m/s, -1.8 rad/s): half the speed limit, 90 % of the turn rate's."""

    def predict(self, obs, state=None, episode_start=None, deterministic=True):  # type: ignore[no-untyped-def]
        return np.tile(np.float32([0.5, -0.9]), (len(obs), 1)), state


def test_a_compensation_beyond_the_limits_slows_the_robot_on_the_arc_asked_for() -> None:
    """With half-strength actuators the cruise's (0.25, -1.8) would need the commands (0.5, -3.6): past omega_max, so
    both are scaled by 2 / 3.6 and the robot drives the arc asked for (omega / u = -7.2), slower; clipping the turn
    rate alone would bend it to -2 / 0.5."""
    from baselines.robust import RobustPTController, RobustPTParams

    controller = RobustPTController(RobustPTParams(T_con=T_CON, estimator=None, workers=1), cruise=TightTurn())
    controller._filter = WeakActuators()  # type: ignore[assignment]
    u, omega = one_step(controller, -1.0, 0.4, 0.3, 0.0)
    assert omega == pytest.approx(-2.0, rel=1e-12) and omega / u == pytest.approx(-7.2, rel=1e-6)
