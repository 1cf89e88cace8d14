"""Coercion and checking of user input: the one validation layer of env, vector env, controllers and CLI.

Every function takes the parameter's name and the value as given, returns the value as a plain Python
type, or raises a ValueError of one line naming the parameter, the value and what is allowed. They accept
what users pass: Python and numpy numbers, 0-d arrays, lists, tuples and numpy arrays for pairs, and (with
``text=True``, for the CLI and YAML files) numbers written as text such as ``"3e-4"`` or ``"1e5"``.

>>> as_float("learning_rate", "3e-4", 0.0, 1.0, text=True)
0.0003
>>> as_int("total_timesteps", 1e5, 1)
100000
>>> as_int("n_envs", 2.7, 1)
Traceback (most recent call last):
...
ValueError: n_envs=2.7 is invalid: expected an integer in [1, inf]
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np

POSE_LIMIT = 1e9
"""Largest |x|, |y| [m] and |psi| [rad] of a pose option: beyond it differences of poses overflow."""


def _number(x: float) -> str:
    """A bound as users read it: 4294967295 exactly, 1e+06 short."""
    return str(int(x)) if (math.isfinite(x) and float(x).is_integer() and abs(x) < 1e6) or x == 2**32 - 1 else f"{x:g}"


def _bounds(low: float, high: float, low_inclusive: bool, high_inclusive: bool) -> str:
    return f"{'[' if low_inclusive else '('}{_number(low)}, {_number(high)}{']' if high_inclusive else ')'}"


def _scalar(value: Any, text: bool) -> Any:
    """A 0-d array or numpy scalar as the Python scalar; a numeric string as a float when ``text``."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()
    elif isinstance(value, np.generic):
        value = value.item()
    if text and isinstance(value, str):
        try:
            return float(value.strip())
        except ValueError:
            return value
    return value


def _show(name: str, text: str) -> str:
    """``name=value`` for keywords, ``--flag value`` for command-line options."""
    return f"{name} {text}" if name.startswith("--") else f"{name}={text}"


