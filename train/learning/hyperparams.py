"""Hyperparameters of ``dwr-gym train``, in three layers, each overriding the one before: the shipped defaults
(train/hyperparams/), a YAML file in rl-zoo3's format (``{env_id: {n_timesteps: ..., policy: ...,
policy_kwargs: "dict(...)", ...}}``), then the command line; checked before any training starts.
"""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path
from typing import Any

from dwr_gym.validation import as_bool, as_float, as_int
from train.learning.config import MAX_TIMESTEPS, MAX_TRAIN_ENVS, ConfigError, TrainConfig
from train.learning.jitted.lagrangian import LAGRANGE_DEFAULTS, LagrangeSettings
from train.learning.learners import find_learner

ENV_SECTION = re.compile(r"^(dwr_gym:)?DWRPointStabilization-v\d+$")
ZOO_KEYS_UNSUPPORTED = ("normalize", "frame_stack", "env_wrapper", "callback", "vec_env_wrapper")
HYPERPARAMS_DIR = Path(__file__).resolve().parent.parent / "hyperparams"


def hyperparams_file(algo: str, residual: bool) -> Path:
    """The shipped rl-zoo3 YAML of tuned settings: train/hyperparams/[residual_]<algo>.yml."""
    return HYPERPARAMS_DIR / f"{'residual_' if residual else ''}{algo}.yml"


def default_hyperparams(algo: str, residual: bool, env_id: str) -> dict[str, Any]:
    """Defaults that train well on ``env_id`` on 2 CPU cores, read from its section of the shipped rl-zoo3 YAML
    (the residual variants explore less); its n_envs and n_timesteps are those of :func:`default_budget`."""
    path = str(hyperparams_file(algo, residual))
    params = zoo_to_sb3(load_zoo_yaml(path, env_id), path)
    params.pop("n_timesteps", None)
    params.pop("n_envs", None)
    return params


def default_budget(algo: str, residual: bool, env_id: str) -> tuple[int, int]:
    """(n_envs, n_timesteps) of the shipped YAML: the defaults of --num-envs and --total-timesteps."""
    section = load_zoo_yaml(str(hyperparams_file(algo, residual)), env_id)
    # (ES has no n_envs: its robots are population_size x episodes of its own keys)
    return int(section.get("n_envs", 1)), int(float(section["n_timesteps"]))


def fill_budget(config: TrainConfig) -> TrainConfig:
    """Give --num-envs and --total-timesteps, when left unset (None), the algorithm's defaults."""
    if config.num_envs is None or config.total_timesteps is None:
        envs, steps = default_budget(config.algo, config.residual, config.env_id)
        config.num_envs = envs if config.num_envs is None else config.num_envs
        config.total_timesteps = steps if config.total_timesteps is None else config.total_timesteps
    return config


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


