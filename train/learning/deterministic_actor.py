"""An on-policy agent's deterministic action without stable-baselines3's per-call bookkeeping.

``model.predict(obs, deterministic=True)`` of a PPO or A2C model with a Gaussian policy is the actor network's mean,
clipped to the action space. Around those three layers SB3 switches the modules to evaluation mode (a walk over
every submodule), builds a ``torch.distributions.Normal`` and checks its arguments, on every call: on a batch of
1,000 robots that bookkeeping is as long as the network itself, and ``dwr-gym compare`` calls it some 50,000 times.
:class:`DeterministicActor` computes the same mean with the same modules, in the same order and precision (float32
features, the policy's own ``extract_features``, ``mlp_extractor.forward_actor`` and ``action_net``), so its actions
equal ``predict``'s to the last bit (``tests/test_deterministic_actor.py`` checks every shipped agent); any other
model, or a stochastic action, goes to ``predict`` as before.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def deterministic_actor(model: Any) -> Any:
    """``model`` wrapped in a :class:`DeterministicActor` where its deterministic action is the Gaussian policy's mean
    (SB3's ``ActorCriticPolicy`` with a ``DiagGaussianDistribution``, unsquashed, on flat Box spaces); else ``model``."""
    try:
        from gymnasium import spaces
        from stable_baselines3.common.distributions import DiagGaussianDistribution
        from stable_baselines3.common.policies import ActorCriticPolicy
    except ImportError:  # pragma: no cover - SB3 is a dependency of every saved agent
        return model
    policy = getattr(model, "policy", None)
    if (
        not isinstance(policy, ActorCriticPolicy)
        or any(  # a subclass that acts otherwise (a recurrent or masked policy): leave it to predict
            getattr(type(policy), name) is not getattr(ActorCriticPolicy, name)
            for name in ("predict", "_predict", "get_distribution", "_get_action_dist_from_latent")
        )
        or type(policy.action_dist) is not DiagGaussianDistribution
        or policy.squash_output
        or not isinstance(policy.action_space, spaces.Box)
        or not isinstance(policy.observation_space, spaces.Box)
    ):
        return model
    return DeterministicActor(model)


class DeterministicActor:
    """``predict`` of an SB3 Gaussian actor-critic: the mean action computed directly when ``deterministic``, the
    model's own ``predict`` otherwise; every other attribute is the model's."""

    def __init__(self, model: Any) -> None:
        self.model = model
        policy = model.policy
        self._obs_shape = policy.observation_space.shape
        self._low, self._high = policy.action_space.low, policy.action_space.high
        self._action_shape = policy.action_space.shape

    def __getattr__(self, name: str) -> Any:
        return getattr(self.model, name)

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = False
    ) -> tuple[NDArray[Any], Any]:
        """As ``model.predict``; the deterministic action without building a distribution."""
        import torch as th

        if not deterministic:
            return self.model.predict(observation, state, episode_start, deterministic)
        observation = np.array(observation)
        vectorized = observation.shape != self._obs_shape
        if vectorized and observation.shape[1:] != self._obs_shape:  # predict's own error for a wrong shape
            return self.model.predict(observation, state, episode_start, deterministic)
        policy = self.model.policy
        if policy.training:  # as predict does (on every call: here only when a learner switched it back)
            policy.set_training_mode(False)
        with th.no_grad():
            obs = th.as_tensor(observation.reshape((-1, *self._obs_shape)), device=policy.device)
            features = policy.extract_features(obs, policy.pi_features_extractor)
            mean = policy.action_net(policy.mlp_extractor.forward_actor(features))
        actions = np.clip(mean.cpu().numpy().reshape((-1, *self._action_shape)), self._low, self._high)
        return (actions if vectorized else actions.squeeze(axis=0)), state
