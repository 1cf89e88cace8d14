"""The state estimate (baselines/estimation.py): the filter's math against the model, what it estimates, and the
policies that sit behind it."""

from __future__ import annotations

import numpy as np
import pytest

from baselines.estimation import (
    NOMINAL_RESPONSE,
    PoseFilter,
    PoseFilterParams,
    compensated_commands,
    predict,
    robot_velocities,
)
from dwr_gym import model

DT = 0.05


def drive(commands: np.ndarray, response: tuple[float, float, float, float] = NOMINAL_RESPONSE, delay: int = 0,
          start: tuple[float, float, float] = (-1.0, 0.5, 0.3)) -> np.ndarray:  # fmt: skip
    """True goal-frame poses (steps + 1, 3) of one robot that executes ``commands`` (steps, 2) ``delay`` periods late."""
    x, y, psi = start
    poses = [start]
    executed = np.concatenate([np.zeros((delay, 2)), commands])[: len(commands)]
    b_u, b_w, a, g = response
    for u, w in executed:
        x, y, psi = model.unicycle_step_exact(x, y, psi, a * u + b_u, a * w + g * u + b_w, DT)
        poses.append((x, y, psi))
    return np.array(poses)


def run_filter(poses: np.ndarray, commands: np.ndarray, noise: float = 0.0, seed: int = 0,
               params: PoseFilterParams | None = None) -> tuple[np.ndarray, PoseFilter]:  # fmt: skip
    """The filter's returned poses fed with the measured poses and the commands sent one period before."""
    rng = np.random.default_rng(seed)
    pose_filter = PoseFilter(params, DT)
    out, sent = [], np.zeros(2)
    for k, pose in enumerate(poses[:-1]):
        measured = pose + noise * rng.standard_normal(3)
        out.append(pose_filter.update(measured[None], sent[None])[0])
        sent = commands[k]
    return np.array(out), pose_filter


def wiggle(steps: int, seed: int = 1) -> np.ndarray:
    """Commands that change often enough to tell the robot's response (and any delay) apart."""
    t = np.arange(steps) * DT
    rng = np.random.default_rng(seed)
    u = 0.25 + 0.1 * np.sin(0.9 * t) + 0.05 * np.sign(np.sin(2.3 * t + rng.uniform()))
    w = 0.8 * np.sin(1.7 * t) + 0.4 * np.sign(np.sin(3.1 * t))
    return np.stack([u, w], axis=1)


def test_prediction_is_the_exact_arc_and_its_jacobian_is_the_arcs_derivative() -> None:
    mean = np.array([[0.3, -0.2, 1.1, 0.02, -0.1, 0.9, -0.5]])
    covariance = np.eye(7)[None] * 1e-12
    u, w = np.array([0.4]), np.array([1.3])
    new, _ = predict(mean, covariance, u, w, DT, np.zeros((7, 7)))
    u_robot, w_robot = robot_velocities(u, w, mean[:, 3:])
    np.testing.assert_allclose(new[0, :3], model.unicycle_step_exact(0.3, -0.2, 1.1, u_robot[0], w_robot[0], DT),
                               rtol=0, atol=1e-15)  # fmt: skip
    np.testing.assert_array_equal(new[0, 3:], mean[0, 3:])  # the response walks, it does not drift
    # the covariance propagates through the Jacobian: compare with central differences of the arc
    unit = np.eye(7)[None]
    _, propagated = predict(mean, unit, u, w, DT, np.zeros((7, 7)))
    jacobian = np.zeros((7, 7))
    for j in range(7):
        step = np.zeros((1, 7))
        step[0, j] = 1e-6
        plus, _ = predict(mean + step, covariance, u, w, DT, np.zeros((7, 7)))
        minus, _ = predict(mean - step, covariance, u, w, DT, np.zeros((7, 7)))
        jacobian[:, j] = (plus[0] - minus[0]) / 2e-6
    np.testing.assert_allclose(propagated[0], jacobian @ jacobian.T, atol=2e-4)  # the chord's Jacobian: O((w dt)^2)


