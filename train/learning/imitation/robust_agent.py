"""The robust prescribed-time agent: ``robust-pt`` whose cruise is a learned network (see train.learning.imitation.robust_dagger)."""

from __future__ import annotations

from typing import Any

from dwr_gym.params import EnvParams


def agent(model: Any, params: EnvParams, **robust_kwargs: Any) -> Any:
    """The whole agent: ``robust-pt`` (with ``robust_kwargs``) whose cruise is the network."""
    from baselines.expert import ExpertPolicy
    from baselines.robust import RobustPTController, RobustPTParams

    controller_params = RobustPTParams.from_kwargs(dt=params.dt, u_max=params.u_max, omega_max=params.omega_max,
                                                   k=params.k, **robust_kwargs)  # fmt: skip
    return ExpertPolicy(RobustPTController(controller_params, cruise=model), params.u_max, params.omega_max)
