"""The training configuration: a dataclass whose fields are the options of ``dwr-gym train``.

Its hyperparameters are resolved by :mod:`train.learning.hyperparams`.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from dwr_gym.validation import as_bool, as_choice, as_float, as_int
from train.env_ids import DEFAULT_ENV_ID, ENV_HELP, UNRECORDED_ENV_ID, check_env_id, env_keywords
from train.learning.learners import ALGORITHMS, BACKENDS, find_learner, options_help

ALGO_HELP, BACKEND_HELP = options_help()
LEARNED_FROM: tuple[str, ...] = ("reward", "expert", "expert, then reward")
"""What an agent learned from, as its config.yaml records it (``learned_from``): the env's reward (RL, residual
RL), an expert's actions (cloning, DAgger), or both in turn (RL fine-tuning of a cloned network, ``--init-from``)."""
MAX_TIMESTEPS = 10**10
MAX_TRAIN_ENVS = 4096
"""More training envs than this give rollouts of little use and risk exhausting memory; larger values are refused."""
BUDGET_HELP = {
    "n_envs": "n_envs of train/hyperparams/<algo>.yml: 256 for PPO, 64 for SAC and TD3",
    "n_timesteps": "n_timesteps of train/hyperparams/<algo>.yml: 2048000 for PPO, 1000000 for SAC and TD3",
}
"""The defaults of --num-envs and --total-timesteps as the CLI shows them; they live in the shipped YAML files
(tests/test_zoo.py holds the two together)."""


class ConfigError(ValueError):
    """A configuration the user must fix; the CLI prints it as one line with exit code 2."""


def option(default: Any, help: str, **kwargs: Any) -> Any:
    """A dataclass field with the one-line help that the CLI shows."""
    return field(default=default, metadata={"help": help, **kwargs})


