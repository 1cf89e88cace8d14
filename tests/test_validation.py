"""The validation layer: what users pass is accepted, the rest is one clear line naming the parameter."""

from __future__ import annotations

import json
import math

import gymnasium as gym
import numpy as np
import pytest

import dwr_gym  # noqa: F401  (registers the env)
from baselines.controllers import ConventionalPTCParams, PTCParams
from dwr_gym.env import DWRPointStabilizationEnv
from dwr_gym.params import EnvParams
from dwr_gym.validation import as_float, as_int, as_interval, as_pose
from train.learning.config import ConfigError, TrainConfig, check_device
from train.learning.hyperparams import load_zoo_yaml, parse_overrides, resolve_hyperparams
from train.reporting.results import json_safe

ENV_ID = "DWRPointStabilization-v0"
#: This module pins the behaviour of DWRPointStabilization-v0 (fixed T_con, the paper's reward), which Gymnasium
#: rightly calls out of date now that v1 exists; that warning is not what these tests test.
pytestmark = pytest.mark.filterwarnings("ignore:.*DWRPointStabilization-v0 is out of date:DeprecationWarning")


@pytest.mark.parametrize("value", [20, 20.0, np.float64(20), np.float32(20), np.int64(20), np.array(20.0)])
def test_numbers_of_any_python_or_numpy_type_are_accepted(value: object) -> None:
    params = EnvParams(T_con=value, substeps=np.int64(2), start_distance=np.array([0.5, 1.0]))  # type: ignore[arg-type]
    assert params.T_con == 20.0 and type(params.T_con) is float
    assert params.substeps == 2 and type(params.substeps) is int
    assert params.start_distance == (0.5, 1.0)
    assert PTCParams(K1=np.float32(2.0)).K1 == 2.0 and ConventionalPTCParams(power=np.int64(2)).power == 2


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"T_con": "20"}, "T_con='20' is invalid (a string; write it as a number)"),
        ({"T_con": np.array([20.0])}, "T_con=array of shape (1,) is invalid"),
        ({"substeps": 2.5}, "substeps=2.5 is invalid: expected an integer"),
        ({"start_distance": "12"}, "start_distance='12' is invalid: expected a pair"),
        ({"T_con": 5e-324, "dt": 5e-324}, "T_con=5e-324 is invalid"),
        ({"T_con": 0.01}, "T_con=0.01 is invalid: expected dt <= T_con"),  # dt left at its default: blame T_con
        ({"T_con": 1.0, "dt": 2.0}, "dt=2.0 is invalid: expected dt <= T_con"),
        ({"T_con": 1e6, "dt": 1e6}, "dt=1000000.0 is invalid: expected one step's travel"),  # not arena_radius
        ({"goal_tolerance": 6}, "goal_tolerance=6.0 is invalid: expected goal_tolerance=6 m below arena_radius"),
        ({"arena_radius": 1.0}, "arena_radius=1.0 is invalid: expected start_distance"),
        ({"integrator": 1}, "integrator=1 is invalid: expected one of"),
    ],
)
def test_bad_or_inconsistent_parameters_name_the_one_the_user_set(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError) as error:
        EnvParams(**kwargs)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_pose_options_reject_strings_and_poses_that_would_overflow() -> None:
    env = gym.make(ENV_ID)
    with pytest.raises(ValueError, match=r"options\['start'\]='123' is invalid"):
        env.unwrapped.reset(options={"start": "123"})
    with pytest.raises(ValueError, match="within"):
        env.unwrapped.reset(options={"start": (1.7e308, 0.0, 0.0)})
    assert as_pose("start", np.array([1.0, 2.0, 0.5])) == (1.0, 2.0, 0.5)


def test_render_mode_of_the_wrong_type_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match="render_mode=1 is invalid"):
        DWRPointStabilizationEnv(render_mode=1)  # type: ignore[arg-type]


def test_vector_env_step_before_reset_and_an_empty_reset_mask() -> None:
    venv = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode="vector_entry_point")
    with pytest.raises(gym.error.ResetNeeded):
        venv.step(np.zeros((3, 2)))
    obs, _ = venv.reset(seed=0)
    again, _ = venv.reset(options={"reset_mask": np.zeros(3, dtype=bool)})
    np.testing.assert_array_equal(again, obs)  # resetting no sub-env changes nothing
    with pytest.raises(ValueError, match="num_envs=100000000 is invalid"):
        gym.make_vec(ENV_ID, num_envs=100_000_000, vectorization_mode="vector_entry_point")


def test_coercion_helpers_accept_text_only_when_asked() -> None:
    assert as_float("learning_rate", "3e-4", 0, 1, text=True) == 3e-4
    assert as_int("--total-timesteps", "1e5", 1, text=True) == 100_000
    with pytest.raises(ValueError, match=r"--total-timesteps 2\.5 is invalid"):
        as_int("--total-timesteps", "2.5", 1, text=True)
    with pytest.raises(ValueError, match="learning_rate='3e-4' is invalid"):
        as_float("learning_rate", "3e-4")
    assert as_interval("start_distance", [1.5, 3.0], 0, 5) == (1.5, 3.0)


