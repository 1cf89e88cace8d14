"""The training configuration: a dataclass whose fields are the options of ``dwr-gym train``.

Hyperparameters come from three layers, each overriding the one before: the defaults here, a YAML
file in rl-zoo3's format (``{env_id: {n_timesteps: ..., policy: ..., policy_kwargs: "dict(...)", ...}}``),
then the command line.
"""

from __future__ import annotations

import ast
import dataclasses
import inspect
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ALGORITHMS: tuple[str, ...] = ("ppo", "sac", "td3")
ENV_ID = "DWRPointStabilization-v0"
ZOO_KEYS_UNSUPPORTED = ("normalize", "frame_stack", "env_wrapper", "callback", "vec_env_wrapper")


class ConfigError(ValueError):
    """A configuration the user must fix; the CLI prints it as one line with exit code 2."""


def option(default: Any, help: str, **kwargs: Any) -> Any:
    """A dataclass field with the one-line help that the CLI shows."""
    return field(default=default, metadata={"help": help, **kwargs})


@dataclass
class TrainConfig:
    """Everything a training run needs; written beside the model as config.yaml so it can be re-run exactly."""

    algo: str = option("ppo", "algorithm: ppo, sac or td3")
    total_timesteps: int = option(200_000, "total environment steps over all envs")
    num_envs: int = option(16, "robots simulated in one native vector env")
    seed: int = option(0, "seed of the env, the network initialisation and the sampling")
    residual: bool = option(False, "learn a residual on the expert: action = clip(expert + scale * residual)")
    residual_scale: float = option(0.5, "scale of the residual action, in (0, 2]")
    expert: str = option("ptc", "controller under the residual: any of evaluate --controllers")
    env_kwargs: dict[str, Any] = field(
        default_factory=dict, metadata={"help": "env keywords KEY=VALUE, e.g. T_con=25 heading_weight=5"}
    )
    hyperparams: str | None = option(None, "YAML file of hyperparameters in rl-zoo3's format")
    eval_freq: int = option(20_000, "evaluate every this many env steps on a fixed seeded scenario set")
    eval_episodes: int = option(100, "size of the fixed random scenario set used for evaluation")
    eval_seed: int = option(12345, "seed of the evaluation scenario set (kept apart from the training seed)")
    checkpoint_freq: int = option(50_000, "save a checkpoint every this many env steps")
    run_dir: str | None = option(None, "output directory (default: runs/<algo>[-residual]-seed<seed>)")
    device: str = option("cpu", "torch device")
    resume: str | None = option(None, "checkpoint (.zip) to continue from; its run's config is reused")
    progress: bool = option(True, "show a progress bar")
    algo_kwargs: dict[str, Any] = field(
        default_factory=dict, metadata={"help": "resolved hyperparameters (defaults, then the YAML file)", "cli": False}
    )

    def validate(self) -> None:
        """Raise ConfigError naming the option, the value and what is allowed."""
        if self.algo not in ALGORITHMS:
            raise ConfigError(f"--algo {self.algo!r} is invalid: expected one of {', '.join(ALGORITHMS)}")
        positive = ("total_timesteps", "num_envs", "eval_freq", "eval_episodes", "checkpoint_freq")
        for name in positive:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"--{name.replace('_', '-')} {value!r} is invalid: expected a positive integer")
        if not (isinstance(self.residual_scale, (int, float)) and 0 < self.residual_scale <= 2):
            raise ConfigError(f"--residual-scale {self.residual_scale!r} is invalid: expected a number in (0, 2]")
        from baselines.controllers import CONTROLLER_NAMES

        if self.expert not in CONTROLLER_NAMES:
            raise ConfigError(f"--expert {self.expert!r} is invalid: expected one of {', '.join(CONTROLLER_NAMES)}")
        from dwr_gym.params import EnvParams

        try:
            EnvParams.from_kwargs(**self.env_kwargs)
        except ValueError as error:
            raise ConfigError(f"invalid env keyword: {error}") from error
        if self.hyperparams is not None and not Path(self.hyperparams).is_file():
            raise ConfigError(f"--hyperparams {self.hyperparams!r} is invalid: no such file")
        if self.resume is not None and not Path(self.resume).is_file():
            raise ConfigError(f"--resume {self.resume!r} is invalid: no such checkpoint file")

    def default_run_dir(self) -> str:
        return f"runs/{self.algo}{'-residual' if self.residual else ''}-seed{self.seed}"

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ConfigError(f"unknown config key(s) {unknown}; allowed: {', '.join(sorted(names))}")
        return cls(**data)


