"""The paper's mathematics as pure, batched functions.

Every function takes numpy arrays of matching, broadcastable shapes and returns arrays of the same
shape: one call handles N robots. Given Python floats instead, the same code runs on the ``math``
module (see :data:`SCALAR_MATH`), which is what keeps a single robot's step cheap; on large float64
arrays, the transcendental functions numpy evaluates one element at a time are torch's SIMD kernels (see
:data:`ARRAY_MATH` and :data:`TORCH_FUNCTIONS`). Nothing here keeps state or knows about Gymnasium; the
single env, the vector env and the controllers in :mod:`baselines` all call these functions, so
each equation of the paper is written exactly once.

Equation numbers refer to Zhang, Chen and Chen, "Prescribed-Time Fractional Order Control of DWR
via Time-Varying Scaling Function" (2023). Coordinates are those of the goal frame: the goal sits
at the origin with heading 0 (the paper's setting); :func:`to_goal_frame` maps any goal pose there.
"""

from __future__ import annotations

import math
import os
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
Integrator = Literal["exact", "euler", "rk4"]
INTEGRATORS: tuple[str, ...] = ("exact", "euler", "rk4")

#: Distances below this are treated as this in the divisions of eqs. (5) and (7) [m].
DISTANCE_FLOOR = 1e-9
#: Bound of |e_psi| implied by eq. (6): |alpha - psi| <= pi and |zeta| <= pi/6.
MAX_ORIENTATION_ERROR = 7.0 * np.pi / 6.0


class _ScalarMath:
    """numpy's function names over Python floats, from the ``math`` module (10-50x faster than numpy on scalars)."""

    sin, cos, tanh, sqrt, hypot, expm1 = math.sin, math.cos, math.tanh, math.sqrt, math.hypot, math.expm1
    arctan2, arcsin, floor, abs = math.atan2, math.asin, math.floor, abs
    maximum, minimum = max, min

    @staticmethod
    def where(condition: bool, if_true: float, if_false: float) -> float:
        return if_true if condition else if_false

    @staticmethod
    def logical_not(value: bool) -> bool:
        return not value

    @staticmethod
    def copy(value: float) -> float:
        return value


#: The namespace the functions use for Python floats; numpy (or :data:`ARRAY_MATH`) serves arrays.
SCALAR_MATH: Any = _ScalarMath

#: Below this many elements numpy computes the float64 functions too: a torch call costs a few microseconds
#: more than its kernel, and the vector env's step, measured step by step against its numpy-only path, was
#: slower with torch up to 1536 robots and faster from 2048 (on CPUs with and without AVX512).
TORCH_MIN_SIZE = 2048
_torch: Any = None  # the torch module once imported; False if it cannot be
_FLOAT64 = np.dtype(np.float64)


def _torch_module() -> Any:
    """torch, imported on first use; False without torch (the ``train`` extra) or with DWR_GYM_TORCH=0."""
    global _torch
    if _torch is None:
        _torch = False
        if os.environ.get("DWR_GYM_TORCH", "1") != "0":
            try:
                import torch

                _torch = torch
            except ImportError:  # the env's math needs only numpy
                pass
    return _torch


def _numpy_has_simd_float64() -> bool:
    """Whether this numpy computes float64 tanh, arcsin and arctan2 with SIMD (Intel's SVML, on CPUs with
    AVX512_SKX); elsewhere it computes them one element at a time, as it always does sin and cos."""
    try:  # what numpy.show_runtime() reports (numpy._core since numpy 2)
        from numpy._core._multiarray_umath import __cpu_features__
    except ImportError:
        try:
            from numpy.core._multiarray_umath import __cpu_features__
        except ImportError:
            return False
    return bool(__cpu_features__.get("AVX512_SKX"))


#: The float64 functions torch computes for large arrays: those this numpy evaluates one element at a time
#: (numpy's SIMD tanh, arcsin and arctan2 beat torch's: docs/throughput.md).
TORCH_FUNCTIONS: frozenset[str] = frozenset(
    ("sin", "cos") if _numpy_has_simd_float64() else ("sin", "cos", "tanh", "arcsin", "arctan2")
)


