"""The model functions against hand-computed values, finite differences and scipy's solve_ivp."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from dwr_gym import model

K = 1.0 / (2.0 * math.pi)


def test_distance_and_azimuth_hand_values() -> None:
    # goal at the origin; robot at (-3, -4): the goal lies at atan2(4, 3) from it
    assert model.distance(-3.0, -4.0) == pytest.approx(5.0)
    assert model.azimuth(-3.0, -4.0) == pytest.approx(math.atan2(4.0, 3.0))
    assert model.azimuth(-1.0, 0.0) == pytest.approx(0.0)
    assert model.azimuth(0.0, -1.0) == pytest.approx(math.pi / 2)


def test_azimuth_is_zero_at_the_goal_even_for_negative_zero() -> None:
    assert model.azimuth(0.0, 0.0) == 0.0
    assert model.azimuth(-0.0, -0.0) == 0.0


def test_orientation_error_hand_value() -> None:
    # eq. (6): alpha = pi/2, psi = 0, d = 1, k = 1/(2 pi)
    expected = math.pi / 2 + math.asin(K * (math.pi / 2) * math.tanh(1.0))
    assert model.orientation_error(math.pi / 2, 0.0, 1.0, K) == pytest.approx(expected)
    # k = 0 reduces (6) to alpha - psi, ref. [9]'s case (Remark 1)
    assert model.orientation_error(1.0, -0.5, 3.0, 0.0) == pytest.approx(1.5)


def test_orientation_error_wraps_alpha_minus_psi() -> None:
    e = model.orientation_error(3.0, -3.0, 0.0, K)  # alpha - psi = 6 -> 6 - 2 pi
    assert e == pytest.approx(6.0 - 2.0 * math.pi)


def test_constraint_functions_hand_values() -> None:
    assert model.velocity_constraint(math.pi / 2, 0.0) == pytest.approx(0.5)  # eq. (9)
    assert model.velocity_constraint(math.pi, 0.0) == pytest.approx(0.0)
    assert model.improved_velocity_constraint(1.0, 1.0) == pytest.approx(0.5)  # eq. (10)
    assert model.improved_velocity_constraint_min(1.0) == pytest.approx(1.0 / (1.0 + (7 * math.pi / 6) ** 2))


def test_lyapunov_hand_value() -> None:
    assert model.lyapunov(3.0, 4.0) == pytest.approx(12.5)  # eq. (21)


def test_conventional_scaling_properties() -> None:
    T = 20.0
    assert model.conventional_scaling(0.0, T) == pytest.approx(1.0)  # mu_1(t0, T) = 1
    assert model.conventional_scaling(10.0, T) == pytest.approx(2.0)
    t = np.linspace(0.0, 19.99, 200)
    assert np.all(np.diff(model.conventional_scaling(t, T)) > 0)  # grows toward T
    assert model.conventional_scaling(T, T, max_gain=1e3) == pytest.approx(1e3)  # guarded, finite
    assert model.conventional_scaling_power(10.0, T, 1, 1) == pytest.approx(4.0)  # eq. (13), n + m = 2


def test_switching_time_matches_eq17_and_rounds_to_T_con_for_the_paper() -> None:
    d0, e0, T, beta, Kg, p_min = 0.8, 1.0, 20.0, 0.6, 5.0, 0.5
    expected = T * (1 - math.exp(-((d0**2 + e0**2) ** (1 - beta)) / ((1 - beta) * 2 * Kg * p_min)))
    assert model.switching_time(d0, e0, T, beta, Kg, p_min) == pytest.approx(expected)
    paper = model.switching_time(0.8, math.pi, 20.0, 24 / 25, 1.2, model.improved_velocity_constraint_min(1.0))
    assert paper == 20.0  # the reason for the gain cap


def test_fractional_scaling_is_constant_after_switching_time() -> None:
    T, t_v = 20.0, 12.0
    t = np.array([0.0, 6.0, 12.0, 15.0, 40.0])
    mu = model.fractional_scaling(t, T, t_v)
    assert mu[0] == pytest.approx(1.0 / T)
    assert mu[1] == pytest.approx(1.0 / 14.0)
    assert np.allclose(mu[2:], 1.0 / (T - t_v))
    assert model.fractional_scaling(T, T, T, max_gain=50.0) == pytest.approx(50.0)


def test_backstepping_delta_matches_eq19() -> None:
    x = np.array([-3.0, -0.2, 1e-3, 0.7, 3.5])
    assert np.allclose(model.backstepping_delta(x), (1 - np.cos(x)) / x, rtol=1e-12)
    assert model.backstepping_delta(0.0) == 0.0


@pytest.mark.parametrize("u, omega", [(0.3, 0.0), (0.3, 0.7), (-0.2, -1.5), (0.0, 2.0)])
def test_exact_step_matches_solve_ivp(u: float, omega: float) -> None:
    x0, y0, psi0, dt = 0.4, -0.3, 2.9, 0.37

    def rhs(_t: float, s: np.ndarray) -> list[float]:
        return [u * math.cos(s[2]), u * math.sin(s[2]), omega]  # eq. (1)

    ref = solve_ivp(rhs, (0.0, dt), [x0, y0, psi0], rtol=1e-12, atol=1e-13).y[:, -1]
    x, y, psi = model.unicycle_step_exact(x0, y0, psi0, u, omega, dt)
    assert x == pytest.approx(ref[0], abs=1e-10)
    assert y == pytest.approx(ref[1], abs=1e-10)
    assert psi == pytest.approx(model.wrap_angle(ref[2]), abs=1e-10)


def test_euler_converges_to_exact_at_first_order_and_rk4_is_accurate() -> None:
    args = (0.0, 0.0, 0.3, 0.5, 1.2)
    exact = np.array(model.unicycle_step_exact(*args, 1.0))
    errors = [
        np.max(np.abs(np.array(model.integrate_unicycle(*args, 1.0, "euler", n)) - exact)) for n in (10, 20, 40, 80)
    ]
    assert errors[-1] < 5e-3
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 1.8) & (ratios < 2.2))  # first order
    rk4 = np.array(model.integrate_unicycle(*args, 1.0, "rk4", 8))
    assert np.max(np.abs(rk4 - exact)) < 1e-6


def test_rates_match_finite_differences_of_the_kinematics() -> None:
    # eqs. (4), (5), (7) are the time derivatives of (2), (3), (6) along (1)
    x, y, psi, u, omega, h = -0.7, 0.4, 0.9, 0.35, -0.6, 1e-6
    alpha, dist = model.azimuth(x, y), model.distance(x, y)
    x2, y2, psi2 = model.unicycle_step_exact(x, y, psi, u, omega, h)
    x0, y0, psi0 = model.unicycle_step_exact(x, y, psi, u, omega, -h)
    fd = lambda f: (f(x2, y2, psi2) - f(x0, y0, psi0)) / (2 * h)  # noqa: E731
    assert model.distance_rate(u, alpha, psi) == pytest.approx(fd(lambda a, b, c: model.distance(a, b)), rel=1e-6)
    assert model.azimuth_rate(u, alpha, psi, dist) == pytest.approx(fd(lambda a, b, c: model.azimuth(a, b)), rel=1e-6)
    e_fd = fd(lambda a, b, c: model.orientation_error(model.azimuth(a, b), c, model.distance(a, b), K))
    assert model.orientation_error_rate(u, omega, alpha, psi, dist, K) == pytest.approx(e_fd, rel=1e-6)


def test_wrap_angle_range() -> None:
    a = np.linspace(-50, 50, 10001)
    w = model.wrap_angle(a)
    assert np.all(np.abs(w) <= math.pi + 1e-12)
    assert np.allclose(np.sin(w), np.sin(a)) and np.allclose(np.cos(w), np.cos(a))


def test_goal_frame_round_trip() -> None:
    pose = (3.0, -2.0, 2.5)
    goal = (1.0, 4.0, -1.2)
    back = model.from_goal_frame(*model.to_goal_frame(*pose, *goal), *goal)
    assert np.allclose(back, pose)


finite = st.floats(-1e8, 1e8, allow_nan=False)
angle = st.floats(-10.0, 10.0, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(x=finite, y=finite, psi=angle, u=st.floats(-10, 10), omega=st.floats(-10, 10))
def test_no_nan_or_inf_anywhere(x: float, y: float, psi: float, u: float, omega: float) -> None:
    d, alpha = model.distance(x, y), model.azimuth(x, y)
    values = [
        d,
        alpha,
        model.orientation_error(alpha, psi, d, K),
        model.distance_rate(u, alpha, psi),
        model.azimuth_rate(u, alpha, psi, d),
        model.orientation_error_rate(u, omega, alpha, psi, d, K),
        model.improved_velocity_constraint(model.orientation_error(alpha, psi, d, K), 1.0),
        model.velocity_constraint(alpha, psi),
        model.lyapunov(d, 1.0),
        *model.unicycle_step_exact(x, y, psi, u, omega, 0.05),
    ]
    assert np.all(np.isfinite(values))


@pytest.mark.parametrize("alpha_minus_psi", [math.pi, -math.pi])
def test_edge_states_are_finite(alpha_minus_psi: float) -> None:
    # d = 0 exactly, alpha - psi = +-pi
    for d in (0.0, 1e-300, 0.5):
        e = model.orientation_error(0.0, -alpha_minus_psi, d, K)
        assert abs(e) <= model.MAX_ORIENTATION_ERROR + 1e-12
        assert np.isfinite(model.azimuth_rate(1.0, 0.0, -alpha_minus_psi, d))
        assert np.isfinite(model.orientation_error_rate(1.0, 1.0, 0.0, -alpha_minus_psi, d, K))


# (function, scalar arguments, positions that may be arrays): each function broadcasts a float beside an array
BROADCAST = [
    (model.distance, (-0.3, 0.4), (0, 1)),
    (model.azimuth, (-0.3, 0.4), (0, 1)),
    (model.arcsine_term, (1.2, 0.7, K), (0, 1)),
    (model.arcsine_term_rate, (1.2, -0.3, 0.7, 0.2, K), (0, 1, 2, 3)),
    (model.azimuth_rate, (0.4, 1.2, -0.5, 0.7), (0, 1, 2, 3)),
    (model.distance_rate, (0.4, 1.2, -0.5), (0, 1, 2)),
    (model.orientation_error, (1.2, -0.5, 0.7, K), (0, 1, 2)),
    (model.conventional_scaling, (5.0, 20.0), (0, 1)),
    (model.conventional_scaling_power, (5.0, 20.0, 1, 1), (0, 1)),
    (model.fractional_scaling, (5.0, 20.0, 12.0), (0, 1, 2)),
    (model.unicycle_derivative, (0.9, 0.4, -0.3), (0, 1, 2)),
    (model.unicycle_step_exact, (0.1, -0.2, 0.9, 0.4, 1.7, 0.05), (0, 1, 2, 3, 4)),
    (model.velocity_constraint, (1.2, -0.5), (0, 1)),
]


@pytest.mark.parametrize(("function", "args", "positions"), BROADCAST, ids=[b[0].__name__ for b in BROADCAST])
def test_a_float_beside_an_array_broadcasts(function: object, args: tuple, positions: tuple[int, ...]) -> None:
    """ "Arrays of matching, broadcastable shapes": one argument an array of two robots, the others floats."""

    def first_robot(values: object) -> list[float]:  # each output (or each of a tuple), at robot 0
        outputs = values if isinstance(values, tuple) else (values,)
        return [float(np.atleast_1d(v)[0]) for v in outputs]

    scalar = first_robot(function(*args))  # type: ignore[operator]
    for position in positions:
        mixed = list(args)
        mixed[position] = np.array([args[position], args[position] + 0.1])
        result = first_robot(function(*mixed))  # type: ignore[operator]
        np.testing.assert_allclose(result, scalar, rtol=1e-15, atol=1e-15, err_msg=str(position))


@pytest.mark.parametrize("h", [0.2, 0.5, -1.0, 3.0])
def test_sinc_beyond_the_series_is_sin_h_over_h(h: float) -> None:
    assert model.sinc(h) == pytest.approx(math.sin(h) / h, rel=1e-15)
    batch = model.sinc(np.array([0.05, h, 0.0]))
    np.testing.assert_allclose(batch, [math.sin(0.05) / 0.05, math.sin(h) / h, 1.0], rtol=1e-15)
    assert model.sinc(np.zeros(0)).shape == (0,)  # an empty batch is an empty batch


def test_backstepping_delta_of_one_robot_matches_eq19() -> None:
    for x in (-3.0, -0.2, 1e-3, 0.7, 3.5):
        assert model.backstepping_delta(x) == pytest.approx((1 - math.cos(x)) / x, rel=1e-12)


def test_scaling_functions_from_t0_and_their_default_caps() -> None:
    assert model.conventional_scaling(8.0, 20.0, t0=3.0) == pytest.approx(20.0 / 15.0)  # T / (T + t0 - t)
    assert model.conventional_scaling(3.0, 20.0, t0=3.0) == pytest.approx(1.0)  # 1 at t0
    assert model.conventional_scaling_power(15.0, 20.0, 1, 1) == pytest.approx(16.0)  # (20 / 5)^2
    assert model.conventional_scaling_power(18.0, 20.0, 2, 1) == pytest.approx(1000.0)  # (20 / 2)^3
    assert model.conventional_scaling(20.0, 20.0) == pytest.approx(1e6, rel=1e-12)  # the documented default cap
    assert model.conventional_scaling_power(20.0, 20.0, 1, 1) == pytest.approx(1e6, rel=1e-12)
    assert model.fractional_scaling(20.0, 20.0, 20.0) == pytest.approx(1e6, rel=1e-12)


def test_integrate_unicycle_defaults_to_one_exact_step() -> None:
    args = (0.1, -0.2, 0.9, 0.4, 1.7, 0.05)
    assert model.integrate_unicycle(*args) == model.unicycle_step_exact(*args)
    batch = [np.array([v, v]) for v in args[:5]]
    np.testing.assert_array_equal(model.integrate_unicycle(*batch, 0.05), model.unicycle_step_exact(*batch, 0.05))


@pytest.mark.parametrize("integrator", ["exact", "euler", "rk4"])
def test_turning_on_the_spot_moves_only_the_heading(integrator: str) -> None:
    x, y, psi = model.integrate_unicycle(0.3, -0.4, 3.0, 0.0, 2.0, 0.25, integrator, 2)  # type: ignore[arg-type]
    assert (x, y) == (0.3, -0.4)
    assert psi == pytest.approx(3.0 + 0.5 - 2.0 * math.pi)  # wrapped to [-pi, pi)


def test_scaling_power_caps_only_its_result_at_max_gain() -> None:
    """With n + m = 1 and a cap above mu_1's own default cap (1e6), mu_1 itself is capped at max_gain, not 1e6."""
    assert model.conventional_scaling_power(20.0 - 2e-8, 20.0, 1, 0, max_gain=1e9) == pytest.approx(1e9, rel=1e-6)


