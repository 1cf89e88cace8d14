"""The controllers by name: what ``--controllers``, ``--expert`` and :func:`make_controller` accept.

The registry imports the laws; no law imports the registry, so a new law is added here, in one place.
"""

from __future__ import annotations

from typing import Any

from baselines.base import Controller, ControllerParams
from baselines.controllers import (
    ConventionalPTCController,
    ConventionalPTCParams,
    FabregasController,
    FabregasParams,
    FixedTimeController,
    FixedTimeParams,
    PTCController,
    PTCParams,
)
from baselines.polar import (
    AstolfiController,
    AstolfiParams,
    PrescribedTimeAstolfiController,
    PrescribedTimeAstolfiParams,
)

CONTROLLERS: dict[str, type[Controller]] = {
    cls.name: cls
    for cls in (
        PTCController,
        ConventionalPTCController,
        FabregasController,
        FixedTimeController,
        AstolfiController,
        PrescribedTimeAstolfiController,
    )
}
PARAMS: dict[str, type[ControllerParams]] = {
    "ptc": PTCParams,
    "conventional-ptc": ConventionalPTCParams,
    "fabregas": FabregasParams,
    "fixed-time": FixedTimeParams,
    "astolfi": AstolfiParams,
    "pt-astolfi": PrescribedTimeAstolfiParams,
}

#: Every name :func:`make_controller` knows: the analytic laws above, the minimum-energy NMPC ``optimal`` of
#: :mod:`baselines.nmpc` and the robust prescribed-time expert ``robust-pt`` of :mod:`baselines.robust` (both plan
#: with CasADi: the ``optimal`` extra).
CONTROLLER_NAMES: tuple[str, ...] = (*CONTROLLERS, "optimal", "robust-pt")


def make_controller(name: str, **kwargs: Any) -> Controller:
    """A controller by its name (one of :data:`CONTROLLER_NAMES`)."""
    if name == "optimal":
        from baselines.nmpc import OptimalController, OptimalParams

        return OptimalController(OptimalParams.from_kwargs(**kwargs))
    if name == "robust-pt":
        from baselines.robust import RobustPTController, RobustPTParams

        return RobustPTController(RobustPTParams.from_kwargs(**kwargs))
    if name not in CONTROLLERS:
        raise ValueError(f"controller={name!r} is invalid: expected one of {', '.join(CONTROLLER_NAMES)}")
    return CONTROLLERS[name](PARAMS[name].from_kwargs(**kwargs))  # type: ignore[call-arg]


__all__ = ["CONTROLLERS", "CONTROLLER_NAMES", "PARAMS", "make_controller"]
