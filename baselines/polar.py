"""Laws in Astolfi's polar coordinates, which also steer the final heading to the goal's."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from baselines.base import Controller, ControllerInput, ControllerParams, array_namespace, prescribed_time
from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.validation import as_bool, as_float


def astolfi_commands(
    inputs: ControllerInput,
    k_rho: float,
    k_alpha: float,
    k_beta: float,
    reverse: bool,
    direction: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Astolfi's law in polar coordinates (rho, alpha, beta): (k_rho rho, k_alpha alpha + k_beta beta), signed
    for reversing when ``reverse`` and the goal is behind (|alpha| > pi/2), or as ``direction`` (+1 forward,
    -1 reverse, per robot) says when it is given."""
    rho = inputs.distance
    xp = array_namespace(rho)
    alpha = model.bearing_error(inputs.azimuth, inputs.heading)
    if direction is None:
        direction = xp.where(xp.abs(alpha) > 0.5 * np.pi, -1.0, 1.0) if reverse else xp.ones_like(rho)
    alpha = xp.where(direction < 0.0, model.wrap_angle(alpha + np.pi), alpha)
    beta = model.wrap_angle(-inputs.heading - alpha)
    return direction * k_rho * rho, k_alpha * alpha + k_beta * beta


# ---------------------------------------------------------------------------------------------
# Astolfi's polar-coordinate pose stabilizer
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AstolfiParams(ControllerParams):
    """v = k_rho rho, omega = k_alpha alpha + k_beta beta with k_rho > 0, k_beta < 0, k_alpha > k_rho."""

    k_rho: float = 0.3  # [1/s]
    k_alpha: float = 0.8  # [1/s]
    k_beta: float = -0.15  # [1/s]
    reverse: bool = True
    """Drive backwards when the goal is behind the robot (|alpha| > pi/2)."""

    def validate(self) -> None:
        as_float("k_rho", self.k_rho, 0.0, 1e9, low_inclusive=False)
        as_float("k_beta", self.k_beta, -1e9, 0.0, high_inclusive=False)
        as_float("k_alpha", self.k_alpha, self.k_rho, 1e9, low_inclusive=False)
        as_bool("reverse", self.reverse)


class AstolfiController(Controller):
    """Astolfi (1999) / Siegwart's polar law, the one that also steers the final heading to the goal's."""

    name = "astolfi"
    traceable = True

    def __init__(self, params: AstolfiParams | None = None, **kwargs: Any) -> None:
        self.params: AstolfiParams = params if params is not None else AstolfiParams.from_kwargs(**kwargs)

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        return astolfi_commands(inputs, p.k_rho, p.k_alpha, p.k_beta, p.reverse)


# ---------------------------------------------------------------------------------------------
# Astolfi's law on the paper's time scale: the full pose by a prescribed time (not a law of the paper)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PrescribedTimeAstolfiParams(ControllerParams):
    """Dimensionless gains of Astolfi's law in the scaled time s = ln(T / (T - t)), and the arrival time.

    In s, the closed loop converges exponentially: rho at rate k_rho, (alpha, beta) at the roots of
    r^2 - (k_alpha - k_rho) r - k_beta k_rho = 0 (here 1.6 and 1.6, both above k_rho, so the heading
    settles before the position does). k_rho > 1/2 keeps u bounded near T; rates above 1 keep omega bounded.
    """

    k_rho: float = 1.5
    k_alpha: float = 4.7
    k_beta: float = -1.7
    reverse: bool = True
    """Drive backwards when the goal is behind the robot (|alpha| > pi/2)."""
    T_con: float = 20.0  # [s]
    """Prescribed time when the input does not carry it (an expert reads it from the observation); > 0."""
    arrival_fraction: float = 0.98
    """T of the scaling is arrival_fraction * T_con: the margin left for the last control periods; in (0, 1]."""
    max_gain: float = 50.0
    """Guard: cap of mu_1(t, T) of eq. (12), which is infinite at T."""

    def validate(self) -> None:
        as_float("k_rho", self.k_rho, 0.0, 1e9, low_inclusive=False)
        as_float("k_beta", self.k_beta, -1e9, 0.0, high_inclusive=False)
        as_float("k_alpha", self.k_alpha, self.k_rho, 1e9, low_inclusive=False)
        as_bool("reverse", self.reverse)
        as_float("T_con", self.T_con, 0.0, 1e9, low_inclusive=False)
        as_float("arrival_fraction", self.arrival_fraction, 0.0, 1.0, low_inclusive=False)
        as_float("max_gain", self.max_gain, 1.0, 1e9)


class PrescribedTimeAstolfiController(Controller):
    """Astolfi's law times mu_1(t, T) / T of eq. (12): the full pose, heading included, by T = arrival_fraction T_con.

    Multiplying an autonomous, exponentially stable closed loop by 1 / (T - t) is the time-scale change
    s = ln(T / (T - t)): what Astolfi's law does over s in [0, inf) happens here over t in [0, T). The paper
    applies the same scaling, eq. (12), to its own law; this one also steers the heading (Theorem 8 asks
    for it, PTC does not reach it). It is our addition, used as the base of residual agents.
    """

    name = "pt-astolfi"
    traceable = True

    def __init__(self, params: PrescribedTimeAstolfiParams | None = None, **kwargs: Any) -> None:
        self.params: PrescribedTimeAstolfiParams = (
            params if params is not None else PrescribedTimeAstolfiParams.from_kwargs(**kwargs)
        )

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        p = self.params
        u, omega = astolfi_commands(inputs, p.k_rho, p.k_alpha, p.k_beta, p.reverse)
        T_con = prescribed_time(inputs, p.T_con)
        T = p.arrival_fraction * (np.asarray(T_con, dtype=np.float64) if array_namespace(u) is np else T_con)
        rate = model.conventional_scaling(inputs.time, T, max_gain=p.max_gain) / T  # eq. (12) over T: 1 / (T - t)
        return u * rate, omega * rate
