"""RL fine-tuning of a saved network (``dwr-gym train --init-from``): the run adopts the saved agent's architecture,
starts from its weights (actor, critic and the exploration noise's log_std), and with ``--critic-warmup N`` lets
only the value function learn for the first N env steps, so that a critic that cloning never trained does not
steer the first policy updates (the RL benchmark's robust RL).
"""

from __future__ import annotations

from typing import Any

from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import algorithm_class
from train.learning.runs import saved_model


def load_source(config: TrainConfig) -> Any:
    """The saved model of ``--init-from``, loaded on the CPU; a ConfigError names it if it is not this algorithm's."""
    path = saved_model(str(config.init_from))
    if not path.is_file():
        raise ConfigError(f"--init-from {config.init_from!r} is invalid: {path} does not exist")
    try:
        return algorithm_class(config.algo).load(path, device="cpu")
    except Exception as error:  # a zip of another algorithm or no SB3 model at all
        raise ConfigError(f"--init-from {config.init_from!r} is invalid: not a {config.algo.upper()} model "
                          f"({type(error).__name__}: {str(error)[:120]})") from None  # fmt: skip


def adopt_architecture(config: TrainConfig, source: Any) -> None:
    """Set the run's network architecture (``net_arch``, ``activation_fn``) to the saved model's, in place."""
    saved = dict(getattr(source, "policy_kwargs", {}) or {})
    kwargs = dict(config.algo_kwargs.get("policy_kwargs") or {})
    if "net_arch" in saved:
        kwargs["net_arch"] = saved["net_arch"]
    if "activation_fn" in saved:
        kwargs["activation_fn"] = f"nn.{saved['activation_fn'].__name__}"
    config.algo_kwargs["policy_kwargs"] = kwargs


def load_weights(model: Any, source: Any) -> None:
    """Copy the saved policy's parameters into ``model``'s (the whole policy: actor, critic, log_std)."""
    try:
        model.policy.load_state_dict(source.policy.state_dict())
    except RuntimeError as error:
        raise ConfigError(f"--init-from: the saved network does not fit this run's: {str(error)[:200]}") from None


def actor_parameters(policy: Any) -> list[Any]:
    """The parameters of PPO's actor: its hidden layers, the mean head and log_std (not the critic's)."""
    params = [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]
    if isinstance(getattr(policy, "log_std", None), type(params[0])):
        params.append(policy.log_std)
    return params


def make_warmup_callback(warmup: int) -> Any:
    """A callback that freezes the actor until ``warmup`` env steps are done (their gradients are not computed,
    so Adam leaves them as they are), then lets it learn."""
    from stable_baselines3.common.callbacks import BaseCallback

    class CriticWarmup(BaseCallback):
        def _on_step(self) -> bool:
            return True

        def _on_rollout_start(self) -> None:  # before the rollout whose update comes next
            frozen = self.num_timesteps < warmup
            for param in actor_parameters(self.model.policy):
                param.requires_grad_(not frozen)

        def _on_training_start(self) -> None:
            self._on_rollout_start()

    return CriticWarmup()


__all__ = ["actor_parameters", "adopt_architecture", "load_source", "load_weights", "make_warmup_callback"]
