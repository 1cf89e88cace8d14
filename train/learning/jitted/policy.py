"""The policy of the jitted PPO (``dwr-gym train --backend jax``): stable-baselines3's PPO ``MlpPolicy`` in flax,
and its hyperparameters under the names of train/hyperparams/ppo.yml.

The network is the one SB3 builds for ``PPO("MlpPolicy", env, policy_kwargs=dict(net_arch=[64, 64]))``: separate
actor and critic MLPs of ``net_arch`` with ``activation_fn`` (tanh), a linear mean head, a state-independent
``log_std`` and a linear value head, orthogonally initialised with SB3's gains (sqrt(2) for the hidden layers,
0.01 for the mean, 1 for the value), biases zero. So :mod:`train.learning.jitted.export` can copy the weights into an
SB3 model tensor for tensor.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, fields
from typing import Any

from train.learning.config import ConfigError
from train.learning.jitted.lagrangian import LAGRANGE_DEFAULTS, LagrangeSettings

#: SB3 PPO hyperparameters the jitted trainer implements, with SB3's defaults.
SB3_PPO_DEFAULTS: dict[str, Any] = {
    "n_steps": 2048, "batch_size": 64, "n_epochs": 10, "gamma": 0.99, "gae_lambda": 0.95, "learning_rate": 3e-4,
    "ent_coef": 0.0, "clip_range": 0.2, "vf_coef": 0.5, "max_grad_norm": 0.5, "normalize_advantage": True,
}  # fmt: skip
#: Keys of the YAML that change nothing in the jitted trainer (``policy`` must be MlpPolicy, checked upstream).
IGNORED_KEYS = ("policy", "verbose", "stats_window_size", "tensorboard_log")
POLICY_KEYS = ("net_arch", "activation_fn", "log_std_init", "ortho_init")
#: ``policy_kwargs`` key (ours, not SB3's) that turns on observation normalisation; folded into the first
#: layers on export, so the exported model needs no wrapper.
NORMALIZE_KEY = "normalize_observations"
#: Hyperparameter (ours, both backends' PPO) that anneals the exploration noise: :attr:`PPOSettings.log_std_final`.
ANNEAL_KEY = "log_std_final"
#: Hyperparameter (ours, both backends' PPO): the noise follows that schedule (:attr:`PPOSettings.log_std_fixed`).
FIXED_KEY = "log_std_fixed"


@dataclass(frozen=True)
class PPOSettings:
    """The hyperparameters of one jitted PPO run, named as in train/hyperparams/ppo.yml (SB3's names)."""

    n_envs: int = 256
    """Robots simulated side by side (``--num-envs``)."""
    n_steps: int = 64
    """Steps each robot takes per rollout; one update learns from n_envs * n_steps transitions."""
    batch_size: int = 1024
    """Minibatch size of the gradient steps."""
    n_epochs: int = 4
    """Passes over each rollout."""
    gamma: float = 0.99
    gae_lambda: float = 0.95
    learning_rate: float = 3e-4
    """Adam's step size (eps 1e-5, as SB3); with ``linear_schedule`` it decays linearly to 0 over the budget."""
    linear_schedule: bool = False
    """True for rl-zoo3's ``learning_rate: lin_<value>``."""
    ent_coef: float = 0.0
    clip_range: float = 0.2
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    normalize_advantage: bool = True
    net_arch: tuple[int, ...] = (64, 64)
    activation: str = "tanh"
    """Hidden activation: the lower-case name of policy_kwargs' ``activation_fn`` (nn.Tanh: tanh)."""
    log_std_init: float = 0.0
    ortho_init: bool = True
    log_std_final: float | None = None
    """Anneal the exploration noise (ours, not SB3's): after each update the state-independent log standard
    deviation is capped at log_std_init + (log_std_final - log_std_init) * (env steps done / budget), so that
    the noise, whose energy v1 charges, shrinks towards exp(log_std_final) by the end of the budget. None: learned
    freely, as SB3's."""
    log_std_fixed: bool = False
    """With it the log standard deviation *follows* the schedule of ``log_std_final`` (from log_std_init; constant
    without log_std_final) instead of being capped by it: exploration whatever the reward says. On v2 the energy
    of the noise, charged until T_con, otherwise teaches the agent to shrink it before it has found the goal."""
    normalize_observations: bool = False
    """Scale observations by a running mean and standard deviation (as VecNormalize, without its clipping);
    exported by folding the statistics into the first layers."""
    critic_warmup: int = 0
    """``--critic-warmup``: env steps at the start during which only the critic learns (the actor's gradients are
    zero, so Adam leaves it as it is): a residual agent's advantages then come from a fitted value function."""
    constraint: LagrangeSettings = field(default_factory=LagrangeSettings)
    """PPO-Lagrangian (``lagrangian: 1`` and :class:`train.learning.jitted.lagrangian.LagrangeSettings`' keys): the
    deadline and the heading as constraints, a cost critic and multipliers per T_con bin
    (:mod:`train.learning.jitted.ppo_lagrangian`)."""

    @property
    def steps_per_update(self) -> int:
        return self.n_envs * self.n_steps

    @property
    def minibatch_size(self) -> int:
        """batch_size, or the whole rollout where it is smaller (as SB3 then takes one minibatch of it all)."""
        return min(self.batch_size, self.steps_per_update)

    @property
    def minibatches(self) -> int:
        return self.steps_per_update // self.minibatch_size

    @classmethod
    def from_algo_kwargs(cls, algo_kwargs: dict[str, Any], n_envs: int) -> PPOSettings:
        """The settings of resolved hyperparameters (:func:`train.learning.hyperparams.resolve_hyperparams`);
        a hyperparameter the jitted trainer does not implement is a ConfigError naming it."""
        kwargs = {k: v for k, v in algo_kwargs.items() if k not in IGNORED_KEYS}
        policy = dict(kwargs.pop("policy_kwargs", None) or {})
        log_std_final = kwargs.pop(ANNEAL_KEY, None)
        log_std_fixed = bool(kwargs.pop(FIXED_KEY, False))
        given = {key: kwargs.pop(key) for key in LAGRANGE_DEFAULTS if key in kwargs}
        try:
            constraint = LagrangeSettings.from_values({**LAGRANGE_DEFAULTS, **given})
        except ValueError as error:
            raise ConfigError(str(error)) from None
        unknown = sorted(set(kwargs) - set(SB3_PPO_DEFAULTS))
        if unknown:
            raise ConfigError(f"hyperparameter(s) {unknown} are not implemented by --backend jax; it implements "
                              f"{', '.join(SB3_PPO_DEFAULTS)}, {ANNEAL_KEY}, {FIXED_KEY}, {', '.join(LAGRANGE_DEFAULTS)} "
                              f"and policy_kwargs {', '.join(POLICY_KEYS)}")  # fmt: skip
        unknown = sorted(set(policy) - set(POLICY_KEYS) - {NORMALIZE_KEY})
        if unknown:
            raise ConfigError(f"policy_kwargs {unknown} are not implemented by --backend jax; it implements "
                              f"{', '.join((*POLICY_KEYS, NORMALIZE_KEY))}")  # fmt: skip
        values = {**SB3_PPO_DEFAULTS, **kwargs}
        rate = values.pop("learning_rate")
        linear = isinstance(rate, str)
        arch = policy.get("net_arch", [64, 64])
        if isinstance(arch, dict):
            if arch.get("pi") != arch.get("vf"):
                raise ConfigError(f"policy_kwargs net_arch={arch!r} is invalid for --backend jax: pi and vf must match")
            arch = arch["pi"]
        activation = str(policy.get("activation_fn", "nn.Tanh")).split(".")[-1].lower()
        if activation not in ACTIVATIONS:
            raise ConfigError(f"policy_kwargs activation_fn={policy['activation_fn']!r} is invalid for --backend "
                              f"jax: expected one of {', '.join('nn.' + a.title() for a in ACTIVATIONS)}")  # fmt: skip
        settings = cls(
            n_envs=int(n_envs), n_steps=int(values["n_steps"]), batch_size=int(values["batch_size"]),
            n_epochs=int(values["n_epochs"]), gamma=float(values["gamma"]), gae_lambda=float(values["gae_lambda"]),
            learning_rate=float(rate[4:]) if linear else float(rate), linear_schedule=linear,
            ent_coef=float(values["ent_coef"]), clip_range=float(values["clip_range"]),
            vf_coef=float(values["vf_coef"]), max_grad_norm=float(values["max_grad_norm"]),
            normalize_advantage=bool(values["normalize_advantage"]), net_arch=tuple(int(s) for s in arch),
            activation=activation, log_std_init=float(policy.get("log_std_init", 0.0)),
            ortho_init=bool(policy.get("ortho_init", True)),
            log_std_final=None if log_std_final is None else float(log_std_final), log_std_fixed=log_std_fixed,
            normalize_observations=bool(policy.get(NORMALIZE_KEY, False)), constraint=constraint,
        )  # fmt: skip
        settings.check()
        return settings

    def check(self) -> None:
        """Raise ConfigError unless a rollout splits into whole minibatches."""
        if self.steps_per_update % self.minibatch_size:
            raise ConfigError(
                f"batch_size={self.batch_size} is invalid for --backend jax: it must divide n_steps * n_envs = "
                f"{self.n_steps} * {self.n_envs} = {self.steps_per_update} (the minibatches are a reshape)"
            )

    def log_std_cap(self, fraction: Any) -> Any:
        """The cap on the log standard deviation after ``fraction`` (0-1) of the budget (log_std_final set)."""
        final = self.log_std_init if self.log_std_final is None else self.log_std_final
        return self.log_std_init + (final - self.log_std_init) * fraction

    def as_dict(self) -> dict[str, Any]:
        """The settings by name; the constraint's keys only where it is on (else as before it existed)."""
        values = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "constraint"}
        if self.constraint.lagrangian:
            values.update({f.name: getattr(self.constraint, f.name) for f in fields(self.constraint)})
        return values


