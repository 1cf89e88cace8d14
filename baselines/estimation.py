"""A state estimate that any controller or agent can sit behind: an extended Kalman filter on eq. (1).

Pose noise fed straight into a feedback law becomes command chatter, a dropped measurement freezes the
law's view, and an unmodelled velocity disturbance (a slope, a slipping or failing wheel) becomes a
steady error. The filter of this module predicts the pose with the commands the policy sent, through
the exact zero-order-hold arc of eq. (1) (:func:`dwr_gym.model.unicycle_step_exact`), and corrects it
with each measurement. Its state per robot is the goal-frame pose and a model of what the robot does with
a command (u, omega):

    s = (x, y, psi, b_u, b_omega, a, g),   u_robot = a u + b_u,   omega_robot = a omega + g u + b_omega,
    (x, y, psi)+ = arc(x, y, psi, u_robot, omega_robot, dt),   (b_u, b_omega, a, g)+ = (b_u, b_omega, a, g) + w:

an additive velocity disturbance (a slope, a push, a mis-calibrated odometry) and an input gain a with a
coupling g [1/m] of the turn rate to the forward speed, which is what a slipping or failing wheel does to a
differential drive (a wheel at efficiency e_R, e_L of track b gives a = (e_R + e_L) / 2, g = (e_R - e_L) / b).
This is a disturbance observer: :func:`compensated_commands` inverts the model, so that the robot does what
the law asked for. A measurement repeated bit for bit (what :class:`dwr_gym.disturbances.MeasurementDropout` delivers, and what
a stale sensor buffer delivers on a robot) is treated as no measurement: the filter predicts through it.

- :func:`predict` and :func:`correct` are the filter's math, pure and batched over N robots;
- :class:`PoseFilterParams` are its noise levels, a validated frozen dataclass;
- :class:`PoseFilter` keeps the estimate of N robots between calls;
- :class:`FilteredPolicy` puts any policy with stable-baselines3's ``predict`` (an SB3 model, an
  :class:`~baselines.expert.ExpertPolicy`, a hand-over agent) behind the filter.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from baselines.base import ControllerInput, ControllerParams
from dwr_gym import model
from dwr_gym.validation import as_float

#: The filter's state: the pose (x, y, psi), the additive disturbance (b_u, b_omega), the input gain a and coupling g.
STATE_SIZE = 7
#: A new delay replaces the assumed one when its score is below this fraction of the assumed one's.
DELAY_SWITCH = 0.5
#: What the robot does with a command when nothing disturbs it: (b_u, b_omega, a, g) = (0, 0, 1, 0).
NOMINAL_RESPONSE = (0.0, 0.0, 1.0, 0.0)
Array = NDArray[np.float64]


def _pair(name: str, value: Any, low: float, high: float) -> tuple[float, float]:
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise ValueError(f"{name}={value!r} is invalid: expected two numbers (linear, angular) in [{low}, {high}]")
    return (as_float(f"{name}[0]", value[0], low, high), as_float(f"{name}[1]", value[1], low, high))


@dataclass(frozen=True)
class PoseFilterParams(ControllerParams):
    """Noise levels (standard deviations) and priors of the filter; the defaults suit the env's disturbance sets."""

    position_noise: float = 0.01  # [m]
    """Measurement noise of x and y."""
    heading_noise: float = 0.01  # [rad]
    """Measurement noise of the heading."""
    velocity_noise: tuple[float, float] = (0.03, 0.1)  # [m/s, rad/s]
    """How far the robot's (u, omega) may stray in one period from what the model predicts (actuation noise)."""
    disturbance_rate: tuple[float, float] = (0.02, 0.1)  # [m/s / sqrt(s), rad/s / sqrt(s)]
    """Random-walk intensities of (b_u, b_omega): how fast the filter lets the additive disturbance change."""
    gain_rate: float = 0.02  # [1 / sqrt(s)]
    """Random-walk intensity of the input gain a; 0 with ``gain_prior`` 0 fixes it at 1."""
    coupling_rate: float = 0.2  # [1/m / sqrt(s)]
    """Random-walk intensity of the coupling g; 0 with ``coupling_prior`` 0 fixes it at 0."""
    disturbance_prior: tuple[float, float] = (0.05, 0.3)  # [m/s, rad/s]
    """Standard deviations of (b_u, b_omega) at an episode's start (their mean is 0)."""
    gain_prior: float = 0.05
    """Standard deviation of a at an episode's start (its mean is 1)."""
    coupling_prior: float = 0.2  # [1/m]
    """Standard deviation of g at an episode's start (its mean is 0)."""
    disturbance_limit: tuple[float, float] = (0.25, 1.0)  # [m/s, rad/s]
    """Guard: (b_u, b_omega) are clipped to +-this, so that a transient cannot command the limits."""
    gain_range: tuple[float, float] = (0.3, 1.5)
    """Guard: a is clipped to this range; its inverse scales the command."""
    coupling_limit: float = 6.0  # [1/m]
    """Guard: g is clipped to +-this."""
    max_delay: int = 12  # [control periods]
    """The input delays the filter tells apart, 0 to this: it predicts with the command the robot executes now and
    returns the pose predicted for when the next command takes effect (a Smith predictor); 0 assumes none."""
    delay_memory: float = 1.0  # [s]
    """Time constant over which the heading's residuals decide the delay."""

    def validate(self) -> None:
        as_float("position_noise", self.position_noise, 0.0, 1e3, low_inclusive=False)
        as_float("heading_noise", self.heading_noise, 0.0, 1e3, low_inclusive=False)
        set_ = object.__setattr__
        set_(self, "velocity_noise", _pair("velocity_noise", self.velocity_noise, 1e-9, 1e3))
        set_(self, "disturbance_rate", _pair("disturbance_rate", self.disturbance_rate, 0.0, 1e3))
        set_(self, "disturbance_prior", _pair("disturbance_prior", self.disturbance_prior, 0.0, 1e3))
        set_(self, "disturbance_limit", _pair("disturbance_limit", self.disturbance_limit, 0.0, 1e3))
        for name in ("gain_rate", "coupling_rate", "gain_prior", "coupling_prior", "coupling_limit"):
            as_float(name, getattr(self, name), 0.0, 1e3)
        if (
            isinstance(self.max_delay, bool)
            or not isinstance(self.max_delay, (int, np.integer))
            or not 0 <= self.max_delay <= 100
        ):
            raise ValueError(
                f"max_delay={self.max_delay!r} is invalid: expected an integer in [0, 100] (control periods)"
            )
        as_float("delay_memory", self.delay_memory, 0.0, 1e6, low_inclusive=False)
        low, high = _pair("gain_range", self.gain_range, 1e-3, 1e3)
        if not low <= 1.0 <= high:
            raise ValueError(f"gain_range={self.gain_range!r} is invalid: expected (low, high) with low <= 1 <= high")
        set_(self, "gain_range", (low, high))

    def process_covariance(self, dt: float) -> Array:
        """Q (7, 7) of one control period: velocity noise moves the pose, the robot's response walks."""
        v_u, v_w = self.velocity_noise
        r_u, r_w = self.disturbance_rate
        return np.diag([(v_u * dt) ** 2, (v_u * dt) ** 2, (v_w * dt) ** 2, r_u**2 * dt, r_w**2 * dt,
                        self.gain_rate**2 * dt, self.coupling_rate**2 * dt])  # fmt: skip

    def measurement_covariance(self) -> Array:
        """R (3, 3) of a pose measurement."""
        return np.diag([self.position_noise**2, self.position_noise**2, self.heading_noise**2])

    def initial_covariance(self) -> Array:
        """P (7, 7) at an episode's start: the first measurement's noise and the response's prior."""
        return np.diag([self.position_noise**2, self.position_noise**2, self.heading_noise**2,
                        self.disturbance_prior[0] ** 2, self.disturbance_prior[1] ** 2,
                        self.gain_prior**2, self.coupling_prior**2])  # fmt: skip

    def clip(self, mean: Array) -> Array:
        """Guard: the response's estimate (columns 3-6 of ``mean``) within its limits, in place."""
        (b_u, b_w), (low, high) = self.disturbance_limit, self.gain_range
        np.clip(mean[:, 3], -b_u, b_u, out=mean[:, 3])
        np.clip(mean[:, 4], -b_w, b_w, out=mean[:, 4])
        np.clip(mean[:, 5], low, high, out=mean[:, 5])
        np.clip(mean[:, 6], -self.coupling_limit, self.coupling_limit, out=mean[:, 6])
        return mean


