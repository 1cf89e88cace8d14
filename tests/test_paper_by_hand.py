"""The paper's equations against arithmetic written out here, independent of dwr_gym.model.

Each reference below is a line-by-line transcription of the paper's equations on the ``math`` module,
so that a slip in the library (a missing factor, a wrong exponent, a wrong series coefficient, a
disturbance applied at the wrong place) fails here and not only in a recorded golden output.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import dwr_gym  # noqa: F401  (registers the envs)
from baselines import (
    ControllerInput,
    ConventionalPTCController,
    FabregasController,
    FixedTimeController,
    PTCController,
    PTCParams,
)
from dwr_gym import model
from dwr_gym.disturbances import ActuatorFault, VelocityBias, VelocityRandomWalk, VelocitySinusoid, WheelSlip
from dwr_gym.robots import DifferentialDrive

pytestmark = pytest.mark.filterwarnings("ignore:.*out of date")  # v0 is what these tests step
K = 1.0 / (2.0 * math.pi)
ENV_ID = "DWRPointStabilization-v0"


def wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def ptc_by_hand(
    d: float, alpha: float, psi: float, t: float, d0: float, e0: float, p: PTCParams
) -> tuple[float, float]:
    """(u, omega) of eqs. (16)-(19), written from the paper with the two documented guards (gain cap, stop)."""
    bearing = wrap(alpha - psi)  # alpha - psi in [-pi, pi), eq. (6) after ref. [9]
    zeta = math.asin(p.k * alpha * math.tanh(d))  # eq. (6)
    e = bearing + zeta  # eq. (6)
    p_star = 1.0 / (1.0 + p.Ke * e * e)  # eq. (10)
    p_min = 1.0 / (1.0 + p.Ke * (7.0 * math.pi / 6.0) ** 2)  # eq. (10) at |e| = 7 pi / 6
    exponent = -((d0 * d0 + e0 * e0) ** (1.0 - p.beta)) / ((1.0 - p.beta) * 2.0 * p.K * p_min)
    t_v = p.T_con * (1.0 - math.exp(exponent))  # eq. (17)
    mu = 1.0 / (p.T_con - t) if t <= t_v else 1.0 / (p.T_con - t_v)  # eq. (17)
    mu = min(mu, p.max_gain)  # the documented gain cap (the states here are all before T_con)
    u = p.K1 * mu * p_star * d ** (2.0 * p.beta - 1.0)  # eq. (16)
    alpha_dot = u * math.sin(bearing) / d  # eq. (5)
    d_dot = -u * math.cos(bearing)  # eq. (4)
    zeta_dot = p.k * (alpha_dot * math.tanh(d) + alpha * (1.0 - math.tanh(d) ** 2) * d_dot)
    zeta_dot /= math.sqrt(1.0 - (p.k * alpha * math.tanh(d)) ** 2)  # last term of eq. (18)
    x = e - zeta
    delta = (1.0 - math.cos(x)) / x  # eq. (19)
    feedback = p.K2 * p_star * mu * abs(e) ** (2.0 * p.beta - 1.0) * math.copysign(1.0, e)
    omega = d * u * delta + alpha_dot + zeta_dot + feedback  # eq. (18)
    return u, omega


def ptc(params: PTCParams, d: float, alpha: float, psi: float, t: float, d0: float, e0: float) -> tuple[float, float]:
    inputs = ControllerInput(*(np.array([v], dtype=np.float64) for v in (d, alpha, psi, t, d0, e0)))
    u, omega = PTCController(params)(inputs)
    return float(u[0]), float(omega[0])


def test_ptc_worked_example_of_eqs_16_to_19() -> None:
    """Figure 5's gains at d = 0.5, alpha = 0, psi = -0.5, t = 10 s (t_v rounds to T_con = 20 s, so mu* = 1/10)."""
    u, omega = ptc(PTCParams.paper_fig5(), 0.5, 0.0, -0.5, 10.0, 0.8, math.pi)
    # alpha = 0: zeta = 0, e_psi = alpha - psi = 0.5, p* = 1 / (1 + 0.25) = 0.8, 2 beta - 1 = 0.92
    u_expected = 2.0 * 0.1 * 0.8 * 0.5**0.92  # (16): K1 mu* p* d^(2 beta - 1)
    alpha_dot = u_expected * math.sin(0.5) / 0.5  # (5)
    zeta_dot = K * alpha_dot * math.tanh(0.5)  # the k(...) term of (18) with alpha = 0, zeta = 0
    delta = (1.0 - math.cos(0.5)) / 0.5  # (19)
    omega_expected = 0.5 * u_expected * delta + alpha_dot + zeta_dot + 10.0 * 0.8 * 0.1 * 0.5**0.92  # (18)
    assert u == pytest.approx(u_expected, rel=1e-12)
    assert omega == pytest.approx(omega_expected, rel=1e-12)


