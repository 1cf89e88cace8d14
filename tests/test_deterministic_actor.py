"""The deterministic actor (train.learning.deterministic_actor) acts as stable-baselines3's predict, to the last bit."""

from __future__ import annotations

import numpy as np
import pytest

from train.learning.agents import load_agent, pretrained_paths
from train.learning.deterministic_actor import DeterministicActor, deterministic_actor


def _observations(model, n: int, seed: int) -> np.ndarray:
    space = model.observation_space
    rng = np.random.default_rng(seed)
    low, high = np.maximum(space.low, -5.0), np.minimum(space.high, 5.0)
    return rng.uniform(low, high, size=(n, *space.shape)).astype(space.dtype)


@pytest.mark.parametrize("name", sorted(pretrained_paths()))
def test_every_shipped_agent_acts_as_predict_to_the_last_bit(name: str) -> None:
    from stable_baselines3 import PPO

    from train.learning.hyperparams import algorithm_class
    from train.learning.runs import MODEL_FILE, load_config

    path = pretrained_paths()[name]
    config = load_config(path)
    model = algorithm_class(config.algo, config.backend).load(path / MODEL_FILE, device="cpu")
    actor = deterministic_actor(model)
    if isinstance(model, PPO):
        assert isinstance(actor, DeterministicActor)
    obs = _observations(model, 257, seed=1)
    expected, _ = model.predict(obs, deterministic=True)
    actions, _ = actor.predict(obs, deterministic=True)
    assert actions.dtype == expected.dtype and actions.shape == expected.shape
    np.testing.assert_array_equal(actions, expected)
    single, _ = actor.predict(obs[3], deterministic=True)  # one observation: one action, as predict
    np.testing.assert_array_equal(single, model.predict(obs[3], deterministic=True)[0])


def test_a_stochastic_action_and_a_wrong_shape_go_to_predict() -> None:
    from stable_baselines3 import PPO

    from dwr_gym.env import DWRPointStabilizationEnv

    model = PPO("MlpPolicy", DWRPointStabilizationEnv(), n_steps=8, batch_size=8, seed=0, device="cpu")
    actor = deterministic_actor(model)
    assert isinstance(actor, DeterministicActor)
    obs = _observations(model, 5, seed=2)
    model.set_random_seed(3)
    expected, _ = model.predict(obs, deterministic=False)
    model.set_random_seed(3)
    np.testing.assert_array_equal(actor.predict(obs, deterministic=False)[0], expected)
    with pytest.raises(ValueError):
        actor.predict(np.zeros((5, 3), dtype=np.float32), deterministic=True)
    model.policy.set_training_mode(True)  # as a learner leaves it: switched back, as predict does
    actor.predict(obs, deterministic=True)
    assert not model.policy.training


@pytest.mark.parametrize("name", ["ppo", "residual-ppo"])
def test_the_loaded_agents_use_it(name: str) -> None:
    _, policy = load_agent(pretrained_paths()[name])
    assert isinstance(policy if name == "ppo" else policy.model, DeterministicActor)


def test_a_policy_that_acts_otherwise_keeps_its_own_predict() -> None:
    from stable_baselines3 import PPO
    from stable_baselines3.common.policies import ActorCriticPolicy

    from dwr_gym.env import DWRPointStabilizationEnv

    class Shifted(ActorCriticPolicy):
        def _predict(self, observation, deterministic=False):  # type: ignore[no-untyped-def]
            return super()._predict(observation, deterministic) + 0.5

    model = PPO(Shifted, DWRPointStabilizationEnv(), n_steps=8, batch_size=8, seed=0, device="cpu")
    assert deterministic_actor(model) is model
