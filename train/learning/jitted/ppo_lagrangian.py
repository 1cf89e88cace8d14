"""PPO-Lagrangian on the jitted PPO (``lagrangian: 1`` in the hyperparameters of ``--algo ppo --backend jax``): the
on-policy reference of constrained RL (Ray, Achiam and Amodei 2019; OmniSafe's PPOLag), with the multipliers of the
Lagrangian APG (:mod:`train.learning.jitted.lagrangian`: per T_con bin, in PID form).

The constrained MDP is the env's (docs/environment.md): the return, v2's energy and miss, is maximised subject to

- the deadline: the per-step cost ``info["cost"]`` (1 at the step that ends an episode not in time), whose episode
  sum is the deadline violation, at a rate of at most ``cost_budget`` per T_con bin;
- the heading: the per-step cost ``info["heading_violation"]`` (the final |heading error| beyond the env's heading
  tolerance, 0 on v2: |psi| itself, paid at the step that ends the episode), at a mean of at most ``heading_budget``.

Beside the network of the jitted PPO (exported to SB3 unchanged), a cost critic (an MLP of the same ``net_arch``
with one output per constraint, parameters ``params["cost"]``) learns each cost's value; GAE gives the cost
advantages A_c as it gives the reward's A_r (with the same gamma and lambda, the same truncation bootstrap). Each
update first measures, on the episodes that ended in its rollout, the violation rate and mean heading error per T_con
bin and moves the multipliers by :func:`train.learning.jitted.lagrangian.pid_update` (a bin where no episode ended
keeps its multipliers); then the epochs follow the clipped surrogate of the combined advantage

    A = (A_r - sum_c lambda_c(T_con bin) A_c) / (1 + sum_c lambda_c(T_con bin)),

each transition's multipliers those of its episode's T_con bin. The division keeps the advantage's scale as the
multipliers grow (OmniSafe's ``_compute_adv_surrogate``). With ``normalize_advantage`` A_r is standardised per
minibatch (SB3's PPO) and each A_c centred only (OmniSafe's ``standardized_adv_c``), so that lambda weighs a cost in
its own units against the reward's standardised advantage. The cost critic's squared error enters the loss with
``vf_coef``, as the value's.

The multipliers live in the runner (:class:`LagrangianRunner`), so a run saves and resumes them bit for bit.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp

from train.learning.config import ConfigError
from train.learning.jitted import lagrangian
from train.learning.jitted.policy import (
    PPOSettings,
    activation_function,
    dense_layer,
    gaussian_entropy,
    gaussian_log_prob,
)
from train.learning.jitted.ppo import JaxPPO, Runner, Transition, clipped_surrogate, gae

#: The env's info keys a transition keeps: the two costs (deadline, heading, in the order of
#: :data:`train.learning.jitted.lagrangian.CONSTRAINTS`), the episode's T_con (its bin) and energy (the log's).
COST_KEYS = ("cost", "heading_violation")
INFO_KEYS = (*COST_KEYS, "T_con", "energy")


class LagrangianRunner(Runner):
    """:class:`train.learning.jitted.ppo.Runner` and the multipliers' PID state
    (:class:`train.learning.jitted.lagrangian.Multipliers`, arrays (2, bins))."""

    multipliers: Any


def make_cost_critic(settings: PPOSettings, costs: int) -> nn.Module:
    """The cost critic: obs (..., n) -> the value of each of ``costs`` costs (..., costs), an MLP of ``net_arch``
    with the value network's activation and initialisation (SB3's gains: sqrt(2) hidden, 1 for the head)."""

    dense = functools.partial(dense_layer, settings)
    activation = activation_function(settings.activation)

    class CostCritic(nn.Module):
        @nn.compact
        def __call__(self, obs: Any) -> Any:
            hidden = obs
            for i, size in enumerate(settings.net_arch):
                hidden = activation(dense(size, math.sqrt(2.0), f"cost_{i}")(hidden))
            return dense(costs, 1.0, "cost")(hidden)

    return CostCritic()


class JaxPPOLagrangian(JaxPPO):
    """:class:`train.learning.jitted.ppo.JaxPPO` with the constraints (module docstring): its runner a
    :class:`LagrangianRunner`, its parameters ``{"params": the PPO network's, "cost": the cost critic's}``."""

    info_keys = INFO_KEYS

    def __init__(self, settings: PPOSettings, env: Any, env_params: Any) -> None:
        if not settings.constraint.lagrangian:
            raise ConfigError("PPO-Lagrangian needs lagrangian=1 in its hyperparameters")
        if not hasattr(env_params, "T_con_range"):
            raise ConfigError("lagrangian=1 is invalid for this env: its multipliers are per T_con bin, and the env "
                              "draws no T_con (expected a DWRPointStabilization env)")  # fmt: skip
        super().__init__(settings, env, env_params)
        self.constraint = settings.constraint
        self.cost_critic = make_cost_critic(settings, len(lagrangian.CONSTRAINTS))

    def _init(self, rng: Any) -> LagrangianRunner:
        runner = super()._init(rng)
        cost = self.cost_critic.init(jax.random.fold_in(rng, 1), jnp.zeros((self.obs_dim,), jnp.float32))
        params = {**runner.params, "cost": cost["params"]}
        fields = {f.name: getattr(runner, f.name) for f in dataclasses.fields(runner)}
        fields.update(params=params, opt_state=self.optimizer.init(params))
        multipliers = lagrangian.initial_multipliers(self.constraint, jnp)
        return LagrangianRunner(**fields, multipliers=multipliers)

    def policy(self, params: Any, obs: Any) -> tuple[Any, Any, Any]:
        return self.network.apply({"params": params["params"]}, obs)

    def cost_values(self, params: Any, obs: Any) -> Any:
        """Each cost's value (..., 2) of the observations."""
        return self.cost_critic.apply({"params": params["cost"]}, obs)

    def zero_metrics(self) -> dict[str, Any]:
        """PPO's metrics and, summed per T_con bin (bins,), the episodes ended and their costs and energy."""
        bins = jnp.zeros(self.constraint.multiplier_bins, jnp.float32)
        return {**super().zero_metrics(), "bin_episodes": bins, "bin_cost": bins, "bin_heading": bins,
                "bin_energy": bins}  # fmt: skip

    def prepare(self, runner: Any, transitions: Transition) -> tuple[Any, tuple[Any, ...], dict[str, Any]]:
        """The multipliers moved by this rollout's ended episodes, then PPO's batch with the cost advantages, the
        cost returns and each transition's multipliers."""
        s, constraint = self.settings, self.constraint
        info = transitions.info
        done = transitions.terminated | transitions.truncated
        bins = lagrangian.T_con_bin(info["T_con"], self.env_params.T_con_range, constraint.multiplier_bins, jnp)
        # (a step that ends no episode in bin -1: no bin counts it)
        ended_bin = jnp.where(done, bins, -1).reshape(-1)
        measured, counts = lagrangian.violations(info["cost"].reshape(-1), info["heading_violation"].reshape(-1),
                                                 ended_bin, constraint, jnp)  # fmt: skip
        energy, _ = lagrangian.binned_means(info["energy"].reshape(1, -1), ended_bin, constraint.multiplier_bins, jnp)
        multipliers = lagrangian.pid_update(runner.multipliers, measured, counts, constraint, jnp)
        runner = runner.replace(multipliers=multipliers)

        advantages, returns = self.advantages(runner.params, transitions, runner.obs)
        costs = jnp.stack([info[name] for name in COST_KEYS], axis=-1)  # (n_steps, n_envs, 2)
        cost_values = self.cost_values(runner.params, transitions.obs)
        final_costs = self.cost_values(runner.params, transitions.final_obs)
        last_costs = self.cost_values(runner.params, runner.obs)
        per_cost = jax.vmap(gae, in_axes=(2, 2, None, None, 2, 1, None, None), out_axes=2)
        cost_advantages, cost_returns = per_cost(costs, cost_values, transitions.terminated, transitions.truncated,
                                                 final_costs, last_costs, s.gamma, s.gae_lambda)  # fmt: skip
        weights = jnp.moveaxis(multipliers.value[:, bins], 0, -1)  # (n_steps, n_envs, 2): each episode's bin's
        batch = (transitions.obs, transitions.action, transitions.log_prob, advantages, returns, cost_advantages,
                 cost_returns, weights)  # fmt: skip
        metrics = {"bin_episodes": counts, "bin_cost": measured[0] * counts, "bin_heading": measured[1] * counts,
                   "bin_energy": energy[0] * counts}  # fmt: skip
        return runner, batch, metrics

    def loss(self, params: Any, batch: tuple[Any, ...]) -> Any:
        """The clipped surrogate of the combined advantage (module docstring) + ent_coef * (-entropy) + vf_coef *
        (the value's squared error + the cost critic's, summed over the costs)."""
        s = self.settings
        obs, actions, old_log_prob, advantages, returns, cost_advantages, cost_returns, weights = batch
        mean, log_std, values = self.policy(params, obs)
        if s.normalize_advantage and advantages.shape[0] > 1:
            advantages = (advantages - advantages.mean()) / (jnp.std(advantages, ddof=1) + 1e-8)
            cost_advantages = cost_advantages - cost_advantages.mean(axis=0)
        combined = (advantages - jnp.sum(weights * cost_advantages, axis=-1)) / (1.0 + jnp.sum(weights, axis=-1))
        policy_loss = clipped_surrogate(gaussian_log_prob(actions, mean, log_std), old_log_prob, combined,
                                        s.clip_range)  # fmt: skip
        value_loss = jnp.mean((returns - values) ** 2)
        cost_loss = jnp.mean(jnp.sum((cost_returns - self.cost_values(params, obs)) ** 2, axis=-1))
        entropy_loss = -jnp.mean(gaussian_entropy(log_std) * jnp.ones_like(values))
        return policy_loss + s.ent_coef * entropy_loss + s.vf_coef * (value_loss + cost_loss)


def constraint_rows(metrics: dict[str, Any], multipliers: Any) -> dict[str, Any]:
    """The constraint log's values (:class:`train.learning.jitted.constraint_log.ConstraintLog`) of a chunk's summed
    metrics (:meth:`JaxPPOLagrangian.zero_metrics`' keys) and the multipliers after it (used by its last update)."""
    import numpy as np

    counts = np.asarray(metrics["bin_episodes"], np.float64)
    per = np.maximum(counts, 1.0)
    value = np.asarray(multipliers.value)
    return {"episodes": counts, "violation_rate": np.asarray(metrics["bin_cost"]) / per,
            "heading": np.asarray(metrics["bin_heading"]) / per, "energy": np.asarray(metrics["bin_energy"]) / per,
            "deadline_multiplier": value[0], "heading_multiplier": value[1]}  # fmt: skip


__all__ = ["COST_KEYS", "INFO_KEYS", "JaxPPOLagrangian", "LagrangianRunner", "constraint_rows", "make_cost_critic"]
