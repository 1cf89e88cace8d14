"""The jitted PPO's weights written into a stable-baselines3 PPO ``MlpPolicy`` of the same architecture, so that a
run of ``dwr-gym train --backend jax`` leaves SB3 model files that ``train.learning.agents.load_agent``,
``dwr-gym evaluate``, ``compare`` and ``robustness`` load like any other.

SB3's deterministic action is clip(mean) to the action space, the same as the JAX policy's. Observation
normalisation, when the run used it, is folded into the first hidden layer of the actor and of the critic
(``W' = W / sigma``, ``b' = b - (mu / sigma) W``), so the exported model takes raw observations and needs no wrapper.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from train.learning.jitted.policy import NORMALIZE_KEY


def folded_params(params: Any, obs_mean: Any = None, obs_var: Any = None) -> dict[str, dict[str, np.ndarray]]:
    """The network's parameters as float64 numpy arrays, with the observation scaling (if given) folded into
    the first layers: a network on raw observations that computes what ``params`` computes on normalised ones."""
    from train.learning.jitted.ppo import OBS_EPSILON

    layers = {name: {k: np.asarray(v, np.float64) for k, v in layer.items()} if isinstance(layer, dict) else layer
              for name, layer in params["params"].items()}  # fmt: skip
    layers["log_std"] = np.asarray(params["params"]["log_std"], np.float64)
    if obs_mean is not None:
        scale = 1.0 / np.sqrt(np.asarray(obs_var, np.float64) + OBS_EPSILON)
        shift = np.asarray(obs_mean, np.float64) * scale
        for name in ("policy_0", "value_0"):
            kernel, bias = layers[name]["kernel"], layers[name]["bias"]
            layers[name] = {"kernel": kernel * scale[:, None], "bias": bias - shift @ kernel}
    return layers


def sb3_policy_kwargs(algo_kwargs: dict[str, Any]) -> dict[str, Any]:
    """The SB3 constructor keywords of the resolved hyperparameters, without our own policy keywords."""
    from train.learning.hyperparams import build_algo_kwargs

    kwargs = dict(algo_kwargs)
    kwargs["policy_kwargs"] = {k: v for k, v in (kwargs.get("policy_kwargs") or {}).items() if k != NORMALIZE_KEY}
    kwargs.pop("policy", None)
    return build_algo_kwargs(kwargs)


class SB3Exporter:
    """An SB3 PPO model built once on the native env with the run's hyperparameters; :meth:`load` copies JAX
    weights into it, :meth:`save` writes it as a model .zip."""

    def __init__(self, vec_env: Any, algo_kwargs: dict[str, Any], seed: int = 0) -> None:
        from stable_baselines3 import PPO

        self.model = PPO("MlpPolicy", vec_env, seed=seed, device="cpu", verbose=0, **sb3_policy_kwargs(algo_kwargs))

    def load(self, params: Any, obs_mean: Any = None, obs_var: Any = None, timesteps: int = 0) -> Any:
        """The SB3 model holding ``params`` (and the folded observation scaling); returns the model."""
        import torch

        layers = folded_params(params, obs_mean, obs_var)
        policy = self.model.policy
        hidden = {"policy": policy.mlp_extractor.policy_net, "value": policy.mlp_extractor.value_net}
        targets: list[tuple[Any, dict[str, np.ndarray]]] = [
            (policy.action_net, layers["action"]),
            (policy.value_net, layers["value"]),
        ]
        for prefix, sequential in hidden.items():
            linears = [m for m in sequential if isinstance(m, torch.nn.Linear)]
            names = sorted((k for k in layers if k.startswith(f"{prefix}_")), key=lambda k: int(k.split("_")[1]))
            if len(linears) != len(names):
                raise ValueError(f"the SB3 policy has {len(linears)} {prefix} layers, the JAX network {len(names)}")
            targets += [(linear, layers[name]) for linear, name in zip(linears, names, strict=True)]
        with torch.no_grad():
            for linear, layer in targets:
                if tuple(linear.weight.shape) != layer["kernel"].T.shape:
                    raise ValueError(f"layer shapes differ: SB3 {tuple(linear.weight.shape)}, JAX "
                                     f"{layer['kernel'].T.shape}")  # fmt: skip
                linear.weight.copy_(torch.as_tensor(layer["kernel"].T, dtype=linear.weight.dtype))
                linear.bias.copy_(torch.as_tensor(layer["bias"], dtype=linear.bias.dtype))
            policy.log_std.copy_(torch.as_tensor(layers["log_std"], dtype=policy.log_std.dtype))
        self.model.num_timesteps = int(timesteps)
        return self.model

    def save(self, path: Any) -> None:
        self.model.save(path)
