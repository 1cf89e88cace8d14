"""Each controller parameter's documented range: a value just past either end is refused with a one-line error
naming the parameter and the range, a value just inside is taken (the docs and the messages state these ranges)."""

from __future__ import annotations

import dataclasses
import math
import re

import pytest

from baselines.controllers import ConventionalPTCParams, FabregasParams, FixedTimeParams, PTCParams
from baselines.estimation import PoseFilterParams
from baselines.nmpc import OptimalParams
from baselines.polar import AstolfiParams, PrescribedTimeAstolfiParams
from baselines.robust import RobustPTParams

K_MAX = 1.0 / (2.0 * math.pi)

#: class -> {parameter: (low bracket and value, high, high bracket)}; "(" and ")" exclude the end, "[" "]" include it
RANGES: dict[type, dict[str, tuple[str, float, float, str]]] = {
    PTCParams: {**{n: ("(", 0.0, 1e9, "]") for n in ("K1", "K2", "K", "Ke", "T_con")}, "beta": ("(", 0.5, 1.0, ")"),
                "k": ("[", 0.0, K_MAX, "]"), "stop_distance": ("[", 0.0, 1.0, "]"), "max_gain": ("(", 0.05, 1e9, "]")},
    ConventionalPTCParams: {**{n: ("(", 0.0, 1e9, "]") for n in ("K1", "K2", "Ke", "T_con")},
                            "k": ("[", 0.0, K_MAX, "]"), "stop_distance": ("[", 0.0, 1.0, "]"),
                            "max_gain": ("(", 0.05, 1e9, "]")},
    FabregasParams: {"K0": ("(", 0.0, 1e9, "]"), "K_omega": ("(", 0.0, 1e9, "]"), "K_i": ("[", 0.0, 1e9, "]"),
                     "dt": ("(", 0.0, 10.0, "]"), "speed_limit": ("(", 0.0, 1e9, "]")},
    FixedTimeParams: {**{n: ("(", 0.0, 1e9, "]") for n in ("k1", "k2", "k3", "k4", "Ke")}, "a": ("(", 0.0, 1.0, ")"),
                      "b": ("(", 1.0, 10.0, "]"), "k": ("[", 0.0, K_MAX, "]"), "stop_distance": ("[", 0.0, 1.0, "]")},
    AstolfiParams: {"k_rho": ("(", 0.0, 1e9, "]"), "k_beta": ("[", -1e9, 0.0, ")"), "k_alpha": ("(", 0.3, 1e9, "]")},
    PrescribedTimeAstolfiParams: {"k_rho": ("(", 0.0, 1e9, "]"), "k_beta": ("[", -1e9, 0.0, ")"),
                                  "k_alpha": ("(", 1.5, 1e9, "]"), "T_con": ("(", 0.0, 1e9, "]"),
                                  "arrival_fraction": ("(", 0.0, 1.0, "]"), "max_gain": ("[", 1.0, 1e9, "]")},
    OptimalParams: {**{n: ("(", 0.0, 1e6, "]") for n in ("T_con", "dt", "u_max", "omega_max", "arrival_time")},
                    "arrival_fraction": ("(", 0.0, 1.0, "]"), "replan_tolerance": ("[", 0.0, 1e6, "]")},
    RobustPTParams: {**{n: ("(", 0.0, 1e6, "]") for n in ("T_con", "dt", "u_max", "omega_max")},
                     **{n: ("(", 0.0, 1e9, "]") for n in ("k_along", "k_lateral", "k_heading", "k_rho")},
                     "plan_arrival": ("(", 0.0, 1.0, ")"), "finish_arrival": ("(", 0.8, 1.0, "]"),
                     "tube": ("(", 0.0, 1e3, "]"), "near_goal": ("[", 0.0, 1e3, "]"), "k_beta": ("[", -1e9, 0.0, ")"),
                     "k_alpha": ("(", 1.5, 1e9, "]"), "reverse_hysteresis": ("[", 0.0, 0.5 * math.pi, ")"),
                     "max_gain": ("(", 0.05, 1e9, "]"), "k": ("[", 0.0, K_MAX, "]"),
                     "handover_time": ("(", 0.0, 1.0, "]"), "handover_margin": ("[", 0.0, 1e6, "]")},
    PoseFilterParams: {"position_noise": ("(", 0.0, 1e3, "]"), "heading_noise": ("(", 0.0, 1e3, "]"),
                       **{n: ("[", 0.0, 1e3, "]") for n in ("gain_rate", "coupling_rate", "gain_prior",
                                                            "coupling_prior", "coupling_limit")},
                       "delay_memory": ("(", 0.0, 1e6, "]")},
}  # fmt: skip
CASES = [(cls, name, *bounds) for cls, fields in RANGES.items() for name, bounds in fields.items()]