@dataclass
class TrainConfig:
    """Everything a training run needs; written beside the model as config.yaml so it can be re-run exactly."""

    algo: str = option("ppo", ALGO_HELP)
    backend: str = option("sb3", BACKEND_HELP)
    threads: int | None = option(
        None,
        "torch threads while it trains and evaluates; the caller's count is restored afterwards",
        shown_default="1: a small network waits on a thread pool, most on a busy machine",
        metavar="N",
    )
    env_id: str = option(DEFAULT_ENV_ID, ENV_HELP, flag="--env", metavar="ID")
    total_timesteps: int | None = option(
        None, "total environment steps over all envs", shown_default=BUDGET_HELP["n_timesteps"], metavar="N"
    )
    num_envs: int | None = option(
        None, "robots simulated in one native vector env", shown_default=BUDGET_HELP["n_envs"], metavar="N"
    )
    seed: int = option(0, "seed of the env, the network initialisation and the sampling")
    residual: bool = option(False, "learn a residual on the expert: action = clip(expert + scale * residual)")
    residual_scale: float = option(0.5, "scale of the residual action, in (0, 2]")
    expert: str = option("ptc", "controller under the residual: any of evaluate --controllers")
    action_time_scale: float = option(
        0.0,
        "T_REF [s]: the action (a residual agent's residual) times min(1, T_REF / T_con), so that one behaviour serves "
        "every T_con, as the optimum's commands scale (train.learning.time_scale); 0: off",
        metavar="T_REF",
    )
    action_repeat: int = option(1, "hold each action for this many control periods (train.learning.wrappers)")
    normalize_obs: bool = option(False, "normalise observations (VecNormalize; statistics saved beside the model)")
    normalize_reward: bool = option(False, "scale rewards by the running deviation of the return (training only)")
    env_kwargs: dict[str, Any] = field(
        default_factory=dict, metadata={"help": "env keywords KEY=VALUE, e.g. T_con=25 heading_weight=5"}
    )
    hyperparams: str | None = option(
        None, "YAML file of hyperparameters in rl-zoo3's format, and/or KEY=VALUE overrides (e.g. learning_rate=1e-4)"
    )
    hyperparam_overrides: dict[str, Any] = field(
        default_factory=dict, metadata={"help": "hyperparameters given as KEY=VALUE on the command line", "cli": False}
    )
    time_limit: float | None = option(
        None, "stop after this many seconds of training (saved as a finished run)", shown_default="none", metavar="S"
    )
    eval_freq: int = option(200_000, "evaluate every this many env steps on a fixed seeded scenario set")
    eval_episodes: int = option(100, "size of the fixed random scenario set used for evaluation")
    eval_seed: int = option(12345, "seed of the evaluation scenario set (kept apart from the training seed)")
    checkpoint_freq: int = option(500_000, "save a checkpoint every this many env steps")
    run_dir: str | None = option(
        None, "output directory", shown_default="runs/<algo>[-residual]-seed<seed>", metavar="DIR"
    )
    device: str = option("cpu", "torch device: auto, cpu, cuda, cuda:N or mps; the config records the one used")
    resume: str | None = option(
        None,
        "a run directory (or a checkpoint .zip in one) to continue; its saved config is reused",
        shown_default="",
        metavar="RUN_DIR|CHECKPOINT",
    )
    init_from: str | None = option(
        None,
        "a saved agent of the same algorithm (run directory or .zip; --algo es: a PPO agent's actor) whose network "
        "starts this run (RL fine-tuning); its architecture is adopted",
        shown_default="none: a fresh network",
        metavar="RUN_DIR|ZIP",
    )
    critic_warmup: int = option(
        0,
        "with --init-from or --residual: env steps at the start during which only the value function learns (PPO)",
        metavar="N",
    )
    overwrite: bool = option(False, "delete the outputs of an earlier run in --run-dir and start afresh")
    progress: bool = option(True, "show a progress bar")
    algo_kwargs: dict[str, Any] = field(
        default_factory=dict, metadata={"help": "resolved hyperparameters (defaults, then the YAML file)", "cli": False}
    )

    def validate(self) -> None:
        """Coerce the options to their types, or raise ConfigError naming the option, the value and what is allowed."""
        try:
            self._coerce()
        except ValueError as error:
            raise ConfigError(str(error)) from None
        from baselines.registry import CONTROLLER_NAMES

        if self.expert not in CONTROLLER_NAMES:
            raise ConfigError(f"--expert {self.expert!r} is invalid: expected one of {', '.join(CONTROLLER_NAMES)}")
        try:
            self.env_params()
        except ValueError as error:
            raise ConfigError(f"invalid env keyword: {error}") from None
        if self.hyperparams is not None and not Path(self.hyperparams).is_file():
            raise ConfigError(f"--hyperparams {self.hyperparams!r} is invalid: no such file")
        if self.init_from is not None and not Path(self.init_from).exists():
            raise ConfigError(f"--init-from {self.init_from!r} is invalid: no such run directory or model file")
        try:  # the algorithm on the backend, and the options it implements (train.learning.learners)
            find_learner(self.algo, self.backend).check_options(self)
        except ValueError as error:
            raise ConfigError(str(error)) from None
        if self.critic_warmup and ((self.init_from is None and not self.residual) or self.algo != "ppo"):
            raise ConfigError(f"--critic-warmup {self.critic_warmup} is invalid: it needs --init-from or --residual, "
                              "and --algo ppo")  # fmt: skip
        if self.resume is not None and not Path(self.resume).exists():
            raise ConfigError(f"--resume {self.resume!r} is invalid: no such run directory or checkpoint file")
        self.device = check_device(self.device)

    def _coerce(self) -> None:
        self.algo = as_choice("--algo", self.algo, ALGORITHMS)
        self.backend = as_choice("--backend", self.backend, BACKENDS)
        if self.threads is not None:
            self.threads = as_int("--threads", self.threads, 1, 1024, text=True)
        self.env_id = check_env_id(self.env_id)
        if self.total_timesteps is not None:  # None: the algorithm's default, set by resolve_hyperparams
            self.total_timesteps = as_int("--total-timesteps", self.total_timesteps, 1, MAX_TIMESTEPS, text=True)
        if self.num_envs is not None:
            self.num_envs = as_int("--num-envs", self.num_envs, 1, MAX_TRAIN_ENVS, text=True)
        self.seed = as_int("--seed", self.seed, 0, 2**32 - 1, text=True)
        self.action_repeat = as_int("--action-repeat", self.action_repeat, 1, 100, text=True)
        self.eval_seed = as_int("--eval-seed", self.eval_seed, 0, 2**32 - 1, text=True)
        if self.time_limit is not None:
            self.time_limit = as_float("--time-limit", self.time_limit, 0.0, 1e9, low_inclusive=False, text=True)
        self.eval_freq = as_int("--eval-freq", self.eval_freq, 1, MAX_TIMESTEPS, text=True)
        self.eval_episodes = as_int("--eval-episodes", self.eval_episodes, 1, 100_000, text=True)
        self.critic_warmup = as_int("--critic-warmup", self.critic_warmup, 0, MAX_TIMESTEPS, text=True)
        self.checkpoint_freq = as_int("--checkpoint-freq", self.checkpoint_freq, 1, MAX_TIMESTEPS, text=True)
        self.residual_scale = as_float(
            "--residual-scale", self.residual_scale, 0.0, 2.0, low_inclusive=False, text=True
        )
        self.action_time_scale = as_float("--action-time-scale", self.action_time_scale, 0.0, 3600.0, text=True)
        for name in ("residual", "overwrite", "progress", "normalize_obs", "normalize_reward"):
            setattr(self, name, as_bool(f"--{name}", getattr(self, name)))
        if not isinstance(self.env_kwargs, dict) or not isinstance(self.hyperparam_overrides, dict):
            raise ValueError("env_kwargs and hyperparam_overrides must be mappings")

    def env_keywords(self) -> dict[str, Any]:
        """The keywords of the env trained on: those ``env_id`` is registered with, then ``env_kwargs``."""
        return env_keywords(self.env_id, self.env_kwargs)

    def env_params(self) -> Any:
        """The :class:`~dwr_gym.params.EnvParams` of the env trained on (``robot`` and ``disturbances`` left out)."""
        from dwr_gym.disturbances import split_env_kwargs
        from dwr_gym.params import EnvParams

        return EnvParams.from_kwargs(**split_env_kwargs(self.env_keywords())[0])

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
        return cls(**{"env_id": UNRECORDED_ENV_ID, **data})


def check_device(device: Any) -> str:
    """The torch device to use: 'auto' picks cuda, then mps, then cpu; an absent device is a ConfigError."""
    text = str(device).strip().lower()
    if not re.fullmatch(r"auto|cpu|mps|cuda(:\d+)?", text):
        raise ConfigError(f"--device {device!r} is invalid: expected auto, cpu, cuda, cuda:N or mps")
    if text == "cpu":
        return text
    import torch

    cuda, mps = (
        torch.cuda.is_available(),
        bool(getattr(torch.backends, "mps", None)) and torch.backends.mps.is_available(),
    )
    if text == "auto":
        return "cuda" if cuda else "mps" if mps else "cpu"
    if text == "mps" and not mps:
        raise ConfigError("--device 'mps' is invalid: this machine has no MPS (Apple GPU) device; use cpu or auto")
    if text.startswith("cuda"):
        if not cuda:
            raise ConfigError(f"--device {text!r} is invalid: torch sees no CUDA device here; use cpu or auto")
        index = int(text.partition(":")[2] or 0)
        if index >= torch.cuda.device_count():
            raise ConfigError(f"--device {text!r} is invalid: only {torch.cuda.device_count()} CUDA device(s)")
    return text