def test_compensated_commands_invert_the_response_and_keep_the_curvature_within_the_limits() -> None:
    rng = np.random.default_rng(0)
    u, w = rng.uniform(-0.4, 0.4, 200), rng.uniform(-1.5, 1.5, 200)
    response = np.stack([rng.uniform(-0.05, 0.05, 200), rng.uniform(-0.3, 0.3, 200), rng.uniform(0.6, 1.2, 200),
                         rng.uniform(-3, 3, 200)], axis=1)  # fmt: skip
    u_c, w_c = compensated_commands(u, w, response)
    np.testing.assert_allclose(robot_velocities(u_c, w_c, response), (u, w), atol=1e-12)
    limits = np.array([0.5, 2.0])
    u_c, w_c = compensated_commands(u, w, response, limits)
    assert np.all(np.abs(u_c) <= 0.5 + 1e-12) and np.all(np.abs(w_c) <= 2.0 + 1e-12)
    u_r, w_r = robot_velocities(u_c, w_c, response)
    reachable = (np.abs(response[:, 0]) < 0.5 * response[:, 2] * 0.5) & (np.abs(u_r) > 1e-3)
    # where a scale fits, the robot does a fraction s <= 1 of what was asked: the same curvature, slower
    scale = u_r[reachable] / u[reachable]
    assert np.all(scale <= 1 + 1e-9) and np.all(scale > 0)
    np.testing.assert_allclose(w_r[reachable], scale * w[reachable], atol=1e-9)


def test_the_estimate_is_closer_to_the_truth_than_the_noisy_measurement() -> None:
    commands = wiggle(400)
    poses = drive(commands)
    estimate, _ = run_filter(poses, commands, noise=0.01)
    error = np.hypot(*(estimate[100:, :2] - poses[100:-1, :2]).T)
    assert np.sqrt(np.mean(error**2)) < 0.5 * 0.01 * np.sqrt(2)  # half the measurement's position error


def test_a_repeated_measurement_is_no_measurement_the_estimate_moves_on_with_the_commands() -> None:
    commands = np.tile([0.3, 0.0], (60, 1))
    poses = drive(commands, start=(-1.0, 0.0, 0.0))
    pose_filter, sent = PoseFilter(dt=DT), np.zeros(2)
    for k in range(60):
        measured = poses[min(k, 20)]  # the sensor's last value, held from period 20 on
        estimate = pose_filter.update(measured[None], sent[None])[0]
        sent = commands[k]
    assert estimate[0] == pytest.approx(poses[59, 0], abs=1e-3)  # not stuck at the held x = poses[20, 0]
    assert abs(poses[20, 0] - poses[59, 0]) > 0.5


@pytest.mark.parametrize(("response", "expected"), [
    ((0.0, 0.15, 1.0, 0.0), {1: 0.15}),  # a constant turn: b_omega
    ((0.0, 0.0, 0.75, -3.125), {2: 0.75, 3: -3.125}),  # the right wheel at half its command, track 0.16 m
])  # fmt: skip
def test_the_observer_learns_the_robots_response(response: tuple, expected: dict[int, float]) -> None:
    commands = wiggle(600)
    poses = drive(commands, response)
    _, pose_filter = run_filter(poses, commands, noise=0.002)
    learned = pose_filter.response[0]
    for index, value in expected.items():
        assert learned[index] == pytest.approx(value, abs=0.08 * max(1.0, abs(value))), learned
    u_c, w_c = compensated_commands(np.array([0.2]), np.array([0.5]), pose_filter.response)
    np.testing.assert_allclose(robot_velocities(u_c, w_c, np.array([response])), ([0.2], [0.5]), atol=0.06)


def test_the_input_delay_is_told_apart_and_none_is_found_where_there_is_none() -> None:
    commands = wiggle(400)
    _, delayed = run_filter(drive(commands, delay=4), commands, noise=0.005)
    assert delayed.delay[0] == 4
    _, prompt = run_filter(drive(commands), commands, noise=0.005)
    assert prompt.delay[0] == 0


def test_filter_params_name_what_is_wrong() -> None:
    with pytest.raises(ValueError, match="position_noise"):
        PoseFilterParams(position_noise=0.0)
    with pytest.raises(ValueError, match="gain_range"):
        PoseFilterParams(gain_range=(1.2, 1.5))
    with pytest.raises(ValueError, match="max_delay"):
        PoseFilterParams(max_delay=-1)
    with pytest.raises(ValueError, match="velocity_noise"):
        PoseFilterParams(velocity_noise=(0.1,))  # type: ignore[arg-type]