def nudge(value: float, direction: float) -> float:
    """A value a relative 1e-12 (at least 1e-12) past ``value`` in ``direction``."""
    return value + direction * max(abs(value) * 1e-12, 1e-12)


def number(value: float) -> str:
    return f"{value:g}"


@pytest.mark.parametrize(("cls", "name", "low_bracket", "low", "high", "high_bracket"), CASES,
                         ids=[f"{c.__name__}.{n}" for c, n, *_ in CASES])  # fmt: skip
def test_a_value_just_past_either_end_is_refused_and_one_just_inside_is_taken(
    cls: type, name: str, low_bracket: str, low: float, high: float, high_bracket: str
) -> None:
    allowed = f"{low_bracket}{number(low)}, {number(high)}{high_bracket}"
    outside = [low if low_bracket == "(" else nudge(low, -1), high if high_bracket == ")" else nudge(high, 1)]
    for value in outside:
        with pytest.raises(ValueError, match=rf"^{name}={re.escape(repr(float(value)))} is invalid: expected a finite "
                                             rf"number in {re.escape(allowed)}$"):  # fmt: skip
            cls(**{name: value})
    field = next(f for f in dataclasses.fields(cls) if f.name == name)
    for value in (nudge(low, 1), nudge(high, -1)):
        try:
            taken = getattr(cls(**{name: value}), name)
        except ValueError as error:  # another parameter's range depends on this one (K <= min(0.6 K1, K2) ...)
            coupled = str(error).split("=")[0] != name or "min(0.6 K1, K2)" in str(error)
            assert coupled, error
            continue
        assert taken == value, field


#: class -> {integer parameter: (low, high)}, with the keywords another parameter's range needs
INTEGERS: list[tuple[type, str, int, int, dict]] = [
    (ConventionalPTCParams, "power", 1, 10, {}),
    (OptimalParams, "hold_steps", 1, 10_000, {"replan_every": 0}),
    (OptimalParams, "replan_every", 0, 1_000_000, {"hold_steps": 1}),
    (OptimalParams, "workers", 0, 256, {}),
    (RobustPTParams, "hold_steps", 1, 10_000, {}),
    (RobustPTParams, "max_replans", 0, 1_000, {}),
    (RobustPTParams, "workers", 0, 256, {}),
    (PoseFilterParams, "max_delay", 0, 100, {}),
]


@pytest.mark.parametrize(("cls", "name", "low", "high", "others"), INTEGERS,
                         ids=[f"{c.__name__}.{n}" for c, n, *_ in INTEGERS])  # fmt: skip
def test_an_integer_parameter_takes_both_ends_and_refuses_one_past_them(
    cls: type, name: str, low: int, high: int, others: dict
) -> None:
    for value in (low, high):
        assert getattr(cls(**{name: value, **others}), name) == value
    for value in (low - 1, high + 1):
        with pytest.raises(ValueError, match=rf"^{name}={value} is invalid: expected an integer in \[{low}, {high}\]"):
            cls(**{name: value, **others})


BOOLEANS = [(AstolfiParams, "reverse"), (PrescribedTimeAstolfiParams, "reverse"), (OptimalParams, "heading"),
            (RobustPTParams, "plan"), (RobustPTParams, "cancel_disturbance")]  # fmt: skip


@pytest.mark.parametrize(("cls", "name"), BOOLEANS, ids=[f"{c.__name__}.{n}" for c, n in BOOLEANS])
def test_a_switch_takes_true_or_false_and_names_itself_otherwise(cls: type, name: str) -> None:
    assert getattr(cls(**{name: False}), name) is False
    with pytest.raises(ValueError, match=rf"^{name}='yes' is invalid: expected True or False"):
        cls(**{name: "yes"})
