"""Every parameter of every controller: its range, refused outside it with its name, kept as given."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from baselines import (
    CONTROLLERS,
    AstolfiParams,
    ConventionalPTCParams,
    FabregasParams,
    FixedTimeParams,
    PrescribedTimeAstolfiParams,
    PTCParams,
    make_controller,
)

K_MAX = 1.0 / (2.0 * math.pi)
# (class, field, lowest, highest, lowest excluded, highest excluded); None: no bound tested on that side
PARAM_RANGES = [
    *[(PTCParams, f, 0.0, 1e9, True, False) for f in ("K1", "K2", "Ke", "T_con")],
    (PTCParams, "K", 0.0, None, True, False), (PTCParams, "beta", 0.5, 1.0, True, True),
    (PTCParams, "k", 0.0, K_MAX, False, False), (PTCParams, "stop_distance", 0.0, 1.0, False, False),
    (PTCParams, "max_gain", 1.0 / 20.0, 1e9, True, False),
    *[(ConventionalPTCParams, f, 0.0, 1e9, True, False) for f in ("K1", "K2", "Ke", "T_con")],
    (ConventionalPTCParams, "k", 0.0, K_MAX, False, False),
    (ConventionalPTCParams, "stop_distance", 0.0, 1.0, False, False),
    (ConventionalPTCParams, "max_gain", 1.0 / 20.0, 1e9, True, False),
    (FabregasParams, "K0", 0.0, 1e9, True, False), (FabregasParams, "K_omega", 0.0, 1e9, True, False),
    (FabregasParams, "K_i", 0.0, 1e9, False, False), (FabregasParams, "dt", 0.0, 10.0, True, False),
    (FabregasParams, "speed_limit", 0.0, 1e9, True, False),
    *[(FixedTimeParams, f, 0.0, 1e9, True, False) for f in ("k1", "k2", "k3", "k4", "Ke")],
    (FixedTimeParams, "a", 0.0, 1.0, True, True), (FixedTimeParams, "b", 1.0, 10.0, True, False),
    (FixedTimeParams, "k", 0.0, K_MAX, False, False), (FixedTimeParams, "stop_distance", 0.0, 1.0, False, False),
    (AstolfiParams, "k_rho", 0.0, None, True, False), (AstolfiParams, "k_beta", -1e9, 0.0, False, True),
    (AstolfiParams, "k_alpha", None, 1e9, False, False),
    (PrescribedTimeAstolfiParams, "k_beta", -1e9, 0.0, False, True),
    (PrescribedTimeAstolfiParams, "k_alpha", None, 1e9, False, False),
    (PrescribedTimeAstolfiParams, "T_con", 0.0, 1e9, True, False),
    (PrescribedTimeAstolfiParams, "arrival_fraction", 0.0, 1.0, True, False),
    (PrescribedTimeAstolfiParams, "max_gain", 1.0, 1e9, False, False),
]  # fmt: skip


@pytest.mark.parametrize(("cls", "field", "low", "high", "low_excluded", "high_excluded"), PARAM_RANGES,
                         ids=[f"{c.__name__}.{f}" for c, f, *_ in PARAM_RANGES])  # fmt: skip
def test_each_controller_parameter_takes_its_range_and_names_itself_outside(
    cls: type, field: str, low: float | None, high: float | None, low_excluded: bool, high_excluded: bool
) -> None:
    for edge, excluded, outside in ((low, low_excluded, -1), (high, high_excluded, 1)):
        if edge is None:
            continue
        beyond = float(np.nextafter(edge, outside * math.inf))  # the next float past the bound
        for value, valid in ((edge, not excluded), (beyond, False)):
            if valid:
                optional = field == "speed_limit"  # None by default: numpy numbers are not converted there
                params = cls.from_kwargs(**{field: np.int64(edge) if edge == int(edge) and not optional else edge})
                assert type(getattr(params, field)) is float and getattr(params, field) == edge
            else:
                with pytest.raises(ValueError, match=re.escape(f"{field}={float(value)!r} is invalid")):
                    cls.from_kwargs(**{field: value})


def test_a_gain_too_large_for_its_own_bound_is_named_itself() -> None:
    for cls in (AstolfiParams, PrescribedTimeAstolfiParams):  # not k_alpha, which must exceed it
        with pytest.raises(ValueError, match=re.escape("k_rho=2000000000.0 is invalid")):
            cls.from_kwargs(k_rho=2e9)


def test_conventional_power_is_an_integer_from_1_to_10() -> None:
    assert ConventionalPTCParams(power=10).power == 10
    for bad in (0, 11, 1.5):
        with pytest.raises(ValueError, match=re.escape(f"power={bad!r} is invalid")):
            ConventionalPTCParams(power=bad)


@pytest.mark.parametrize("name", list(CONTROLLERS))
def test_a_controller_keeps_the_params_it_is_given_and_builds_them_from_keywords(name: str) -> None:
    cls, params_cls = CONTROLLERS[name], type(make_controller(name).params)
    field = {"fabregas": "K0", "astolfi": "k_rho", "pt-astolfi": "k_rho"}.get(name, "Ke")
    given = params_cls.from_kwargs(**{field: 0.3})
    assert cls(given).params is given
    assert cls(**{field: 0.3}).params == given and make_controller(name, **{field: 0.3}).params == given
    if name in ("astolfi", "pt-astolfi"):  # any positive k_rho below k_alpha
        assert make_controller(name, k_rho=1e-9).params.k_rho == 1e-9
    assert repr(cls(given)) == f"{cls.__name__}({given})"
