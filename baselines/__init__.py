"""Analytic controllers for DWR point stabilization, and their expert-policy wrapper."""

from baselines.base import Controller, ControllerInput
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
from baselines.expert import ExpertPolicy, controller_input_from_observation
from baselines.polar import (
    AstolfiController,
    AstolfiParams,
    PrescribedTimeAstolfiController,
    PrescribedTimeAstolfiParams,
)
from baselines.registry import CONTROLLER_NAMES, CONTROLLERS, make_controller

__all__ = [
    "CONTROLLERS",
    "CONTROLLER_NAMES",
    "AstolfiController",
    "AstolfiParams",
    "Controller",
    "ControllerInput",
    "ConventionalPTCController",
    "ConventionalPTCParams",
    "ExpertPolicy",
    "FabregasController",
    "FabregasParams",
    "FixedTimeController",
    "FixedTimeParams",
    "PTCController",
    "PTCParams",
    "PrescribedTimeAstolfiController",
    "PrescribedTimeAstolfiParams",
    "controller_input_from_observation",
    "make_controller",
]
