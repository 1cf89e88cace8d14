"""Disturbances drawn per episode: the training distribution of robust agents (domain randomisation).

``gym.make(..., disturbance_distribution=DisturbanceDistribution())`` gives every episode (every sub-env's
episode in the vector env) its own robot: each of the seven kinds of :mod:`dwr_gym.disturbances` is present with
its probability, at a magnitude drawn uniformly up to its bound. The defaults reach beyond the evaluation sets of
``dwr-gym evaluate --scenarios disturbed fault delay noise``, so that an agent trained on them meets nothing
larger there. Off by default; without it the envs are what they were, bit for bit.

The draws come from each robot's own generator, seeded by the distribution's ``seed`` and the env's reset seed:
sub-env i of ``make_vec(..., num_envs=N).reset(seed=s)`` draws what ``make(...).reset(seed=s + i)`` draws.
``env.unwrapped.perturbation.episode()`` tells what was drawn for the current episodes. :class:`RandomPerturbation` applies them, at the same two
places and in the same order as :class:`~dwr_gym.disturbances.Perturbation` (delay, wheels, additive velocities;
a dropped measurement holds the pose features), for N robots with N different robots' parameters at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym import robots
from dwr_gym.disturbances import POSE_FEATURES
from dwr_gym.model import FloatArray
from dwr_gym.params import EnvParams, check_range
from dwr_gym.robots import ROBOTS, DifferentialDrive

#: TurtleBot3 Burger's wheel geometry without a speed limit: the wheels of slip and faults when no robot is given.
DEFAULT_GEOMETRY = DifferentialDrive(
    ROBOTS["turtlebot3_burger"].wheel_radius, ROBOTS["turtlebot3_burger"].track_width, name="burger-geometry"
)
KINDS: tuple[str, ...] = ("bias", "sinusoid", "random_walk", "slip", "fault", "delay", "dropout")
#: Per-step random numbers are drawn this many at a time per robot (a generator call per robot and step is slow).
CHUNK = 64


def _pair(name: str, value: Any, high: float) -> tuple[float, float]:
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ValueError(f"{name}={value!r} is invalid: expected two numbers (linear, angular) in [0, {high}]")
    return (check_range(f"{name}[0]", value[0], 0.0, high), check_range(f"{name}[1]", value[1], 0.0, high))


def _interval(name: str, value: Any, low: float, high: float) -> tuple[float, float]:
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ValueError(f"{name}={value!r} is invalid: expected (low, high) with {low} <= low <= high <= {high}")
    first, second = check_range(f"{name}[0]", value[0], low, high), check_range(f"{name}[1]", value[1], low, high)
    if first > second:
        raise ValueError(f"{name}={value!r} is invalid: expected (low, high) with low <= high")
    return first, second


@dataclass(frozen=True)
class DisturbanceDistribution:
    """Per-episode draws of all seven disturbances; each kind is present with ``probability``.

    Magnitudes are uniform in [0, bound] (signs uniform for the bias), times and periods in their ranges.
    """

    probability: float = 0.5
    """Chance that each kind is present in an episode, independently of the others."""
    bias: tuple[float, float] = (0.05, 0.3)  # [m/s, rad/s]
    """Bound of |VelocityBias.linear| and |VelocityBias.angular|."""
    sinusoid: tuple[float, float] = (0.1, 0.4)  # [m/s, rad/s]
    """Bound of the VelocitySinusoid amplitudes."""
    sinusoid_period: tuple[float, float] = (2.0, 8.0)  # [s]
    """Range of the sinusoid's period (its phase is uniform)."""
    random_walk: tuple[float, float] = (0.02, 0.1)  # [m/s / sqrt(s), rad/s / sqrt(s)]
    """Bound of the VelocityRandomWalk intensities."""
    slip: float = 0.4
    """Bound of each wheel's slip, 1 - WheelSlip efficiency (both wheels drawn independently)."""
    fault: float = 0.8
    """Bound of the ActuatorFault's lost fraction (1 - fraction) of a wheel drawn at random."""
    fault_start: tuple[float, float] = (0.0, 0.5)
    """Range of the fault's start, as a fraction of the episode's T_con."""
    delay: int = 6  # [control periods]
    """Bound of the InputDelay (an integer drawn uniformly in [0, delay])."""
    dropout: float = 0.4
    """Bound of the MeasurementDropout probability."""
    seed: int = 0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "probability", check_range("probability", self.probability, 0.0, 1.0))
        set_(self, "bias", _pair("bias", self.bias, 10.0))
        set_(self, "sinusoid", _pair("sinusoid", self.sinusoid, 10.0))
        low, high = _interval("sinusoid_period", self.sinusoid_period, 0.0, 1e6)
        if low <= 0.0:
            raise ValueError(f"sinusoid_period={self.sinusoid_period!r} is invalid: expected periods > 0 s")
        set_(self, "sinusoid_period", (low, high))
        set_(self, "random_walk", _pair("random_walk", self.random_walk, 10.0))
        set_(self, "slip", check_range("slip", self.slip, 0.0, 1.0, high_inclusive=False))
        set_(self, "fault", check_range("fault", self.fault, 0.0, 1.0))
        set_(self, "fault_start", _interval("fault_start", self.fault_start, 0.0, 1.0))
        if isinstance(self.delay, bool) or not isinstance(self.delay, (int, np.integer)) or not 0 <= self.delay <= 100:
            raise ValueError(f"delay={self.delay!r} is invalid: expected an integer in [0, 100] (control periods)")
        set_(self, "delay", int(self.delay))
        set_(self, "dropout", check_range("dropout", self.dropout, 0.0, 1.0, high_inclusive=False))
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed={self.seed!r} is invalid: expected an integer >= 0")

    def perturbation(self, drive: DifferentialDrive | None, params: EnvParams, n: int) -> RandomPerturbation:
        """The robots of N episodes drawn from this distribution (what the envs step)."""
        return RandomPerturbation(self, drive, params, n)


