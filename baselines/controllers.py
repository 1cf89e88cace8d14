"""Analytic point-stabilization laws, batched over N robots.

Each controller maps :class:`ControllerInput` (arrays of shape (N,) in the goal frame) to the
commands (u [m/s], omega [rad/s]). Its parameters are a frozen, validated dataclass; the paper's
values are presets. All the mathematics comes from :mod:`dwr_gym.model`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from baselines.base import (
    K_MAX,
    Controller,
    ControllerInput,
    ControllerParams,
    array_namespace,
    prescribed_time,
    signed_power,
)
from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.validation import as_float, as_int


def feedforward_angular_velocity(
    inputs: ControllerInput, linear_velocity: FloatArray, k: float
) -> tuple[FloatArray, FloatArray]:
    """The part of eq. (18) that cancels the drift of eq. (7): d u Delta + alpha_dot + zeta_dot.

    Returns it with e_psi of eq. (6), which the feedback part needs.
    """
    d, alpha, psi = inputs.distance, inputs.azimuth, inputs.heading
    orientation_err = model.orientation_error(alpha, psi, d, k)
    zeta = model.arcsine_term(alpha, d, k)
    alpha_rate = model.azimuth_rate(linear_velocity, alpha, psi, d)
    d_rate = model.distance_rate(linear_velocity, alpha, psi)
    zeta_rate = model.arcsine_term_rate(alpha, alpha_rate, d, d_rate, k)
    delta = model.backstepping_delta(orientation_err - zeta)
    return d * linear_velocity * delta + alpha_rate + zeta_rate, orientation_err


# ---------------------------------------------------------------------------------------------
# The paper's prescribed-time fractional-order law, eqs. (16)-(19)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PTCParams(ControllerParams):
    """Parameters of the prescribed-time fractional-order law; defaults are the paper's Figure 5."""

    K1: float = 2.0
    """Gain of the linear velocity, eq. (16); > 0."""
    K2: float = 10.0
    """Gain of the angular velocity, eq. (18); > 0."""
    K: float = 1.2
    """Gain in t_v of eq. (17); 0 < K <= min(0.6 K1, K2) (Table 1)."""
    Ke: float = 1.0
    """Gain of the constraint function p*, eq. (10); > 0."""
    T_con: float = 20.0  # [s]
    """Prescribed time; > 0."""
    beta: float = 24.0 / 25.0
    """Fractional order, 1/2 < beta < 1."""
    k: float = K_MAX
    """Gain of the arcsine term of eq. (6), 0 <= k <= 1/(2 pi)."""
    stop_distance: float = 0.005  # [m]
    """Guard: both commands are 0 when d < stop_distance (the paper suggests stopping within ~1 cm)."""
    max_gain: float = 10.0  # [1/s]
    """Guard: cap of mu*(t) of eq. (17), which is unbounded when t_v rounds to T_con."""

    def validate(self) -> None:
        for name in ("K1", "K2", "K", "Ke", "T_con"):
            as_float(name, getattr(self, name), 0.0, 1e9, low_inclusive=False)
        as_float("beta", self.beta, 0.5, 1.0, low_inclusive=False, high_inclusive=False)
        as_float("k", self.k, 0.0, K_MAX)
        bound = min(0.6 * self.K1, self.K2)
        if self.K > bound * (1.0 + 1e-12):
            raise ValueError(f"K={self.K!r} is invalid: expected 0 < K <= min(0.6 K1, K2) = {bound:g}")
        as_float("stop_distance", self.stop_distance, 0.0, 1.0)
        as_float("max_gain", self.max_gain, 1.0 / self.T_con, 1e9, low_inclusive=False)

    @classmethod
    def paper_fig5(cls, **overrides: Any) -> PTCParams:
        """Figures 5 and 6: K1 = 2, K2 = 10, K = 1.2, Ke = 1, T_con = 20, beta = 24/25, k = 1/(2 pi)."""
        return cls.from_kwargs(**{"K1": 2.0, "K2": 10.0, "K": 1.2, "T_con": 20.0, **overrides})

    @classmethod
    def paper_fig7(cls, **overrides: Any) -> PTCParams:
        """Figures 7 and 9: K1 = 2.5, K2 = 40, K = 1.2, Ke = 1, T_con = 70, beta = 24/25, k = 1/(2 pi)."""
        return cls.from_kwargs(**{"K1": 2.5, "K2": 40.0, "K": 1.2, "T_con": 70.0, **overrides})

    @property
    def p_min(self) -> float:
        """p*_min of eq. (17): the minimum of eq. (10) over |e_psi| <= 7 pi / 6."""
        return model.improved_velocity_constraint_min(self.Ke)


