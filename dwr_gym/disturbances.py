"""Disturbances, actuator faults and delays: the robot that is not the ideal unicycle of eq. (1).

Each disturbance is a small frozen dataclass with its units in its fields' comments. They are passed
to either env as ``disturbances=[...]`` (and the wheel model as ``robot=...``), are off by default,
and with none of them the envs are bit-for-bit the nominal ones. A :class:`Perturbation` holds their
per-robot state; :func:`dwr_gym.core.transition` calls it at exactly two places, the same for the
single env, the vector env and the evaluation rollouts:

- :meth:`Perturbation.command` turns the commanded (u, omega) into the velocities the robot really
  has: input delay, then the wheels (saturation, slip, fault), then the additive disturbances;
- :meth:`Perturbation.measure` turns the observation of the true (or noisy) pose into the measured
  one: a dropped measurement holds the last pose features (0-5); the clock (6-9) runs on.

Random disturbances draw from their own generator per robot, seeded by the disturbance's ``seed``
and the env's reset seed, so sub-env i of a vector env reset with seed s draws what a single env
reset with seed s + i draws.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym import robots
from dwr_gym.model import FloatArray
from dwr_gym.params import EnvParams, check_range
from dwr_gym.robots import DifferentialDrive
from dwr_gym.validation import reject_unknown

#: The env keywords that are not fields of EnvParams: the robot's wheels and the disturbances.
ROBOT_KEYWORDS = ("robot", "wheel_saturation", "disturbances", "disturbance_distribution")

#: Number of pose features at the start of the observation (distance ... orientation error).
POSE_FEATURES = 6
WHEELS: tuple[str, ...] = ("left", "right")


def _check_seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed={seed!r} is invalid: expected an integer >= 0")
    return int(seed)


@dataclass(frozen=True)
class VelocityBias:
    """A constant velocity added to the commanded one (e.g. a slope, a mis-calibrated odometry)."""

    linear: float = 0.0  # [m/s]
    angular: float = 0.0  # [rad/s]

    def __post_init__(self) -> None:
        object.__setattr__(self, "linear", check_range("VelocityBias.linear", self.linear, -100.0, 100.0))
        object.__setattr__(self, "angular", check_range("VelocityBias.angular", self.angular, -100.0, 100.0))


@dataclass(frozen=True)
class VelocitySinusoid:
    """A sinusoidal velocity a sin(2 pi t / period + phase) added to the command (e.g. a periodic push)."""

    linear_amplitude: float = 0.0  # [m/s]
    angular_amplitude: float = 0.0  # [rad/s]
    period: float = 5.0  # [s]
    phase: float = 0.0  # [rad]

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "linear_amplitude", check_range("VelocitySinusoid.linear_amplitude", self.linear_amplitude, 0, 100))
        set_(self, "angular_amplitude",
             check_range("VelocitySinusoid.angular_amplitude", self.angular_amplitude, 0, 100))  # fmt: skip
        set_(self, "period", check_range("VelocitySinusoid.period", self.period, 0.0, 1e6, low_inclusive=False))
        set_(self, "phase", check_range("VelocitySinusoid.phase", self.phase, -1e6, 1e6))


@dataclass(frozen=True)
class VelocityRandomWalk:
    """A velocity disturbance that performs a random walk from zero at each episode's start.

    Per control period dt its increments are Gaussian with standard deviation intensity * sqrt(dt).
    """

    linear_intensity: float = 0.0  # [m/s / sqrt(s)]
    angular_intensity: float = 0.0  # [rad/s / sqrt(s)]
    seed: int = 0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "linear_intensity",
             check_range("VelocityRandomWalk.linear_intensity", self.linear_intensity, 0.0, 100.0))  # fmt: skip
        set_(self, "angular_intensity",
             check_range("VelocityRandomWalk.angular_intensity", self.angular_intensity, 0.0, 100.0))  # fmt: skip
        set_(self, "seed", _check_seed(self.seed))


@dataclass(frozen=True)
class WheelSlip:
    """Each wheel moves the ground at ``efficiency`` times its commanded speed (1 = no slip). Needs ``robot``."""

    left: float = 1.0  # [-], in [0, 1]
    right: float = 1.0  # [-], in [0, 1]

    def __post_init__(self) -> None:
        object.__setattr__(self, "left", check_range("WheelSlip.left", self.left, 0.0, 1.0))
        object.__setattr__(self, "right", check_range("WheelSlip.right", self.right, 0.0, 1.0))


@dataclass(frozen=True)
class ActuatorFault:
    """From ``start_time`` on, one wheel turns at ``fraction`` of its command (0 = a dead motor). Needs ``robot``."""

    wheel: str = "right"  # 'left' or 'right'
    fraction: float = 0.5  # [-], in [0, 1]
    start_time: float = 0.0  # [s] after the episode's start

    def __post_init__(self) -> None:
        if self.wheel not in WHEELS:
            raise ValueError(
                f"ActuatorFault.wheel={self.wheel!r} is invalid: expected 'left' or 'right' (a differential drive has two)"
            )
        object.__setattr__(self, "fraction", check_range("ActuatorFault.fraction", self.fraction, 0.0, 1.0))
        object.__setattr__(self, "start_time", check_range("ActuatorFault.start_time", self.start_time, 0.0, 1e6))


@dataclass(frozen=True)
class InputDelay:
    """The robot executes the command of ``steps`` control periods ago (it stands still before the first)."""

    steps: int = 1  # [control periods]

    def __post_init__(self) -> None:
        if isinstance(self.steps, bool) or not isinstance(self.steps, (int, np.integer)) or self.steps < 0:
            raise ValueError(f"InputDelay.steps={self.steps!r} is invalid: expected an integer >= 0")
        object.__setattr__(self, "steps", int(self.steps))


@dataclass(frozen=True)
class MeasurementDropout:
    """Each control period the pose measurement is lost with ``probability``; the last one is held."""

    probability: float = 0.0  # [-], in [0, 1)
    seed: int = 0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "probability",
             check_range("MeasurementDropout.probability", self.probability, 0.0, 1.0, high_inclusive=False))  # fmt: skip
        set_(self, "seed", _check_seed(self.seed))


Disturbance = (
    VelocityBias | VelocitySinusoid | VelocityRandomWalk | WheelSlip | ActuatorFault | InputDelay | MeasurementDropout
)
DISTURBANCE_TYPES: tuple[type, ...] = (VelocityBias, VelocitySinusoid, VelocityRandomWalk, WheelSlip, ActuatorFault,
                                       InputDelay, MeasurementDropout)  # fmt: skip
_RANDOM = (VelocityRandomWalk, MeasurementDropout)
#: Values a random disturbance draws per robot and period.
_DRAW_SIZE = {VelocityRandomWalk: 2, MeasurementDropout: 1}
#: Periods of random values drawn at once per robot (:meth:`Perturbation._draw`).
DRAW_BLOCK = 64


def _sample(rng: np.random.Generator, item: Any, count: int) -> FloatArray:
    """The next ``count`` values of a random disturbance's generator: standard normal (random walk) or uniform."""
    return rng.standard_normal(count) if isinstance(item, VelocityRandomWalk) else rng.random(count)