HYPERPARAMS_DIR = Path(__file__).parent / "hyperparams"


def hyperparams_file(algo: str, residual: bool) -> Path:
    """The shipped rl-zoo3 YAML of tuned settings: train/hyperparams/[residual_]<algo>.yml."""
    return HYPERPARAMS_DIR / f"{'residual_' if residual else ''}{algo}.yml"


def default_hyperparams(algo: str, residual: bool) -> dict[str, Any]:
    """Defaults that train well on this env on 2 CPU cores, read from the shipped rl-zoo3 YAML (the residual
    variants explore less); n_envs and n_timesteps there equal the defaults of TrainConfig."""
    params = zoo_to_sb3(load_zoo_yaml(str(hyperparams_file(algo, residual))), str(hyperparams_file(algo, residual)))
    params.pop("n_timesteps", None)
    params.pop("n_envs", None)
    return params


def zoo_to_sb3(zoo: dict[str, Any], path: str) -> dict[str, Any]:
    """rl-zoo3's spellings as ours: policy_kwargs "dict(...)" parsed, noise_type/noise_std as action_noise_sigma."""
    zoo = dict(zoo)
    if isinstance(zoo.get("policy_kwargs"), str):
        zoo["policy_kwargs"] = parse_policy_kwargs(zoo["policy_kwargs"])
    noise_type = zoo.pop("noise_type", None)
    if noise_type not in (None, "normal"):
        raise ConfigError(f"--hyperparams {path!r}: noise_type {noise_type!r} is invalid: expected 'normal'")
    if "noise_std" in zoo:
        zoo["action_noise_sigma"] = float(zoo.pop("noise_std"))
    return zoo


_SAFE_NAMES = {"True": True, "False": False, "None": None}


def parse_policy_kwargs(text: str) -> dict[str, Any]:
    """Parse rl-zoo3's ``"dict(net_arch=[64, 64], activation_fn=nn.Tanh, log_std_init=-2)"`` without eval."""

    def value(node: ast.AST) -> Any:
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -value(node.operand)
        if isinstance(node, (ast.List, ast.Tuple)):
            return [value(e) for e in node.elts]
        if isinstance(node, ast.Dict):
            return {value(k): value(v) for k, v in zip(node.keys, node.values, strict=True) if k is not None}
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "dict" and not node.args:
            return {kw.arg: value(kw.value) for kw in node.keywords}
        if isinstance(node, ast.Name) and node.id in _SAFE_NAMES:
            return _SAFE_NAMES[node.id]
        if (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id in ("nn", "th", "torch")
        ):
            return f"nn.{node.attr}"
        raise ConfigError(f"policy_kwargs {text!r} is invalid: cannot read {ast.dump(node)[:60]}")

    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as error:
        raise ConfigError(f"policy_kwargs {text!r} is invalid: {error.msg}") from error
    result = value(tree.body)
    if not isinstance(result, dict):
        raise ConfigError(f"policy_kwargs {text!r} is invalid: expected dict(...)")
    return result