def robot_velocities(u: Array, omega: Array, response: Array) -> tuple[Array, Array]:
    """What the robot does with commands (N,) under the response (N, 4) = (b_u, b_omega, a, g)."""
    b_u, b_w, a, g = response.T
    return a * u + b_u, a * omega + g * u + b_w


def compensated_commands(u: Array, omega: Array, response: Array, limits: Array | None = None) -> tuple[Array, Array]:
    """The commands for which the robot, with the response (N, 4), does (u, omega): the inverse of
    :func:`robot_velocities`.

    With ``limits`` (u_max, omega_max), where those commands exceed them, (u, omega) are scaled down by one factor
    per robot until they fit: the robot keeps the curvature it was asked for and slows down (with a failing wheel,
    turning at full speed may be impossible, turning slower is not). Only what cannot be had even standing still
    is clipped.
    """
    b_u, b_w, a, g = response.T
    if limits is None:
        u_command = (u - b_u) / a
        return u_command, (omega - b_w - g * u_command) / a
    # the commands are affine in the scale s: u_c = s A_u + B_u, omega_c = s A_w + B_w
    slope_u, offset_u = u / a, -b_u / a
    slope_w, offset_w = (omega - g * slope_u) / a, (-b_w - g * offset_u) / a
    scale = np.ones_like(u)
    for slope, offset, limit in ((slope_u, offset_u, limits[0]), (slope_w, offset_w, limits[1])):
        room = limit - np.sign(slope) * offset  # how far s A may go before |s A + B| reaches the limit
        with np.errstate(divide="ignore", invalid="ignore"):
            fits = np.where(np.abs(slope) > 1e-12, room / np.abs(slope), 1.0)
        scale = np.minimum(scale, np.clip(fits, 0.0, 1.0))
    u_command = np.clip(scale * slope_u + offset_u, -limits[0], limits[0])
    return u_command, np.clip(scale * slope_w + offset_w, -limits[1], limits[1])