STATES = [  # d, alpha, psi, t, d0, e0
    (0.8, 0.3, -1.1, 0.0, 0.8, 1.2),
    (0.37, -2.5, 1.9, 7.5, 1.4, -2.0),
    (2.2, 1.0, 1.3, 15.0, 2.5, 0.4),
    (0.05, -0.4, 2.8, 19.0, 0.9, 3.0),
    (1.3, 2.9, -2.9, 3.0, 1.3, -0.2),
]


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize(
    "params",
    [PTCParams.paper_fig5(), PTCParams.paper_fig7(T_con=20.0),
     PTCParams(K1=100.0, K2=100.0, K=60.0, beta=0.6, T_con=20.0, max_gain=1e3)],  # t_v < T_con: the frozen branch
    ids=["fig5", "fig7", "t_v-before-T_con"],
)  # fmt: skip
def test_ptc_equals_eqs_16_to_19_by_hand(state: tuple[float, ...], params: PTCParams) -> None:
    u, omega = ptc(params, *state)
    u_expected, omega_expected = ptc_by_hand(*state, params)
    assert u == pytest.approx(u_expected, rel=1e-11, abs=1e-14)
    assert omega == pytest.approx(omega_expected, rel=1e-11, abs=1e-14)


def test_the_t_v_case_really_freezes_the_gain() -> None:
    """The third parameter set above does switch: mu* after t_v is 1 / (T_con - t_v), not 1 / (T_con - t)."""
    params = PTCParams(K1=100.0, K2=100.0, K=60.0, beta=0.6, T_con=20.0, max_gain=1e3)
    d0, e0 = 0.9, 3.0
    p_min = 1.0 / (1.0 + (7.0 * math.pi / 6.0) ** 2)
    t_v = 20.0 * (1.0 - math.exp(-((d0**2 + e0**2) ** 0.4) / (0.4 * 2.0 * 60.0 * p_min)))
    assert 0.0 < t_v < 19.0
    inputs = ControllerInput(*(np.array([v]) for v in (1.0, 0.0, 0.0, 19.0, d0, e0)))
    assert PTCController(params).scaling(inputs)[0] == pytest.approx(1.0 / (20.0 - t_v), rel=1e-12)


@pytest.mark.parametrize("h", [1e-9, 1e-4, 0.01, 0.03, 0.05, -0.05, 0.0999, 0.1])
def test_sinc_series_branch_equals_sin_h_over_h(h: float) -> None:
    """|h| <= 0.1 is the series branch, which the env takes at dt = 0.05 (|omega dt / 2| <= 0.05)."""
    assert abs(h) <= model.SINC_SERIES_LIMIT
    assert model.sinc(h) == pytest.approx(math.sin(h) / h, rel=2e-16, abs=0)
    assert model.sinc(np.array([h, 0.5]))[0] == pytest.approx(math.sin(h) / h, rel=2e-16, abs=0)


