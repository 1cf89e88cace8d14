"""The robustness scenario sets of ``dwr-gym evaluate --scenarios disturbed fault delay noise``.

Each set is the 'random' set of start poses run with the env keywords below: one typical magnitude
of each kind of imperfection, chosen so that the nominal PTC law is visibly challenged but not
hopeless. ``dwr-gym robustness`` sweeps the magnitudes instead.
"""

from __future__ import annotations

from typing import Any

from dwr_gym.disturbances import (
    ActuatorFault,
    InputDelay,
    MeasurementDropout,
    VelocityBias,
    VelocityRandomWalk,
    VelocitySinusoid,
)
from dwr_gym.robots import ROBOTS, DifferentialDrive

ROBUSTNESS_SETS: tuple[str, ...] = ("disturbed", "fault", "delay", "noise")

#: TurtleBot3 Burger's wheel geometry without its speed limit, so that wheel faults act on the default env's
#: u_max and omega_max (which the shipped agents were trained with).
UNLIMITED_BURGER = DifferentialDrive(
    ROBOTS["turtlebot3_burger"].wheel_radius, ROBOTS["turtlebot3_burger"].track_width, name="burger-geometry"
)


def robustness_env_kwargs(name: str, T_con: float) -> dict[str, Any]:
    """The env keywords of robustness set ``name`` for prescribed time ``T_con`` [s]."""
    if name == "disturbed":  # additive velocity disturbances: bias, a periodic push, a random walk
        return {"disturbances": [VelocityBias(linear=-0.02, angular=0.1),
                                 VelocitySinusoid(linear_amplitude=0.05, angular_amplitude=0.2, period=4.0),
                                 VelocityRandomWalk(linear_intensity=0.01, angular_intensity=0.05)]}  # fmt: skip
    if name == "fault":  # the right motor drops to half its command a quarter of the way to T_con
        return {"robot": UNLIMITED_BURGER,
                "disturbances": [ActuatorFault(wheel="right", fraction=0.5, start_time=T_con / 4)]}  # fmt: skip
    if name == "delay":  # 0.2 s of input delay at dt = 0.05 s
        return {"disturbances": [InputDelay(steps=4)]}
    if name == "noise":  # 1 cm / 0.01 rad pose noise, 20 % dropped measurements, 5 % actuation noise
        return {"observation_noise": 0.01, "actuation_noise": 0.05, "disturbances": [MeasurementDropout(0.2)]}
    raise ValueError(f"scenario={name!r} is invalid: expected one of {', '.join(ROBUSTNESS_SETS)}")
