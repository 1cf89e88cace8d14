"""What every controller shares: the input, the parameter base class and the batched law interface."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.validation import coerce_numbers, reject_unknown

K_MAX = 1.0 / (2.0 * math.pi)


class ControllerInput(NamedTuple):
    """What every law needs, in the goal frame; arrays of shape (N,)."""

    distance: FloatArray  # d, eq. (2) [m]
    azimuth: FloatArray  # alpha, eq. (3) [rad]
    heading: FloatArray  # psi relative to the goal heading [rad]
    time: FloatArray  # t since the episode start [s]
    initial_distance: FloatArray  # d_0 [m]
    initial_orientation_error: FloatArray  # e_psi0 [rad]
    prescribed_time: FloatArray | None = None  # T_con [s] if known from the observation, else the law's own

    @classmethod
    def from_pose(
        cls, x: ArrayLike, y: ArrayLike, psi: ArrayLike, time: ArrayLike, initial: tuple[ArrayLike, ArrayLike]
    ) -> ControllerInput:
        """Build the input from goal-frame poses; ``initial`` is (d_0, e_psi0)."""
        x, y, psi = (np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in (x, y, psi))
        dist, alpha = model.distance(x, y), model.azimuth(x, y)
        n = dist.shape
        return cls(
            dist, alpha, model.wrap_angle(psi), np.broadcast_to(np.asarray(time, dtype=np.float64), n),
            np.broadcast_to(np.asarray(initial[0], dtype=np.float64), n),
            np.broadcast_to(np.asarray(initial[1], dtype=np.float64), n),
        )  # fmt: skip


@dataclass(frozen=True)
class ControllerParams:
    """Base of the parameter dataclasses: validation hook and keyword construction."""

    def __post_init__(self) -> None:
        coerce_numbers(self)
        self.validate()

    def validate(self) -> None:
        """Raise ValueError naming the parameter, the value and the allowed range."""

    @classmethod
    def from_kwargs(cls, **kwargs: Any) -> Any:
        """Build from keywords, rejecting unknown ones."""
        reject_unknown(cls, kwargs)
        return cls(**kwargs)


def array_namespace(*values: Any) -> Any:
    """numpy for numpy arrays and Python floats, ``jax.numpy`` for jax arrays (traced or not): the namespace the
    stateless laws compute in (:func:`dwr_gym.model.namespace`), so one copy of each law runs in numpy and in jitted
    JAX code (``jax.jit``, ``lax.scan``; the residual agents of ``dwr-gym train --backend jax``)."""
    xp = model.namespace(*values)
    return xp if model.is_traceable(xp) else np


class Controller:
    """A batched feedback law (u, omega) = law(input).

    ``traceable``: the law is a pure function of its input, written on :func:`array_namespace`, so it also runs on
    jax arrays inside ``jax.jit``; laws with state (an integral, a plan) are not.
    """

    name: ClassVar[str] = "controller"
    traceable: ClassVar[bool] = False
    params: ControllerParams

    def __call__(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        u, omega = self.compute(inputs)
        xp = array_namespace(u, omega)
        # Guard: no NaN or inf may leave a controller, whatever the state.
        return xp.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0), xp.nan_to_num(omega, nan=0.0, posinf=0.0, neginf=0.0)

    def compute(self, inputs: ControllerInput) -> tuple[FloatArray, FloatArray]:
        """The law itself; subclasses implement it."""
        raise NotImplementedError

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Reset internal state (only stateful laws have any) for the robots in ``mask``."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.params})"


def prescribed_time(inputs: ControllerInput, own: float) -> FloatArray | float:
    """T_con from the input when the caller observed it (an expert acting on the env), else the law's own."""
    return own if inputs.prescribed_time is None else inputs.prescribed_time


def signed_power(x: ArrayLike, exponent: float) -> FloatArray:
    """|x|^exponent sign(x), in numpy (float64) or, for a jax array, in jax.numpy."""
    xp = array_namespace(x)
    if xp is np:
        x = np.asarray(x, dtype=np.float64)
    return xp.sign(x) * xp.abs(x) ** exponent  # type: ignore[no-any-return]
