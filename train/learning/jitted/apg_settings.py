"""The hyperparameters of ``dwr-gym train --algo apg --backend jax`` (:mod:`train.learning.jitted.apg`), under the names
of train/hyperparams/apg.yml; checked here, before jax is imported, so bad values end the command in one line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from dwr_gym.validation import as_float, as_int
from train.learning.config import ConfigError
from train.learning.jitted.lagrangian import LAGRANGE_DEFAULTS, LagrangeSettings

#: YAML keys of APG, with their defaults; ``policy_kwargs`` (the network) is read as the ES reads it.
APG_DEFAULTS: dict[str, Any] = {"episodes": 64, "learning_rate": 3e-4, "max_grad_norm": 1.0, "state_grad_clip": 64.0,
                                 "near_miss_clip": None, "near_miss_distance": 0.05, "hold_steps": 0,
                                 "hold_weight": 10.0, "hold_heading_weight": 0.0, "keep_best": 0,
                                 "validation_episodes": 256, "teacher_episodes": 0, "teacher_iterations": 400,
                                 "teacher_learning_rate": 0.02, "clone_steps": 4000,
                                 "weight_average": 0.0, **LAGRANGE_DEFAULTS}  # fmt: skip
#: Observations of fresh episodes the fixed observation scaling is computed from.
INITIAL_OBSERVATIONS = 1024


@dataclass(frozen=True)
class APGSettings:
    """One APG run's hyperparameters, named as in train/hyperparams/apg.yml."""

    episodes: int = 64
    """Episodes per update (each a fresh start and T_con)."""
    learning_rate: float = 3e-4
    """Adam's step size; with ``linear_schedule`` its value at the start, decaying linearly to 0 over the budget."""
    linear_schedule: bool = False
    """True for rl-zoo3's ``learning_rate: lin_<value>``: the steps shrink to 0 by the end of the budget, so that the
    run ends on a policy the last updates no longer move far (with a constant rate the policy's energy, measured,
    swings between 0.45 and 9 from one evaluation to the next)."""
    max_grad_norm: float = 1.0
    """The update's gradient is clipped to this global norm."""
    state_grad_clip: float = 64.0
    """The cotangent of the env state is clipped to this norm at every step of the backward pass (0: not clipped),
    each episode's as its own return's gradient alone would be, whatever ``episodes`` is. (Until 2026-11-27 the clip
    acted on the batch mean's gradient, where each episode's cotangent is 1/``episodes`` of its own: the shipped
    ``state_grad_clip: 1`` at 64 episodes was this 64, which the yml files now say.)"""
    near_miss_clip: float | None = None
    """With a value, the state's gradient clip of the episodes that end near the goal but not at it (the goal tolerance
    < distance at the end <= ``near_miss_distance``): a wider clip lets more of their miss into the gradient, where the
    arrival bonus, a step, has none; the other episodes keep ``state_grad_clip`` (or its decay). None (the default):
    every episode at ``state_grad_clip``."""
    near_miss_distance: float = 0.05
    """[m] The outer edge of the near misses of ``near_miss_clip``."""
    hold_steps: int = 0
    """With > 0, the update also follows the miss over the last ``hold_steps`` control periods before T_con (``-
    hold_weight`` times the distance to the goal, averaged over them), not only at T_con: a robot that is at the goal
    a little before T_con and stays there is within the tolerance at T_con whatever the timing of its last steps. The
    return (and what ``keep_best`` and the evaluations measure) is v2's own; this is in the gradient only. 0 (the
    default): off."""
    hold_weight: float = 10.0
    """The weight per metre of the miss over the ``hold_steps`` (10: the weight of v2's miss at T_con)."""
    hold_heading_weight: float = 0.0
    """With > 0 (and ``hold_steps``), the update also follows the heading error over the same last steps, linearly:
    this weight per radian times 2 |sin(psi / 2)| (|psi| near the goal's heading), averaged over them. v2 pays the
    heading as 5 (cos psi - 1), whose gradient vanishes as psi does (1.9 per radian at the 0.39 rad the agents end
    at); this one does not. Gradient only, as ``hold_weight``. 0 (the default): off."""
    keep_best: int = 0
    """Every ``keep_best`` updates the policy's mean return is measured on ``validation_episodes`` fixed episodes of
    the run's own (not the evaluations'), and the run exports the best policy so measured rather than the last
    (0: off, the last is exported). The updates go on from the last policy either way: the guard chooses what the
    run keeps, not what it explores. On the residual on PTC the policy's energy swings between 0.45 and 9 from one
    evaluation to the next (docs/rl-apg.md); this keeps the run's result on the good side of the swing."""
    validation_episodes: int = 256
    """The fixed episodes of ``keep_best`` (their env steps count in the run's)."""
    teacher_episodes: int = 0
    """With > 0, the policy starts cloned from the best command sequences of this many fresh episodes, each found on its
    own by ``teacher_iterations`` Adam steps of ``teacher_learning_rate`` on its return
    (:mod:`train.learning.jitted.apg_teacher`; their env steps count); 0, the default: from its initial weights."""
    teacher_iterations: int = 400
    """Adam steps of the teacher's search, on each episode's sequence."""
    teacher_learning_rate: float = 0.02
    """Adam's step size of the teacher's search (on the actions before their tanh)."""
    clone_steps: int = 4000
    """Least-squares steps of the cloning (minibatches of 4,096 observation-action pairs)."""
    weight_average: float = 0.0
    """With a value in (0, 1), the run keeps an exponential moving average of the network's weights, this its decay
    per update (Polyak averaging: 0.995 averages over some 200 updates), and that average, not the last network, is
    what ``keep_best`` validates and the run exports; the updates go on from the last network. At the end of a run
    the policy's in-time rate swings by 5-10 points at T_con 10 s from one evaluation to the next whatever the batch
    (docs/rl-constrained.md): the step's, and the average sits inside the swing. 0 (the default): off."""
    constraint: LagrangeSettings = field(default_factory=LagrangeSettings)
    """The deadline and the heading as constraints with Lagrange multipliers per T_con bin (``lagrangian: 1`` and
    :class:`train.learning.jitted.lagrangian.LagrangeSettings`' keys): the multipliers, not ``hold_weight`` and
    ``hold_heading_weight``, then weigh the distance and the heading error over the hold window (the last step
    before T_con without one)."""
    net_arch: tuple[int, ...] = (64, 64)
    activation: str = "tanh"
    ortho_init: bool = True
    normalize_observations: bool = True

    @classmethod
    def from_algo_kwargs(cls, algo_kwargs: dict[str, Any]) -> APGSettings:
        """The settings of resolved hyperparameters; an unknown key or a bad value is a ConfigError of one line."""
        from train.learning.jitted.policy import actor_hyperparameters, network_fields

        values, policy = actor_hyperparameters(algo_kwargs, APG_DEFAULTS, "APG")
        rate = values["learning_rate"]
        linear = isinstance(rate, str) and rate.startswith("lin_")
        try:
            rate = as_float("learning_rate", rate[4:] if linear else rate, 0.0, 100.0, low_inclusive=False, text=True)
        except ValueError:
            raise ConfigError(f"learning_rate={values['learning_rate']!r} is invalid: expected a number in (0, 100], "
                              "or lin_<number> for a linear decay to 0") from None  # fmt: skip
        try:
            return cls(
                episodes=as_int("episodes", values["episodes"], 1, 65536, text=True),
                learning_rate=rate,
                linear_schedule=linear,
                max_grad_norm=as_float("max_grad_norm", values["max_grad_norm"], 0.0, 1e9, low_inclusive=False,
                                       text=True),
                state_grad_clip=as_float("state_grad_clip", values["state_grad_clip"], 0.0, 1e9, text=True),
                near_miss_clip=clip_beside("near_miss_clip", values["near_miss_clip"], values["state_grad_clip"],
                                           "no episode is clipped"),
                near_miss_distance=as_float("near_miss_distance", values["near_miss_distance"], 0.0, 100.0,
                                            low_inclusive=False, text=True),
                hold_steps=as_int("hold_steps", values["hold_steps"], 0, 100_000, text=True),
                hold_weight=as_float("hold_weight", values["hold_weight"], 0.0, 1e6, low_inclusive=False, text=True),
                hold_heading_weight=heading_beside(values["hold_heading_weight"], values["hold_steps"]),
                keep_best=as_int("keep_best", values["keep_best"], 0, 1_000_000, text=True),
                validation_episodes=as_int("validation_episodes", values["validation_episodes"], 1, 65536, text=True),
                teacher_episodes=as_int("teacher_episodes", values["teacher_episodes"], 0, 65536, text=True),
                teacher_iterations=as_int("teacher_iterations", values["teacher_iterations"], 1, 1_000_000, text=True),
                teacher_learning_rate=as_float("teacher_learning_rate", values["teacher_learning_rate"], 0.0, 100.0,
                                               low_inclusive=False, text=True),
                clone_steps=as_int("clone_steps", values["clone_steps"], 1, 10_000_000, text=True),
                weight_average=as_float("weight_average", values["weight_average"], 0.0, 1.0, high_inclusive=False,
                                        text=True),
                constraint=constraint_beside(values),
                **network_fields(policy, "APG"),
            )  # fmt: skip
        except ValueError as error:
            raise ConfigError(str(error)) from None

    def ppo_settings(self) -> Any:
        """The jitted PPO's settings of the same network, whose actor is the APG policy."""
        from train.learning.jitted.policy import actor_network_settings

        return actor_network_settings(self)