def _vectorised(name: str) -> Any:
    """numpy's float64 function ``name``, computed by torch for large contiguous float64 arrays when it is
    one of :data:`TORCH_FUNCTIONS`.

    numpy evaluates float64 sin and cos (and, without AVX512, tanh, arcsin and arctan2) one element at a
    time; torch's kernels use SIMD (SLEEF, within 1 ulp), 2-3x faster. Results agree with numpy's to about
    1e-16. torch computes them on the calling thread: its thread pool would split a call of a few
    microseconds across the cores, and on a busy machine every such call waits for a thread the scheduler
    has set aside (measured in docs/throughput.md). So torch's thread count is 1 for the call, and
    restored right after it: the user's setting holds everywhere else.
    """
    numpy_fn = getattr(np, name)
    torch_name = {"arctan2": "atan2", "arcsin": "asin"}.get(name, name)

    def fn(*args: Any) -> Any:
        first = args[0]
        if type(first) is np.ndarray and first.size >= TORCH_MIN_SIZE and name in TORCH_FUNCTIONS:
            shape = first.shape
            for a in args:  # float64 dtypes are one object: compared by identity; flags: made once
                if not (type(a) is np.ndarray and a.dtype is _FLOAT64 and a.shape == shape
                        and (flags := a.flags).c_contiguous and flags.writeable):  # fmt: skip
                    return numpy_fn(*args)
            torch = _torch_module()
            if torch:
                threads = torch.get_num_threads()
                if threads == 1:
                    return getattr(torch, torch_name)(*map(torch.from_numpy, args)).numpy()
                torch.set_num_threads(1)
                try:
                    return getattr(torch, torch_name)(*map(torch.from_numpy, args)).numpy()
                finally:
                    torch.set_num_threads(threads)
        return numpy_fn(*args)

    fn.__name__ = name
    return fn


class _ArrayMath:
    """numpy, with the float64 transcendental functions of :func:`_vectorised` (the namespace of arrays)."""

    sin, cos, tanh, arcsin, arctan2 = (
        staticmethod(_vectorised(n)) for n in ("sin", "cos", "tanh", "arcsin", "arctan2")
    )

    def __getattr__(self, name: str) -> Any:
        return getattr(np, name)


#: The namespace the functions use for numpy arrays.
ARRAY_MATH: Any = _ArrayMath()


def namespace(*values: Any) -> Any:
    """:data:`ARRAY_MATH` (numpy) if any value is a numpy array, the array's own namespace if it is an array of
    another library (the array API's ``__array_namespace__``: ``jax.numpy`` for jax arrays, traced or not),
    else :data:`SCALAR_MATH`.

    The functions of the single env's step test ``type(x) is float`` inline first and call this only
    for arrays: for one robot the call cost more than the function's arithmetic (8 calls were 8 % of
    the step's instructions).
    """
    for value in values:
        if type(value) is not float:  # float first: the single env's case
            if isinstance(value, np.ndarray):
                return ARRAY_MATH
            if hasattr(value, "__array_namespace__") and not isinstance(value, np.generic):  # numpy's scalars: math
                return value.__array_namespace__()
    return SCALAR_MATH


def is_traceable(xp: Any) -> bool:
    """Whether ``xp`` is the namespace of another array library than numpy (jax.numpy): its arrays may be traced
    by a compiler, so the functions take no Python branch on their values and write no array in place."""
    return xp is not ARRAY_MATH and xp is not SCALAR_MATH


def wrap_angle(angle: ArrayLike) -> FloatArray:
    """Wrap angles to [-pi, pi) (to within one rounding error)."""
    xp = SCALAR_MATH if type(angle) is float else namespace(angle)
    return angle - (2.0 * np.pi) * xp.floor((angle + np.pi) * (0.5 / np.pi))  # floor: ~5x np.mod's speed