def predict(
    mean: Array, covariance: Array, linear_velocity: Array, angular_velocity: Array, dt: float, process: Array
) -> tuple[Array, Array]:
    """Prediction over one control period with the commands held: the arc of eq. (1) and its Jacobian.

    ``mean`` (N, 7), ``covariance`` (N, 7, 7), commands (N,), ``process`` Q (7, 7). The Jacobian is that of
    the chord along the mid-heading (exact for the arc up to terms in (omega dt)^2).
    """
    x, y, psi = mean[:, 0], mean[:, 1], mean[:, 2]
    u_c, w_c = linear_velocity, angular_velocity
    u, w = robot_velocities(u_c, w_c, mean[:, 3:])
    new_x, new_y, new_psi = model.unicycle_step_exact(x, y, psi, u, w, dt)
    mid = psi + 0.5 * w * dt
    cos_mid, sin_mid = np.cos(mid), np.sin(mid)
    dx_du, dy_du = dt * cos_mid, dt * sin_mid  # d(x+, y+) / d(u_robot)
    dx_dw, dy_dw = -0.5 * u * dt * dt * sin_mid, 0.5 * u * dt * dt * cos_mid  # d(x+, y+) / d(omega_robot)
    jacobian = np.broadcast_to(np.eye(STATE_SIZE), covariance.shape).copy()
    jacobian[:, 0, 2], jacobian[:, 1, 2] = -u * dt * sin_mid, u * dt * cos_mid
    for column, du, dw in ((3, 1.0, 0.0), (4, 0.0, 1.0), (5, u_c, w_c), (6, 0.0, u_c)):  # d(u, omega)_robot / d state
        jacobian[:, 0, column] = dx_du * du + dx_dw * dw
        jacobian[:, 1, column] = dy_du * du + dy_dw * dw
        jacobian[:, 2, column] = dt * dw
    new_mean = np.concatenate([np.stack([new_x, new_y, new_psi], axis=1), mean[:, 3:]], axis=1)
    new_covariance = jacobian @ covariance @ jacobian.transpose(0, 2, 1) + process
    return new_mean, new_covariance


