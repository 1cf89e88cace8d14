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
#: ``max_return_drop`` at or above this: no update is checked (nor undone).
MAX_DROP = 1e9
APG_DEFAULTS: dict[str, Any] = {"episodes": 64, "learning_rate": 3e-4, "max_grad_norm": 1.0, "state_grad_clip": 64.0,
                                 "state_grad_clip_final": None, "state_grad_clip_decay": 1.0,
                                 "near_miss_clip": None, "near_miss_distance": 0.05, "near_miss_weight": 1.0,
                                 "hold_steps": 0, "hold_fraction": 0.0, "hold_weight": 10.0,
                                 "hold_heading_weight": 0.0, "hold_bonus": 0.0,
                                 "hold_bonus_width": 0.005, "short_T_con_share": 0.0, "short_T_con_max": 20.0,
                                 "max_return_drop": MAX_DROP, "keep_best": 0,
                                 "validation_episodes": 256, "teacher_episodes": 0, "teacher_iterations": 400,
                                 "teacher_learning_rate": 0.02, "clone_steps": 4000, "teacher_rounds": 1,
                                 **LAGRANGE_DEFAULTS}  # fmt: skip
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
    state_grad_clip_final: float | None = None
    """With a value, the clip decays geometrically from ``state_grad_clip`` to this over the updates the budget buys
    (then stays there): a wide clip first, which lets the pose at T_con into the gradient and learns to arrive, and a
    tight one last, which weighs the energy more (docs/what-was-tried.md, the clip probes); None (the default): fixed."""
    state_grad_clip_decay: float = 1.0
    """The share of the budget's updates over which ``state_grad_clip_final`` is reached (1: at the end, when the
    rate reaches 0 too; 0.5: half-way, so that the second half's updates are at the final clip)."""
    near_miss_clip: float | None = None
    """With a value, the state's gradient clip of the episodes that end near the goal but not at it (the goal tolerance
    < distance at the end <= ``near_miss_distance``): a wider clip lets more of their miss into the gradient, where the
    arrival bonus, a step, has none; the other episodes keep ``state_grad_clip`` (or its decay). None (the default):
    every episode at ``state_grad_clip``."""
    near_miss_distance: float = 0.05
    """[m] The outer edge of the near misses of ``near_miss_clip`` and ``near_miss_weight``."""
    near_miss_weight: float = 1.0
    """The weight of a near miss's gradient in the update (its clip scaled with it, so its gradient is this times
    the clipped one): above 1 the few episodes that miss the bonus by less than ``near_miss_distance`` weigh more
    than their share of the batch. 1 (the default): every episode weighs the same."""
    hold_steps: int = 0
    """With > 0, the update also follows the miss over the last ``hold_steps`` control periods before T_con (``-
    hold_weight`` times the distance to the goal, averaged over them), not only at T_con: a robot that is at the goal
    a little before T_con and stays there is within the tolerance at T_con whatever the timing of its last steps. The
    return (and what ``keep_best`` and the evaluations measure) is v2's own; this is in the gradient only. 0 (the
    default): off."""
    hold_fraction: float = 0.0
    """With > 0 (instead of ``hold_steps``), the window is this share of each episode's own T_con: ceil(hold_fraction *
    T_con / dt) control periods (at 0.1: 20 at T_con 10 s, 120 at 60 s). With time-scaled actions the policy is one
    behaviour in T_con's own time, and a window of fixed length asks it to arrive at 0.9 of T_con at 10 s but at 0.98
    at 60 s; this one asks the same share at every T_con. 0 (the default): the window is ``hold_steps``."""
    hold_weight: float = 10.0
    """The weight per metre of the miss over the ``hold_steps`` (10: the weight of v2's miss at T_con)."""
    hold_heading_weight: float = 0.0
    """With > 0 (and ``hold_steps``), the update also follows the heading error over the same last steps, linearly:
    this weight per radian times 2 |sin(psi / 2)| (|psi| near the goal's heading), averaged over them. v2 pays the
    heading as 5 (cos psi - 1), whose gradient vanishes as psi does (1.9 per radian at the 0.39 rad the agents end
    at); this one does not. Gradient only, as ``hold_weight``. 0 (the default): off."""
    hold_bonus: float = 0.0
    """With > 0 (and a hold window), the update also follows a smooth stand-in for v2's arrival bonus over the same
    last steps: this weight times sigmoid((goal_tolerance - distance) / ``hold_bonus_width``), averaged over them.
    v2 pays its bonus (10) as a step at the tolerance, which has no gradient, while the misses mostly end 1-2 cm from
    the goal (docs/what-was-tried.md, near misses): ``hold_weight``'s 10 per metre makes the last centimetre worth
    0.1; this one's slope at the tolerance is hold_bonus / (4 hold_bonus_width) (500 per metre at 10 and 5 mm), and
    fades beyond a few widths. Gradient only, as ``hold_weight``. 0 (the default): off."""
    hold_bonus_width: float = 0.005
    """[m] The width of ``hold_bonus``'s sigmoid: its slope is within a tenth of its peak up to about 3.6 widths from the
    tolerance."""
    short_T_con_share: float = 0.0
    """The share of each update's episodes whose T_con is drawn from [the env's lowest T_con, ``short_T_con_max``]
    rather than the env's whole range (the start pose drawn as for the others): more practice at the short deadlines,
    where the agents miss most. The validation episodes of ``keep_best`` and every evaluation keep the env's own
    draw. 0 (the default): every episode as the env draws it."""
    short_T_con_max: float = 20.0
    """[s] The upper end of the short episodes' T_con (clamped to the env's range)."""
    max_return_drop: float = MAX_DROP
    """An update after which the same episodes' mean return is lower by more than this is undone (the weights and
    Adam's state as before it; the replay's env steps count); :data:`MAX_DROP` (the default): none checked. Off by
    default because on the residual on PTC it undoes nearly every update (measured: a step along the batch's own
    gradient lowers that batch's return in 85-100 % of updates, docs/rl-apg.md)."""
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
    teacher_rounds: int = 1
    """Rounds of the lesson: 1 clones the teacher's sequences once; each further round (DAgger) plays the cloned policy
    on ``teacher_episodes`` fresh episodes, teaches the best sequence from a drawn state of each, and refits on all."""
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
                state_grad_clip_final=clip_beside("state_grad_clip_final", values["state_grad_clip_final"],
                                                  values["state_grad_clip"], "no clip to decay from"),
                state_grad_clip_decay=as_float("state_grad_clip_decay", values["state_grad_clip_decay"], 0.0, 1.0,
                                               low_inclusive=False, text=True),
                near_miss_clip=clip_beside("near_miss_clip", values["near_miss_clip"], values["state_grad_clip"],
                                           "no episode is clipped"),
                near_miss_distance=as_float("near_miss_distance", values["near_miss_distance"], 0.0, 100.0,
                                            low_inclusive=False, text=True),
                near_miss_weight=weight_beside(values["near_miss_weight"], values["state_grad_clip"]),
                hold_steps=as_int("hold_steps", values["hold_steps"], 0, 100_000, text=True),
                hold_fraction=fraction_beside(values["hold_fraction"], values["hold_steps"]),
                hold_weight=as_float("hold_weight", values["hold_weight"], 0.0, 1e6, low_inclusive=False, text=True),
                hold_heading_weight=heading_beside(values["hold_heading_weight"], values["hold_steps"],
                                                   values["hold_fraction"]),
                hold_bonus=window_beside("hold_bonus", values["hold_bonus"], values["hold_steps"],
                                         values["hold_fraction"]),
                hold_bonus_width=as_float("hold_bonus_width", values["hold_bonus_width"], 0.0, 10.0,
                                          low_inclusive=False, text=True),
                short_T_con_share=as_float("short_T_con_share", values["short_T_con_share"], 0.0, 1.0, text=True),
                short_T_con_max=as_float("short_T_con_max", values["short_T_con_max"], 0.0, 1e6, low_inclusive=False,
                                         text=True),
                max_return_drop=as_float("max_return_drop", values["max_return_drop"], 0.0, MAX_DROP, text=True),
                keep_best=as_int("keep_best", values["keep_best"], 0, 1_000_000, text=True),
                validation_episodes=as_int("validation_episodes", values["validation_episodes"], 1, 65536, text=True),
                teacher_episodes=as_int("teacher_episodes", values["teacher_episodes"], 0, 65536, text=True),
                teacher_iterations=as_int("teacher_iterations", values["teacher_iterations"], 1, 1_000_000, text=True),
                teacher_learning_rate=as_float("teacher_learning_rate", values["teacher_learning_rate"], 0.0, 100.0,
                                               low_inclusive=False, text=True),
                clone_steps=as_int("clone_steps", values["clone_steps"], 1, 10_000_000, text=True),
                teacher_rounds=as_int("teacher_rounds", values["teacher_rounds"], 1, 1000, text=True),
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
    """The option ``name`` (a clip that acts beside ``state_grad_clip``, such as ``state_grad_clip_final``) checked:
    None, or a number in (0, 1e9] where ``state_grad_clip`` (``clip``) is on; ``why`` says what a clip of 0 leaves."""
    if value is None:
        return None
    checked = as_float(name, value, 0.0, 1e9, low_inclusive=False, text=True)
    if float(clip) == 0.0:
        raise ValueError(
            f"{name}={value!r} is invalid with state_grad_clip=0 ({why}): expected a state_grad_clip > 0, or no {name}"
        )
    return checked