ACTIVATIONS = ("tanh", "relu", "elu", "leakyrelu", "silu", "gelu", "sigmoid")
#: torch's class name of each activation (``policy_kwargs``' ``activation_fn``, nn.<name>), by our name.
TORCH_ACTIVATIONS = {"tanh": "Tanh", "relu": "ReLU", "elu": "ELU", "leakyrelu": "LeakyReLU", "silu": "SiLU",
                     "gelu": "GELU", "sigmoid": "Sigmoid"}  # fmt: skip
#: The ``policy_kwargs`` of the actor-only learners (ES, APG): the network, and whether observations are scaled.
NETWORK_KEYS = ("net_arch", "activation_fn", "ortho_init", "normalize_observations")


def actor_hyperparameters(
    algo_kwargs: dict[str, Any], defaults: dict[str, Any], learner: str
) -> tuple[dict[str, Any], dict[str, Any]]:
    """An actor-only learner's (ES, APG) resolved hyperparameters split in two: its own values (``defaults`` with the
    given ones) and ``policy_kwargs``; an unknown key of either, or a policy other than MlpPolicy, is a ConfigError of
    one line naming ``learner``."""
    kwargs = {k: v for k, v in algo_kwargs.items() if k not in ("policy", "verbose")}
    policy = dict(kwargs.pop("policy_kwargs", None) or {})
    unknown = sorted(set(kwargs) - set(defaults))
    if unknown:
        raise ConfigError(f"hyperparameter(s) {unknown} are not accepted by {learner}; accepted: "
                          f"{', '.join(defaults)}, policy_kwargs")  # fmt: skip
    unknown = sorted(set(policy) - set(NETWORK_KEYS))
    if unknown:
        raise ConfigError(f"policy_kwargs {unknown} are not implemented by {learner}; it implements "
                          f"{', '.join(NETWORK_KEYS)}")  # fmt: skip
    if algo_kwargs.get("policy", "MlpPolicy") != "MlpPolicy":
        raise ConfigError(f"policy={algo_kwargs['policy']!r} is invalid: expected 'MlpPolicy'")
    return {**defaults, **kwargs}, policy