class PTCController(Controller):
    """The paper's prescribed-time fractional-order law: u of eq. (16), omega of eqs. (18)-(19)."""

    name = "ptc"
    traceable = True

    def __init__(self, params: PTCParams | None = None, **kwargs: Any) -> None:
        self.params: PTCParams = params if params is not None else PTCParams.from_kwargs(**kwargs)

    def scaling(self, inputs: ControllerInput) -> FloatArray:
        """mu*(t, T_con) of eq. (17) with t_v from d_0 and e_psi0, capped at ``max_gain``."""
        p = self.params
        T_con = prescribed_time(inputs, p.T_con)
        t_v = model.switching_time(
            inputs.initial_distance, inputs.initial_orientation_error, T_con, p.beta, p.K, p.p_min
        )
        return model.fractional_scaling(inputs.time, T_con, t_v, p.max_gain)  # type: ignore[arg-type]

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        mu = self.scaling(inputs)
        d = inputs.distance
        orientation_err = model.orientation_error(inputs.azimuth, inputs.heading, d, p.k)
        p_star = model.improved_velocity_constraint(orientation_err, p.Ke)
        u = p.K1 * mu * p_star * d ** (2.0 * p.beta - 1.0)  # eq. (16)
        feedforward, _ = feedforward_angular_velocity(inputs, u, p.k)
        omega = feedforward + p.K2 * p_star * mu * signed_power(orientation_err, 2.0 * p.beta - 1.0)  # eq. (18)
        # Guard: eqs. (5) and (18) are singular at d = 0; stop within stop_distance as the paper suggests.
        moving = d >= p.stop_distance
        xp = array_namespace(d)
        return xp.where(moving, u, 0.0), xp.where(moving, omega, 0.0)


@dataclass(frozen=True)
class ConventionalPTCParams(ControllerParams):
    """Parameters of the conventional prescribed-time law (Figure 8's comparison)."""

    K1: float = 2.0
    K2: float = 10.0
    Ke: float = 1.0
    T_con: float = 20.0  # [s]
    k: float = K_MAX
    power: int = 1
    """n + m of eq. (13); the gain grows as (T_con / (T_con - t))^power / T_con."""
    stop_distance: float = 0.005  # [m]
    max_gain: float = 10.0  # [1/s]
    """Guard: cap of the scaling, which eqs. (12)-(13) make infinite at T_con."""

    def validate(self) -> None:
        for name in ("K1", "K2", "Ke", "T_con"):
            as_float(name, getattr(self, name), 0.0, 1e9, low_inclusive=False)
        as_float("k", self.k, 0.0, K_MAX)
        as_int("power", self.power, 1, 10)
        as_float("stop_distance", self.stop_distance, 0.0, 1.0)
        as_float("max_gain", self.max_gain, 1.0 / self.T_con, 1e9, low_inclusive=False)


class ConventionalPTCController(Controller):
    """Conventional PTC: the structure of eqs. (16)-(18) with beta = 1 and the scaling of eqs. (12)-(13)."""

    name = "conventional-ptc"
    traceable = True

    def __init__(self, params: ConventionalPTCParams | None = None, **kwargs: Any) -> None:
        self.params: ConventionalPTCParams = (
            params if params is not None else ConventionalPTCParams.from_kwargs(**kwargs)
        )

    def scaling(self, inputs: ControllerInput) -> FloatArray:
        """mu(t, T_con) / T_con, eqs. (12)-(13): equal to 1 / T_con at t = 0 and unbounded toward T_con."""
        p = self.params
        T_con = prescribed_time(inputs, p.T_con)
        mu = model.conventional_scaling_power(inputs.time, T_con, p.power, 0, max_gain=1e12)  # type: ignore[arg-type]
        return array_namespace(mu).minimum(mu / T_con, p.max_gain)  # type: ignore[no-any-return]

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        mu = self.scaling(inputs)
        orientation_err = model.orientation_error(inputs.azimuth, inputs.heading, inputs.distance, p.k)
        p_star = model.improved_velocity_constraint(orientation_err, p.Ke)
        u = p.K1 * mu * p_star * inputs.distance
        feedforward, _ = feedforward_angular_velocity(inputs, u, p.k)
        omega = feedforward + p.K2 * p_star * mu * orientation_err
        moving = inputs.distance >= p.stop_distance  # Guard: as in PTCController.
        xp = array_namespace(inputs.distance)
        return xp.where(moving, u, 0.0), xp.where(moving, omega, 0.0)


# ---------------------------------------------------------------------------------------------
# Ref. [9]: Fabregas et al. (2020)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FabregasParams(ControllerParams):
    """Parameters of ref. [9]'s law u = K0 d p, omega = K_omega sin(alpha - psi) (+ K_i integral)."""

    K0: float = 0.1  # [1/s]
    K_omega: float = 0.75  # [1/s]
    K_i: float = 0.0  # [1/s^2]
    """Integral gain on alpha - psi; 0 disables the integral term."""
    dt: float = 0.05  # [s]
    """Period at which the law is called (used by the integral term)."""
    speed_limit: float | None = None  # [m/s]
    """Optional saturation of u."""

    def validate(self) -> None:
        as_float("K0", self.K0, 0.0, 1e9, low_inclusive=False)
        as_float("K_omega", self.K_omega, 0.0, 1e9, low_inclusive=False)
        as_float("K_i", self.K_i, 0.0, 1e9)
        as_float("dt", self.dt, 0.0, 10.0, low_inclusive=False)
        if self.speed_limit is not None:
            as_float("speed_limit", self.speed_limit, 0.0, 1e9, low_inclusive=False)