def test_scalar_math_is_numpys_names_over_python_numbers() -> None:
    xp = model.SCALAR_MATH
    assert xp.where(True, 1.5, 2.5) == 1.5 and xp.where(False, 1.5, 2.5) == 2.5
    assert xp.logical_not(True) is False and xp.logical_not(False) is True
    assert xp.copy(1.5) == 1.5 and xp.maximum(1.0, 2.0) == 2.0 and xp.minimum(1.0, 2.0) == 1.0
    assert model.namespace(1.0, 2.0) is xp and model.namespace(1.0, np.zeros(2)) is model.ARRAY_MATH


TORCH_PROBE = """
import json, sys
import numpy as np
from dwr_gym import model
rng = np.random.default_rng(0)
x, y = rng.uniform(-0.9, 0.9, 2048), rng.uniform(-3.0, 3.0, 2048)
xp, result, calls = model.ARRAY_MATH, {}, []
xp.sin(x)
result["torch imported"] = "torch" in sys.modules
import torch
for name in ("sin", "cos", "tanh", "asin", "atan2"):  # count what torch computes
    setattr(torch, name, (lambda f, n: lambda *a: (calls.append(n), f(*a))[1])(getattr(torch, name), name))
for name in ("sin", "cos", "tanh", "arcsin", "arctan2"):
    args = (x, y) if name == "arctan2" else (x,)
    big = getattr(xp, name)(*args)
    assert type(big) is np.ndarray and big.dtype == np.float64 and big.shape == x.shape, name
    assert getattr(xp, name).__name__ == name
    result[name] = float(np.max(np.abs(big - getattr(np, name)(*args))))
    # below TORCH_MIN_SIZE, strided, float32 or read-only arrays: numpy's own function, bit for bit
    readonly = x.copy()
    readonly.flags.writeable = False
    for case in (x[:10], x[::2], x.astype(np.float32), readonly):
        other = (y[: case.size].astype(case.dtype),) if name == "arctan2" else ()
        assert np.array_equal(getattr(xp, name)(case, *other), getattr(np, name)(case, *other)), name
result["torch calls"] = calls
print(json.dumps(result))
"""