@pytest.mark.parametrize("omega", [2.0, -1.3, 0.7, 0.01, 4.0])
def test_exact_step_at_the_envs_dt_equals_the_closed_form_arc_and_solve_ivp(omega: float) -> None:
    """One control period of dt = 0.05 s: |omega dt / 2| <= 0.1 takes the series branch of sin(h) / h."""
    x0, y0, psi0, u, dt = 0.4, -0.3, 2.9, 0.45, 0.05
    # the arc of eq. (1) with u, omega held: x = x0 + u / omega (sin(psi0 + omega t) - sin(psi0)), ...
    closed = (x0 + u / omega * (math.sin(psi0 + omega * dt) - math.sin(psi0)),
              y0 - u / omega * (math.cos(psi0 + omega * dt) - math.cos(psi0)), wrap(psi0 + omega * dt))  # fmt: skip
    ivp = solve_ivp(lambda _t, s: [u * math.cos(s[2]), u * math.sin(s[2]), omega], (0.0, dt), [x0, y0, psi0],
                    rtol=1e-13, atol=1e-14).y[:, -1]  # fmt: skip
    step = model.unicycle_step_exact(x0, y0, psi0, u, omega, dt)
    np.testing.assert_allclose(step, closed, rtol=0, atol=1e-13)  # u / omega amplifies rounding
    np.testing.assert_allclose(step[:2], ivp[:2], rtol=0, atol=1e-12)
    env = gym.make(ENV_ID)
    env.reset(options={"start": (x0, y0, psi0), "goal": (0.0, 0.0, 0.0)})
    info = env.step(np.array([u / 0.5, omega / 2.0], dtype=np.float32))[4]
    u_env, omega_env = info["linear_velocity"], info["angular_velocity"]  # the float32 action, as applied
    arc = (x0 + u_env / omega_env * (math.sin(psi0 + omega_env * dt) - math.sin(psi0)),
           y0 - u_env / omega_env * (math.cos(psi0 + omega_env * dt) - math.cos(psi0)))  # fmt: skip
    np.testing.assert_allclose(info["pose"][:2], arc, rtol=0, atol=1e-13)


# ---------------------------------------------------------------------------------------------
# The documented order of the command side: delay, the wheels (saturation, slip, fault), then additive disturbances
# ---------------------------------------------------------------------------------------------
BURGER_R, BURGER_B, BURGER_LIMIT = 0.033, 0.160, 0.22 / 0.033  # TurtleBot3 Burger: radius, track [m], [rad/s]


def step_burger(action: tuple[float, float], bias: tuple[float, float]) -> dict[str, float]:
    env = gym.make(ENV_ID, robot="turtlebot3_burger", disturbances=[VelocityBias(*bias)])
    env.reset(options={"start": (0.0, 0.0, 0.0), "goal": (1.0, 0.0, 0.0)})
    return env.step(np.array(action, dtype=np.float32))[4]  # type: ignore[no-any-return]


def test_additive_disturbance_acts_after_the_wheel_saturation_at_full_speed() -> None:
    """Full speed ahead: both wheels at their limit 0.22 / 0.033 rad/s, then the bias adds (0.05, 0.3)."""
    info = step_burger((1.0, 0.0), (0.05, 0.3))
    assert info["disturbance"]["commanded_linear_velocity"] == pytest.approx(0.22)
    assert info["linear_velocity"] == pytest.approx(0.22 + 0.05, rel=1e-12)  # not cut back to 0.22 by the wheels
    assert info["angular_velocity"] == pytest.approx(0.3, rel=1e-12)
    # and the robot moved along the arc of (0.27, 0.3) for dt = 0.05 s
    u, omega, dt = 0.27, 0.3, 0.05
    assert info["pose"][0] == pytest.approx(u / omega * math.sin(omega * dt), abs=1e-12)
    assert info["pose"][1] == pytest.approx(u / omega * (1.0 - math.cos(omega * dt)), abs=1e-12)


def test_additive_disturbance_acts_after_a_saturated_turn() -> None:
    """Action (1, 1): u = 0.22 m/s, omega = 2 r w_max / b = 2.75 rad/s ask w_L = 0 and w_R = 2 w_max; the default
    'scale' saturation halves both wheels (u = 0.11, omega = 1.375), then the bias adds (0.05, 0.3)."""
    info = step_burger((1.0, 1.0), (0.05, 0.3))
    assert info["disturbance"]["commanded_angular_velocity"] == pytest.approx(2 * BURGER_R * BURGER_LIMIT / BURGER_B)
    assert info["disturbance"]["wheel_saturated"]
    assert info["linear_velocity"] == pytest.approx(0.11 + 0.05, rel=1e-12)
    assert info["angular_velocity"] == pytest.approx(1.375 + 0.3, rel=1e-12)


GEOMETRY = {"robot": DifferentialDrive(0.033, 0.16)}  # TurtleBot3 Burger's wheels without a speed limit


def velocities(env: gym.Env, action: tuple[float, float], steps: int) -> list[tuple[float, float]]:  # type: ignore[type-arg]
    env.reset(seed=0, options={"start": (0.0, 0.0, 0.0), "goal": (1.0, 0.0, 0.0)})
    infos = [env.step(np.array(action, dtype=np.float32))[4] for _ in range(steps)]
    return [(i["linear_velocity"], i["angular_velocity"]) for i in infos]