class FabregasController(Controller):
    """Ref. [9]: u = K0 d p with p of eq. (9); omega = K_omega sin(alpha - psi) + K_i * integral."""

    name = "fabregas"

    def __init__(self, params: FabregasParams | None = None, **kwargs: Any) -> None:
        self.params: FabregasParams = params if params is not None else FabregasParams.from_kwargs(**kwargs)
        self._integral: FloatArray = np.zeros(0)

    def reset(self, mask: ArrayLike | None = None) -> None:
        if mask is None:
            self._integral = np.zeros(0)
        elif self._integral.size:
            self._integral[np.asarray(mask, dtype=bool)] = 0.0

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        u = p.K0 * inputs.distance * model.velocity_constraint(inputs.azimuth, inputs.heading)  # eq. (9)
        if p.speed_limit is not None:
            u = np.minimum(u, p.speed_limit)
        bearing = model.bearing_error(inputs.azimuth, inputs.heading)
        omega = p.K_omega * np.sin(bearing)
        if p.K_i > 0.0:
            if self._integral.shape != bearing.shape:
                self._integral = np.zeros_like(bearing)
            self._integral = self._integral + bearing * p.dt
            omega = omega + p.K_i * self._integral
        return u, omega


# ---------------------------------------------------------------------------------------------
# Ref. [23]: fixed-time comparison
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FixedTimeParams(ControllerParams):
    """Fixed-time pair k1 |x|^a sign(x) + k2 |x|^b sign(x) on d and on e_psi, 0 < a < 1 < b."""

    k1: float = 0.1
    """Gain of the low power on d."""
    k2: float = 0.1
    """Gain of the high power on d."""
    k3: float = 1.0
    """Gain of the low power on e_psi."""
    k4: float = 1.0
    """Gain of the high power on e_psi."""
    a: float = 0.5
    b: float = 1.5
    Ke: float = 1.0
    k: float = K_MAX
    stop_distance: float = 0.005  # [m]

    def validate(self) -> None:
        for name in ("k1", "k2", "k3", "k4", "Ke"):
            as_float(name, getattr(self, name), 0.0, 1e9, low_inclusive=False)
        as_float("a", self.a, 0.0, 1.0, low_inclusive=False, high_inclusive=False)
        as_float("b", self.b, 1.0, 10.0, low_inclusive=False)
        as_float("k", self.k, 0.0, K_MAX)
        as_float("stop_distance", self.stop_distance, 0.0, 1.0)


class FixedTimeController(Controller):
    """Fixed-time law after ref. [23], with the feedforward of eq. (18).

    u = p* (k1 d^a + k2 d^b), omega = d u Delta + alpha_dot + zeta_dot + p* (k3 |e|^a + k4 |e|^b) sign(e).
    For the scalar system x' = -(c1 |x|^a + c2 |x|^b) sign(x) every solution settles before
    1 / (c1 (1 - a)) + 1 / (c2 (b - 1)), whatever x(0) (Polyakov 2012). Here the gains are scaled by
    p* >= p*_min, so each channel's bound is :meth:`settling_time_bound`, ignoring their coupling.
    """

    name = "fixed-time"
    traceable = True

    def __init__(self, params: FixedTimeParams | None = None, **kwargs: Any) -> None:
        self.params: FixedTimeParams = params if params is not None else FixedTimeParams.from_kwargs(**kwargs)

    def settling_time_bound(self) -> dict[str, float]:
        """Fixed-time bounds [s] of the distance and orientation channels, with p* at its minimum."""
        p = self.params
        p_min = model.improved_velocity_constraint_min(p.Ke)
        return {
            "distance": (1.0 / (p.k1 * (1.0 - p.a)) + 1.0 / (p.k2 * (p.b - 1.0))) / p_min,
            "orientation": (1.0 / (p.k3 * (1.0 - p.a)) + 1.0 / (p.k4 * (p.b - 1.0))) / p_min,
        }

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        d = inputs.distance
        orientation_err = model.orientation_error(inputs.azimuth, inputs.heading, d, p.k)
        p_star = model.improved_velocity_constraint(orientation_err, p.Ke)
        u = p_star * (p.k1 * d**p.a + p.k2 * d**p.b)
        feedforward, _ = feedforward_angular_velocity(inputs, u, p.k)
        feedback = p.k3 * signed_power(orientation_err, p.a) + p.k4 * signed_power(orientation_err, p.b)
        omega = feedforward + p_star * feedback
        moving = d >= p.stop_distance  # Guard: eqs. (5) and (18) are singular at d = 0.
        xp = array_namespace(d)
        return xp.where(moving, u, 0.0), xp.where(moving, omega, 0.0)


__all__ = [
    "Controller",
    "ControllerInput",
    "ConventionalPTCController",
    "ConventionalPTCParams",
    "FabregasController",
    "FabregasParams",
    "FixedTimeController",
    "FixedTimeParams",
    "PTCController",
    "PTCParams",
]
