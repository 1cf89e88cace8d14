"""Analytic controllers for DWR point stabilization, and their expert-policy wrapper."""

from baselines.controllers import (
    CONTROLLER_NAMES,
    CONTROLLERS,
    AstolfiController,
    AstolfiParams,
    Controller,
    ControllerInput,
    ConventionalPTCController,
    ConventionalPTCParams,
    FabregasController,
    FabregasParams,
    FixedTimeController,
    FixedTimeParams,
    PrescribedTimeAstolfiController,
    PrescribedTimeAstolfiParams,
    PTCController,
    PTCParams,
    make_controller,
)
from baselines.expert import ExpertPolicy, controller_input_from_observation

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
