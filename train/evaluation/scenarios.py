"""The scenario sets: named start and goal poses with the env keywords they are run with.

``paper-fig5`` and ``paper-fig7`` are the paper's figures (their own T_con and gains); ``random`` draws
seeded starts from the env's start ranges; the robustness sets of :mod:`train.evaluation.disturbance_sets`
are the random starts on an imperfect robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.base import Controller
from baselines.registry import make_controller
from dwr_gym import core
from dwr_gym.disturbances import split_env_kwargs
from dwr_gym.params import EnvParams
from train.evaluation.disturbance_sets import ROBUSTNESS_SETS, robustness_env_kwargs

SCENARIO_SETS: tuple[str, ...] = ("paper-fig5", "paper-fig7", "random")
FIG5_HEADINGS = (0.0, -math.pi / 4, -math.pi / 2, -3 * math.pi / 4, math.pi, 3 * math.pi / 4, math.pi / 2, math.pi / 4)


@dataclass(frozen=True)
class Scenario:
    """A named set of N start and goal poses (world frame) with the env keywords they are run with."""

    name: str
    starts: NDArray[np.float64]  # (N, 3)
    goals: NDArray[np.float64]  # (N, 3)
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    controller_kwargs: dict[str, dict[str, Any]] = field(default_factory=dict)
    """Per-controller keyword overrides, e.g. the paper's gains for its figure."""
    labels: tuple[str, ...] = ()
    T_cons: NDArray[np.float64] | None = None
    """Each episode's prescribed time (N,) when the env draws T_con per episode (``T_con_range``)."""

    @property
    def size(self) -> int:
        return int(self.starts.shape[0])


def make_scenario(name: str, n: int = 100, seed: int = 0, env_kwargs: dict[str, Any] | None = None) -> Scenario:
    """A named scenario set: 'paper-fig5', 'paper-fig7' or 'random' (``n`` seeded random starts).

    The paper's sets keep the paper's T_con (20 s and 70 s; a ``T_con`` in ``env_kwargs`` replaces it) and
    ignore a ``T_con_range``; the random sets draw each episode's T_con from ``T_con_range`` when there is one.
    """
    env_kwargs = dict(env_kwargs or {})
    if name in ("paper-fig5", "paper-fig7"):
        env_kwargs.pop("T_con_range", None)
    if name == "paper-fig5":
        starts = np.array([(0.0, 0.0, h) for h in FIG5_HEADINGS])
        goals = np.tile([0.8, 0.0, 0.0], (len(FIG5_HEADINGS), 1))
        labels = tuple(f"psi0={math.degrees(h):+.0f}deg" for h in FIG5_HEADINGS)
        return Scenario(name, starts, goals, {"T_con": 20.0, **env_kwargs}, {}, labels)
    if name == "paper-fig7":
        starts = np.array([[-0.4, 0.0, math.radians(-178.0)]])
        goals = np.array([[0.8, 0.0, 0.0]])
        gains = {"ptc": {"K1": 2.5, "K2": 40.0, "K": 1.2}, "conventional-ptc": {"K1": 2.5, "K2": 40.0}}
        return Scenario(name, starts, goals, {"T_con": 70.0, **env_kwargs}, gains, ("psi0=-178deg",))
    if name == "random" or name in ROBUSTNESS_SETS:
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ValueError(f"n={n!r} is invalid: expected an integer >= 1")
        params = EnvParams.from_kwargs(**split_env_kwargs(env_kwargs)[0])
        if name in ROBUSTNESS_SETS:  # the random starts, on the imperfect robot
            env_kwargs = {**robustness_env_kwargs(name, params.T_con), **env_kwargs}
        rng = np.random.default_rng(seed)
        local = np.array([core.sample_start(rng, params) for _ in range(n)])
        T_cons = None if params.T_con_range is None else rng.uniform(*params.T_con_range, size=n)
        return Scenario(name, local, np.zeros((n, 3)), env_kwargs, {}, (), T_cons)
    raise ValueError(f"scenario={name!r} is invalid: expected one of {', '.join((*SCENARIO_SETS, *ROBUSTNESS_SETS))}")


def controller_for(name: str, scenario: Scenario, params: EnvParams, **overrides: Any) -> Controller:
    """Controller ``name`` configured for a scenario: its T_con (and dt for the integral law), its presets."""
    kwargs: dict[str, Any] = {}
    if name in ("ptc", "conventional-ptc"):
        kwargs["T_con"] = params.T_con  # the expert reads T_con from the observation; this keeps repr honest
    if name == "fabregas":
        kwargs["dt"] = params.dt
    if name in ("optimal", "robust-pt"):
        kwargs.update(T_con=params.T_con, dt=params.dt, u_max=params.u_max, omega_max=params.omega_max)
    kwargs.update(scenario.controller_kwargs.get(name, {}))
    kwargs.update(overrides)
    return make_controller(name, **kwargs)