def test_sinusoidal_disturbance_by_hand() -> None:
    """u + a_u sin(2 pi t / period + phase), t the start of each control period (k dt)."""
    env = gym.make(ENV_ID, disturbances=[VelocitySinusoid(0.1, 0.2, period=2.0, phase=0.3)])
    for k, (u, omega) in enumerate(velocities(env, (0.5, 0.25), 6)):
        wave = math.sin(2.0 * math.pi * k * 0.05 / 2.0 + 0.3)
        assert u == pytest.approx(0.25 + 0.1 * wave, rel=1e-12)
        assert omega == pytest.approx(0.5 + 0.2 * wave, rel=1e-12)


def test_wheel_slip_and_wheel_faults_by_hand() -> None:
    """Command (0.25 m/s, 0.5 rad/s): wheel rim speeds r w = u -+ omega b / 2 = 0.21 and 0.29 m/s."""
    slip = gym.make(ENV_ID, **GEOMETRY, disturbances=[WheelSlip(left=0.8, right=0.6)])
    u, omega = velocities(slip, (0.5, 0.25), 1)[0]
    assert u == pytest.approx((0.21 * 0.8 + 0.29 * 0.6) / 2.0, rel=1e-12)  # (v_L + v_R) / 2
    assert omega == pytest.approx((0.29 * 0.6 - 0.21 * 0.8) / 0.16, rel=1e-12)  # (v_R - v_L) / b
    fault = gym.make(ENV_ID, **GEOMETRY, disturbances=[ActuatorFault("left", 0.5, start_time=0.1)])
    before, _, after = velocities(fault, (0.5, 0.25), 3)  # periods starting at 0, 0.05 and 0.1 s
    assert before == pytest.approx((0.25, 0.5), rel=1e-12)
    assert after == pytest.approx(((0.21 * 0.5 + 0.29) / 2.0, (0.29 - 0.21 * 0.5) / 0.16), rel=1e-12)
    right = gym.make(ENV_ID, **GEOMETRY, disturbances=[ActuatorFault("right", 0.5)])
    assert velocities(right, (0.5, 0.25), 1)[0] == pytest.approx(
        ((0.21 + 0.29 * 0.5) / 2.0, (0.29 * 0.5 - 0.21) / 0.16)
    )


def test_random_walk_increments_have_the_documented_spread_and_restart_each_episode() -> None:
    """Increments of standard deviation intensity sqrt(dt) = 0.2 sqrt(0.05) = 0.0447 m/s per period, from 0."""
    env = gym.make(ENV_ID, T_con=40.0, disturbances=[VelocityRandomWalk(linear_intensity=0.2, seed=1)])
    walk = np.array([u for u, _ in velocities(env, (0.0, 0.0), 1000)])
    increments = np.diff(np.concatenate([[0.0], walk]))
    assert np.std(increments) == pytest.approx(0.2 * math.sqrt(0.05), rel=0.1)
    assert abs(np.mean(increments)) < 0.01
    assert np.all([omega == 0.0 for _, omega in velocities(env, (0.0, 0.0), 50)])
    first = velocities(env, (0.0, 0.0), 1)[0][0]  # a new episode starts the walk at 0: one increment from there
    assert abs(first) < 5 * 0.2 * math.sqrt(0.05) < np.max(np.abs(walk))


def feedforward_by_hand(d: float, alpha: float, psi: float, u: float, k: float) -> tuple[float, float]:
    """(d u Delta + alpha_dot + zeta_dot of eq. (18), e_psi of eq. (6)) for the linear velocity u."""
    bearing = wrap(alpha - psi)
    zeta = math.asin(k * alpha * math.tanh(d))
    alpha_dot, d_dot = u * math.sin(bearing) / d, -u * math.cos(bearing)
    zeta_dot = k * (alpha_dot * math.tanh(d) + alpha * (1.0 - math.tanh(d) ** 2) * d_dot)
    zeta_dot /= math.sqrt(1.0 - (k * alpha * math.tanh(d)) ** 2)
    return d * u * (1.0 - math.cos(bearing)) / bearing + alpha_dot + zeta_dot, bearing + zeta


def law(controller: object, d: float, alpha: float, psi: float, t: float) -> tuple[float, float]:
    inputs = ControllerInput(*(np.array([v], dtype=np.float64) for v in (d, alpha, psi, t, 0.8, 1.0)))
    u, omega = controller(inputs)  # type: ignore[operator]
    return float(u[0]), float(omega[0])