def clip_beside(name: str, value: Any, clip: Any, why: str) -> float | None:
    """The option ``name`` (a clip that acts beside ``state_grad_clip``, such as ``near_miss_clip``) checked:
    None, or a number in (0, 1e9] where ``state_grad_clip`` (``clip``) is on; ``why`` says what a clip of 0 leaves."""
    if value is None:
        return None
    checked = as_float(name, value, 0.0, 1e9, low_inclusive=False, text=True)
    if float(clip) == 0.0:
        raise ValueError(
            f"{name}={value!r} is invalid with state_grad_clip=0 ({why}): expected a state_grad_clip > 0, or no {name}"
        )
    return checked


def heading_beside(value: Any, hold_steps: Any) -> float:
    """``hold_heading_weight`` checked: a number in [0, 1e6], above 0 only with ``hold_steps`` (its window)."""
    checked = as_float("hold_heading_weight", value, 0.0, 1e6, text=True)
    if checked > 0.0 and int(hold_steps) == 0:
        raise ValueError(f"hold_heading_weight={value!r} is invalid with hold_steps=0 (it acts over the last "
                         "hold_steps before T_con): expected a hold_steps > 0, or hold_heading_weight 0")  # fmt: skip
    return checked


def constraint_beside(values: dict[str, Any]) -> LagrangeSettings:
    """The constraint's settings checked; with ``lagrangian`` on, the hand-set weights it replaces must be off."""
    constraint = LagrangeSettings.from_values(values)
    if constraint.lagrangian:
        for name in ("hold_heading_weight",):
            if float(values[name]) != 0.0:
                raise ValueError(f"{name}={values[name]!r} is invalid with lagrangian=1 (the multipliers weigh the "
                                 f"constraints): expected {name} 0")  # fmt: skip
    return constraint


def check_apg_kwargs(params: dict[str, Any]) -> dict[str, Any]:
    """``params`` with its APG values coerced (for config.yaml), or a ConfigError; called by resolve_hyperparams."""
    settings = APGSettings.from_algo_kwargs(params)
    checked = {k: getattr(settings.constraint if k in LAGRANGE_DEFAULTS else settings, k) for k in APG_DEFAULTS}
    checked["lagrangian"] = int(checked["lagrangian"])
    if settings.linear_schedule:
        checked["learning_rate"] = f"lin_{settings.learning_rate:g}"
    return {**params, **checked}
