"""Robot wheels, disturbances, faults, delay and dropout: off is the nominal env, on acts as documented."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import dwr_gym  # noqa: F401  (registers the env)
from baselines import ExpertPolicy, PTCController
from dwr_gym.disturbances import (
    ActuatorFault,
    InputDelay,
    MeasurementDropout,
    VelocityBias,
    VelocityRandomWalk,
    VelocitySinusoid,
    WheelSlip,
)
from dwr_gym.robots import ROBOTS, DifferentialDrive, wheel_speeds
from tests.test_cli import dwr_gym as run_cli

ENV_ID = "DWRPointStabilization-v0"
#: This module pins the behaviour of DWRPointStabilization-v0 (fixed T_con, the paper's reward), which Gymnasium
#: rightly calls out of date now that v1 exists; that warning is not what these tests test.
pytestmark = pytest.mark.filterwarnings("ignore:.*DWRPointStabilization-v0 is out of date:DeprecationWarning")
GEOMETRY = DifferentialDrive(0.033, 0.16)  # TurtleBot3 Burger's wheels without a speed limit


def trajectory(env: gym.Env[Any, Any], seed: int, steps: int, noise: float = 0.3) -> dict[str, np.ndarray]:
    """Observations, rewards and poses of the PTC expert with seeded action noise, over episodes."""
    expert = ExpertPolicy.from_env(env, PTCController())
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed)
    record: dict[str, list[Any]] = {"obs": [obs], "reward": [], "pose": [info["pose"]], "info": [info]}
    for _ in range(steps):
        action = expert.predict(obs)[0] + noise * rng.standard_normal(2).astype(np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        record["obs"].append(obs)
        record["reward"].append(reward)
        record["pose"].append(info["pose"])
        record["info"].append(info)
        if terminated or truncated:
            obs, info = env.reset()
    return {key: np.array(value) if key != "info" else value for key, value in record.items()}  # type: ignore[misc]


def test_v0_defaults_are_bit_for_bit_those_before_the_feature() -> None:
    """Figures recorded from DWRPointStabilization-v0 before disturbances existed (commit 28d861d)."""
    env = gym.make(ENV_ID)
    expert = ExpertPolicy.from_env(env, PTCController())
    rng = np.random.default_rng(5)
    obs, info = env.reset(seed=11)
    total, poses = 0.0, []
    for _ in range(900):
        obs, reward, terminated, truncated, info = env.step(
            expert.predict(obs)[0] + 0.3 * rng.standard_normal(2).astype(np.float32)
        )
        total += float(reward)
        if terminated or truncated:
            poses.append(info["pose"])
            obs, info = env.reset()
    poses.append(info["pose"])
    assert total == pytest.approx(13.978367796599011, rel=1e-12, abs=0)
    np.testing.assert_allclose(poses, [[0.002740155381513572, 0.0016437223879707087, -2.7830966946496556],
                                       [-0.009216928555902695, -0.002940444468343407, 0.3163614585512385],
                                       [-0.017403925036136622, -0.0006777282144361039, 0.06514943701958001]],
                               rtol=1e-12, atol=1e-15)  # fmt: skip
    assert float(np.sum(obs, dtype=np.float64)) == pytest.approx(21.290495712310076, rel=1e-7)
    assert "disturbance" not in info


def test_zero_disturbances_reproduce_the_nominal_trajectories_exactly() -> None:
    zero = [VelocityBias(0.0, 0.0), VelocitySinusoid(0.0, 0.0), VelocityRandomWalk(0.0, 0.0, seed=3),
            InputDelay(0), MeasurementDropout(0.0)]  # fmt: skip
    nominal = trajectory(gym.make(ENV_ID), seed=2, steps=700)
    disturbed = trajectory(gym.make(ENV_ID, disturbances=zero), seed=2, steps=700)
    for key in ("obs", "reward", "pose"):
        np.testing.assert_array_equal(disturbed[key], nominal[key], err_msg=key)
    assert disturbed["info"][1]["disturbance"]["measurement_held"] is False
    # the wheels add only the rounding of (u, omega) -> (w_L, w_R) -> (u, omega)
    wheels = trajectory(gym.make(ENV_ID, robot=GEOMETRY, disturbances=[WheelSlip(1.0, 1.0)]), seed=2, steps=700)
    np.testing.assert_allclose(wheels["pose"], nominal["pose"], rtol=0, atol=1e-9)


def test_disturbed_vector_env_matches_single_envs_step_by_step() -> None:
    kwargs = {"robot": "turtlebot3_burger", "wheel_saturation": "clip", "T_con": 8.0,
              "disturbances": [VelocityBias(0.01, -0.05), VelocitySinusoid(0.02, 0.1, period=3.0),
                               VelocityRandomWalk(0.02, 0.1, seed=4), WheelSlip(0.9, 0.95),
                               ActuatorFault("left", 0.7, start_time=2.0), InputDelay(2),
                               MeasurementDropout(0.3, seed=5)]}  # fmt: skip
    vec = gym.make_vec(ENV_ID, num_envs=3, autoreset_mode="same_step", **kwargs)
    ref = SyncVectorEnv([lambda: gym.make(ENV_ID, **kwargs) for _ in range(3)], autoreset_mode=AutoresetMode.SAME_STEP)
    obs, _ = vec.reset(seed=7)
    ref_obs, _ = ref.reset(seed=7)
    np.testing.assert_allclose(obs, ref_obs, rtol=1e-6, atol=1e-7)
    vec.action_space.seed(1)
    held = resets = 0
    for _ in range(400):
        actions = vec.action_space.sample()
        obs, rewards, terminated, truncated, info = vec.step(actions)
        ref_obs, ref_rewards, ref_terminated, ref_truncated, ref_info = ref.step(actions)
        np.testing.assert_allclose(obs, ref_obs, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(rewards, ref_rewards, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(terminated | truncated, ref_terminated | ref_truncated)
        np.testing.assert_allclose(info["linear_velocity"], ref_info["linear_velocity"], rtol=1e-9, atol=1e-12)
        for key in ("measurement_held", "fault_active", "wheel_saturated"):
            np.testing.assert_array_equal(info["disturbance"][key], ref_info["disturbance"][key], err_msg=key)
        held += int(info["disturbance"]["measurement_held"].sum())
        resets += int((terminated | truncated).sum())
    assert held > 100 and resets >= 3  # dropout and autoreset were both exercised


def test_a_fault_starts_at_its_time_and_not_before() -> None:
    start = 3.0
    nominal = trajectory(gym.make(ENV_ID, robot=GEOMETRY), seed=4, steps=120, noise=0.0)
    faulty = trajectory(
        gym.make(ENV_ID, robot=GEOMETRY, disturbances=[ActuatorFault("right", 0.2, start_time=start)]),
        seed=4, steps=120, noise=0.0,
    )  # fmt: skip
    steps_before = round(start / 0.05)  # steps 1..60 start before t = 3 s; step 61 is the first faulty one
    np.testing.assert_array_equal(faulty["pose"][: steps_before + 1], nominal["pose"][: steps_before + 1])
    assert not np.allclose(faulty["pose"][steps_before + 1], nominal["pose"][steps_before + 1], rtol=0, atol=1e-9)
    active = [info["disturbance"]["fault_active"] for info in faulty["info"][1:]]
    assert active == [False] * steps_before + [True] * (120 - steps_before)


def test_input_delay_executes_the_command_of_k_periods_ago() -> None:
    env = gym.make(ENV_ID, disturbances=[InputDelay(3)])
    env.reset(seed=0, options={"start": (0.0, 0.0, 0.0), "goal": (1.0, 0.0, 0.0)})
    commands = [(0.2, 0.0), (0.4, 0.1), (0.6, -0.2), (0.8, 0.3), (1.0, 0.0)]
    applied = [env.step(np.array(c, dtype=np.float32))[4] for c in commands]
    assert [i["linear_velocity"] for i in applied[:3]] == [0.0, 0.0, 0.0]
    assert applied[3]["linear_velocity"] == pytest.approx(0.2 * 0.5)
    assert applied[4]["angular_velocity"] == pytest.approx(0.1 * 2.0)
    assert applied[4]["disturbance"]["commanded_linear_velocity"] == pytest.approx(0.5)


@pytest.mark.parametrize("robot", sorted(ROBOTS))
@pytest.mark.parametrize("saturation", ["clip", "scale"])
def test_preset_wheel_limits_are_never_exceeded(robot: str, saturation: str) -> None:
    drive = ROBOTS[robot]
    env = gym.make(ENV_ID, robot=robot, wheel_saturation=saturation)
    params = env.unwrapped.params  # type: ignore[attr-defined]
    assert params.u_max == pytest.approx(drive.max_linear_velocity)
    assert params.omega_max == pytest.approx(drive.max_angular_velocity)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    corners = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1], [1, 0.3], [0.2, -1]], dtype=np.float32)
    actions = np.concatenate([corners, rng.uniform(-1.5, 1.5, (100, 2)).astype(np.float32)])
    saturated = 0
    for action in actions:
        info = env.step(action)[4]
        left, right = wheel_speeds(info["linear_velocity"], info["angular_velocity"], drive)
        assert max(abs(left), abs(right)) <= drive.max_wheel_speed * (1 + 1e-12)
        saturated += info["disturbance"]["wheel_saturated"]
        if saturation == "scale":  # the curvature of the command is kept
            u_cmd = info["disturbance"]["commanded_linear_velocity"]
            omega_cmd = info["disturbance"]["commanded_angular_velocity"]
            assert info["angular_velocity"] * u_cmd == pytest.approx(omega_cmd * info["linear_velocity"], abs=1e-12)
    assert saturated > 10  # the limits were reached


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"robot": DifferentialDrive}, "robot="),
        ({"robot": "roomba"}, "robot='roomba' is invalid: expected a DifferentialDrive or one of turtlebot3_burger"),
        ({"robot": "e_puck", "wheel_saturation": "bend"}, "wheel_saturation='bend' is invalid"),
        ({"disturbances": [InputDelay(600)]}, "InputDelay.steps=600 is invalid: expected an integer in [0, 599]"),
        ({"disturbances": ["bias"]}, "disturbances item 'bias' is invalid"),
        (
            {"disturbances": [WheelSlip(0.5, 1.0)]},
            "WheelSlip acts on the wheels: pass robot=... (a preset or a DifferentialDrive) with it",
        ),
        ({"wheel_saturation": "clip"}, "wheel_saturation='clip' is invalid without a robot: pass robot=... too"),
        ({"robot": GEOMETRY, "disturbances": [ActuatorFault(start_time=31.0)]}, "ActuatorFault.start_time=31.0"),
    ],
)
def test_bad_settings_name_the_setting_and_the_range(kwargs: dict[str, Any], message: str) -> None:
    for make in (lambda: gym.make(ENV_ID, **kwargs), lambda: gym.make_vec(ENV_ID, num_envs=2, **kwargs)):
        with pytest.raises(ValueError) as error:
            make()
        assert message in str(error.value)
        assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: DifferentialDrive(-0.03, 0.16), "wheel_radius=-0.03 is invalid: expected a finite number in (0, 10]"),
        (lambda: DifferentialDrive(0.03, 0.16, max_wheel_speed=0.0), "max_wheel_speed=0.0 is invalid"),
        (lambda: ActuatorFault(wheel="third"), "ActuatorFault.wheel='third' is invalid: expected 'left' or 'right'"),
        (lambda: ActuatorFault(fraction=1.5), "ActuatorFault.fraction=1.5 is invalid: expected a finite number in [0, 1]"),
        (lambda: InputDelay(-1), "InputDelay.steps=-1 is invalid: expected an integer >= 0"),
        (lambda: MeasurementDropout(1.0), "MeasurementDropout.probability=1.0 is invalid"),
        (lambda: VelocityRandomWalk(0.1, math.nan), "VelocityRandomWalk.angular_intensity=nan is invalid"),
        (lambda: VelocityRandomWalk(seed=-1), "seed=-1 is invalid: expected an integer >= 0"),
        (lambda: VelocitySinusoid(period=0.0), "VelocitySinusoid.period=0.0 is invalid"),
    ],
)  # fmt: skip
def test_bad_disturbance_settings_name_the_setting_and_the_range(build: Any, message: str) -> None:
    with pytest.raises(ValueError) as error:
        build()
    assert message in str(error.value)


def test_random_disturbances_are_seeded_and_reproducible() -> None:
    kwargs = {"disturbances": [VelocityRandomWalk(0.05, 0.2, seed=1), MeasurementDropout(0.5, seed=2)]}
    first = trajectory(gym.make(ENV_ID, **kwargs), seed=3, steps=200)
    again = trajectory(gym.make(ENV_ID, **kwargs), seed=3, steps=200)
    np.testing.assert_array_equal(first["pose"], again["pose"])
    other = {"disturbances": [VelocityRandomWalk(0.05, 0.2, seed=9), MeasurementDropout(0.5, seed=2)]}
    assert not np.array_equal(trajectory(gym.make(ENV_ID, **other), seed=3, steps=200)["pose"], first["pose"])
    held = [info["disturbance"]["measurement_held"] for info in first["info"][1:]]
    assert 0.4 < np.mean(held) < 0.6
    for step in np.flatnonzero(held)[:20] + 1:  # a held measurement repeats the pose features; the clock runs on
        np.testing.assert_array_equal(first["obs"][step][:6], first["obs"][step - 1][:6])
        assert first["obs"][step][6] != first["obs"][step - 1][6] or first["obs"][step][6] == 0.0


def test_evaluate_robustness_sets_and_robustness_sweep_end_to_end(tmp_path: Path) -> None:
    result = run_cli("evaluate", "--controllers", "ptc", "--scenarios", "disturbed", "fault", "delay", "noise",
                     "--n", "8", "--optimum", "none", "--out", str(tmp_path / "eval"), "--no-progress",
                     "--env-kwargs", "robot=turtlebot3_burger")  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = json.loads((tmp_path / "eval" / "evaluation.json").read_text())
    assert [r["scenario"] for r in rows] == ["disturbed", "fault", "delay", "noise"]
    assert all(r["n"] == 8 for r in rows)
    assert all(0.1 < r["peak_u_max"] <= 0.22 + 1e-9 for r in rows if r["scenario"] in ("fault", "delay"))
    result = run_cli("robustness", "--disturbances", "delay", "--controllers", "ptc", "--no-shipped-agents",
                     "--n", "6", "--out", str(tmp_path / "rob"), "--no-progress")  # fmt: skip
    assert result.returncode == 0, result.stderr
    rows = json.loads((tmp_path / "rob" / "robustness.json").read_text())
    magnitudes = [r["magnitude"] for r in rows]
    assert magnitudes == [0, 4, 8, 16, 24, 32][: len(magnitudes)]  # until it arrives in fewer than half
    assert len(magnitudes) == 6 or rows[-1]["success_rate"] < 0.5
    assert rows[0]["success_rate"] == 1.0 and rows[-1]["success_rate"] < rows[0]["success_rate"]
    assert (tmp_path / "rob" / "robustness_delay.png").stat().st_size > 10_000
    assert "| delay (" in (tmp_path / "rob" / "robustness.md").read_text()
    bad = run_cli("robustness", "--disturbances", "gravity", "--no-shipped-agents")
    assert bad.returncode == 2 and "--disturbances 'gravity' is invalid: expected any of bias" in bad.stderr


def test_tolerance_table_reads_the_largest_magnitude_held_without_a_dip() -> None:
    from train.evaluation.robustness import tolerated
    from train.reporting.tables import tolerance_markdown

    def row(policy: str, magnitude: float, rate: float) -> dict[str, Any]:
        return {"disturbance": "delay", "magnitude": magnitude, "policy": policy, "success_rate": rate, "n": 100}

    rows = [row("a", 0, 1.0), row("a", 4, 0.96), row("a", 8, 0.5), row("a", 16, 0.97),  # a dip ends it at 4
            row("b", 0, 0.9), row("b", 4, 1.0), row("b", 8, 1.0), row("b", 16, 1.0),  # fails undisturbed
            row("c", 0, 1.0), row("c", 4, 1.0), row("c", 8, 0.95), row("c", 16, 0.95)]  # fmt: skip
    assert tolerated(rows) == {("delay", "a"): 4, ("delay", "b"): None, ("delay", "c"): 16}
    assert "| 4 | - | 16+ |" in tolerance_markdown(rows)


# (class, field, lowest allowed, highest allowed, whether the highest is excluded)
DISTURBANCE_RANGES = [
    (VelocityBias, "linear", -100.0, 100.0, False), (VelocityBias, "angular", -100.0, 100.0, False),
    (VelocitySinusoid, "linear_amplitude", 0.0, 100.0, False), (VelocitySinusoid, "angular_amplitude", 0.0, 100.0, False),
    (VelocitySinusoid, "phase", -1e6, 1e6, False),
    (VelocityRandomWalk, "linear_intensity", 0.0, 100.0, False),
    (VelocityRandomWalk, "angular_intensity", 0.0, 100.0, False),
    (WheelSlip, "left", 0.0, 1.0, False), (WheelSlip, "right", 0.0, 1.0, False),
    (ActuatorFault, "fraction", 0.0, 1.0, False), (ActuatorFault, "start_time", 0.0, 1e6, False),
    (MeasurementDropout, "probability", 0.0, 1.0, True),
]  # fmt: skip


@pytest.mark.parametrize(("cls", "field", "low", "high", "high_excluded"), DISTURBANCE_RANGES,
                         ids=[f"{c.__name__}.{f}" for c, f, *_ in DISTURBANCE_RANGES])  # fmt: skip
def test_each_disturbance_field_takes_its_range_as_a_float_and_names_itself_outside(
    cls: type, field: str, low: float, high: float, high_excluded: bool
) -> None:
    for inside in (low, np.float32(0.5 * (low + high)), high - 1e-9 if high_excluded else high):
        value = getattr(cls(**{field: inside}), field)
        assert type(value) is float and value == float(inside), (inside, value)  # numpy numbers become floats
    step = 1e-6 * max(1.0, abs(high))
    for outside in (low - step, high if high_excluded else high + step, math.nan):
        with pytest.raises(ValueError, match=re.escape(f"{cls.__name__}.{field}={outside!r} is invalid")):
            cls(**{field: outside})


def test_disturbance_integers_are_validated_and_kept_as_ints() -> None:
    assert InputDelay(np.int64(3)).steps == 3 and type(InputDelay(np.int64(3)).steps) is int
    for cls in (VelocityRandomWalk, MeasurementDropout):
        assert type(cls(seed=np.int64(7)).seed) is int and cls(seed=np.int64(7)).seed == 7
        for bad in (-1, 1.5, True):
            with pytest.raises(ValueError, match=re.escape(f"seed={bad!r} is invalid")):
                cls(seed=bad)
    assert type(VelocitySinusoid(period=np.int64(3)).period) is float and VelocitySinusoid(period=1e6).period == 1e6
    with pytest.raises(ValueError, match=r"VelocitySinusoid.period=0.0 is invalid: expected a finite number in \(0, "):
        VelocitySinusoid(period=0.0)


def test_random_disturbances_without_a_seed_draw_fresh_entropy() -> None:
    kwargs = {"disturbances": [VelocityRandomWalk(0.05, 0.2), MeasurementDropout(0.3)]}
    first, second = gym.make(ENV_ID, **kwargs), gym.make(ENV_ID, **kwargs)
    for env in (first, second):
        env.reset(options={"start": (0.0, 0.0, 0.0), "goal": (1.0, 0.0, 0.0)})  # no seed
    walks = [[env.step(np.zeros(2, np.float32))[4]["linear_velocity"] for _ in range(5)] for env in (first, second)]
    assert walks[0] != walks[1] and all(np.isfinite(walks).ravel())


def test_the_disturbance_flags_are_booleans_from_the_reset_on_and_float32_stays_float32() -> None:
    kwargs = {"robot": "turtlebot3_burger", "disturbances": [VelocityBias(0.01, 0.0), MeasurementDropout(0.2)]}
    _, info = gym.make(ENV_ID, **kwargs).reset(seed=0)
    for key in ("wheel_saturated", "fault_active", "measurement_held"):
        assert info["disturbance"][key] is False, key
    vec = gym.make_vec(ENV_ID, num_envs=3, dtype="float32", **kwargs)
    _, infos = vec.reset(seed=0)
    assert all(infos["disturbance"][key].dtype == np.bool_ for key in ("wheel_saturated", "measurement_held"))
    _, _, _, _, infos = vec.step(np.full((3, 2), 0.5, np.float32))
    assert infos["linear_velocity"].dtype == np.float32 and infos["angular_velocity"].dtype == np.float32
    np.testing.assert_allclose(infos["linear_velocity"], 0.5 * 0.22 + 0.01, rtol=1e-6)


class StandStill:
    """A policy that never moves: it fails at every magnitude."""

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> Any:
        return np.zeros((np.shape(observation)[0], 2), dtype=np.float32), None


def test_a_policy_that_fell_below_half_is_not_run_at_larger_magnitudes() -> None:
    """The sweep gives up on a policy once it arrives in fewer than half of the episodes (its tolerance is known)."""
    from train.evaluation.robustness import GIVE_UP_LEVEL, SWEEPS, sweep

    rows = sweep({"still": StandStill(), "ptc": "ptc"}, ["delay"], n=4, env_kwargs={"T_con": 20.0})
    magnitudes = {policy: [r["magnitude"] for r in rows if r["policy"] == policy] for policy in ("still", "ptc")}
    assert GIVE_UP_LEVEL == 0.5
    assert magnitudes["still"] == [0.0]
    kept = [m for m in SWEEPS["delay"].magnitudes]
    first_low = next((i for i, m in enumerate(kept) if m not in magnitudes["ptc"]), len(kept))
    assert magnitudes["ptc"] == kept[:first_low]
    below = [r for r in rows if r["policy"] == "ptc" and r["success_rate"] < GIVE_UP_LEVEL]
    assert len(below) <= 1 and (not below or below[0]["magnitude"] == magnitudes["ptc"][-1])


def test_the_command_rate_is_of_what_was_commanded_not_of_what_a_disturbed_robot_did() -> None:
    """Under a sinusoidal push the robot's velocities wave while the commands stay put: the command rate is still
    the one step 0 -> (0.25 m/s, 2 rad/s); the velocity rate is that of the recorded velocities."""
    from dwr_gym.params import EnvParams
    from tests.test_controllers import TurnAndGo
    from train.evaluation.rollout import rollout

    params = EnvParams(T_con=2.0)  # 60 steps to the horizon, none arrives
    starts = np.array([[-1.0, 0.0, 0.0], [2.0, 1.0, 0.5]])
    push = {"disturbances": [VelocitySinusoid(0.1, 0.5, period=0.6)]}
    result = rollout(TurnAndGo(), params, starts, np.zeros((2, 3)), record=True, env_kwargs=push)
    np.testing.assert_allclose(result.command_rate_rms, math.sqrt((0.25**2 + 2.0**2) / 0.05**2 / 60))
    trajectory = result.trajectory
    assert trajectory is not None and trajectory["linear_velocity"].shape == (60, 2)
    velocities = np.stack([trajectory["linear_velocity"], trajectory["angular_velocity"]], axis=-1)  # (60, 2, 2)
    assert np.ptp(velocities[:, 0, 0]) > 0.15  # the robot did not do as commanded
    steps = np.diff(np.concatenate([np.zeros((1, 2, 2)), velocities]), axis=0)
    np.testing.assert_allclose(result.velocity_rate_rms, np.sqrt(np.sum(steps**2, axis=(0, 2)) / 0.05**2 / 60))
    assert np.all(result.velocity_rate_rms > 1.2 * result.command_rate_rms)  # so the two metrics differ here


def test_random_disturbances_drawn_ahead_are_the_numbers_of_one_draw_per_period() -> None:
    """The random walk's and the dropout's values, drawn DRAW_BLOCK periods ahead, are each robot's own stream as one
    draw per period would take it, also when some robots are re-seeded in the middle of a block."""
    from dwr_gym.disturbances import DRAW_BLOCK, Perturbation
    from dwr_gym.params import EnvParams

    items = (VelocityRandomWalk(0.1, 0.2, seed=7), MeasurementDropout(0.3, seed=8))
    n, periods, reseed_at = 5, DRAW_BLOCK * 2 + 9, DRAW_BLOCK + 17
    perturbation = Perturbation(None, items, EnvParams(), n)
    perturbation.seed(list(range(n)), [(3, i) for i in range(n)])

    def stream(item_seed: int, key: tuple[int, ...]) -> np.random.Generator:
        return np.random.Generator(np.random.PCG64(np.random.SeedSequence([item_seed, *key])))

    walks = [stream(7, (3, i)) for i in range(n)]
    drops = [stream(8, (3, i)) for i in range(n)]
    for period in range(periods):
        if period == reseed_at:
            perturbation.seed([1, 3], [(9, 1), (9, 3)])
            walks[1], walks[3], drops[1], drops[3] = (
                stream(7, (9, 1)),
                stream(7, (9, 3)),
                stream(8, (9, 1)),
                stream(8, (9, 3)),
            )
        np.testing.assert_array_equal(perturbation._draw(0), np.array([rng.standard_normal(2) for rng in walks]))
        np.testing.assert_array_equal(perturbation._draw(1)[:, 0], np.array([rng.random() for rng in drops]))
