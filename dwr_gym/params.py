"""Typed, validated parameters of the DWRPointStabilization task."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from dwr_gym.model import INTEGRATORS
from dwr_gym.validation import as_bool, as_choice, as_float, as_int, as_interval, blame, reject_unknown

MIN_T_CON = 1e-3  # [s]
POTENTIALS = ("lyapunov", "distance")
MIN_DT = 1e-6  # [s]


check_range = as_float
"""Kept as the name earlier code imports: see :func:`dwr_gym.validation.as_float`."""
check_interval = as_interval


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
    shaping_potential: str = "lyapunov"
    """The potential Phi = -P of the progress term: P = L of eq. (21) ('lyapunov', v0 and v1), or P = d ('distance',
    v2: continuous at the goal, where eq. (21)'s orientation error, through the azimuth, is undefined and jumps)."""
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
    hold_to_T_con: bool = False
    """Hold every episode to T_con (v2): arriving does not end it; it terminates at T_con (the time is observed),
    where arrival, heading and the miss are paid, or on leaving the arena. False ends it on arrival (v0, v1)."""
    terminal_distance_weight: float = 0.0  # [1/m]
    """With ``hold_to_T_con``: the miss, -terminal_distance_weight * d, paid where the episode ends (the "late" term)."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "T_con", as_float("T_con", self.T_con, MIN_T_CON, 1e6))
        if self.T_con_range is not None:
            set_(self, "T_con_range", as_interval("T_con_range", self.T_con_range, MIN_T_CON, 1e6))
        set_(self, "dt", as_float("dt", self.dt, MIN_DT, 1e6))
        set_(self, "u_max", as_float("u_max", self.u_max, 0.0, 100.0, low_inclusive=False))
        set_(self, "omega_max", as_float("omega_max", self.omega_max, 0.0, 100.0, low_inclusive=False))
        set_(self, "goal_tolerance", as_float("goal_tolerance", self.goal_tolerance, 0.0, 10.0, low_inclusive=False))
        if self.heading_tolerance is not None:
            tolerance = as_float("heading_tolerance", self.heading_tolerance, 0.0, math.pi, low_inclusive=False)
            set_(self, "heading_tolerance", tolerance)
        set_(self, "horizon_factor", as_float("horizon_factor", self.horizon_factor, 1.0, 100.0, low_inclusive=False))
        set_(self, "arena_radius", as_float("arena_radius", self.arena_radius, 0.0, 1e6, low_inclusive=False))
        set_(self, "start_distance", as_interval("start_distance", self.start_distance, 0.0, 1e6))
        set_(self, "start_heading", as_interval("start_heading", self.start_heading, -math.pi, math.pi))
        set_(self, "integrator", as_choice("integrator", self.integrator, INTEGRATORS))
        set_(self, "substeps", as_int("substeps", self.substeps, 1, 1000))
        set_(self, "k", as_float("k", self.k, 0.0, 1.0 / (2.0 * math.pi)))
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
            set_(self, name, as_float(name, getattr(self, name), 0.0, 1e6))
        set_(self, "shaping_discount", as_float("shaping_discount", self.shaping_discount, 0.0, 1.0))
        set_(self, "zero_terminal_potential", as_bool("zero_terminal_potential", self.zero_terminal_potential))
        set_(self, "hold_to_T_con", as_bool("hold_to_T_con", self.hold_to_T_con))
        set_(self, "shaping_potential", as_choice("shaping_potential", self.shaping_potential, POTENTIALS))
        weight = as_float("terminal_distance_weight", self.terminal_distance_weight, 0.0, 1e6)
        set_(self, "terminal_distance_weight", weight)
        set_(self, "time_gain_cap", as_float("time_gain_cap", self.time_gain_cap, 1.0, 1e6))
        set_(self, "observation_noise", as_float("observation_noise", self.observation_noise, 0.0, 10.0))
        set_(self, "actuation_noise", as_float("actuation_noise", self.actuation_noise, 0.0, 10.0))
        self._check_consistency()

    def _check_consistency(self) -> None:
        """Checks between parameters; each error names the one of the pair that the user set."""
        if self.dt > self.T_con_min:
            self._conflict(
                blame(self, "dt", "T_con_range" if self.T_con_range is not None else "T_con"),
                f"dt <= T_con (dt={self.dt:g} s, smallest T_con={self.T_con_min:g} s)",
            )
        step = self.u_max * self.dt
        if step >= self.arena_radius:
            self._conflict(
                blame(self, "arena_radius", "dt", "u_max"),
                f"one step's travel u_max * dt = {step:g} m below arena_radius={self.arena_radius:g} m",
            )
        if self.goal_tolerance >= self.arena_radius:
            self._conflict(
                blame(self, "goal_tolerance", "arena_radius"),
                f"goal_tolerance={self.goal_tolerance:g} m below arena_radius={self.arena_radius:g} m",
            )
        if self.start_distance[1] > self.arena_radius:
            self._conflict(
                blame(self, "start_distance", "arena_radius"),
                f"start_distance={self.start_distance} within arena_radius={self.arena_radius:g} m",
            )

        if self.terminal_distance_weight != 0.0 and not self.hold_to_T_con:
            self._conflict("terminal_distance_weight", "0 unless hold_to_T_con=True (the miss is paid at T_con)")

    def _conflict(self, name: str, expected: str) -> None:
        raise ValueError(f"{name}={getattr(self, name)!r} is invalid: expected {expected}")

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
        """Time at which the longest episode ends at the latest [s]: T_con with ``hold_to_T_con``, else its truncation."""
        return self.T_con_max if self.hold_to_T_con else self.horizon_factor * self.T_con_max

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
        """Control periods until the end of an episode of prescribed time ``T_con`` (its truncation, or T_con itself
        with ``hold_to_T_con``)."""
        if self.hold_to_T_con:
            return self.prescribed_steps_of(T_con)
        return math.ceil(self.horizon_factor * T_con / self.dt - 1e-9)

    def as_dict(self) -> dict[str, Any]:
        """The parameters as a plain dict of constructor keywords."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
