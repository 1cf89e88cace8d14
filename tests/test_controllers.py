"""The analytic controllers: the paper's scenarios, the scaling functions, safety and validation."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from baselines import (
    CONTROLLERS,
    AstolfiParams,
    ControllerInput,
    ConventionalPTCParams,
    ExpertPolicy,
    FabregasParams,
    FixedTimeController,
    FixedTimeParams,
    PTCController,
    PTCParams,
    make_controller,
)
from dwr_gym import model
from dwr_gym.params import EnvParams
from train.evaluation.evaluate import evaluate
from train.evaluation.rollout import rollout
from train.evaluation.scenarios import FIG5_HEADINGS, Scenario, make_scenario

FIG5 = make_scenario("paper-fig5")
FIG7 = make_scenario("paper-fig7")

#: Two tests here run the expert through DWRPointStabilization-v0 (fixed T_con), which Gymnasium rightly calls out
#: of date now that v1 exists; that warning is not what they test.
pytestmark = pytest.mark.filterwarnings("ignore:.*DWRPointStabilization-v0 is out of date:DeprecationWarning")


def run(controller: str, scenario: Scenario, **env_kwargs: Any) -> Any:
    scenario = Scenario(scenario.name, scenario.starts, scenario.goals, {**scenario.env_kwargs, **env_kwargs},
                        scenario.controller_kwargs)  # fmt: skip
    return evaluate({controller: controller}, scenario)[controller]


@pytest.mark.parametrize("controller", ["ptc", "conventional-ptc", "fixed-time", "astolfi", "fabregas"])
@pytest.mark.parametrize("scenario", [FIG5, FIG7], ids=["fig5", "fig7"])
def test_each_controller_reaches_1cm_in_the_paper_scenarios(controller: str, scenario: Scenario) -> None:
    result = run(controller, scenario, horizon_factor=6.0)  # time enough for the laws without a deadline
    reached = result.final_distance <= 0.01
    if controller == "fabregas" and scenario is FIG5:
        # ref. [9]'s law stalls at |alpha - psi| = pi (p = 0, sin(pi) = 0): the paper's point in Section 3.1
        stalled = np.isclose(np.array(FIG5_HEADINGS), math.pi)
        assert np.all(reached[~stalled]) and not np.any(reached[stalled])
        assert result.final_distance[stalled][0] == pytest.approx(0.8)
    else:
        assert np.all(reached), result.final_distance


def test_ptc_arrives_before_T_con_for_the_eight_fig5_headings() -> None:
    result = run("ptc", FIG5)
    assert result.success.all()
    assert np.all(result.arrival_time < 20.0)


@pytest.mark.parametrize("T_con", [20.0, 25.0, 30.0, 35.0])
def test_ptc_arrives_before_each_prescribed_time_fig6(T_con: float) -> None:
    scenario = Scenario("fig6", np.array([[0.0, 0.0, math.pi]]), np.array([[0.8, 0.0, 0.0]]), {"T_con": T_con})
    result = evaluate({"ptc": "ptc"}, scenario)["ptc"]
    assert result.success[0] and result.arrival_time[0] < T_con


def test_ptc_scaling_properties() -> None:
    ptc = PTCController(K1=100.0, K2=100.0, K=60.0, beta=0.6, T_con=20.0)  # gains that make t_v < T_con
    d0, e0 = np.full(5, 0.8), np.full(5, 0.5)
    t_v = float(model.switching_time(0.8, 0.5, 20.0, 0.6, 60.0, ptc.params.p_min))
    assert 0.0 < t_v < 20.0
    times = np.array([0.0, 0.5 * t_v, t_v, t_v + 1.0, 19.9])
    inputs = ControllerInput(np.ones(5), np.zeros(5), np.zeros(5), times, d0, e0)
    mu = ptc.scaling(inputs)
    assert mu[0] == pytest.approx(1.0 / 20.0)  # mu*(0) = 1/T_con, i.e. mu_1(t0) / T_con = 1/T_con
    assert mu[1] > mu[0]  # grows toward t_v
    assert np.allclose(mu[2:], 1.0 / (20.0 - t_v))  # constant after t_v


def test_paper_gain_cap_is_what_bounds_mu_star() -> None:
    ptc = PTCController(PTCParams.paper_fig5())
    inputs = ControllerInput(np.ones(3), np.zeros(3), np.zeros(3), np.array([19.0, 19.99, 25.0]),
                             np.full(3, 0.8), np.full(3, math.pi))  # fmt: skip
    mu = ptc.scaling(inputs)
    assert mu[0] == pytest.approx(1.0)
    assert np.all(mu[1:] == ptc.params.max_gain)


def random_inputs(n: int, seed: int) -> ControllerInput:
    rng = np.random.default_rng(seed)
    d = np.concatenate([np.zeros(10), 10.0 ** rng.uniform(-12, 2, n - 10)])
    alpha = rng.uniform(-math.pi, math.pi, n)
    psi = np.concatenate([alpha[:5] - math.pi, rng.uniform(-math.pi, math.pi, n - 5)])  # alpha - psi = pi too
    time = rng.uniform(0.0, 200.0, n)
    return ControllerInput(d, alpha, model.wrap_angle(psi), time, rng.uniform(0, 5, n), rng.uniform(-3.6, 3.6, n))


@pytest.mark.parametrize("name", list(CONTROLLERS))
def test_no_controller_output_is_nan_or_inf(name: str) -> None:
    controller = make_controller(name)
    for seed in range(3):
        u, omega = controller(random_inputs(20000, seed))
        assert np.all(np.isfinite(u)) and np.all(np.isfinite(omega))


def test_ptc_presets_are_the_papers() -> None:
    fig5, fig7 = PTCParams.paper_fig5(), PTCParams.paper_fig7()
    assert (fig5.K1, fig5.K2, fig5.K, fig5.Ke, fig5.T_con, fig5.beta) == (2.0, 10.0, 1.2, 1.0, 20.0, 24 / 25)
    assert (fig7.K1, fig7.K2, fig7.T_con) == (2.5, 40.0, 70.0)
    assert fig5.k == pytest.approx(1 / (2 * math.pi))


BAD = [
    (PTCParams, "K1", 0.0), (PTCParams, "K2", -1.0), (PTCParams, "K", 5.0), (PTCParams, "Ke", float("nan")),
    (PTCParams, "T_con", -20.0), (PTCParams, "beta", 0.5), (PTCParams, "beta", 1.0), (PTCParams, "k", 0.2),
    (PTCParams, "stop_distance", -0.1), (PTCParams, "max_gain", 0.0),
    (ConventionalPTCParams, "K1", -2.0), (ConventionalPTCParams, "power", 0), (ConventionalPTCParams, "T_con", 0.0),
    (FabregasParams, "K0", 0.0), (FabregasParams, "K_omega", -0.75), (FabregasParams, "K_i", -1.0),
    (FabregasParams, "speed_limit", 0.0), (FabregasParams, "dt", 0.0),
    (FixedTimeParams, "a", 1.2), (FixedTimeParams, "b", 0.9), (FixedTimeParams, "k1", 0.0),
    (AstolfiParams, "k_rho", -0.3), (AstolfiParams, "k_beta", 0.15), (AstolfiParams, "k_alpha", 0.2),
]  # fmt: skip


@pytest.mark.parametrize("cls, name, value", BAD)
def test_every_invalid_controller_parameter_is_named(cls: type, name: str, value: float) -> None:
    with pytest.raises(ValueError, match=name) as error:
        cls.from_kwargs(**{name: value})
    assert repr(value) in str(error.value) or str(value) in str(error.value)


def test_ptc_enforces_K_at_most_min_of_0_6_K1_and_K2() -> None:
    with pytest.raises(ValueError, match=r"K <= min\(0.6 K1, K2\) = 1.2"):
        PTCParams(K1=2.0, K2=10.0, K=1.3)
    with pytest.raises(ValueError, match="unknown parameter"):
        PTCParams.from_kwargs(K3=1.0)
    with pytest.raises(ValueError, match="controller"):
        make_controller("pid")


def test_fixed_time_bound_is_documented_and_finite() -> None:
    bound = FixedTimeController().settling_time_bound()
    p_min = model.improved_velocity_constraint_min(1.0)
    assert bound["distance"] == pytest.approx((1 / (0.1 * 0.5) + 1 / (0.1 * 0.5)) / p_min)
    result = run("fixed-time", FIG5)
    assert np.all(result.arrival_time <= bound["distance"])


def test_astolfi_controls_the_final_heading_and_ptc_does_not_in_general() -> None:
    scenario = make_scenario("random", n=200, seed=3)
    results = evaluate({"astolfi": "astolfi", "ptc": "ptc"}, scenario)
    assert np.mean(results["astolfi"].final_heading_error) < 0.6
    assert np.mean(results["ptc"].final_heading_error) > 1.0


def test_expert_through_the_env_reproduces_the_controller_integrated_directly() -> None:
    env = gym.make("DWRPointStabilization-v0", u_max=50.0, omega_max=50.0, dt=0.02)  # no saturation
    controller = PTCController(PTCParams.paper_fig5())
    expert = ExpertPolicy.from_env(env, controller)
    obs, info = env.reset(options={"start": (0.0, 0.0, 2.0), "goal": (0.8, 0.0, 0.0)})
    x, y, psi = model.to_goal_frame(0.0, 0.0, 2.0, 0.8, 0.0, 0.0)
    d0 = float(model.distance(x, y))
    e0 = float(model.orientation_error(model.azimuth(x, y), psi, d0, controller.params.k))
    for step in range(1500):
        action, _ = expert.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        direct = ControllerInput.from_pose(x, y, psi, step * 0.02, (d0, e0))
        u, omega = controller(direct)
        x, y, psi = model.integrate_unicycle(x, y, psi, u, omega, 0.02)
        assert info["pose"][0] - 0.8 == pytest.approx(float(x[0]), abs=2e-4)
        assert info["pose"][1] == pytest.approx(float(y[0]), abs=2e-4)
        if terminated or truncated:
            break
    assert info["is_success"] and step > 100


def test_expert_in_sb3_evaluate_policy_and_on_batches() -> None:
    from stable_baselines3.common.evaluation import evaluate_policy
    from stable_baselines3.common.monitor import Monitor

    env = Monitor(gym.make("DWRPointStabilization-v0"))
    expert = ExpertPolicy.from_env(env, PTCController())
    rewards, lengths = evaluate_policy(expert, env, n_eval_episodes=5, return_episode_rewards=True)
    assert len(rewards) == 5 and all(length < 400 for length in lengths)  # arrives before T_con = 20 s = 400 steps

    vec = gym.make_vec("DWRPointStabilization-v0", num_envs=64)
    obs, _ = vec.reset(seed=0)
    actions, state = expert.predict(obs)
    assert actions.shape == (64, 2) and actions.dtype == np.float32 and state is None
    with pytest.raises(ValueError, match="observation"):
        expert.predict(np.zeros(7))


def test_rollout_of_the_expert_arrives_for_the_default_random_set() -> None:
    params = EnvParams()
    scenario = make_scenario("random", n=500, seed=1)
    expert = ExpertPolicy(PTCController(), params.u_max, params.omega_max)
    result = rollout(expert, params, scenario.starts, scenario.goals)
    assert result.success.all()
    assert np.nanmax(result.arrival_time) < params.T_con


@pytest.mark.parametrize("T_con", [10.0, 60.0])
def test_pt_astolfi_reaches_the_full_pose_by_any_T_con(T_con: float) -> None:
    """The law of baselines.polar: every episode in time, the heading too, for a little more energy than PTC."""
    scenario = make_scenario("random", n=100, seed=4, env_kwargs={"T_con": T_con, "start_distance": (0.3, 3.0)})
    results = evaluate({"pt-astolfi": "pt-astolfi", "ptc": "ptc"}, scenario)
    law, ptc = results["pt-astolfi"], results["ptc"]
    assert law.success.all() and np.nanmax(law.arrival_time) <= T_con
    assert np.mean(law.final_heading_error) < 0.12 < np.mean(ptc.final_heading_error)
    assert np.mean(law.energy) < 1.5 * np.mean(ptc.energy)  # 1.04-1.25x on the sets measured


def test_pt_astolfi_is_astolfi_on_the_time_scale_of_eq_12() -> None:
    from baselines.polar import AstolfiController, AstolfiParams, PrescribedTimeAstolfiController

    inputs = ControllerInput.from_pose([1.0, -0.5], [0.3, 0.8], [2.0, -1.0], 4.0, (1.0, 0.5))
    scaled = PrescribedTimeAstolfiController(T_con=20.0, arrival_fraction=0.5)(inputs)
    plain = AstolfiController(AstolfiParams(k_rho=1.5, k_alpha=4.7, k_beta=-1.7))(inputs)
    for a, b in zip(scaled, plain, strict=True):  # rate 1 / (T - t) with T = 0.5 * 20 s, t = 4 s
        np.testing.assert_allclose(a, b / 6.0, rtol=1e-12)