def load_zoo_yaml(path: str, env_id: str) -> dict[str, Any]:
    """The hyperparameters for ``env_id`` from an rl-zoo3 YAML file (its section ``env_id`` or ``dwr_gym:env_id``)."""
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text())
    except (yaml.YAMLError, UnicodeDecodeError, OSError) as error:
        raise ConfigError(f"--hyperparams {path!r} is invalid: {str(error).splitlines()[0]}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"--hyperparams {path!r} is invalid: expected a mapping {{{env_id}: {{...}}}}")
    names = [name for name in (env_id, f"dwr_gym:{env_id}") if name in data]
    if not names:
        found = ", ".join(map(repr, data))[:80]
        ours = [key for key in data if isinstance(key, str) and ENV_SECTION.match(key)]
        hint = f"; add one, or train on {ours[0].removeprefix('dwr_gym:')} with --env" if ours else ""
        raise ConfigError(f"--hyperparams {path!r} has no section {env_id!r} (found: {found}){hint}")
    section = data[names[0]]
    if not isinstance(section, dict):
        raise ConfigError(f"--hyperparams {path!r} is invalid: the section must be a mapping")
    unsupported = sorted(set(section) & set(ZOO_KEYS_UNSUPPORTED))
    if unsupported:
        raise ConfigError(f"--hyperparams {path!r}: {unsupported} not supported by dwr-gym train")
    return dict(section)


def parse_overrides(items: list[str]) -> dict[str, Any]:
    """``KEY=VALUE`` (or rl-zoo3's ``KEY:VALUE``) pairs; VALUE is read as YAML, so 3e-4 and [64, 64] work."""
    import yaml

    overrides: dict[str, Any] = {}
    for item in items:
        positions = [i for i in (item.find("="), item.find(":")) if i >= 0]
        cut = min(positions) if positions else len(item)
        key, sep, raw = item[:cut], item[cut : cut + 1], item[cut + 1 :]
        if not sep or not key.strip() or not raw.strip():
            raise ConfigError(f"--hyperparams item {item!r} is invalid: expected KEY=VALUE, e.g. learning_rate=1e-4")
        try:
            overrides[key.strip()] = yaml.safe_load(raw)
        except yaml.YAMLError:
            overrides[key.strip()] = raw
    return overrides


def resolve_hyperparams(config: TrainConfig, explicit: set[str]) -> TrainConfig:
    """Merge defaults, the YAML file and the command line (``explicit`` names the options the user gave)."""
    params = default_hyperparams(config.algo, config.residual, config.env_id)
    layers = [load_zoo_yaml(config.hyperparams, config.env_id)] if config.hyperparams is not None else []
    layers.append(dict(config.hyperparam_overrides))
    for layer, source in zip(layers, ("YAML", "--hyperparams")[-len(layers) :], strict=True):
        try:
            if "n_timesteps" in layer:
                steps = as_int(f"n_timesteps ({source})", layer.pop("n_timesteps"), 1, MAX_TIMESTEPS, text=True)
                if "total_timesteps" not in explicit:
                    config.total_timesteps = steps
            if "n_envs" in layer:
                envs = as_int(f"n_envs ({source})", layer.pop("n_envs"), 1, MAX_TRAIN_ENVS, text=True)
                if "num_envs" not in explicit:
                    config.num_envs = envs
        except ValueError as error:
            raise ConfigError(str(error)) from None
        params.update(zoo_to_sb3(layer, config.hyperparams if source == "YAML" else "--hyperparams"))
    config.algo_kwargs = check_algo_kwargs(config.algo, params, config.backend)
    return fill_budget(config)


def _check_lagrange_keys(algo: str, params: dict[str, Any], backend: str) -> dict[str, Any]:
    """PPO-Lagrangian's keys (train.learning.jitted.lagrangian) checked: the jitted PPO's only, each in its range."""
    given = sorted(set(params) & set(LAGRANGE_DEFAULTS))
    if not given:
        return params
    if algo != "ppo" or backend != "jax":
        raise ConfigError(f"hyperparameter(s) {given} are options of --algo ppo --backend jax (PPO-Lagrangian) and "
                          f"--algo apg, not of --algo {algo} --backend {backend}")  # fmt: skip
    try:
        LagrangeSettings.from_values({**LAGRANGE_DEFAULTS, **{key: params[key] for key in given}})
    except ValueError as error:
        raise ConfigError(str(error)) from None
    return params


ACTIVATIONS = ("nn.Tanh", "nn.ReLU", "nn.ELU", "nn.LeakyReLU", "nn.SiLU", "nn.GELU", "nn.Sigmoid")
_INT_KEYS = {"n_steps": 1, "batch_size": 1, "n_epochs": 1, "buffer_size": 1, "learning_starts": 0,
             "gradient_steps": -1, "target_update_interval": 1, "policy_delay": 1, "stats_window_size": 1,
             "top_quantiles_to_drop_per_net": 0}  # fmt: skip
_FLOAT_KEYS = {"gamma": (0.0, 1.0), "gae_lambda": (0.0, 1.0), "tau": (0.0, 1.0), "ent_coef": (0.0, 1e6),
               "vf_coef": (0.0, 1e6), "max_grad_norm": (0.0, 1e6), "clip_range": (0.0, 1e6),
               "action_noise_sigma": (0.0, 10.0), "target_policy_noise": (0.0, 10.0),
               "target_noise_clip": (0.0, 10.0), "log_std_final": (-20.0, 5.0)}  # fmt: skip


def _check_policy_kwargs(value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ConfigError(f"policy_kwargs={value!r} is invalid: expected a mapping such as dict(net_arch=[64, 64])")
    kwargs = dict(value)
    arch = kwargs.get("net_arch")
    layers = list(arch.values()) if isinstance(arch, dict) else [arch]
    for sizes in layers if arch is not None else []:
        if not isinstance(sizes, list) or not sizes:
            raise ConfigError(f"policy_kwargs net_arch={arch!r} is invalid: expected a list of layer sizes")
        try:
            [as_int("net_arch layer", size, 1, 65536) for size in sizes]
        except ValueError as error:
            raise ConfigError(f"policy_kwargs net_arch={arch!r} is invalid: {error}") from None
    if "activation_fn" in kwargs:
        name = str(kwargs["activation_fn"])
        name = name if name.startswith("nn.") else f"nn.{name.split('.')[-1]}"
        if name not in ACTIVATIONS:
            raise ConfigError(
                f"policy_kwargs activation_fn={kwargs['activation_fn']!r} is invalid: expected one of "
                f"{', '.join(ACTIVATIONS)}"
            )
        kwargs["activation_fn"] = name
    if "log_std_init" in kwargs:
        try:
            kwargs["log_std_init"] = as_float("log_std_init", kwargs["log_std_init"], -20.0, 5.0, text=True)
        except ValueError as error:
            raise ConfigError(f"policy_kwargs {error}") from None
    return kwargs


def algorithm_class(algo: str, backend: str = "sb3") -> Any:
    """The class whose model files a run of ``algo`` on ``backend`` writes: its learner's ``model``
    (:mod:`train.learning.learners`; the jitted PPO and ES save an SB3 PPO); a ConfigError naming the extra to
    install where its library is missing."""
    try:
        return find_learner(algo, backend).model_class()
    except (ValueError, ImportError) as error:
        raise ConfigError(str(error)) from None


_ALIASES = {"lr": "learning_rate", "learning-rate": "learning_rate", "batch": "batch_size", "epochs": "n_epochs",
            "discount": "gamma", "net_arch": "policy_kwargs"}  # fmt: skip
"""Names users type for a hyperparameter that stable-baselines3 calls otherwise."""


def check_algo_kwargs(algo: str, params: dict[str, Any], backend: str = "sb3") -> dict[str, Any]:
    """The hyperparameters coerced to their types; unknown or ill-typed ones raise ConfigError before any work."""
    try:
        learner = find_learner(algo, backend)
    except ValueError as error:
        raise ConfigError(str(error)) from None
    if learner.hyperparams is not None:  # a learner with hyperparameters of its own (ES's)
        if "policy_kwargs" in params:
            params = {**params, "policy_kwargs": _check_policy_kwargs(params["policy_kwargs"] or {})}
        return learner.function(learner.hyperparams)(params)
    cls = algorithm_class(algo, backend)
    accepted = set(inspect.signature(cls.__init__).parameters) - {"self", "env", "device", "seed"}
    accepted |= {"action_noise_sigma"} | ({"log_std_final", "log_std_fixed"} if algo == "ppo" else set())
    params = _check_lagrange_keys(algo, params, backend)
    accepted |= set(LAGRANGE_DEFAULTS) if algo == "ppo" and backend == "jax" else set()
    unknown = sorted(set(params) - accepted)
    if unknown:
        import difflib

        shown = sorted(key for key in accepted if not key.startswith("_") and key not in ("verbose", "tensorboard_log"))
        near = {key: [_ALIASES[key]] if key in _ALIASES else difflib.get_close_matches(key, shown, n=1, cutoff=0.6)
                for key in unknown}  # fmt: skip
        hints = ", ".join(
            f"{near[key][0]} for {key}" if len(unknown) > 1 else near[key][0] for key in unknown if near[key]
        )
        library = " of sbx" if backend == "sbx" else ""
        raise ConfigError(f"hyperparameter(s) {unknown} are not accepted by {algo.upper()}{library}"
                          f"{f' (did you mean {hints}?)' if hints else ''}; accepted: {', '.join(shown)}")  # fmt: skip
    checked = dict(params)
    try:
        for key, low in _INT_KEYS.items():
            if key in checked:
                checked[key] = as_int(key, checked[key], low, 10**9, text=True)
        for key, (low, high) in _FLOAT_KEYS.items():
            if key in checked and not (key == "ent_coef" and isinstance(checked[key], str) and "auto" in checked[key]):
                checked[key] = as_float(key, checked[key], low, high, text=True)
        lr = checked.get("learning_rate")
        if isinstance(lr, str) and lr.startswith("lin_"):
            as_float("learning_rate", lr[4:], 0.0, 1.0, low_inclusive=False, text=True)
        elif lr is not None:
            checked["learning_rate"] = as_float("learning_rate", lr, 0.0, 1.0, low_inclusive=False, text=True)
    except ValueError as error:
        hint = " or 'lin_<number>'" if "learning_rate" in str(error) else ""
        raise ConfigError(f"{error}{hint}") from None
    if "log_std_fixed" in checked:
        try:
            checked["log_std_fixed"] = as_bool("log_std_fixed", checked["log_std_fixed"])
        except ValueError as error:
            raise ConfigError(str(error)) from None
    if "policy_kwargs" in checked:
        checked["policy_kwargs"] = _check_policy_kwargs(checked["policy_kwargs"] or {})
    if "policy" in checked and checked["policy"] != "MlpPolicy":
        raise ConfigError(f"policy={checked['policy']!r} is invalid: expected 'MlpPolicy' (observations are a vector)")
    return checked


def steps_per_collection(config: TrainConfig) -> int:
    """Env steps between two checks of the budget: PPO collects n_steps * num_envs per update; SAC and TD3
    step every env train_freq times (counted in steps) before they look at the budget again."""
    if config.algo == "ppo":
        return int(config.algo_kwargs.get("n_steps", 2048)) * config.num_envs
    freq = config.algo_kwargs.get("train_freq", 1)
    steps = (
        freq if isinstance(freq, int) else freq[0] if isinstance(freq, (list, tuple)) and freq[1:] == ["step"] else 1
    )
    return int(steps) * config.num_envs


def steps_to_run(config: TrainConfig, done: int = 0) -> int:
    """The env steps a run at ``done`` steps will actually take to reach --total-timesteps (a whole number of
    collections: the budget rounded up), so that progress bars show the work that will run."""
    chunk = steps_per_collection(config)
    return -(-(config.total_timesteps - done) // chunk) * chunk


def rollout_rounding(config: TrainConfig) -> str | None:
    """A note when PPO's rollouts round the budget up (it collects n_steps * num_envs steps per update)."""
    if config.algo != "ppo":
        return None
    chunk = steps_per_collection(config)
    rounded = steps_to_run(config)
    if rounded == config.total_timesteps:
        return None
    return (f"note: PPO collects n_steps * num_envs = {chunk} steps per update, so --total-timesteps "
            f"{config.total_timesteps} runs {rounded} steps")  # fmt: skip


def build_algo_kwargs(params: dict[str, Any], backend: str = "sb3") -> dict[str, Any]:
    """Turn resolved hyperparameters into the keyword arguments of the SB3 (or sbx) constructor."""
    import numpy as np
    import torch

    kwargs = dict(params)
    lr = kwargs.get("learning_rate")
    if isinstance(lr, str):
        start = float(lr[4:])
        kwargs["learning_rate"] = lambda progress_remaining: progress_remaining * start
    policy_kwargs = dict(kwargs.get("policy_kwargs") or {})
    if backend == "sbx":
        from train.learning.sb3.sbx_backend import sbx_policy_kwargs

        policy_kwargs = sbx_policy_kwargs(policy_kwargs)
    elif isinstance(policy_kwargs.get("activation_fn"), str):
        policy_kwargs["activation_fn"] = getattr(torch.nn, policy_kwargs["activation_fn"].split(".")[-1])
    kwargs["policy_kwargs"] = policy_kwargs
    kwargs.pop("log_std_final", None)  # PPO's annealed noise: a callback of train.learning.training, not SB3's
    kwargs.pop("log_std_fixed", None)
    for key in LAGRANGE_DEFAULTS:  # PPO-Lagrangian's (the jitted PPO's): its SB3 export is a plain PPO
        kwargs.pop(key, None)
    sigma = kwargs.pop("action_noise_sigma", None)
    if sigma:
        from stable_baselines3.common.noise import NormalActionNoise

        kwargs["action_noise"] = NormalActionNoise(np.zeros(2), sigma * np.ones(2))
    return kwargs
