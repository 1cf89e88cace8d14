"""What the agent sees: the observation space and the features of a state."""

from __future__ import annotations

import contextlib
import math

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from dwr_gym import model
from dwr_gym.model import FloatArray
from dwr_gym.params import EnvParams
from dwr_gym.state import ErrorCoordinates, TaskState, error_coordinates

# The ufunc behind np.clip, without np.clip's Python wrapper: faster than np.clip, and than maximum then minimum.
try:  # (numpy._core since numpy 2)
    from numpy._core.umath import clip
except ImportError:
    from numpy.core.umath import clip

#: Names of the observation features, in order.
OBSERVATION_NAMES: tuple[str, ...] = (
    "distance",
    "cos_azimuth",
    "sin_azimuth",
    "cos_heading",
    "sin_heading",
    "orientation_error",
    "time_fraction",
    "T_con",
    "initial_distance",
    "initial_orientation_error",
)


def observation_space(params: EnvParams) -> spaces.Box:
    """The observation space; see the env's docstring for the table."""
    e_max = model.MAX_ORIENTATION_ERROR
    d_max = 2.0 * params.arena_radius
    low = np.array([0, -1, -1, -1, -1, -e_max, 0, 0, 0, -e_max], dtype=np.float32)
    high = np.array(
        [d_max, 1, 1, 1, 1, e_max, params.horizon_factor, params.T_con_max, params.arena_radius, e_max],
        dtype=np.float32,
    )
    return spaces.Box(low, high, dtype=np.float32)


def observe(
    state: TaskState,
    coords: ErrorCoordinates,
    params: EnvParams,
    space: spaces.Box,
    pose_noise: FloatArray | None = None,
) -> NDArray[np.float32]:
    """Observation features (N, 10) of ``state``, whose true error coordinates are ``coords``; (10,) for one robot.

    With ``pose_noise`` (N, 3) (or (3,)) of standard-normal samples, the features are those of the
    pose measured with noise of standard deviation ``params.observation_noise``. Values are clipped
    to the space's bounds. For arrays of another library than numpy (jax's, maybe traced), the features are
    computed without writing in place (:func:`features_array_api`), in the space's dtype, with shape (..., 10).
    """
    if pose_noise is not None:
        sigma = params.observation_noise
        coords = error_coordinates(
            state.x + sigma * pose_noise[..., 0], state.y + sigma * pose_noise[..., 1],
            model.wrap_angle(state.psi + sigma * pose_noise[..., 2]), params.k,
        )  # fmt: skip
    dist = coords.distance
    if type(dist) is not np.ndarray and type(dist) is not float:  # jax's arrays (model.namespace's test)
        return features_array_api(state, coords, params, space, model.namespace(dist))
    if type(dist) is float:  # one robot (as model.namespace decides, without its call)
        # one robot: cos(alpha) and sin(alpha) of eq. (3) as -x/d and -y/d, (1, 0) at the goal
        cos_alpha, sin_alpha = (-coords.x / dist, -coords.y / dist) if dist > 0.0 else (1.0, 0.0)
        features = np.array(
            [dist, cos_alpha, sin_alpha, math.cos(coords.psi), math.sin(coords.psi), coords.orientation_error,
             state.step_count * (params.dt / state.T_con), state.T_con, state.initial_distance,
             state.initial_orientation_error], dtype=np.float32,
        )  # fmt: skip
        return clip(features, space.low, space.high, out=features)  # the ufunc: 6x np.clip's speed here
    features = np.empty((len(OBSERVATION_NAMES), dist.shape[0]), dtype=np.float32)  # filled row by row: contiguous
    features[0] = dist
    # -cos(alpha) and -sin(alpha) of eq. (3) without trigonometry; 0 / 0 at the goal, where they are set to (1, 0)
    at_goal = dist.size and dist.min() == 0.0  # distances are >= 0: a reduction is cheaper than a search
    with np.errstate(divide="ignore", invalid="ignore") if at_goal else contextlib.nullcontext():
        np.divide(coords.x, dist, out=features[1], casting="same_kind")
        np.divide(coords.y, dist, out=features[2], casting="same_kind")
    np.negative(features[1:3], out=features[1:3])  # -(x / d) is (-x) / d exactly, and cheaper in float32
    if at_goal:
        index = np.flatnonzero(dist == 0.0)
        features[1, index], features[2, index] = 1.0, 0.0
    heading = coords.psi.astype(np.float32)  # float32 trigonometry: ~10x faster, and the features are float32
    np.cos(heading, out=features[3])
    np.sin(heading, out=features[4])
    features[5] = coords.orientation_error
    features[6] = state.step_count * (params.dt / state.T_con)
    features[7] = state.T_con
    features[8] = state.initial_distance
    features[9] = state.initial_orientation_error
    clip(features, space.low[:, None], space.high[:, None], out=features)  # one pass: 3x maximum then minimum
    return features.T


def features_array_api(
    state: TaskState, coords: ErrorCoordinates, params: EnvParams, space: spaces.Box, xp: object
) -> object:
    """The features of :func:`observe` for arrays of any shape (...) of an array-API library (jax.numpy): (..., 10)
    in ``space.dtype``, with no write in place and no branch on values, so a compiler can trace it."""
    dtype = space.dtype
    dist = coords.distance
    at_goal = dist == 0.0
    safe = xp.where(at_goal, 1.0, dist)  # type: ignore[attr-defined]
    heading = xp.asarray(coords.psi, dtype=dtype)  # type: ignore[attr-defined]  # in the features' dtype, as numpy's
    rows = (
        dist, xp.where(at_goal, 1.0, -coords.x / safe), xp.where(at_goal, 0.0, -coords.y / safe),  # type: ignore[attr-defined]
        xp.cos(heading), xp.sin(heading), coords.orientation_error,  # type: ignore[attr-defined]
        state.step_count * (params.dt / state.T_con), state.T_con, state.initial_distance,
        state.initial_orientation_error,
    )  # fmt: skip
    features = xp.stack([xp.asarray(row, dtype=dtype) for row in rows], axis=-1)  # type: ignore[attr-defined]
    return xp.clip(features, space.low, space.high)  # type: ignore[attr-defined]
