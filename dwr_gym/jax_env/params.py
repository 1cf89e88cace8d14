"""FunctionalParams: the task's parameters as a JAX pytree, built from (and validated as) the numpy EnvParams.

The dynamic fields are leaves, so ``jax.vmap`` can run robots of different parameters at once (domain
randomisation: ``params.replace(u_max=...)``); the static ones (integrator, sub-steps, exact shaping, noise,
dtype, the observation bounds) choose the compiled code. Build them with :func:`functional_params` or
:meth:`FunctionalParams.from_env_params`: validation happens there, once, and the functions trust them.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium
import jax
import numpy as np
from flax import struct

from dwr_gym.disturbances import ROBOT_KEYWORDS, split_env_kwargs
from dwr_gym.params import EnvParams
from dwr_gym.validation import as_choice

DTYPES = ("float32", "float64")


def check_dtype(dtype: Any) -> str:
    """``dtype`` as "float32" or "float64"; float64 needs jax_enable_x64 (otherwise jax computes in float32)."""
    name = as_choice("dtype", np.dtype(dtype).name if isinstance(dtype, type) else dtype, DTYPES)
    if name == "float64" and not jax.config.jax_enable_x64:
        raise ValueError(
            "dtype='float64' is invalid while jax_enable_x64 is off: expected 'float32', or enable it first "
            "(jax.config.update('jax_enable_x64', True) or JAX_ENABLE_X64=1)"
        )
    return name  # type: ignore[no-any-return]


def check_no_perturbation(kwargs: dict[str, Any]) -> None:
    """Refuse the robot and disturbance keywords: the functional env is the nominal robot of eq. (1)."""
    given = sorted(key for key in ROBOT_KEYWORDS if kwargs.get(key) not in (None, (), []))
    if given:
        _, _, disturbances = split_env_kwargs({key: kwargs[key] for key in given})  # validated as the envs do
        names = sorted({type(item).__name__ for item in disturbances})
        raise ValueError(
            f"{given[0]}={kwargs[given[0]]!r} is invalid for the functional (JAX) env: expected None, as it steps the "
            f"nominal robot only ({', '.join(names) or 'robot'} need the numpy envs' per-robot state)"
        )


@struct.dataclass
class FunctionalParams:
    """The parameters of :class:`dwr_gym.params.EnvParams` (same names, same units) as a pytree.

    ``T_con_range`` is always an interval ((T_con, T_con) for a fixed T_con: low + 0 * draw is T_con exactly) and
    ``heading_tolerance`` a number (inf for None: every heading is within it).
    """

    T_con_range: tuple[float, float]  # [s]
    dt: float  # [s]
    u_max: float  # [m/s]
    omega_max: float  # [rad/s]
    goal_tolerance: float  # [m]
    heading_tolerance: float  # [rad]
    horizon_factor: float
    arena_radius: float  # [m]
    start_distance: tuple[float, float]  # [m]
    start_heading: tuple[float, float]  # [rad]
    k: float
    progress_weight: float
    shaping_discount: float
    time_weight: float  # [1/(m s)]
    time_gain_cap: float
    effort_weight: float  # [1/s]
    energy_weight: float
    arrival_bonus: float
    heading_weight: float
    late_penalty: float  # [1/s]
    arena_penalty: float
    terminal_distance_weight: float  # [1/m]
    # static: they choose the compiled code, and the spaces' bounds
    env_params: EnvParams = struct.field(pytree_node=False)
    """The validated numpy parameters these were built from (the spaces' bounds come from them)."""
    dtype: str = struct.field(pytree_node=False, default="float32")
    """The states' float dtype: "float32", or "float64" with jax_enable_x64."""
    integrator: str = struct.field(pytree_node=False, default="exact")
    substeps: int = struct.field(pytree_node=False, default=1)
    zero_terminal_potential: bool = struct.field(pytree_node=False, default=False)
    hold_to_T_con: bool = struct.field(pytree_node=False, default=False)
    shaping_potential: str = struct.field(pytree_node=False, default="lyapunov")
    observation_noise: float = struct.field(pytree_node=False, default=0.0)  # [m, rad]
    actuation_noise: float = struct.field(pytree_node=False, default=0.0)

    @classmethod
    def from_env_params(cls, params: EnvParams, dtype: str = "float32") -> FunctionalParams:
        """The pytree of validated numpy parameters, for states in ``dtype``."""
        if not isinstance(params, EnvParams):
            raise ValueError(f"params={params!r} is invalid: expected a dwr_gym.params.EnvParams")
        fields = {name: getattr(params, name) for name in cls.__dataclass_fields__ if hasattr(params, name)}
        fields["T_con_range"] = (params.T_con, params.T_con) if params.T_con_range is None else params.T_con_range
        fields["heading_tolerance"] = math.inf if params.heading_tolerance is None else params.heading_tolerance
        return cls(**{**fields, "env_params": params, "dtype": check_dtype(dtype)})

    @property
    def T_con(self) -> float:
        """The prescribed time when it is fixed (no range) [s]."""
        return self.env_params.T_con

    @property
    def max_episode_steps(self) -> int:
        """Control periods until the truncation of the longest episode."""
        return self.env_params.max_episode_steps


def env_kwargs_of(env_id: str, env_kwargs: dict[str, Any]) -> dict[str, Any]:
    """The registered keywords of the numpy env ``env_id`` (a DWRPointStabilization id), updated with ``env_kwargs``."""
    import dwr_gym  # noqa: F401  (registers the ids)

    spec = gymnasium.spec(env_id)
    if "dwr_gym" not in str(spec.entry_point):
        raise ValueError(f"env_id={env_id!r} is invalid: expected a dwr_gym id such as 'DWRPointStabilization-v1'")
    return {**spec.kwargs, **env_kwargs}


def functional_params(
    env_id: str = "DWRPointStabilization-v1", dtype: str = "float32", **env_kwargs: Any
) -> FunctionalParams:
    """The parameters of ``env_id`` (v0, v1 or v2, or their JAX ids) with ``env_kwargs`` (EnvParams' keywords), validated."""
    kwargs = env_kwargs_of(env_id, env_kwargs)
    check_no_perturbation(kwargs)  # what is left of the robot's keywords is empty (None, [], ()): the nominal robot
    nominal = {key: value for key, value in kwargs.items() if key not in ROBOT_KEYWORDS}
    return FunctionalParams.from_env_params(EnvParams.from_kwargs(**nominal), dtype)