def test_behind_the_filter_pose_noise_no_longer_becomes_command_chatter() -> None:
    """The PTC law under 1 cm / 0.01 rad pose noise: the rate of change of its commands with and without the filter."""
    from baselines import ExpertPolicy, PTCController
    from baselines.estimation import FilteredPolicy
    from train.evaluation.evaluate import evaluate
    from train.evaluation.scenarios import make_scenario

    scenario = make_scenario("random", n=20, seed=3, env_kwargs={"observation_noise": 0.01, "T_con": 20.0})
    raw = ExpertPolicy(PTCController(), 0.5, 2.0)
    filtered = FilteredPolicy(ExpertPolicy(PTCController(), 0.5, 2.0), 0.5, 2.0, DT, cancel_disturbance=False)
    results = evaluate({"raw": raw, "filtered": filtered}, scenario, seed=3)
    assert results["filtered"].success.all()
    assert results["filtered"].command_rate_rms.mean() < 0.5 * results["raw"].command_rate_rms.mean()


@pytest.mark.parametrize(("delay", "response"), [(3, NOMINAL_RESPONSE), (2, (0.02, 0.15, 0.9, 0.5))])
def test_the_smith_predictor_returns_the_pose_when_the_next_command_takes_effect(delay: int, response: tuple) -> None:
    """With the input delay D told apart, update() returns the estimate carried through the D commands sent but not
    yet executed: the model's rollout of those commands (with the learned response) from the estimated pose, which
    is where the robot really is D periods later."""
    commands = wiggle(300)
    poses = drive(commands, response, delay=delay)
    pose_filter, sent = PoseFilter(dt=DT), np.zeros(2)
    for k in range(len(commands)):
        returned = pose_filter.update(poses[k][None], sent[None])[0]
        sent = commands[k]
        if k < 150:
            continue
        assert pose_filter.delay[0] == delay
        x, y, psi = pose_filter.mean[0, :3]
        for command in commands[k - delay : k]:  # sent at k - D ... k - 1, executed from k on
            u, w = robot_velocities(command[:1], command[1:], pose_filter.response)
            x, y, psi = model.unicycle_step_exact(x, y, psi, u[0], w[0], DT)
        np.testing.assert_allclose(returned, (x, y, psi), rtol=0, atol=1e-12)
        if k + delay < len(poses):  # and that is where the robot is when the command sent now takes effect
            np.testing.assert_allclose(returned[:2], poses[k + delay, :2], atol=2e-3)


class Recorder:
    """A policy that answers ``action`` and keeps what it was given."""

    def __init__(self, action: tuple[float, float]) -> None:
        self.action = np.float32(action)
        self.seen: list[tuple[np.ndarray, object]] = []

    def predict(self, obs, state=None, episode_start=None, deterministic=True):  # type: ignore[no-untyped-def]
        self.seen.append((np.array(obs), episode_start))
        return np.tile(self.action, (len(obs), 1)), state


def test_behind_the_filter_a_policy_sees_the_pose_features_of_the_robot_and_its_episode_starts() -> None:
    """Without noise or disturbance the filtered observation is the env's (features 0-5 to rounding, 6-9 as they
    are); episode_start reaches the policy; a clock that goes back starts the estimate anew."""
    import gymnasium as gym

    from baselines.estimation import FilteredPolicy

    env = gym.make("DWRPointStabilization-v1", disable_env_checker=True)
    recorder = Recorder((0.6, 0.4))
    policy = FilteredPolicy.from_env(env, recorder)
    obs, _ = env.reset(seed=3)
    for k in range(40):
        start = np.array([k == 0])
        action, _ = policy.predict(obs[None], episode_start=start)
        seen, episode_start = recorder.seen[-1]
        np.testing.assert_array_equal(episode_start, start)
        np.testing.assert_allclose(seen[0, :6], obs[:6], atol=2e-4)
        np.testing.assert_array_equal(seen[0, 6:], obs[6:])
        obs, *_ = env.step(action[0])
    noisy = gym.make("DWRPointStabilization-v1", observation_noise=0.02, disable_env_checker=True)
    obs, _ = noisy.reset(seed=5)
    for k in range(10):  # with pose noise the policy sees the estimate: every pose feature is the estimated pose's
        action, _ = policy.predict(obs)
        seen = recorder.seen[-1][0][0]
        x, y, psi = policy.filter.mean[0, :3]
        assert seen[0] == pytest.approx(np.hypot(x, y), abs=1e-6)
        assert k == 0 or abs(seen[0] - obs[0]) > 1e-6  # (the first estimate is the first measurement)
        np.testing.assert_allclose(seen[1:5], [-x / np.hypot(x, y), -y / np.hypot(x, y), np.cos(psi), np.sin(psi)],
                                   atol=1e-6)  # fmt: skip
        obs, *_ = noisy.step(action)
    obs, _ = env.reset(seed=4)  # a new episode the policy is not told of: its clock goes back to 0
    policy.predict(obs[None])
    np.testing.assert_allclose(recorder.seen[-1][0][0, :6], obs[:6], atol=1e-6)  # the first measurement, exactly