def weight_beside(value: Any, clip: Any) -> float:
    """``near_miss_weight`` checked: a number in (0, 1000], other than 1 only where ``state_grad_clip`` (``clip``) is
    on (the weight scales the clip it travels back with)."""
    checked = as_float("near_miss_weight", value, 0.0, 1000.0, low_inclusive=False, text=True)
    if checked != 1.0 and float(clip) == 0.0:
        raise ValueError(f"near_miss_weight={value!r} is invalid with state_grad_clip=0 (it scales the clip): "
                         "expected a state_grad_clip > 0, or near_miss_weight 1")  # fmt: skip
    return checked


def fraction_beside(value: Any, hold_steps: Any) -> float:
    """``hold_fraction`` checked: a number in [0, 1), above 0 only without ``hold_steps`` (one window or the other)."""
    checked = as_float("hold_fraction", value, 0.0, 1.0, high_inclusive=False, text=True)
    if checked > 0.0 and int(hold_steps) > 0:
        raise ValueError(f"hold_fraction={value!r} is invalid with hold_steps={hold_steps!r} (each sets the window "
                         "before T_con): expected hold_fraction 0, or hold_steps 0")  # fmt: skip
    return checked


def heading_beside(value: Any, hold_steps: Any, hold_fraction: Any = 0.0) -> float:
    """``hold_heading_weight`` checked: a number in [0, 1e6], above 0 only with ``hold_steps`` or ``hold_fraction``
    (its window)."""
    return window_beside("hold_heading_weight", value, hold_steps, hold_fraction)


def window_beside(name: str, value: Any, hold_steps: Any, hold_fraction: Any) -> float:
    """The term ``name`` of the hold window (``hold_heading_weight``, ``hold_bonus``) checked: a number in [0, 1e6],
    above 0 only with ``hold_steps`` or ``hold_fraction`` (its window)."""
    checked = as_float(name, value, 0.0, 1e6, text=True)
    if checked > 0.0 and int(hold_steps) == 0 and float(hold_fraction) == 0.0:
        raise ValueError(f"{name}={value!r} is invalid with hold_steps=0 (it acts over the last "
                         "hold_steps before T_con): expected a hold_steps > 0 or a hold_fraction > 0, or "
                         f"{name} 0")  # fmt: skip
    return checked


def constraint_beside(values: dict[str, Any]) -> LagrangeSettings:
    """The constraint's settings checked; with ``lagrangian`` on, the hand-set weights it replaces must be off."""
    constraint = LagrangeSettings.from_values(values)
    if constraint.lagrangian:
        for name in ("hold_heading_weight", "hold_bonus"):
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
