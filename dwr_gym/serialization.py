"""Env keywords as JSON and back: what a stored env spec (a Minari dataset's, a YAML file's) can hold.

The envs take Python objects for the imperfect robot: ``robot`` (a :class:`~dwr_gym.robots.DifferentialDrive`),
``disturbances`` (instances of :mod:`dwr_gym.disturbances`) and ``disturbance_distribution`` (a
:class:`~dwr_gym.randomization.DisturbanceDistribution`). :func:`env_kwargs_to_json` writes each as a plain dict
(a robot preset by its name), and both envs accept these dicts in their place (:func:`env_kwargs_from_json`), so
``gymnasium.make(EnvSpec.from_json(spec.to_json()))`` rebuilds the same env, disturbances included:

>>> from dwr_gym.disturbances import InputDelay, VelocityBias
>>> from dwr_gym.randomization import DisturbanceDistribution
>>> kwargs = {"T_con_range": (10.0, 60.0), "disturbances": [VelocityBias(linear=-0.02), InputDelay(steps=4)]}
>>> encoded = env_kwargs_to_json(kwargs)
>>> encoded.get("disturbances").pop()
{'type': 'InputDelay', 'steps': 4}
>>> env_kwargs_from_json(env_kwargs_to_json(kwargs)).get("disturbances") == kwargs.get("disturbances")
True
>>> env_kwargs_from_json({"disturbance_distribution": {"probability": 0.3}}).get("disturbance_distribution")
DisturbanceDistribution(probability=0.3, bias=(0.05, 0.3), sinusoid=(0.1, 0.4), sinusoid_period=(2.0, 8.0), random_walk=(0.02, 0.1), slip=0.4, fault=0.8, fault_start=(0.0, 0.5), delay=6, dropout=0.4, seed=0)
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

from dwr_gym.disturbances import DISTURBANCE_TYPES
from dwr_gym.randomization import DisturbanceDistribution
from dwr_gym.robots import ROBOTS, DifferentialDrive

_DISTURBANCES: dict[str, type] = {cls.__name__: cls for cls in DISTURBANCE_TYPES}


def _fields(obj: Any) -> dict[str, Any]:
    """A frozen dataclass's fields, tuples as lists and infinities as None (JSON has neither)."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, tuple):
            value = list(value)
        elif isinstance(value, float) and math.isinf(value):
            value = None
        out[f.name] = value
    return out


def env_kwargs_to_json(kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` with the robot, the disturbances and the distribution as plain dicts, tuples as lists.

    Raises a ValueError naming the keyword whose value has no JSON form.
    """
    out: dict[str, Any] = {}
    for key, value in kwargs.items():
        if key == "robot" and isinstance(value, DifferentialDrive):
            preset = next((name for name, drive in ROBOTS.items() if drive == value), None)
            value = preset or {"type": "DifferentialDrive", **_fields(value)}
        elif key == "disturbances" and value is not None:
            items = value if isinstance(value, (list, tuple)) else [value]
            value = [item if isinstance(item, dict) else {"type": type(item).__name__, **_fields(item)}
                     for item in items]  # fmt: skip
        elif key == "disturbance_distribution" and isinstance(value, DisturbanceDistribution):
            value = _fields(value)
        elif isinstance(value, tuple):
            value = list(value)
        try:
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError):
            raise ValueError(
                f"env keyword {key}={value!r} is invalid for a stored env spec: it has no JSON form; expected "
                "numbers, strings, lists, a robot preset or DifferentialDrive, disturbances of dwr_gym.disturbances "
                "or a DisturbanceDistribution"
            ) from None
        out[key] = value
    return out


def env_kwargs_from_json(kwargs: dict[str, Any]) -> dict[str, Any]:
    """``kwargs`` with the dict forms of :func:`env_kwargs_to_json` turned back into objects; others unchanged."""
    if not any(isinstance(v, (dict, list, tuple)) for v in kwargs.values()):
        return kwargs  # the common case: nothing to decode
    out = dict(kwargs)
    robot = out.get("robot")
    if isinstance(robot, dict):
        out["robot"] = _build("robot", DifferentialDrive, robot, infinite=("max_wheel_speed",))
    disturbances = out.get("disturbances")
    if isinstance(disturbances, dict):
        disturbances = [disturbances]
    if isinstance(disturbances, (list, tuple)) and any(isinstance(item, dict) for item in disturbances):
        out["disturbances"] = [_disturbance(item) if isinstance(item, dict) else item for item in disturbances]
    distribution = out.get("disturbance_distribution")
    if isinstance(distribution, dict):
        fields = {k: tuple(v) if isinstance(v, list) else v for k, v in distribution.items() if k != "type"}
        out["disturbance_distribution"] = _build("disturbance_distribution", DisturbanceDistribution, fields)
    return out


def _disturbance(item: dict[str, Any]) -> Any:
    kind = item.get("type")
    if kind not in _DISTURBANCES:
        raise ValueError(
            f"disturbances item {item!r} is invalid: expected a 'type' of {', '.join(_DISTURBANCES)} and its fields"
        )
    return _build("disturbances", _DISTURBANCES[kind], item)


def _build(key: str, cls: type, fields: dict[str, Any], infinite: tuple[str, ...] = ()) -> Any:
    """``cls(**fields)`` (without 'type'; None as infinity for ``infinite``), or a ValueError naming ``key``."""
    names = {f.name for f in dataclasses.fields(cls)}
    given = {k: (math.inf if k in infinite and v is None else v) for k, v in fields.items() if k != "type"}
    unknown = sorted(set(given) - names)
    if unknown:
        raise ValueError(f"{key} field(s) {', '.join(unknown)} of {cls.__name__} are invalid: expected any of "
                         f"{', '.join(sorted(names))}")  # fmt: skip
    return cls(**given)


__all__ = ["env_kwargs_from_json", "env_kwargs_to_json"]