def correct(
    mean: Array, covariance: Array, measured: Array, valid: NDArray[np.bool_], measurement: Array
) -> tuple[Array, Array]:
    """Kalman correction with a measured pose (N, 3) for the robots where ``valid``; the others keep the prediction."""
    innovation = measured - mean[:, :3]
    innovation[:, 2] = model.wrap_angle(innovation[:, 2])
    cross = covariance[:, :, :3]  # P H^T with H = [I 0]
    gain = np.linalg.solve(covariance[:, :3, :3] + measurement, cross.transpose(0, 2, 1)).transpose(0, 2, 1)
    new_mean = mean + np.einsum("nij,nj->ni", gain, innovation)
    new_mean[:, 2] = model.wrap_angle(new_mean[:, 2])
    new_covariance = covariance - gain @ cross.transpose(0, 2, 1)
    new_covariance = 0.5 * (new_covariance + new_covariance.transpose(0, 2, 1))  # keep it symmetric
    keep = ~valid
    new_mean[keep], new_covariance[keep] = mean[keep], covariance[keep]
    return new_mean, new_covariance


def measured_pose(inputs: ControllerInput) -> Array:
    """The goal-frame pose (N, 3) a controller input describes: alpha = atan2(-y, -x) of eq. (3)."""
    d = np.asarray(inputs.distance, dtype=np.float64)
    return np.stack([-d * np.cos(inputs.azimuth), -d * np.sin(inputs.azimuth), inputs.heading], axis=1)


def with_pose(inputs: ControllerInput, pose: Array) -> ControllerInput:
    """``inputs`` with its distance, azimuth and heading those of the goal-frame ``pose`` (N, 3)."""
    x, y = pose[:, 0], pose[:, 1]
    return inputs._replace(
        distance=model.distance(x, y), azimuth=model.azimuth(x, y), heading=model.wrap_angle(pose[:, 2])
    )