def _describe(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return f"array of shape {value.shape}"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def as_float(
    name: str,
    value: Any,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
    text: bool = False,
) -> float:
    """``value`` as a finite float within the bounds."""
    allowed = f"a finite number in {_bounds(low, high, low_inclusive, high_inclusive)}"
    plain = _scalar(value, text)
    if isinstance(plain, bool) or not isinstance(plain, numbers.Real):
        hint = " (a string; write it as a number)" if isinstance(plain, str) else ""
        raise ValueError(f"{_show(name, _describe(value))} is invalid{hint}: expected {allowed}")
    result = float(plain)
    below = result < low or (result == low and not low_inclusive)
    above = result > high or (result == high and not high_inclusive)
    if not math.isfinite(result) or below or above:
        hint = "" if math.isfinite(result) else " (not finite)"
        raise ValueError(f"{_show(name, repr(result))} is invalid{hint}: expected {allowed}")
    return result


def as_int(name: str, value: Any, low: float = -math.inf, high: float = math.inf, *, text: bool = False) -> int:
    """``value`` as an int within [low, high]; integral floats such as ``1e5`` or ``2.0`` are accepted."""
    allowed = f"an integer in {_bounds(low, high, True, True)}"
    plain = _scalar(value, text)
    if isinstance(plain, bool) or not isinstance(plain, numbers.Real):
        raise ValueError(f"{_show(name, _describe(value))} is invalid: expected {allowed}")
    if isinstance(plain, numbers.Integral):
        result = int(plain)
    elif math.isfinite(plain) and float(plain).is_integer():
        result = int(plain)
    else:
        raise ValueError(f"{_show(name, repr(plain))} is invalid: expected {allowed}")
    if not low <= result <= high:
        raise ValueError(f"{_show(name, repr(result))} is invalid: expected {allowed}")
    return result


def as_bool(name: str, value: Any) -> bool:
    """``value`` as a bool: True/False, numpy bools; nothing else."""
    plain = _scalar(value, False)
    if not isinstance(plain, bool):
        raise ValueError(f"{_show(name, _describe(value))} is invalid: expected True or False")
    return plain


def as_choice(name: str, value: Any, choices: Iterable[Any]) -> Any:
    """``value`` if it is one of ``choices``."""
    options = tuple(choices)
    plain = _scalar(value, False)
    if not isinstance(plain, (str, type(None))) or plain not in options:
        raise ValueError(f"{_show(name, _describe(value))} is invalid: expected one of {', '.join(map(repr, options))}")
    return plain


def _sequence(name: str, value: Any, length: int, expected: str) -> list[Any]:
    if isinstance(value, (str, bytes, dict)) or not isinstance(value, (list, tuple, np.ndarray)):
        raise ValueError(f"{_show(name, _describe(value))} is invalid: expected {expected}")
    items = list(np.asarray(value, dtype=object).reshape(-1)) if isinstance(value, np.ndarray) else list(value)
    if (isinstance(value, np.ndarray) and value.ndim != 1) or len(items) != length:
        raise ValueError(f"{_show(name, _describe(value))} is invalid: expected {expected}")
    return items


def as_interval(name: str, value: Any, low: float, high: float) -> tuple[float, float]:
    """A (min, max) pair within [low, high] with min <= max, from a tuple, list or array of two numbers."""
    expected = f"a pair (min, max) within [{low:g}, {high:g}]"
    first, second = _sequence(name, value, 2, expected)
    pair = as_float(f"{name}[0]", first, low, high), as_float(f"{name}[1]", second, low, high)
    if pair[0] > pair[1]:
        raise ValueError(f"{_show(name, _describe(value))} is invalid: min must not exceed max")
    return pair


def as_pose(name: str, value: Any) -> tuple[float, float, float]:
    """A pose (x [m], y [m], psi [rad]) of three finite numbers of magnitude at most POSE_LIMIT."""
    expected = f"three finite numbers (x [m], y [m], psi [rad]) within [-{POSE_LIMIT:g}, {POSE_LIMIT:g}]"
    try:
        items = _sequence(name, value, 3, expected)
        return tuple(as_float(name, v, -POSE_LIMIT, POSE_LIMIT) for v in items)  # type: ignore[return-value]
    except ValueError:
        raise ValueError(f"{_show(name, _describe(value))} is invalid: expected {expected}") from None


def reject_unknown(cls: type, kwargs: dict[str, Any], also: tuple[str, ...] = ()) -> None:
    """Raise a ValueError for keywords that are neither fields of the dataclass ``cls`` nor in ``also``."""
    allowed = {f.name for f in dataclasses.fields(cls)} | set(also)
    unknown = sorted(set(kwargs) - allowed)
    if unknown:
        raise ValueError(
            f"unknown parameter(s) {', '.join(map(repr, unknown))} for {cls.__name__}; "
            f"allowed: {', '.join(sorted(allowed))}"
        )


def coerce_numbers(instance: Any) -> None:
    """Turn numpy scalars and 0-d arrays in the numeric fields of a frozen dataclass into Python numbers.

    A field counts as numeric when its default is a float or an int (bools excluded); range checks come after.
    """
    for f in dataclasses.fields(instance):
        default, value = f.default, getattr(instance, f.name)
        if isinstance(default, bool) or not isinstance(value, (np.generic, np.ndarray)):
            continue
        if isinstance(default, float):
            object.__setattr__(instance, f.name, as_float(f.name, value))
        elif isinstance(default, int):
            object.__setattr__(instance, f.name, as_int(f.name, value))


def is_default(instance: Any, name: str) -> bool:
    """Whether a dataclass field still holds its default (the user did not set it)."""
    field = next(f for f in dataclasses.fields(instance) if f.name == name)
    return bool(getattr(instance, name) == field.default)


def blame(instance: Any, *names: str) -> str:
    """Of parameters that conflict, the first one the user set (else the first): the one an error names."""
    return next((name for name in names if not is_default(instance, name)), names[0])