class RandomPerturbation:
    """The robots of N episodes, each with the disturbances drawn for it at its reset; see the module's docstring.

    The interface is :class:`~dwr_gym.disturbances.Perturbation`'s: ``seed``, ``reset``, ``command``, ``measure``
    and ``info``.
    """

    def __init__(
        self, distribution: DisturbanceDistribution, drive: DifferentialDrive | None, params: EnvParams, n: int
    ):
        if distribution.delay >= params.max_episode_steps:
            raise ValueError(f"DisturbanceDistribution.delay={distribution.delay} is invalid: expected an integer in "
                             f"[0, {params.max_episode_steps - 1}], shorter than the episode")  # fmt: skip
        self.distribution, self.params, self.n = distribution, params, n
        self.drive = drive if drive is not None else DEFAULT_GEOMETRY
        self._rngs = [np.random.default_rng(0)] * n
        self._seeded = False
        z = np.zeros
        self.bias, self.amplitude, self.intensity, self.walk = z((n, 2)), z((n, 2)), z((n, 2)), z((n, 2))
        self.period, self.phase = np.ones(n), z(n)
        self.efficiency = np.ones((n, 2))  # (left, right) ground speed / wheel speed
        self.fault_wheel, self.fault_fraction, self.fault_start = z(n, dtype=np.int64), np.ones(n), z(n)
        self.delay, self.dropout = z(n, dtype=np.int64), z(n)
        self._buffer = z((n, distribution.delay, 2))  # the last `delay` commands, oldest first
        self._held = z((n, POSE_FEATURES), dtype=np.float32)
        self._normals, self._uniforms = z((n, CHUNK, 2)), z((n, CHUNK))
        self._next_normal, self._next_uniform = np.full(n, CHUNK), np.full(n, CHUNK)  # CHUNK: drawn anew before use
        self.last: dict[str, NDArray[Any]] = {
            "commanded_linear_velocity": z(n), "commanded_angular_velocity": z(n),
            "wheel_saturated": z(n, dtype=bool), "fault_active": z(n, dtype=bool), "measurement_held": z(n, dtype=bool),
        }  # fmt: skip

    def __repr__(self) -> str:
        return f"RandomPerturbation({self.distribution!r}, drive={self.drive!r})"

    def seed(self, index: NDArray[np.intp] | list[int], keys: list[tuple[int, ...]]) -> None:
        """Seed the generators of the robots ``index`` with ``keys`` (one tuple each)."""
        seed = self.distribution.seed
        for robot, key in zip(index, keys, strict=True):
            self._rngs[robot] = np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, *key])))
            self._next_normal[robot] = self._next_uniform[robot] = CHUNK
        self._seeded = True

    def reset(self, index: NDArray[np.intp] | slice, observation: NDArray[np.float32]) -> None:
        """Draw new robots for the episodes ``index`` starting with ``observation`` (its T_con feature sets the fault's time)."""
        if not self._seeded:
            entropy = np.random.SeedSequence().entropy % 2**63  # type: ignore[operator]
            self.seed(list(range(self.n)), [(entropy, i) for i in range(self.n)])
        robots_ = np.arange(self.n)[index]
        batch = np.reshape(observation, (-1, observation.shape[-1]))
        for row, robot in enumerate(robots_):
            self._draw(int(robot), float(batch[row, 7]))
        self._buffer[index] = 0.0
        self.walk[index] = 0.0
        self._held[index] = batch[:, :POSE_FEATURES]
        for value in self.last.values():
            value[index] = 0

    def _draw(self, i: int, T_con: float) -> None:
        """Robot i's disturbances for its next episode: the same number of draws whatever is present."""
        dist, rng = self.distribution, self._rngs[i]
        present = rng.random(len(KINDS)) < dist.probability
        u = rng.random(16)
        on = dict(zip(KINDS, present.tolist(), strict=True))
        self.bias[i] = np.array(dist.bias) * (2.0 * u[0:2] - 1.0) * on["bias"]
        self.amplitude[i] = np.array(dist.sinusoid) * u[2:4] * on["sinusoid"]
        low, high = dist.sinusoid_period
        self.period[i], self.phase[i] = low + (high - low) * u[4], 2.0 * math.pi * u[5]
        self.intensity[i] = np.array(dist.random_walk) * u[6:8] * on["random_walk"]
        self.efficiency[i] = 1.0 - dist.slip * u[8:10] * on["slip"]
        self.fault_wheel[i] = int(u[10] < 0.5)  # 0 left, 1 right
        self.fault_fraction[i] = 1.0 - dist.fault * u[11] * on["fault"]
        low, high = dist.fault_start
        self.fault_start[i] = (low + (high - low) * u[12]) * T_con
        self.delay[i] = min(int(u[13] * (dist.delay + 1)), dist.delay) * on["delay"]
        self.dropout[i] = dist.dropout * u[14] * on["dropout"]

    def command(self, u: Any, omega: Any, step_count: Any) -> tuple[Any, Any]:
        """The velocities (u [m/s], omega [rad/s]) the robots really have for the commanded ones."""
        scalar = not isinstance(u, np.ndarray)
        dtype = np.float64 if scalar else u.dtype
        u_cmd = np.reshape(np.asarray(u, np.float64), (-1,))
        omega_cmd = np.reshape(np.asarray(omega, np.float64), (-1,))
        time = np.reshape(np.asarray(step_count), (-1,)) * self.params.dt  # start of this control period [s]
        u_out, omega_out = u_cmd, omega_cmd
        if self._buffer.shape[1]:
            history = np.concatenate([self._buffer, np.stack([u_cmd, omega_cmd], axis=1)[:, None]], axis=1)
            applied = history[np.arange(self.n), self._buffer.shape[1] - self.delay]
            u_out, omega_out, self._buffer = applied[:, 0], applied[:, 1], history[:, 1:]
        left, right = robots.wheel_speeds(u_out, omega_out, self.drive)
        saturated = np.zeros(self.n, dtype=bool)
        if math.isfinite(self.drive.max_wheel_speed):
            limited_left, limited_right = robots.saturate_wheels(left, right, self.drive)
            saturated = (limited_left != left) | (limited_right != right)
            left, right = limited_left, limited_right
        fault_active = (time >= self.fault_start - 1e-9) & (self.fault_fraction < 1.0)
        factor = np.where(fault_active, self.fault_fraction, 1.0)
        left = left * self.efficiency[:, 0] * np.where(self.fault_wheel == 0, factor, 1.0)
        right = right * self.efficiency[:, 1] * np.where(self.fault_wheel == 1, factor, 1.0)
        u_out, omega_out = robots.body_velocities(left, right, self.drive)
        wave = np.sin(2.0 * math.pi * time / self.period + self.phase)
        self.walk += self._take_normals() * (math.sqrt(self.params.dt) * self.intensity)
        u_out = u_out + self.bias[:, 0] + self.amplitude[:, 0] * wave + self.walk[:, 0]
        omega_out = omega_out + self.bias[:, 1] + self.amplitude[:, 1] * wave + self.walk[:, 1]
        self.last.update(commanded_linear_velocity=u_cmd, commanded_angular_velocity=omega_cmd,
                         wheel_saturated=saturated, fault_active=fault_active)  # fmt: skip
        if scalar:
            return float(u_out[0]), float(omega_out[0])
        return u_out.astype(dtype, copy=False), omega_out.astype(dtype, copy=False)

    def _take_normals(self) -> FloatArray:
        """One pair of standard-normal numbers per robot, from its own generator."""
        for i in np.flatnonzero(self._next_normal >= CHUNK):
            self._normals[i], self._next_normal[i] = self._rngs[i].standard_normal((CHUNK, 2)), 0
        taken = self._normals[np.arange(self.n), self._next_normal]
        self._next_normal += 1
        return taken

    def _take_uniforms(self) -> FloatArray:
        """One uniform number in [0, 1) per robot, from its own generator."""
        for i in np.flatnonzero(self._next_uniform >= CHUNK):
            self._uniforms[i], self._next_uniform[i] = self._rngs[i].random(CHUNK), 0
        taken = self._uniforms[np.arange(self.n), self._next_uniform]
        self._next_uniform += 1
        return taken

    def measure(self, observation: NDArray[np.float32]) -> NDArray[np.float32]:
        """The observation with the pose features of robots whose measurement dropped out held at their last."""
        held = self._take_uniforms() < self.dropout
        batch = np.reshape(observation, (self.n, -1))  # a view: the single env's (10,) is changed too
        batch[held, :POSE_FEATURES] = self._held[held]
        self._held[:] = batch[:, :POSE_FEATURES]
        self.last["measurement_held"] = held
        return observation

    def episode(self) -> dict[str, NDArray[Any]]:
        """What was drawn for each robot's current episode (arrays (N,) or (N, 2))."""
        return {"bias": self.bias.copy(), "sinusoid_amplitude": self.amplitude.copy(), "sinusoid_period": self.period.copy(),
                "random_walk": self.intensity.copy(), "wheel_efficiency": self.efficiency.copy(),
                "fault_wheel": np.where(self.fault_wheel == 1, "right", "left"), "fault_fraction": self.fault_fraction.copy(),
                "fault_start": self.fault_start.copy(), "delay": self.delay.copy(), "dropout": self.dropout.copy()}  # fmt: skip

    def info(self, scalar: bool = False) -> dict[str, Any]:
        """What the disturbances did in the last step: arrays (N,), or Python scalars for one robot."""
        if scalar:
            return {key: value[0].item() for key, value in self.last.items()}
        return {key: value.copy() for key, value in self.last.items()}


__all__ = ["DEFAULT_GEOMETRY", "KINDS", "DisturbanceDistribution", "RandomPerturbation"]