def rotate(x: ArrayLike, y: ArrayLike, cos_angle: ArrayLike, sin_angle: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Rotate the vectors (x, y) by the angles whose cosine and sine are given."""
    return cos_angle * x - sin_angle * y, sin_angle * x + cos_angle * y


def to_goal_frame(
    x: ArrayLike, y: ArrayLike, psi: ArrayLike, goal_x: ArrayLike, goal_y: ArrayLike, goal_psi: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Pose of the robot in the goal's frame (goal at the origin, heading 0)."""
    xp = namespace(goal_psi)
    x_g, y_g = rotate(x - goal_x, y - goal_y, xp.cos(goal_psi), -xp.sin(goal_psi))  # type: ignore[operator]
    return x_g, y_g, wrap_angle(psi - goal_psi)  # type: ignore[operator]


def from_goal_frame(
    x_g: ArrayLike, y_g: ArrayLike, psi_g: ArrayLike, goal_x: ArrayLike, goal_y: ArrayLike, goal_psi: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Inverse of :func:`to_goal_frame`: world pose from a pose in the goal's frame."""
    xp = namespace(goal_psi)
    dx, dy = rotate(x_g, y_g, xp.cos(goal_psi), xp.sin(goal_psi))
    return goal_x + dx, goal_y + dy, wrap_angle(psi_g + goal_psi)  # type: ignore[operator]


# ---------------------------------------------------------------------------------------------
# Kinematics (1) and its integration over one control period
# ---------------------------------------------------------------------------------------------
def unicycle_derivative(
    psi: ArrayLike, linear_velocity: ArrayLike, angular_velocity: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Right-hand side of the kinematic model, eq. (1): (x_dot, y_dot, psi_dot)."""
    xp = namespace(psi)
    u = linear_velocity
    return u * xp.cos(psi), u * xp.sin(psi), angular_velocity + 0.0 * u  # type: ignore[operator]


#: Below this |h| the series of sin(h) / h to h^8 is exact to rounding (its first omitted term is h^10 / 11!).
SINC_SERIES_LIMIT = 0.1


def sinc(h: ArrayLike) -> FloatArray:
    """sin(h) / h, equal to 1 at h = 0: a polynomial where |h| <= SINC_SERIES_LIMIT (no division, no sine),
    sin(h) / h elsewhere."""
    h2 = h * h  # type: ignore[operator]
    series = 1.0 + h2 * (-1.0 / 6.0 + h2 * (1.0 / 120.0 + h2 * (-1.0 / 5040.0 + h2 * (1.0 / 362880.0))))
    xp = SCALAR_MATH if type(h) is float else namespace(h)
    if xp is SCALAR_MATH:
        return series if abs(h) <= SINC_SERIES_LIMIT else math.sin(h) / h  # type: ignore[arg-type, operator, return-value]
    if xp is ARRAY_MATH and not (h2.size and h2.max() > SINC_SERIES_LIMIT * SINC_SERIES_LIMIT):  # type: ignore[union-attr]
        return series  # type: ignore[no-any-return]  # numpy, every |h| small: no sine (np.max's initial= doubles its cost)
    xp = np if xp is ARRAY_MATH else xp  # numpy's own sine here, as before torch's kernels were added
    large = xp.abs(h) > SINC_SERIES_LIMIT
    safe = xp.where(large, h, 1.0)
    return xp.where(large, xp.sin(safe) / safe, series)  # type: ignore[no-any-return]


def unicycle_step_exact(
    x: ArrayLike, y: ArrayLike, psi: ArrayLike, linear_velocity: ArrayLike, angular_velocity: ArrayLike, dt: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Exact zero-order-hold solution of eq. (1) over ``dt`` for constant (u, omega).

    The arc is written as chord length times the direction of the mid-heading,
    ``u dt [sin(h) / h] [cos, sin](psi + h)`` with h = omega dt / 2, which needs no division by
    omega and is exactly the straight line when omega = 0.
    """
    xp = SCALAR_MATH if type(psi) is float is type(angular_velocity) else namespace(psi, angular_velocity)
    half_turn = 0.5 * dt * angular_velocity  # type: ignore[operator]
    chord = linear_velocity * dt * sinc(half_turn)  # type: ignore[operator]
    mid_heading = psi + half_turn  # type: ignore[operator]
    return x + chord * xp.cos(mid_heading), y + chord * xp.sin(mid_heading), wrap_angle(mid_heading + half_turn)  # type: ignore[operator]


def unicycle_step_euler(
    x: ArrayLike, y: ArrayLike, psi: ArrayLike, linear_velocity: ArrayLike, angular_velocity: ArrayLike, dt: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """One explicit Euler step of eq. (1)."""
    x_dot, y_dot, psi_dot = unicycle_derivative(psi, linear_velocity, angular_velocity)
    return x + dt * x_dot, y + dt * y_dot, wrap_angle(psi + dt * psi_dot)


def unicycle_step_rk4(
    x: ArrayLike, y: ArrayLike, psi: ArrayLike, linear_velocity: ArrayLike, angular_velocity: ArrayLike, dt: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """One classical Runge-Kutta step of eq. (1) for constant (u, omega)."""
    k1 = unicycle_derivative(psi, linear_velocity, angular_velocity)
    k2 = unicycle_derivative(psi + 0.5 * dt * k1[2], linear_velocity, angular_velocity)
    k3 = unicycle_derivative(psi + 0.5 * dt * k2[2], linear_velocity, angular_velocity)
    k4 = unicycle_derivative(psi + dt * k3[2], linear_velocity, angular_velocity)
    increments = [dt / 6.0 * (a + 2.0 * b + 2.0 * c + e) for a, b, c, e in zip(k1, k2, k3, k4, strict=True)]
    return x + increments[0], y + increments[1], wrap_angle(psi + increments[2])


_STEPPERS = {"exact": unicycle_step_exact, "euler": unicycle_step_euler, "rk4": unicycle_step_rk4}


def integrate_unicycle(
    x: ArrayLike,
    y: ArrayLike,
    psi: ArrayLike,
    linear_velocity: ArrayLike,
    angular_velocity: ArrayLike,
    dt: float,
    integrator: Integrator = "exact",
    substeps: int = 1,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Advance eq. (1) by one control period ``dt`` with the commands held constant."""
    step = _STEPPERS[integrator]
    if substeps == 1:  # the default: no loop
        return step(x, y, psi, linear_velocity, angular_velocity, dt)
    h = dt / substeps
    for _ in range(substeps):
        x, y, psi = step(x, y, psi, linear_velocity, angular_velocity, h)
    return x, y, psi  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------
# Error coordinates (2)-(8)
# ---------------------------------------------------------------------------------------------
def distance(x: ArrayLike, y: ArrayLike) -> FloatArray:
    """Distance to the goal at the origin, eq. (2)."""
    xp = SCALAR_MATH if type(x) is float is type(y) else namespace(x, y)
    return xp.sqrt(x * x + y * y)  # type: ignore[operator]  # positions are bounded: no overflow


def azimuth(x: ArrayLike, y: ArrayLike) -> FloatArray:
    """Azimuth of the goal seen from the robot, eq. (3): atan2(y_d - y, x_d - x) with the goal at 0."""
    # 0.0 - v turns -0.0 into +0.0, so atan2 gives 0 rather than +-pi at d = 0 exactly.
    xp = SCALAR_MATH if type(x) is float is type(y) else namespace(x, y)
    return xp.arctan2(0.0 - y, 0.0 - x)  # type: ignore[operator]


def bearing_error(alpha: ArrayLike, psi: ArrayLike) -> FloatArray:
    """alpha - psi wrapped to [-pi, pi), the interval eq. (6) assumes (after ref. [9])."""
    return wrap_angle(alpha - psi)  # type: ignore[operator]


def arcsine_term(alpha: ArrayLike, dist: ArrayLike, k: float) -> FloatArray:
    """The auxiliary arcsine function zeta = asin(k alpha tanh d) of eq. (6)."""
    xp = SCALAR_MATH if type(alpha) is float is type(dist) else namespace(alpha, dist)
    return xp.arcsin(k * alpha * xp.tanh(dist))  # type: ignore[operator]


def orientation_error(alpha: ArrayLike, psi: ArrayLike, dist: ArrayLike, k: float) -> FloatArray:
    """Distance-related orientation error e_psi = (alpha - psi) + zeta, eq. (6)."""
    return bearing_error(alpha, psi) + arcsine_term(alpha, dist, k)


def distance_rate(linear_velocity: ArrayLike, alpha: ArrayLike, psi: ArrayLike) -> FloatArray:
    """d_dot = -u cos(alpha - psi), eq. (4)."""
    return -linear_velocity * namespace(alpha, psi).cos(alpha - psi)  # type: ignore[operator]


def azimuth_rate(linear_velocity: ArrayLike, alpha: ArrayLike, psi: ArrayLike, dist: ArrayLike) -> FloatArray:
    """alpha_dot = u sin(alpha - psi) / d, eq. (5)."""
    # Guard: eq. (5) divides by d; below DISTANCE_FLOOR we divide by the floor instead.
    return (
        linear_velocity * namespace(alpha, psi).sin(alpha - psi) / namespace(dist).maximum(dist, DISTANCE_FLOOR)  # type: ignore[operator]
    )


def arcsine_term_rate(
    alpha: ArrayLike, alpha_rate: ArrayLike, dist: ArrayLike, dist_rate: ArrayLike, k: float
) -> FloatArray:
    """zeta_dot, the last term of eqs. (7) and (18)."""
    xp = namespace(alpha, dist)
    tanh_d = xp.tanh(dist)
    numerator = alpha_rate * tanh_d + alpha * (1.0 - tanh_d**2) * dist_rate
    return k * numerator / xp.sqrt(1.0 - (k * alpha * tanh_d) ** 2)


def orientation_error_rate(
    linear_velocity: ArrayLike,
    angular_velocity: ArrayLike,
    alpha: ArrayLike,
    psi: ArrayLike,
    dist: ArrayLike,
    k: float,
) -> FloatArray:
    """e_psi_dot = u sin(e_psi - zeta) / d - omega + zeta_dot, eq. (7) (second line of eq. (8))."""
    alpha_dot = azimuth_rate(linear_velocity, alpha, psi, dist)
    d_dot = distance_rate(linear_velocity, alpha, psi)
    return alpha_dot - angular_velocity + arcsine_term_rate(alpha, alpha_dot, dist, d_dot, k)


def backstepping_delta(angle: ArrayLike) -> FloatArray:
    """Delta = (1 - cos(x)) / x with x = e_psi - zeta, eq. (19); equal to 0 at x = 0.

    Written as (x / 2) sinc^2(x / 2), which is the same function without the 0/0 at x = 0.
    """
    half = 0.5 * angle  # type: ignore[operator]
    xp = namespace(angle)
    if xp is SCALAR_MATH:
        return half * (math.sin(half) / half) ** 2 if half != 0.0 else 0.0
    return half * xp.square(xp.sinc(half / np.pi))


# ---------------------------------------------------------------------------------------------
# Constraint functions (9), (10)
# ---------------------------------------------------------------------------------------------
def velocity_constraint(alpha: ArrayLike, psi: ArrayLike) -> FloatArray:
    """Ref. [9]'s linear-velocity constraint p = (pi - |alpha - psi|) / pi, eq. (9)."""
    bearing = bearing_error(alpha, psi)
    return (np.pi - namespace(bearing).abs(bearing)) / np.pi


def improved_velocity_constraint(orientation_err: ArrayLike, Ke: float) -> FloatArray:
    """The paper's constraint p* = 1 / (1 + Ke e_psi^2), eq. (10)."""
    return 1.0 / (1.0 + Ke * orientation_err * orientation_err)  # type: ignore[operator]


def improved_velocity_constraint_min(Ke: float) -> float:
    """p*_min: the minimum of eq. (10) over the interval |e_psi| <= 7 pi / 6 that eq. (6) allows."""
    return float(improved_velocity_constraint(MAX_ORIENTATION_ERROR, Ke))


# ---------------------------------------------------------------------------------------------
# Scaling functions (12), (13), (17)
# ---------------------------------------------------------------------------------------------
def conventional_scaling(t: ArrayLike, T: float, t0: float = 0.0, max_gain: float = 1e6) -> FloatArray:
    """mu_1(t, T) = T / (T + t0 - t), eq. (12); equal to 1 at t0 and unbounded toward t0 + T."""
    # Guard: eq. (12) is infinite at t = t0 + T and negative after; we cap it at max_gain.
    xp = SCALAR_MATH if type(t) is float is type(T) else namespace(t, T)
    return T / xp.maximum(T + t0 - t, T / max_gain)  # type: ignore[operator]


def conventional_scaling_power(
    t: ArrayLike, T: float, order: int, extra: int, t0: float = 0.0, max_gain: float = 1e6
) -> FloatArray:
    """mu(t, T) = mu_1(t, T)^(n + m), eq. (13), with n = ``order`` and m = ``extra``."""
    return namespace(t, T).minimum(conventional_scaling(t, T, t0, max_gain) ** (order + extra), max_gain)


def switching_time(
    initial_distance: ArrayLike, initial_orientation_error: ArrayLike, T_con: float, beta: float, K: float, p_min: float
) -> FloatArray:
    """t_v of eq. (17): T_con (1 - exp(-(d0^2 + e0^2)^(1-beta) / ((1-beta) 2 K p*_min))).

    For the paper's parameters the exponent is about -150, so t_v equals T_con in double precision;
    :func:`fractional_scaling` caps the gain that this would make unbounded.
    """
    d0, e0 = initial_distance, initial_orientation_error
    exponent = -((d0 * d0 + e0 * e0) ** (1.0 - beta)) / ((1.0 - beta) * 2.0 * K * p_min)  # type: ignore[operator]
    return T_con * -namespace(exponent).expm1(exponent)


def fractional_scaling(t: ArrayLike, T_con: float, switch_time: ArrayLike, max_gain: float = 1e6) -> FloatArray:
    """mu*(t, T_con) of eq. (17): 1 / (T_con - t) up to t_v, then frozen at 1 / (T_con - t_v)."""
    xp = namespace(t, T_con, switch_time)
    time_to_go = T_con - xp.minimum(t, switch_time)
    # Guard: when t_v rounds to T_con, eq. (17) grows without bound; the gain is capped at max_gain.
    return 1.0 / xp.maximum(time_to_go, 1.0 / max_gain)


# ---------------------------------------------------------------------------------------------
# Lyapunov function (21)
# ---------------------------------------------------------------------------------------------
def lyapunov(dist: ArrayLike, orientation_err: ArrayLike) -> FloatArray:
    """L = (d^2 + e_psi^2) / 2, eq. (21)."""
    return 0.5 * (dist * dist + orientation_err * orientation_err)  # type: ignore[operator]