def network_fields(policy: dict[str, Any], learner: str) -> dict[str, Any]:
    """The network fields (``net_arch``, ``activation``, ``ortho_init``, ``normalize_observations``) of an actor-only
    learner's settings from ``policy_kwargs`` (checked by train.learning.hyperparams before); a bad activation is a
    ValueError naming ``learner``."""
    from dwr_gym.validation import as_bool

    arch = policy.get("net_arch", [64, 64])
    if isinstance(arch, dict):
        arch = arch.get("pi", [64, 64])
    activation = str(policy.get("activation_fn", "nn.Tanh")).split(".")[-1].lower()
    if activation not in ACTIVATIONS:
        raise ValueError(f"policy_kwargs activation_fn={policy['activation_fn']!r} is invalid for {learner}: expected "
                         f"one of {', '.join('nn.' + a.title() for a in ACTIVATIONS)}")  # fmt: skip
    return {"net_arch": tuple(int(s) for s in arch), "activation": activation,
            "ortho_init": as_bool("ortho_init", policy.get("ortho_init", True)),
            "normalize_observations": as_bool("normalize_observations", policy.get("normalize_observations", True))}  # fmt: skip


def actor_network_settings(settings: Any) -> PPOSettings:
    """The jitted PPO's settings of an actor-only learner's network (``settings`` has ``net_arch``, ``activation``,
    ``ortho_init`` and ``normalize_observations``): :func:`make_network` builds its actor from them."""
    return PPOSettings(n_envs=1, n_steps=1, batch_size=1, net_arch=settings.net_arch, activation=settings.activation,
                       ortho_init=settings.ortho_init, normalize_observations=settings.normalize_observations)  # fmt: skip