def load_zoo_yaml(path: str) -> dict[str, Any]:
    """The hyperparameters for DWRPointStabilization-v0 from an rl-zoo3 YAML file."""
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text())
    except yaml.YAMLError as error:
        raise ConfigError(f"--hyperparams {path!r} is invalid: {str(error).splitlines()[0]}") from error
    if not isinstance(data, dict):
        raise ConfigError(f"--hyperparams {path!r} is invalid: expected a mapping {{{ENV_ID}: {{...}}}}")
    for key in (ENV_ID, f"dwr_gym:{ENV_ID}"):
        if key in data:
            section = data[key]
            break
    else:
        if len(data) == 1:
            section = next(iter(data.values()))
        else:
            raise ConfigError(f"--hyperparams {path!r} is invalid: no section {ENV_ID!r}")
    if not isinstance(section, dict):
        raise ConfigError(f"--hyperparams {path!r} is invalid: the section must be a mapping")
    unsupported = sorted(set(section) & set(ZOO_KEYS_UNSUPPORTED))
    if unsupported:
        raise ConfigError(f"--hyperparams {path!r}: {unsupported} not supported by dwr-gym train")
    return dict(section)


def resolve_hyperparams(config: TrainConfig, explicit: set[str]) -> TrainConfig:
    """Merge defaults, the YAML file and the command line (``explicit`` names the options the user gave)."""
    params = default_hyperparams(config.algo, config.residual)
    if config.hyperparams is not None:
        zoo = load_zoo_yaml(config.hyperparams)
        if "n_timesteps" in zoo and "total_timesteps" not in explicit:
            config.total_timesteps = int(float(zoo.pop("n_timesteps")))
        zoo.pop("n_timesteps", None)
        if "n_envs" in zoo and "num_envs" not in explicit:
            config.num_envs = int(zoo.pop("n_envs"))
        zoo.pop("n_envs", None)
        params.update(zoo_to_sb3(zoo, config.hyperparams))
    check_algo_kwargs(config.algo, params)
    config.algo_kwargs = params
    return config


def algorithm_class(algo: str) -> Any:
    """The stable-baselines3 class of ``algo``."""
    import stable_baselines3

    return {"ppo": stable_baselines3.PPO, "sac": stable_baselines3.SAC, "td3": stable_baselines3.TD3}[algo]


def check_algo_kwargs(algo: str, params: dict[str, Any]) -> None:
    """Reject hyperparameters the algorithm does not take, before any training starts."""
    accepted = set(inspect.signature(algorithm_class(algo).__init__).parameters) - {"self", "env"}
    accepted |= {"action_noise_sigma"}
    unknown = sorted(set(params) - accepted)
    if unknown:
        raise ConfigError(f"hyperparameter(s) {unknown} are not accepted by {algo.upper()}")
    lr = params.get("learning_rate")
    if isinstance(lr, str) and not (lr.startswith("lin_") and _is_number(lr[4:])):
        raise ConfigError(f"learning_rate {lr!r} is invalid: expected a number or 'lin_<number>'")


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def build_algo_kwargs(params: dict[str, Any]) -> dict[str, Any]:
    """Turn resolved hyperparameters into the keyword arguments of the SB3 constructor."""
    import numpy as np
    import torch

    kwargs = dict(params)
    lr = kwargs.get("learning_rate")
    if isinstance(lr, str):
        start = float(lr[4:])
        kwargs["learning_rate"] = lambda progress_remaining: progress_remaining * start
    policy_kwargs = dict(kwargs.get("policy_kwargs") or {})
    if isinstance(policy_kwargs.get("activation_fn"), str):
        policy_kwargs["activation_fn"] = getattr(torch.nn, policy_kwargs["activation_fn"].split(".")[-1])
    kwargs["policy_kwargs"] = policy_kwargs
    sigma = kwargs.pop("action_noise_sigma", None)
    if sigma:
        from stable_baselines3.common.noise import NormalActionNoise

        kwargs["action_noise"] = NormalActionNoise(np.zeros(2), sigma * np.ones(2))
    return kwargs