def split_env_kwargs(kwargs: dict[str, Any]) -> tuple[dict[str, Any], DifferentialDrive | None, tuple[Any, ...]]:
    """Take ``robot``, ``wheel_saturation``, ``disturbances`` and ``disturbance_distribution`` out of env keywords.

    A robot with finite wheel limits sets ``u_max`` and ``omega_max`` to what its wheels allow, unless
    they are given. Returns (the remaining keywords for :class:`EnvParams`, the drive or None, the
    disturbances: a distribution is returned as the one item).
    """
    reject_unknown(EnvParams, kwargs, also=ROBOT_KEYWORDS)  # the error lists these too, not only EnvParams' fields
    kwargs = dict(kwargs)
    robot = kwargs.pop("robot", None)
    saturation = kwargs.pop("wheel_saturation", None)
    disturbances = kwargs.pop("disturbances", None) or ()
    distribution = kwargs.pop("disturbance_distribution", None)
    drive = None if robot is None else robots.drive_from(robot)
    if saturation is not None:
        if drive is None:
            raise ValueError(f"wheel_saturation={saturation!r} is invalid without a robot: pass robot=... too")
        if saturation not in robots.SATURATIONS:
            raise ValueError(f"wheel_saturation={saturation!r} is invalid: expected 'clip' or 'scale'")
        drive = dataclasses.replace(drive, saturation=saturation)
    if drive is not None and math.isfinite(drive.max_wheel_speed):
        kwargs.setdefault("u_max", drive.max_linear_velocity)
        kwargs.setdefault("omega_max", drive.max_angular_velocity)
    if isinstance(disturbances, DISTURBANCE_TYPES) or not isinstance(disturbances, (list, tuple)):
        disturbances = (disturbances,)
    for item in disturbances:
        if not isinstance(item, DISTURBANCE_TYPES):
            names = ", ".join(t.__name__ for t in DISTURBANCE_TYPES)
            raise ValueError(f"disturbances item {item!r} is invalid: expected instances of {names}")
    if distribution is not None:
        if not callable(getattr(distribution, "perturbation", None)):  # (randomization imports this module)
            raise ValueError(f"disturbance_distribution={distribution!r} is invalid: expected a "
                             "dwr_gym.randomization.DisturbanceDistribution or None")  # fmt: skip
        if disturbances:
            raise ValueError("disturbances and disturbance_distribution are exclusive: the distribution draws all "
                             "seven kinds per episode; pass one of them")  # fmt: skip
        disturbances = (distribution,)
    return kwargs, drive, tuple(disturbances)


