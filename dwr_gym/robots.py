"""Differential-drive actuation: wheel speeds, their limits, and presets of common research robots.

A differential drive with wheel radius r and track width b (distance between the wheels' contact
points) turns the unicycle commands (u, omega) of eq. (1) into wheel angular speeds

    w_R = (u + omega b / 2) / r,    w_L = (u - omega b / 2) / r,

and back: u = r (w_R + w_L) / 2, omega = r (w_R - w_L) / b. Each wheel's speed is limited to
|w| <= max_wheel_speed; :func:`saturate_wheels` enforces it by clipping each wheel (which bends the
path) or by scaling both (which keeps the curvature omega / u).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from dwr_gym.model import FloatArray
from dwr_gym.params import check_range

SATURATIONS: tuple[str, ...] = ("clip", "scale")


@dataclass(frozen=True)
class DifferentialDrive:
    """Wheel geometry and limits of a differential-drive robot."""

    wheel_radius: float  # [m]
    """Radius r of each drive wheel."""
    track_width: float  # [m]
    """Distance b between the two wheels."""
    max_wheel_speed: float = math.inf  # [rad/s]
    """Limit of |w_L| and |w_R|; math.inf leaves the wheels unlimited."""
    saturation: str = "scale"
    """'clip' each wheel at its limit, or 'scale' both by one factor so the curvature is kept."""
    name: str = "custom"
    """Label shown in info and tables."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "wheel_radius", check_range("wheel_radius", self.wheel_radius, 0.0, 10.0, low_inclusive=False))
        set_(self, "track_width", check_range("track_width", self.track_width, 0.0, 10.0, low_inclusive=False))
        if self.max_wheel_speed != math.inf:
            set_(
                self,
                "max_wheel_speed",
                check_range("max_wheel_speed", self.max_wheel_speed, 0.0, 1e4, low_inclusive=False),
            )
        if self.saturation not in SATURATIONS:
            raise ValueError(f"saturation={self.saturation!r} is invalid: expected 'clip' or 'scale'")

    @property
    def max_linear_velocity(self) -> float:
        """u at both wheels' limit [m/s]."""
        return self.wheel_radius * self.max_wheel_speed

    @property
    def max_angular_velocity(self) -> float:
        """omega with the wheels at opposite limits [rad/s]."""
        return 2.0 * self.wheel_radius * self.max_wheel_speed / self.track_width


#: Research robots' drive parameters from their public specifications.
ROBOTS: dict[str, DifferentialDrive] = {
    # ROBOTIS TurtleBot3 e-Manual, "Specifications" (emanual.robotis.com/docs/en/platform/turtlebot3/features/)
    # and turtlebot3_core's turtlebot3_burger.h: WHEEL_RADIUS 0.033 m, WHEEL_SEPARATION 0.160 m,
    # maximum translational velocity 0.22 m/s, i.e. 0.22 / 0.033 = 6.67 rad/s at each wheel.
    "turtlebot3_burger": DifferentialDrive(0.033, 0.160, 0.22 / 0.033, name="turtlebot3_burger"),
    # Same sources, turtlebot3_waffle.h: WHEEL_RADIUS 0.033 m, WHEEL_SEPARATION 0.287 m,
    # maximum translational velocity 0.26 m/s, i.e. 7.88 rad/s at each wheel.
    "turtlebot3_waffle": DifferentialDrive(0.033, 0.287, 0.26 / 0.033, name="turtlebot3_waffle"),
    # K-Team Khepera IV user manual, "Specifications": wheel diameter 42 mm, distance between the
    # wheels 105.4 mm, maximum speed 0.813 m/s, i.e. 0.813 / 0.021 = 38.7 rad/s at each wheel.
    "khepera_iv": DifferentialDrive(0.021, 0.1054, 0.813 / 0.021, name="khepera_iv"),
    # GCtronic e-puck (www.gctronic.com/doc/index.php/e-puck2) and Cyberbotics' Webots e-puck guide
    # (cyberbotics.com/doc/guide/epuck): wheel radius 20.5 mm, axle length 52 mm, 1000 motor steps/s
    # at 1000 steps per revolution, i.e. 2 pi = 6.28 rad/s at each wheel (0.129 m/s).
    "e_puck": DifferentialDrive(0.0205, 0.052, 2.0 * math.pi, name="e_puck"),
}


def drive_from(robot: Any) -> DifferentialDrive:
    """A preset name or a :class:`DifferentialDrive` as a DifferentialDrive; a ValueError otherwise."""
    if isinstance(robot, DifferentialDrive):
        return robot
    if isinstance(robot, str) and robot in ROBOTS:
        return ROBOTS[robot]
    raise ValueError(f"robot={robot!r} is invalid: expected a DifferentialDrive or one of {', '.join(ROBOTS)}")


def wheel_speeds(u: Any, omega: Any, drive: DifferentialDrive) -> tuple[Any, Any]:
    """(w_L, w_R) [rad/s] of the commands (u [m/s], omega [rad/s])."""
    half = 0.5 * drive.track_width * omega
    return (u - half) / drive.wheel_radius, (u + half) / drive.wheel_radius


def body_velocities(left: Any, right: Any, drive: DifferentialDrive) -> tuple[Any, Any]:
    """(u [m/s], omega [rad/s]) of the wheel speeds (w_L, w_R) [rad/s]."""
    r = drive.wheel_radius
    return 0.5 * r * (left + right), r * (right - left) / drive.track_width


def saturate_wheels(left: FloatArray, right: FloatArray, drive: DifferentialDrive) -> tuple[FloatArray, FloatArray]:
    """Wheel speeds (N,) limited to |w| <= max_wheel_speed by the drive's saturation rule."""
    limit = drive.max_wheel_speed
    if drive.saturation == "clip":
        return np.clip(left, -limit, limit), np.clip(right, -limit, limit)
    peak = np.maximum(np.abs(left), np.abs(right))
    factor = np.where(peak > limit, limit / np.maximum(peak, 1e-300), 1.0)
    return left * factor, right * factor


__all__ = ["ROBOTS", "SATURATIONS", "DifferentialDrive", "body_velocities", "drive_from", "saturate_wheels",
           "wheel_speeds"]  # fmt: skip
