"""Hand-over policies: a learned policy that hands the robot to an analytic prescribed-time law for the finish."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.expert import ExpertPolicy
from dwr_gym.params import check_range


class HandoverPolicy:
    """A learned policy that hands the robot over to an analytic prescribed-time law for the finish.

    The network acts until, for the current observation, the robot is within ``distance`` of the goal, or the
    time is past ``time_fraction`` T_con, or the time left is less than ``speed_margin`` times the straight-line
    time d / u_max (the network is behind schedule); then the ``expert`` acts. Put as a residual on the law:
    action = law + w (network - law) with w = 1 before the hand-over and 0 after it. Networks cloned from
    minimum-energy plans spend little energy but miss the last centimetres (see train.learning.imitation.dagger); a
    prescribed-time law that also steers the heading (``pt-astolfi``) finishes from wherever they are.
    """

    def __init__(
        self, model: Any, expert: ExpertPolicy, distance: float, time_fraction: float, speed_margin: float = 0.0
    ) -> None:
        self.model = model
        self.expert = expert
        self.distance = check_range("handover distance", distance, 0.0, 1e6)
        self.time_fraction = check_range("handover time_fraction", time_fraction, 0.0, 1.0, low_inclusive=False)
        self.speed_margin = check_range("handover speed_margin", speed_margin, 0.0, 1e6)

    def handing_over(self, batch: NDArray[np.floating]) -> NDArray[np.bool_]:
        """Which observations (N, 10) the law acts on (features: 0 distance, 6 t / T_con, 7 T_con)."""
        time_left = batch[:, 7] * (1.0 - batch[:, 6])
        behind = time_left < self.speed_margin * batch[:, 0] / self.expert.u_max
        return (batch[:, 0] < self.distance) | (batch[:, 6] > self.time_fraction) | behind

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], Any]:
        obs = np.asarray(observation)
        batch = obs[None] if obs.ndim == 1 else obs
        learned, state = self.model.predict(batch, state, episode_start, deterministic)
        expert, _ = self.expert.predict(batch, episode_start=episode_start)
        action = np.where(self.handing_over(batch)[:, None], expert, np.clip(learned, -1.0, 1.0)).astype(np.float32)
        return (action[0] if obs.ndim == 1 else action), state


def make_handover_policy(
    model: Any, expert: str, params: Any, distance: float, time_fraction: float, speed_margin: float = 0.0
) -> HandoverPolicy:
    """``model`` handing over to the controller named ``expert``, scaled to the action limits of ``params`` (EnvParams)."""
    from baselines.registry import make_controller

    law = ExpertPolicy(make_controller(expert), params.u_max, params.omega_max)
    return HandoverPolicy(model, law, distance, time_fraction, speed_margin)