@pytest.mark.parametrize("switch", ["1", "0"])
def test_torch_backed_functions_equal_numpys_and_DWR_GYM_TORCH_0_keeps_torch_out(switch: str) -> None:
    """In a fresh interpreter (the functions are built at import): torch computes large float64 arrays to within
    1e-15 of numpy; DWR_GYM_TORCH=0 leaves torch unimported and numpy computes everything."""
    pytest.importorskip("torch")
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    # the same calls in this process too, so that a tool mapping tests to the functions they run (mutmut) sees these
    assert model._vectorised("tanh")(np.zeros(3)).tolist() == [0.0, 0.0, 0.0]
    model._torch_module()
    env = {**os.environ, "DWR_GYM_TORCH": switch}
    done = subprocess.run([sys.executable, "-c", TORCH_PROBE], capture_output=True, text=True, env=env, timeout=300,
                          cwd=Path(__file__).resolve().parents[1], check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout)
    assert result.pop("torch imported") is (switch == "1")
    torch_names = {"arcsin": "asin", "arctan2": "atan2"}  # the functions torch computes on this CPU, by torch's names
    expected = [
        torch_names.get(f, f) for f in ("sin", "cos", "tanh", "arcsin", "arctan2") if f in model.TORCH_FUNCTIONS
    ]
    assert result.pop("torch calls") == (expected if switch == "1" else [])
    assert max(result.values()) <= (1e-15 if switch == "1" else 0.0), result  # 1 ulp of values up to pi


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_torch_kernels_run_on_the_calling_thread_and_leave_the_users_thread_count(
    threads: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """torch's thread pool would split each call across the cores, which collapses on a busy machine
    (docs/throughput.md): the calls run with one thread, and the user's setting is back after each."""
    torch = pytest.importorskip("torch")
    monkeypatch.setattr(model, "TORCH_FUNCTIONS", frozenset(("sin", "cos", "tanh", "arcsin", "arctan2")))
    seen: list[int] = []
    original = torch.sin

    def recording_sin(*args: object) -> object:
        seen.append(torch.get_num_threads())
        return original(*args)

    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        monkeypatch.setattr(torch, "sin", recording_sin)
        x = np.linspace(-3.0, 3.0, model.TORCH_MIN_SIZE)
        np.testing.assert_allclose(model.ARRAY_MATH.sin(x), np.sin(x), rtol=0, atol=1e-15)
        assert seen == [1] and torch.get_num_threads() == threads
        for name in ("cos", "tanh", "arcsin", "arctan2"):
            args = (x / 3.0, x + 4.0)[: 2 if name == "arctan2" else 1]
            np.testing.assert_allclose(getattr(model.ARRAY_MATH, name)(*args), getattr(np, name)(*args), atol=1e-15)
            assert torch.get_num_threads() == threads

        def failing_sin(*args: object) -> object:
            raise RuntimeError("kernel failed")

        monkeypatch.setattr(torch, "sin", failing_sin)
        with pytest.raises(RuntimeError, match="kernel failed"):
            model.ARRAY_MATH.sin(x)
        assert torch.get_num_threads() == threads  # restored on errors too
    finally:
        torch.set_num_threads(before)


def test_torch_computes_only_the_functions_numpy_evaluates_one_element_at_a_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    torch = pytest.importorskip("torch")
    calls: list[str] = []
    for name in ("sin", "tanh"):
        original = getattr(torch, name)
        monkeypatch.setattr(torch, name, lambda *a, _f=original, _n=name: calls.append(_n) or _f(*a))
    x = np.linspace(-1.0, 1.0, model.TORCH_MIN_SIZE)
    monkeypatch.setattr(model, "TORCH_FUNCTIONS", frozenset(("sin",)))
    model.ARRAY_MATH.sin(x), model.ARRAY_MATH.tanh(x), model.ARRAY_MATH.sin(x[:-1])  # the last: below the size
    assert calls == ["sin"]