def test_the_filtered_policy_cancels_the_robots_estimated_response_and_keeps_its_limits() -> None:
    """On a robot with a turn bias of 0.3 rad/s, the policy's commands are corrected so that the robot turns as the
    policy asked; without cancel_disturbance they pass as they are; actions past the limits are clipped."""
    import gymnasium as gym

    from baselines.estimation import FilteredPolicy
    from dwr_gym.disturbances import VelocityBias

    turns = {}
    for cancel in (True, False):
        env = gym.make("DWRPointStabilization-v1", disturbances=[VelocityBias(0.0, 0.3)], T_con=20.0,
                       start_distance=(3.0, 3.0), disable_env_checker=True)  # fmt: skip
        policy = FilteredPolicy.from_env(env, Recorder((0.4, 0.1)), cancel_disturbance=cancel)
        obs, _ = env.reset(seed=1)
        for _ in range(120):
            action, _ = policy.predict(obs)
            obs, _, _, _, info = env.step(action)
        turns[cancel] = (info["angular_velocity"], action)
    assert turns[True][0] == pytest.approx(0.1 * 2.0, abs=0.03)  # the robot turns at the asked 0.2 rad/s
    assert turns[False][0] == pytest.approx(0.2 + 0.3, abs=1e-6)  # the bias acts unopposed
    np.testing.assert_array_equal(turns[False][1], np.float32([0.4, 0.1]))
    clipped = FilteredPolicy(Recorder((3.0, -3.0)), 0.5, 2.0, DT, cancel_disturbance=False)
    action, _ = clipped.predict(np.float32([1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 20.0, 1.0, 0.0]))
    np.testing.assert_array_equal(action, np.float32([1.0, -1.0]))
    with pytest.raises(ValueError, match=r"^k=0\.2 is invalid"):
        FilteredPolicy(Recorder((0.0, 0.0)), 0.5, 2.0, DT, k=0.2)
    with pytest.raises(ValueError, match=r"^disturbance_limit\[1\]=2000\.0 is invalid"):
        PoseFilterParams(disturbance_limit=(0.1, 2000.0))


def test_a_repeated_measurement_of_one_robot_does_not_stop_the_others_being_corrected_and_vice_versa() -> None:
    commands = np.tile([0.3, 0.0], (60, 1))
    poses = drive(commands, start=(-1.0, 0.0, 0.0))
    pose_filter, sent = PoseFilter(dt=DT), np.zeros((2, 2))
    for k in range(60):
        # robot 0's sensor holds its value from period 20 on; robot 1's is fresh but 5 cm off in y (a bias to correct)
        measured = np.stack([poses[min(k, 20)], poses[k] + [0.0, 0.05, 0.0]])
        estimate = pose_filter.update(measured, sent)
        sent = np.stack([commands[k], commands[k]])
    assert estimate[0, 0] == pytest.approx(poses[59, 0], abs=1e-3)  # robot 0 moved on with its commands
    assert estimate[1, 1] == pytest.approx(0.05, abs=2e-3)  # robot 1 follows its measurement


def test_the_filters_covariances_are_its_noise_levels() -> None:
    """Q of one period is what the velocity noise moves the pose by and the response's random walks; P at an
    episode's start is the first measurement's noise and the response's prior."""
    params = PoseFilterParams(position_noise=0.02, heading_noise=0.03, velocity_noise=(0.05, 0.2),
                              disturbance_rate=(0.01, 0.04), gain_rate=0.06, coupling_rate=0.3,
                              disturbance_prior=(0.07, 0.25), gain_prior=0.08, coupling_prior=0.4)  # fmt: skip
    dt = 0.1
    np.testing.assert_allclose(np.diag(params.process_covariance(dt)),
                               [0.005**2, 0.005**2, 0.02**2, 0.01**2 * dt, 0.04**2 * dt, 0.06**2 * dt, 0.3**2 * dt])  # fmt: skip
    pose_filter = PoseFilter(params, dt)
    pose_filter.update(np.array([[1.0, 2.0, 0.5]]), np.zeros((1, 2)))
    np.testing.assert_allclose(pose_filter.covariance[0],
                               np.diag([0.02**2, 0.02**2, 0.03**2, 0.07**2, 0.25**2, 0.08**2, 0.4**2]))  # fmt: skip
    np.testing.assert_allclose(params.measurement_covariance(), np.diag([0.02**2, 0.02**2, 0.03**2]))