def make_perturbation(
    drive: DifferentialDrive | None, disturbances: tuple[Any, ...], params: EnvParams, n: int
) -> Perturbation | None:
    """The perturbation of n robots, or None (the nominal env) when there is no robot and no disturbance."""
    if drive is None and not disturbances:
        return None
    if disturbances and callable(getattr(disturbances[0], "perturbation", None)):  # a DisturbanceDistribution
        return disturbances[0].perturbation(drive, params, n)  # type: ignore[no-any-return]
    return Perturbation(drive, disturbances, params, n)


class Perturbation:
    """Per-robot state of a drive and its disturbances for N robots (N = 1 for the single env)."""

    def __init__(self, drive: DifferentialDrive | None, disturbances: tuple[Any, ...], params: EnvParams, n: int):
        self.drive, self.disturbances, self.params, self.n = drive, disturbances, params, n
        for item in disturbances:
            if isinstance(item, (WheelSlip, ActuatorFault)) and drive is None:
                raise ValueError(f"{type(item).__name__} acts on the wheels: pass robot=... (a preset or a "
                                 "DifferentialDrive) with it")  # fmt: skip
            if isinstance(item, InputDelay) and item.steps >= params.max_episode_steps:
                raise ValueError(f"InputDelay.steps={item.steps} is invalid: expected an integer in "
                                 f"[0, {params.max_episode_steps - 1}], shorter than the episode")  # fmt: skip
            if isinstance(item, ActuatorFault) and item.start_time > params.horizon:
                raise ValueError(f"ActuatorFault.start_time={item.start_time} is invalid: expected a time in "
                                 f"[0, {params.horizon}] s, within the episode")  # fmt: skip
        self.delay = sum(item.steps for item in disturbances if isinstance(item, InputDelay))
        self._buffer = np.zeros((n, self.delay, 2))  # the last `delay` commands, oldest first
        self._walk = {i: np.zeros((n, 2)) for i, d in enumerate(disturbances) if isinstance(d, VelocityRandomWalk)}
        self._rngs: dict[int, list[np.random.Generator]] = {}
        self._drawn: dict[int, list[Any]] = {}  # disturbance i: [values (n, width) drawn ahead, columns used]
        self._held = np.zeros((n, POSE_FEATURES), dtype=np.float32)
        self.last: dict[str, NDArray[Any]] = {
            "commanded_linear_velocity": np.zeros(n), "commanded_angular_velocity": np.zeros(n),
            "wheel_saturated": np.zeros(n, dtype=bool), "fault_active": np.zeros(n, dtype=bool),
            "measurement_held": np.zeros(n, dtype=bool),
        }  # fmt: skip

    def __repr__(self) -> str:
        return f"Perturbation(drive={self.drive!r}, disturbances={self.disturbances!r})"

    def seed(self, index: NDArray[np.intp] | list[int], keys: list[tuple[int, ...]]) -> None:
        """Seed the random disturbances' generators of the robots ``index`` with ``keys`` (one tuple each)."""
        for i, item in enumerate(self.disturbances):
            if isinstance(item, _RANDOM):
                rngs = self._rngs.setdefault(i, [np.random.default_rng(0)] * self.n)
                drawn = self._drawn.get(i)
                for robot, key in zip(index, keys, strict=True):
                    rngs[robot] = np.random.Generator(np.random.PCG64(np.random.SeedSequence([item.seed, *key])))
                    if drawn is not None and drawn[1] < drawn[0].shape[1]:  # its values ahead: from its new stream
                        drawn[0][robot, drawn[1] :] = _sample(rngs[robot], item, drawn[0].shape[1] - drawn[1])

    def reset(self, index: NDArray[np.intp] | slice, observation: NDArray[np.float32]) -> None:
        """Start new episodes for the robots ``index`` whose first observation is ``observation``."""
        if any(isinstance(item, _RANDOM) for item in self.disturbances) and not self._rngs:
            entropy = np.random.SeedSequence().entropy % 2**63  # type: ignore[operator]
            self.seed(list(range(self.n)), [(entropy, i) for i in range(self.n)])
        self._buffer[index] = 0.0
        for walk in self._walk.values():
            walk[index] = 0.0
        self._held[index] = np.reshape(observation, (-1, observation.shape[-1]))[:, :POSE_FEATURES]
        for value in self.last.values():
            value[index] = 0

    def _draw(self, i: int) -> FloatArray:
        """The next values of disturbance i's generators, (n, size): drawn DRAW_BLOCK periods ahead, one call per robot,
        the same numbers as one call per robot and period (a generator's stream does not depend on how it is cut)."""
        item, rngs = self.disturbances[i], self._rngs[i]
        size = _DRAW_SIZE[type(item)]
        drawn = self._drawn.get(i)
        if drawn is None or drawn[1] + size > drawn[0].shape[1]:
            # robots that share a generator (never seeded) draw in turn, one period at a time, as they always did
            width = size * (DRAW_BLOCK if len({id(rng) for rng in rngs}) == self.n else 1)
            drawn = self._drawn[i] = [np.array([_sample(rng, item, width) for rng in rngs]).reshape(self.n, width), 0]
        values = drawn[0][:, drawn[1] : drawn[1] + size]
        drawn[1] += size
        return values

    def command(self, u: Any, omega: Any, step_count: Any) -> tuple[Any, Any]:
        """The velocities (u [m/s], omega [rad/s]) the robots really have for the commanded ones."""
        scalar = not isinstance(u, np.ndarray)
        dtype = np.float64 if scalar else u.dtype
        u_cmd, omega_cmd = (
            np.reshape(np.asarray(u, np.float64), (-1,)),
            np.reshape(np.asarray(omega, np.float64), (-1,)),
        )
        time = np.reshape(np.asarray(step_count), (-1,)) * self.params.dt  # start of this control period [s]
        u_out, omega_out = u_cmd, omega_cmd
        if self.delay:
            self._buffer = np.concatenate([self._buffer, np.stack([u_cmd, omega_cmd], axis=1)[:, None]], axis=1)
            (u_out, omega_out), self._buffer = self._buffer[:, 0].T, self._buffer[:, 1:]
        saturated = np.zeros(self.n, dtype=bool)
        fault_active = np.zeros(self.n, dtype=bool)
        if self.drive is not None:
            left, right = robots.wheel_speeds(u_out, omega_out, self.drive)
            if math.isfinite(self.drive.max_wheel_speed):
                limited_left, limited_right = robots.saturate_wheels(left, right, self.drive)
                saturated = (limited_left != left) | (limited_right != right)
                left, right = limited_left, limited_right
            for item in self.disturbances:
                if isinstance(item, WheelSlip):
                    left, right = left * item.left, right * item.right
                elif isinstance(item, ActuatorFault):
                    active = time >= item.start_time - 1e-9
                    fault_active |= active
                    factor = np.where(active, item.fraction, 1.0)
                    left, right = (left * factor, right) if item.wheel == "left" else (left, right * factor)
            u_out, omega_out = robots.body_velocities(left, right, self.drive)
        for i, item in enumerate(self.disturbances):
            if isinstance(item, VelocityBias):
                u_out, omega_out = u_out + item.linear, omega_out + item.angular
            elif isinstance(item, VelocitySinusoid):
                wave = np.sin(2.0 * math.pi * time / item.period + item.phase)
                u_out, omega_out = u_out + item.linear_amplitude * wave, omega_out + item.angular_amplitude * wave
            elif isinstance(item, VelocityRandomWalk):
                walk = self._walk[i]
                walk += self._draw(i) * (math.sqrt(self.params.dt)
                                                       * np.array([item.linear_intensity, item.angular_intensity]))  # fmt: skip
                u_out, omega_out = u_out + walk[:, 0], omega_out + walk[:, 1]
        self.last.update(commanded_linear_velocity=u_cmd, commanded_angular_velocity=omega_cmd,
                         wheel_saturated=saturated, fault_active=fault_active)  # fmt: skip
        if scalar:
            return float(u_out[0]), float(omega_out[0])
        return u_out.astype(dtype, copy=False), omega_out.astype(dtype, copy=False)

    def measure(self, observation: NDArray[np.float32]) -> NDArray[np.float32]:
        """The observation with the pose features of robots whose measurement dropped out held at their last."""
        held = np.zeros(self.n, dtype=bool)
        for i, item in enumerate(self.disturbances):
            if isinstance(item, MeasurementDropout):
                held |= self._draw(i)[:, 0] < item.probability
        batch = np.reshape(observation, (self.n, -1))  # a view: the single env's (10,) is changed too
        batch[held, :POSE_FEATURES] = self._held[held]
        self._held[:] = batch[:, :POSE_FEATURES]
        self.last["measurement_held"] = held
        return observation

    def info(self, scalar: bool = False) -> dict[str, Any]:
        """What the disturbances did in the last step: arrays (N,), or Python scalars for one robot."""
        if scalar:
            return {key: value[0].item() for key, value in self.last.items()}
        return {key: value.copy() for key, value in self.last.items()}


__all__ = [
    "DISTURBANCE_TYPES",
    "ActuatorFault",
    "Disturbance",
    "InputDelay",
    "MeasurementDropout",
    "Perturbation",
    "VelocityBias",
    "VelocityRandomWalk",
    "VelocitySinusoid",
    "WheelSlip",
    "make_perturbation",
    "split_env_kwargs",
]