class PoseFilter:
    """The filter's estimate for N robots, kept between control periods.

    Call :meth:`update` once per control period with what the robots measured and what they were commanded in
    the period before (the command the policy sent, within the limits); it returns the pose (N, 3) to act on.

    The input delay is told apart online: for each delay of 0 to ``max_delay`` periods, the heading change between
    two fresh measurements is compared with the turn the command of that many periods before would have made, and
    the squared differences are averaged over ``delay_memory``; the delay that explains the turns best (by a margin,
    so that noise does not toggle it) is the one the prediction uses, and the returned pose is the estimate carried
    forward through the commands already sent but not yet executed. Without delay this is the plain filter.
    """

    def __init__(self, params: PoseFilterParams | None = None, dt: float = 0.05, **kwargs: Any) -> None:
        self.params = params if params is not None else PoseFilterParams.from_kwargs(**kwargs)
        self.dt = as_float("dt", dt, 0.0, 1e3, low_inclusive=False)
        self._process = self.params.process_covariance(self.dt)
        self._measurement = self.params.measurement_covariance()
        self._forget = float(np.exp(-self.dt / self.params.delay_memory))
        self._resize(0)

    def _resize(self, n: int) -> None:
        depth = self.params.max_delay + 1
        self.mean: Array = np.zeros((n, STATE_SIZE))
        self.covariance: Array = np.zeros((n, STATE_SIZE, STATE_SIZE))
        self._started = np.zeros(n, dtype=bool)
        self._last_measured: Array = np.full((n, 3), np.nan)
        self._history: Array = np.zeros((n, depth, 2))  # the commands of the last periods, oldest first
        self._scores: Array = np.zeros((n, depth))  # how badly each delay explains the recent turns
        self._last_turned: Array = np.full(n, np.nan)  # the last measured heading change (NaN: none)
        self._last_predicted: Array = np.zeros((n, depth))  # the heading changes each delay predicted for it
        self.delay = np.zeros(n, dtype=np.int64)
        """The input delay [control periods] each robot's estimate assumes."""

    def reset(self, mask: ArrayLike | None = None) -> None:
        """Forget the estimate of the robots in ``mask`` (all without one): their next measurement starts anew."""
        if mask is None:
            self._started[:] = False
        elif np.shape(mask) == self._started.shape:  # (a batch of another size is started anew by update anyway)
            self._started[np.asarray(mask, dtype=bool)] = False

    @property
    def response(self) -> Array:
        """The estimated response (N, 4) to a command: (b_u [m/s], b_omega [rad/s], a [-], g [1/m])."""
        return self.mean[:, 3:]

    def update(self, measured: Array, commanded: Array) -> Array:
        """Predict with the command the robots executed (``commanded`` (N, 2) [m/s, rad/s] is the one sent last
        period), correct with ``measured`` (N, 3) unless it repeats the last measurement exactly; returns the pose
        (N, 3) at which the next command will take effect."""
        n = measured.shape[0]
        if self.mean.shape[0] != n:
            self._resize(n)
        fresh = ~self._started
        depth = self._history.shape[1]
        self._history = np.concatenate([self._history[:, 1:], commanded[:, None, :]], axis=1)
        self._history[fresh] = 0.0
        self._history[fresh, -1] = commanded[fresh]
        valid = np.any(measured != self._last_measured, axis=1)
        if depth > 1:
            self._identify_delay(measured, valid & ~fresh)
        executed = self._history[np.arange(n), depth - 1 - self.delay]
        mean, covariance = predict(self.mean, self.covariance, executed[:, 0], executed[:, 1], self.dt, self._process)
        mean, covariance = correct(mean, covariance, measured, valid, self._measurement)
        self.params.clip(mean)
        if fresh.any():  # a new episode starts from its first measurement and the response's prior
            mean[fresh] = np.concatenate([measured[fresh], np.tile(NOMINAL_RESPONSE, (int(fresh.sum()), 1))], axis=1)
            covariance[fresh] = self.params.initial_covariance()
            self._scores[fresh] = 0.0
            self._last_turned[fresh] = np.nan
            self.delay[fresh] = 0
        self.mean, self.covariance, self._last_measured = mean, covariance, measured.copy()
        self._started[:] = True
        return self.ahead()

    def _identify_delay(self, measured: Array, valid: NDArray[np.bool_]) -> None:
        """Score each delay by how well the change of the commands it assumes explains the change of the measured
        turn rate (second differences of the heading: a disturbance that varies slowly, or a response the filter
        has not learnt yet, cancels out; only the commands' own changes are evidence)."""
        n, depth = self._history.shape[:2]
        pair = valid & np.all(np.isfinite(self._last_measured), axis=1)
        turned = np.full(n, np.nan)
        turned[pair] = model.wrap_angle(measured[pair, 2] - self._last_measured[pair, 2])
        history = self._history[:, ::-1].reshape(-1, 2)  # per robot, delay 0 first
        _, omega = robot_velocities(history[:, 0], history[:, 1], np.repeat(self.mean[:, 3:], depth, axis=0))
        predicted = self.dt * omega.reshape(n, depth)
        both = pair & np.isfinite(self._last_turned)
        if both.any():
            residual = (turned[both] - self._last_turned[both])[:, None] - (
                predicted[both] - self._last_predicted[both]
            )
            scores = self._forget * self._scores[both] + residual**2
            self._scores[both] = scores
            rows = np.arange(scores.shape[0])
            best, current = np.argmin(scores, axis=1), self.delay[both]
            better = scores[rows, best] < DELAY_SWITCH * scores[rows, current]
            self.delay[both] = np.where(better, best, current)
        self._last_turned, self._last_predicted = turned, predicted

    def ahead(self) -> Array:
        """The estimated pose carried forward through the commands sent but not yet executed (its delay's)."""
        pose = self.mean[:, :3].copy()
        depth = self._history.shape[1]
        for lag in range(int(self.delay.max(initial=0)), 0, -1):
            moving = self.delay >= lag
            command = self._history[moving, depth - lag]
            u, omega = robot_velocities(command[:, 0], command[:, 1], self.mean[moving, 3:])
            x, y, psi = model.unicycle_step_exact(pose[moving, 0], pose[moving, 1], pose[moving, 2], u, omega, self.dt)
            pose[moving] = np.stack([x, y, psi], axis=1)
        return pose


