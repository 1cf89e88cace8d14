"""Typed, validated parameters of the DWRPointStabilization task."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from dwr_gym.model import INTEGRATORS


def check_range(
    name: str,
    value: Any,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
) -> float:
    """Return ``value`` as a float, or raise a ValueError naming the parameter, the value and the range."""
    lo, hi = "[" if low_inclusive else "(", "]" if high_inclusive else ")"
    allowed = f"a finite number in {lo}{low}, {high}{hi}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name}={value!r} is invalid: expected {allowed}")
    value = float(value)
    below = value < low or (value == low and not low_inclusive)
    above = value > high or (value == high and not high_inclusive)
    if not math.isfinite(value) or below or above:
        raise ValueError(f"{name}={value!r} is invalid: expected {allowed}")
    return value


def check_interval(name: str, value: Any, low: float, high: float) -> tuple[float, float]:
    """Validate a (min, max) pair inside [low, high] with min <= max."""
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ValueError(f"{name}={value!r} is invalid: expected a pair (min, max) within [{low}, {high}]")
    first = check_range(f"{name}[0]", value[0], low, high)
    second = check_range(f"{name}[1]", value[1], low, high)
    if first > second:
        raise ValueError(f"{name}={value!r} is invalid: min must not exceed max")
    return first, second


def reject_unknown(cls: type, kwargs: dict[str, Any]) -> None:
    """Raise a ValueError for keywords that are not fields of the dataclass ``cls``."""
    allowed = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(kwargs) - allowed)
    if unknown:
        raise ValueError(
            f"unknown parameter(s) {', '.join(map(repr, unknown))} for {cls.__name__}; "
            f"allowed: {', '.join(sorted(allowed))}"
        )


@dataclass(frozen=True)
class EnvParams:
    """Parameters of DWRPointStabilization-v0. Every field is a constructor keyword of the env."""

    T_con: float = 20.0  # [s]
    """Prescribed time within which the robot should reach the goal (T_con of eq. (17))."""
    T_con_range: tuple[float, float] | None = None  # [s]
    """If set, each episode draws its T_con uniformly from this range (``T_con`` is then unused)."""
    dt: float = 0.05  # [s]
    """Control period: the commands are held constant for dt seconds."""
    u_max: float = 0.5  # [m/s]
    """Linear velocity at action[0] = 1; actions are clipped to [-1, 1]."""
    omega_max: float = 2.0  # [rad/s]
    """Angular velocity at action[1] = 1."""
    goal_tolerance: float = 0.01  # [m]
    """The robot has arrived when d <= goal_tolerance (the paper suggests about 1 cm)."""
    heading_tolerance: float | None = None  # [rad]
    """If set, arrival also needs |psi - psi_d| <= heading_tolerance; None is the paper's position-only task."""
    horizon_factor: float = 1.5
    """Episodes are truncated at horizon_factor * T_con, so late arrivals are observable."""
    arena_radius: float = 5.0  # [m]
    """The episode terminates (failure) when the robot is farther than this from the goal."""
    start_distance: tuple[float, float] = (0.3, 1.5)  # [m]
    """Range of the random initial distance to the goal."""
    start_heading: tuple[float, float] = (-math.pi, math.pi)  # [rad]
    """Range of the random initial heading relative to the goal heading."""
    integrator: str = "exact"
    """'exact' (zero-order-hold arc), 'euler' or 'rk4'."""
    substeps: int = 1
    """Integration sub-steps per control period."""
    k: float = 1.0 / (2.0 * math.pi)
    """Gain of the arcsine term of the orientation error, eq. (6); 0 <= k <= 1/(2 pi)."""
    progress_weight: float = 1.0
    """Weight of the potential-based progress term on the Lyapunov function (21)."""
    shaping_discount: float = 0.99
    """gamma of the shaping term gamma*Phi(s') - Phi(s); set it to your algorithm's discount."""
    zero_terminal_potential: bool = False
    """Give terminal states the potential 0 in the progress term, which makes its sum over an episode that
    arrives exactly L(s_0) whatever the path (exact potential-based shaping); False is v0's Phi(s')."""
    time_weight: float = 0.5  # [1/(m s)]
    """Weight of the prescribed-time term dt * mu_1(t) * d, with mu_1 of eq. (12)."""
    time_gain_cap: float = 20.0
    """Cap of mu_1(t) in the prescribed-time term (eq. (12) is infinite at T_con)."""
    effort_weight: float = 0.01  # [1/s]
    """Weight of the control-effort term dt * (a_u^2 + a_omega^2) on normalised actions."""
    energy_weight: float = 0.0
    """Weight of the energy term dt * (u^2 + omega^2) on the commands in SI units: the env's ``energy``."""
    arrival_bonus: float = 10.0
    """Reward for arriving at or before T_con."""
    heading_weight: float = 5.0
    """Weight of the heading term heading_weight * (cos(psi - psi_d) - 1) paid on arrival (Theorem 8's final yaw)."""
    late_penalty: float = 1.0  # [1/s]
    """Penalty per second after T_con without arrival."""
    arena_penalty: float = 10.0
    """Penalty for leaving the arena."""
    observation_noise: float = 0.0  # [m, rad]
    """Standard deviation of Gaussian noise on the measured pose (x, y, psi); 0 disables it."""
    actuation_noise: float = 0.0
    """Standard deviation of Gaussian noise added to the normalised action; 0 disables it."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "T_con", check_range("T_con", self.T_con, 0.0, 1e6, low_inclusive=False))
        if self.T_con_range is not None:
            set_(self, "T_con_range", check_interval("T_con_range", self.T_con_range, 1e-6, 1e6))
        set_(self, "dt", check_range("dt", self.dt, 0.0, self.T_con_min, low_inclusive=False))
        set_(self, "u_max", check_range("u_max", self.u_max, 0.0, 100.0, low_inclusive=False))
        set_(self, "omega_max", check_range("omega_max", self.omega_max, 0.0, 100.0, low_inclusive=False))
        set_(self, "goal_tolerance", check_range("goal_tolerance", self.goal_tolerance, 0.0, 10.0, low_inclusive=False))
        if self.heading_tolerance is not None:
            set_(
                self,
                "heading_tolerance",
                check_range("heading_tolerance", self.heading_tolerance, 0.0, math.pi, low_inclusive=False),
            )
        set_(
            self, "horizon_factor", check_range("horizon_factor", self.horizon_factor, 1.0, 100.0, low_inclusive=False)
        )
        set_(
            self,
            "arena_radius",
            check_range("arena_radius", self.arena_radius, self.u_max * self.dt, 1e6, low_inclusive=False),
        )
        start_distance = check_interval("start_distance", self.start_distance, 0.0, self.arena_radius)
        set_(self, "start_distance", start_distance)
        set_(self, "start_heading", check_interval("start_heading", self.start_heading, -math.pi, math.pi))
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator={self.integrator!r} is invalid: expected one of {', '.join(INTEGRATORS)}")
        if isinstance(self.substeps, bool) or not isinstance(self.substeps, int) or not 1 <= self.substeps <= 1000:
            raise ValueError(f"substeps={self.substeps!r} is invalid: expected an integer in [1, 1000]")
        set_(self, "k", check_range("k", self.k, 0.0, 1.0 / (2.0 * math.pi)))
        for name in (
            "progress_weight",
            "time_weight",
            "effort_weight",
            "energy_weight",
            "arrival_bonus",
            "heading_weight",
            "late_penalty",
            "arena_penalty",
        ):
            set_(self, name, check_range(name, getattr(self, name), 0.0, 1e6))
        set_(self, "shaping_discount", check_range("shaping_discount", self.shaping_discount, 0.0, 1.0))
        if not isinstance(self.zero_terminal_potential, (bool, np.bool_)):
            raise ValueError(
                f"zero_terminal_potential={self.zero_terminal_potential!r} is invalid: expected True or False"
            )
        set_(self, "time_gain_cap", check_range("time_gain_cap", self.time_gain_cap, 1.0, 1e6))
        set_(self, "observation_noise", check_range("observation_noise", self.observation_noise, 0.0, 10.0))
        set_(self, "actuation_noise", check_range("actuation_noise", self.actuation_noise, 0.0, 10.0))

    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> EnvParams:
        """Build parameters from keywords, rejecting unknown ones with a ValueError."""
        reject_unknown(cls, kwargs)
        return cls(**kwargs)

    @property
    def T_con_min(self) -> float:
        """The smallest prescribed time an episode can have [s]."""
        return self.T_con if self.T_con_range is None else self.T_con_range[0]

    @property
    def T_con_max(self) -> float:
        """The largest prescribed time an episode can have [s]."""
        return self.T_con if self.T_con_range is None else self.T_con_range[1]

    @property
    def horizon(self) -> float:
        """Time at which the longest episode is truncated [s]."""
        return self.horizon_factor * self.T_con_max

    @cached_property
    def prescribed_steps(self) -> int:
        """Number of control periods within T_con: arriving at or before this step is in time."""
        return self.prescribed_steps_of(self.T_con)

    @cached_property
    def max_episode_steps(self) -> int:
        """Number of control periods until truncation (of the longest episode, with ``T_con_range``)."""
        return self.max_episode_steps_of(self.T_con_max)

    def prescribed_steps_of(self, T_con: float) -> int:
        """Control periods within ``T_con``."""
        return math.floor(T_con / self.dt + 1e-9)

    def max_episode_steps_of(self, T_con: float) -> int:
        """Control periods until the truncation of an episode of prescribed time ``T_con``."""
        return math.ceil(self.horizon_factor * T_con / self.dt - 1e-9)

    def as_dict(self) -> dict[str, Any]:
        """The parameters as a plain dict of constructor keywords."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