@pytest.mark.parametrize("state", [(0.8, 0.3, -1.1, 4.0), (0.37, -2.5, 1.9, 12.0), (2.2, 1.0, 1.3, 17.0)])
@pytest.mark.parametrize("power", [1, 2])
def test_conventional_ptc_by_hand(state: tuple[float, float, float, float], power: int) -> None:
    """Figure 8's comparison: eqs. (16)-(18) with beta = 1 and mu = (T / (T - t))^(n + m) / T of eqs. (12)-(13)."""
    d, alpha, psi, t = state
    mu = min((20.0 / (20.0 - t)) ** power / 20.0, 10.0)  # capped at max_gain = 10 1/s
    e = wrap(alpha - psi) + math.asin(K * alpha * math.tanh(d))
    p_star = 1.0 / (1.0 + e * e)
    u = 2.0 * mu * p_star * d
    feedforward, _ = feedforward_by_hand(d, alpha, psi, u, K)
    expected = (u, feedforward + 10.0 * p_star * mu * e)
    assert law(ConventionalPTCController(power=power), *state) == pytest.approx(expected, rel=1e-11)


@pytest.mark.parametrize("state", [(0.8, 0.3, -1.1), (0.37, -2.5, 1.9), (2.2, 1.0, 1.3), (0.004, 1.0, 0.0)])
def test_fixed_time_law_by_hand(state: tuple[float, float, float]) -> None:
    """u = p* (k1 d^a + k2 d^b), omega = feedforward + p* (k3 |e|^a + k4 |e|^b) sign(e); both 0 within 5 mm."""
    d, alpha, psi = state
    e = wrap(alpha - psi) + math.asin(K * alpha * math.tanh(d))
    p_star = 1.0 / (1.0 + e * e)
    u = p_star * (0.1 * d**0.5 + 0.1 * d**1.5)
    feedforward, _ = feedforward_by_hand(d, alpha, psi, u, K)
    omega = feedforward + p_star * (abs(e) ** 0.5 + abs(e) ** 1.5) * math.copysign(1.0, e)
    expected = (0.0, 0.0) if d < 0.005 else (u, omega)
    assert law(FixedTimeController(), *state, 3.0) == pytest.approx(expected, rel=1e-11, abs=0.0)
    bound = FixedTimeController().settling_time_bound()
    p_min = 1.0 / (1.0 + (7.0 * math.pi / 6.0) ** 2)
    assert bound == pytest.approx(
        {"distance": (1 / 0.05 + 1 / 0.05) / p_min, "orientation": (1 / 0.5 + 1 / 0.5) / p_min}
    )


def test_fabregas_law_and_its_integral_by_hand() -> None:
    """Ref. [9]: u = K0 d (pi - |alpha - psi|) / pi, omega = K_omega sin(alpha - psi) + K_i sum((alpha - psi) dt)."""
    controller = FabregasController(K0=0.1, K_omega=0.75, K_i=0.2, dt=0.05)
    bearings = np.array([1.0, -2.0])
    inputs = ControllerInput(np.array([0.8, 0.5]), bearings, np.zeros(2), np.zeros(2), np.ones(2), np.ones(2))
    for step in range(1, 4):
        u, omega = controller(inputs)
        np.testing.assert_allclose(u, 0.1 * np.array([0.8, 0.5]) * (math.pi - np.abs(bearings)) / math.pi)
        np.testing.assert_allclose(omega, 0.75 * np.sin(bearings) + 0.2 * step * 0.05 * bearings, rtol=1e-12)
    controller.reset(np.array([True, False]))  # robot 0's integral restarts
    np.testing.assert_allclose(
        controller(inputs)[1], 0.75 * np.sin(bearings) + 0.2 * np.array([1, 4]) * 0.05 * bearings
    )
    controller.reset()
    np.testing.assert_allclose(controller(inputs)[1], 0.75 * np.sin(bearings) + 0.2 * 0.05 * bearings)
    limited = FabregasController(K0=0.1, speed_limit=0.03)(inputs)[0]
    np.testing.assert_allclose(
        limited, np.minimum(0.1 * np.array([0.8, 0.5]) * (math.pi - np.abs(bearings)) / math.pi, 0.03)
    )