def test_train_config_coerces_cli_text_and_rejects_the_rest() -> None:
    config = TrainConfig(total_timesteps="1e5", num_envs="8", seed="3", residual_scale="0.5")  # type: ignore[arg-type]
    config.validate()
    assert (config.total_timesteps, config.num_envs, config.seed) == (100_000, 8, 3)
    for field, value, message in [
        ("seed", "-1", "--seed -1 is invalid"),
        ("num_envs", "100000000", "--num-envs 100000000 is invalid"),
        ("device", "gpu", "--device 'gpu' is invalid: expected auto, cpu, cuda, cuda:N or mps"),
        ("device", "tpu9", "--device 'tpu9' is invalid"),
    ]:
        with pytest.raises(ConfigError, match=message):
            TrainConfig(**{field: value}).validate()


def test_device_auto_records_the_device_used_and_an_absent_one_is_refused() -> None:
    import torch

    assert check_device("auto") in ("cpu", "cuda", "mps")
    assert check_device("CPU") == "cpu"
    if not torch.cuda.is_available():
        with pytest.raises(ConfigError, match="no CUDA device"):
            check_device("cuda:0")


def test_yaml_values_are_coerced_or_rejected(tmp_path) -> None:
    path = tmp_path / "hp.yml"

    def resolve(body: str) -> TrainConfig:
        path.write_text(f"{ENV_ID}:\n{body}")
        return resolve_hyperparams(TrainConfig(env_id=ENV_ID, hyperparams=str(path)), set())

    config = resolve("  learning_rate: 3e-4\n  n_timesteps: 1e5\n  batch_size: 64.0\n")
    assert config.algo_kwargs["learning_rate"] == 3e-4 and config.total_timesteps == 100_000
    assert config.algo_kwargs["batch_size"] == 64
    for body, message in [
        ('  batch_size: "abc"\n', "batch_size='abc' is invalid"),
        ("  learning_rate: -1\n", "learning_rate=-1.0 is invalid"),
        ("  learning_rate: .nan\n", "learning_rate=nan is invalid"),
        ("  n_envs: 2.7\n", "n_envs (YAML)=2.7 is invalid"),
        ('  policy_kwargs: "dict(activation_fn=nn.Swish)"\n', "activation_fn='nn.Swish' is invalid"),
    ]:
        with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
            resolve(body)
    path.write_text("CartPole-v1:\n  n_timesteps: 1000\n")
    with pytest.raises(ConfigError, match=r"has no section 'DWRPointStabilization-v0' \(found: 'CartPole-v1'\)$"):
        load_zoo_yaml(str(path), ENV_ID)
    path.write_text(f"{ENV_ID}:\n  n_timesteps: 1000\n")  # a file for v0 does not configure v1
    with pytest.raises(
        ConfigError, match=r"has no section 'DWRPointStabilization-v1'.*train on DWRPointStabilization-v0"
    ):
        load_zoo_yaml(str(path), "DWRPointStabilization-v1")
    path.write_bytes(bytes(range(256)))
    with pytest.raises(ConfigError, match="is invalid"):
        load_zoo_yaml(str(path), ENV_ID)


def test_command_line_hyperparameters_override_the_yaml_file(tmp_path) -> None:
    path = tmp_path / "hp.yml"
    path.write_text(f"{ENV_ID}:\n  learning_rate: 1e-3\n  n_steps: 64\n")
    overrides = parse_overrides(["learning_rate=1e-4", "policy_kwargs:dict(net_arch=[32, 32])"])
    config = resolve_hyperparams(
        TrainConfig(env_id=ENV_ID, hyperparams=str(path), hyperparam_overrides=overrides), set()
    )
    assert config.algo_kwargs["learning_rate"] == 1e-4 and config.algo_kwargs["n_steps"] == 64
    assert config.algo_kwargs["policy_kwargs"] == {"net_arch": [32, 32]}
    with pytest.raises(ConfigError, match="expected KEY=VALUE"):
        parse_overrides(["learning_rate"])


def test_json_output_writes_nan_as_null() -> None:
    text = json.dumps(json_safe([{"t": float("nan"), "x": np.float32(1.5), "n": np.int64(3), "i": math.inf}]))
    assert json.loads(text) == [{"t": None, "x": 1.5, "n": 3, "i": None}]


def test_render_trail_stays_bounded_and_keeps_its_start() -> None:
    from dwr_gym.env import TRAIL_LIMIT, append_trail

    trail: list[tuple[float, float]] = []
    for i in range(10 * TRAIL_LIMIT):
        append_trail(trail, (float(i), 0.0))
    assert len(trail) <= TRAIL_LIMIT and trail[0] == (0.0, 0.0) and trail[-1][0] == 10 * TRAIL_LIMIT - 1