def sb3_network_kwargs(net_arch: tuple[int, ...], activation: str, ortho_init: bool) -> dict[str, Any]:
    """The SB3 PPO ``policy_kwargs`` of an actor-only learner's network (the architecture the exporter builds)."""
    return {
        "net_arch": list(net_arch),
        "activation_fn": f"nn.{TORCH_ACTIVATIONS[activation]}",
        "ortho_init": ortho_init,
    }


def activation_function(name: str) -> Any:
    import flax.linen as nn

    return {"tanh": nn.tanh, "relu": nn.relu, "elu": nn.elu, "leakyrelu": nn.leaky_relu, "silu": nn.silu,
            "gelu": lambda x: nn.gelu(x, approximate=False), "sigmoid": nn.sigmoid}[name]  # fmt: skip


def dense_layer(settings: PPOSettings, size: int, gain: float, name: str) -> Any:
    """A dense layer of ``size`` as SB3 initialises one: orthogonal with ``gain`` (``ortho_init``, else LeCun normal),
    zero bias."""
    import flax.linen as nn

    init = nn.initializers.orthogonal(gain) if settings.ortho_init else nn.initializers.lecun_normal()
    return nn.Dense(size, kernel_init=init, bias_init=nn.initializers.zeros, name=name)


def make_network(settings: PPOSettings, action_dim: int) -> Any:
    """The flax module ``ActorCritic``: obs (..., n) -> (mean (..., action_dim), log_std (action_dim,), value (...)).

    Its parameters are named ``policy_<i>``, ``value_<i>`` (hidden layers), ``action`` (the mean head),
    ``value`` (the value head) and ``log_std``, the names :mod:`train.learning.jitted.export` maps onto SB3's.
    """
    import flax.linen as nn
    import jax.numpy as jnp

    dense = functools.partial(dense_layer, settings)
    activation = activation_function(settings.activation)

    class ActorCritic(nn.Module):
        @nn.compact
        def __call__(self, obs: Any) -> tuple[Any, Any, Any]:
            actor, critic = obs, obs
            for i, size in enumerate(settings.net_arch):
                actor = activation(dense(size, math.sqrt(2.0), f"policy_{i}")(actor))
                critic = activation(dense(size, math.sqrt(2.0), f"value_{i}")(critic))
            mean = dense(action_dim, 0.01, "action")(actor)
            value = dense(1, 1.0, "value")(critic)[..., 0]
            log_std = self.param("log_std", nn.initializers.constant(settings.log_std_init), (action_dim,))
            return mean, log_std, jnp.asarray(value)

    return ActorCritic()


def gaussian_log_prob(actions: Any, mean: Any, log_std: Any) -> Any:
    """log N(actions; mean, exp(log_std)^2), summed over the action dimensions (SB3's DiagGaussianDistribution)."""
    import jax.numpy as jnp

    z = (actions - mean) / jnp.exp(log_std)
    return jnp.sum(-0.5 * z**2 - log_std - 0.5 * math.log(2.0 * math.pi), axis=-1)


def gaussian_entropy(log_std: Any) -> Any:
    import jax.numpy as jnp

    return jnp.sum(log_std + 0.5 * (1.0 + math.log(2.0 * math.pi)), axis=-1)