class FilteredPolicy:
    """Any policy with stable-baselines3's ``predict``, acting on the filter's estimate instead of the measurement.

    Each call feeds the filter the observation and the command sent in the previous period, replaces the
    observation's pose features (0-5) by those of the estimated pose, and asks ``policy`` for the action.
    With ``cancel_disturbance`` the command is corrected by the estimated response of the robot
    (:func:`compensated_commands`: a disturbance observer). The clock features (6-9) pass through. ``episode_start`` (or a clock that goes
    back) starts a robot's estimate anew.

    >>> import gymnasium as gym, dwr_gym
    >>> from baselines import ExpertPolicy, PTCController
    >>> env = gym.make("DWRPointStabilization-v1", observation_noise=0.01)
    >>> policy = FilteredPolicy.from_env(env, ExpertPolicy.from_env(env, PTCController()))
    >>> obs, _ = env.reset(seed=1)
    >>> action, _ = policy.predict(obs)
    >>> action.shape, action.dtype
    ((2,), dtype('float32'))
    """

    def __init__(
        self,
        policy: Any,
        u_max: float,
        omega_max: float,
        dt: float,
        params: PoseFilterParams | None = None,
        *,
        k: float = 1.0 / (2.0 * np.pi),
        cancel_disturbance: bool = True,
    ) -> None:
        self.policy = policy
        self.limits = np.array([as_float("u_max", u_max, 0.0, 1e9, low_inclusive=False),
                                as_float("omega_max", omega_max, 0.0, 1e9, low_inclusive=False)])  # fmt: skip
        self.filter = PoseFilter(params, dt)
        self.k = as_float("k", k, 0.0, 1.0 / (2.0 * np.pi))
        self.cancel_disturbance = bool(cancel_disturbance)
        self._command: Array = np.zeros((0, 2))
        self._time: Array = np.zeros(0)

    @classmethod
    def from_env(cls, env: Any, policy: Any, params: PoseFilterParams | None = None, **kwargs: Any) -> FilteredPolicy:
        """``policy`` behind a filter matched to ``env``'s limits, control period and arcsine gain."""
        from baselines.expert import env_params_of

        env_params = env_params_of(env)
        return cls(policy, env_params.u_max, env_params.omega_max, env_params.dt, params, k=env_params.k, **kwargs)

    @property
    def controller(self) -> Any:
        """The wrapped policy's controller, if it has one (what evaluation asks planners for)."""
        return getattr(self.policy, "controller", None)

    def filtered_observation(self, obs: NDArray[np.floating], pose: Array) -> NDArray[np.float32]:
        """``obs`` (N, 10) with the pose features 0-5 of the goal-frame ``pose`` (N, 3)."""
        x, y, psi = pose.T
        d = model.distance(x, y)
        alpha = model.azimuth(x, y)
        out = np.array(obs, dtype=np.float32, copy=True)
        out[:, 0] = d
        out[:, 1], out[:, 2] = np.cos(alpha), np.sin(alpha)
        out[:, 3], out[:, 4] = np.cos(psi), np.sin(psi)
        out[:, 5] = model.orientation_error(alpha, psi, d, self.k)
        return out

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: NDArray[np.bool_] | None = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], Any]:
        """Normalised actions for one observation (10,) or a batch (N, 10)."""
        from baselines.expert import controller_input_from_observation

        obs = np.asarray(observation, dtype=np.float64)
        single = obs.ndim == 1
        batch = obs[None, :] if single else obs
        n = batch.shape[0]
        if self._command.shape[0] != n:
            self._command, self._time = np.zeros((n, 2)), np.full(n, np.inf)
        inputs = controller_input_from_observation(batch)
        restart = inputs.time < self._time
        if episode_start is not None:
            restart |= np.asarray(episode_start, dtype=bool).reshape(-1)
        self._time = np.asarray(inputs.time, dtype=np.float64).copy()
        self.filter.reset(restart)
        self._command[restart] = 0.0
        pose = self.filter.update(measured_pose(inputs), self._command)
        filtered = self.filtered_observation(batch, pose)
        start = None if episode_start is None else np.asarray(episode_start, dtype=bool).reshape(-1)
        actions, state = self.policy.predict(filtered, state, start, deterministic)
        actions = np.asarray(actions, dtype=np.float64).reshape(n, 2)
        command = np.clip(actions, -1.0, 1.0) * self.limits
        if self.cancel_disturbance:
            u, omega = compensated_commands(command[:, 0], command[:, 1], self.filter.response, self.limits)
            command = np.stack([u, omega], axis=1)
        self._command = command
        out = (command / self.limits).astype(np.float32)
        return (out[0] if single else out), state

    def __call__(self, observation: NDArray[np.floating]) -> NDArray[np.float32]:
        return self.predict(observation)[0]
