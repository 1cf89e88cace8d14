"""Seeds and hyperparameter searches on Ray Tune (``dwr-gym sweep``), each trial the training of ``dwr-gym train``.

A trial calls :func:`train.learning.training.train` (the function behind ``dwr-gym train``) and reports each of
its evaluations to Tune through ``train``'s ``on_evaluation`` hook; ``train`` knows nothing of Tune.
Every run writes its own run directory under ``<out>/runs/``, from which the table of trials (mean +- sd
over seeds), the best configuration as an rl-zoo3 YAML and the learning curves are built.
"""

from __future__ import annotations

import itertools
import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from train.learning.config import ConfigError, TrainConfig
from train.learning.hyperparams import check_algo_kwargs, resolve_hyperparams
from train.learning.runs import EVAL_FILE, read_evaluations

SEARCHES = ("grid", "random", "optuna")
DISTRIBUTIONS = ("uniform", "loguniform", "int")
METRICS = ("return_mean", "success_rate", "energy_mean", "arrival_time_mean", "final_distance_mean")
PARAMS_FILE = "sweep_params.json"
POLICY_KWARGS = ("log_std_init", "net_arch")
"""Searchable keys that go into ``policy_kwargs`` (``--param log_std_init=uniform:-4:-1``)."""
TABLE_COLUMNS = ("success_rate", "return_mean", "energy_mean", "arrival_time_mean")


def parse_value(text: str) -> Any:
    """A number, bool or string as YAML reads it ("3e-4" -> 0.0003, "[64, 64]" -> a list)."""
    import yaml

    value = yaml.safe_load(text)
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return value
    return value


def parse_param(item: str) -> tuple[str, dict[str, Any]]:
    """``KEY=v1,v2,...`` (choices) or ``KEY=uniform|loguniform|int:LOW:HIGH`` (a range) as (key, spec)."""
    key, sep, text = item.partition("=")
    if not sep or not key or not text:
        raise ConfigError(f"--param {item!r} is invalid: expected KEY=v1,v2,... or KEY=uniform|loguniform|int:LOW:HIGH")
    kind, _, bounds = text.partition(":")
    if kind in DISTRIBUTIONS:
        parts = bounds.split(":")
        try:
            low, high = (float(v) for v in parts)
        except ValueError:
            low = high = math.nan
        if (
            len(parts) != 2
            or not (math.isfinite(low) and math.isfinite(high) and low < high)
            or (kind == "loguniform" and low <= 0)
        ):
            raise ConfigError(f"--param {item!r} is invalid: expected {kind}:LOW:HIGH with finite LOW < HIGH"
                              + (" and LOW > 0" if kind == "loguniform" else ""))  # fmt: skip
        return key, {"kind": kind, "low": low, "high": high}
    if text.startswith("["):  # one list-valued choice, e.g. net_arch=[64, 64]
        return key, {"kind": "choice", "values": [parse_value(text)]}
    return key, {"kind": "choice", "values": [parse_value(v) for v in text.split(",")]}


def sample_configurations(space: dict[str, dict[str, Any]], search: str, n: int, seed: int) -> list[dict[str, Any]]:
    """The configurations of a grid (every combination of the choices) or n random draws (seeded)."""
    if search == "grid":
        ranges = [k for k, s in space.items() if s["kind"] != "choice"]
        if ranges:
            raise ConfigError(f"--search grid needs choices (KEY=v1,v2), not ranges: {', '.join(ranges)}")
        keys = list(space)
        return [dict(zip(keys, combo, strict=True)) for combo in itertools.product(*(space[k]["values"] for k in keys))]
    rng = np.random.default_rng(seed)
    configs = []
    for _ in range(n):
        config: dict[str, Any] = {}
        for key, spec in space.items():
            if spec["kind"] == "choice":
                config[key] = spec["values"][rng.integers(len(spec["values"]))]
            elif spec["kind"] == "uniform":
                config[key] = float(rng.uniform(spec["low"], spec["high"]))
            elif spec["kind"] == "loguniform":
                config[key] = float(math.exp(rng.uniform(math.log(spec["low"]), math.log(spec["high"]))))
            else:
                config[key] = int(rng.integers(int(spec["low"]), int(spec["high"]) + 1))
        configs.append(config)
    return configs


def optuna_space(space: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """The search space in Ray Tune's terms, for OptunaSearch."""
    from ray import tune

    def convert(spec: dict[str, Any]) -> Any:
        if spec["kind"] == "choice":
            return tune.choice(spec["values"])
        if spec["kind"] == "uniform":
            return tune.uniform(spec["low"], spec["high"])
        if spec["kind"] == "loguniform":
            return tune.loguniform(spec["low"], spec["high"])
        return tune.randint(int(spec["low"]), int(spec["high"]) + 1)

    return {key: convert(spec) for key, spec in space.items()}


def trial_config(base: dict[str, Any], hp: dict[str, Any], seed: int, run_dir: Path) -> TrainConfig:
    """The TrainConfig of one run: the sweep's base options, this seed, the defaults/YAML, then ``hp``."""
    config = TrainConfig(**{**base, "seed": seed, "run_dir": str(run_dir), "progress": False})
    config.validate()  # the options first (the env id chooses the hyperparameters' section)
    config = resolve_hyperparams(config, set(base))
    hp = dict(hp)
    inner = {key: hp.pop(key) for key in POLICY_KWARGS if key in hp}
    config.algo_kwargs.update(hp)
    if inner:  # searched keys of policy_kwargs (e.g. log_std_init), merged into the resolved ones
        config.algo_kwargs["policy_kwargs"] = {**(config.algo_kwargs.get("policy_kwargs") or {}), **inner}
    check_algo_kwargs(config.algo, config.algo_kwargs, config.backend)
    config.validate()
    return config


def last_evaluation(run_dir: Path) -> dict[str, float] | None:
    """The final row of a run's evaluations.csv, or None."""
    rows = read_evaluations(run_dir / EVAL_FILE)
    return rows[-1] if rows else None


def run_one(base: dict[str, Any], hp: dict[str, Any], seed: int, run_dir: Path, config_id: str, report: Any) -> dict:
    """Train one seed of one configuration (or reuse a finished run: an interrupted sweep resumes)."""
    from train.learning.runs import MODEL_FILE
    from train.learning.training import train

    finished = (run_dir / MODEL_FILE).is_file() and last_evaluation(run_dir) is not None
    if not finished:
        shutil.rmtree(run_dir, ignore_errors=True)  # a run cut off mid-way starts again from scratch
        config = trial_config(base, hp, seed, run_dir)
        run_dir.mkdir(parents=True, exist_ok=True)
        (run_dir / PARAMS_FILE).write_text(json.dumps({"config_id": config_id, "seed": seed, "hyperparams": hp}))
        train(config, command=["dwr-gym", "sweep"], on_evaluation=report)
    row = last_evaluation(run_dir)
    assert row is not None
    return row


def trainable(trial: dict[str, Any]) -> None:
    """A Ray Tune trial: train the seed(s) of one configuration, reporting every evaluation to Tune."""
    from ray import tune

    trial = trial.get("trial", trial)  # grid/random: the grid_search over explicit trials
    out = Path(trial["out"])
    hp = {k: v for k, v in trial.items() if k not in ("out", "base", "seeds", "seed", "config_id", "name")}
    config_id = trial.get("config_id") or f"t{tune.get_context().get_trial_id()}"
    seeds = trial["seeds"] if "seeds" in trial else [trial["seed"]]
    finals: list[dict[str, float]] = []
    for seed in seeds:

        def report(row: dict[str, Any], seed: int = seed) -> None:
            tune.report({**{k: float(row[k]) for k in METRICS}, "timesteps": int(row["timesteps"]), "seed": seed})

        run_dir = out / "runs" / f"{trial['name']}-{config_id}-seed{seed}"
        finals.append(run_one(trial["base"], hp, seed, run_dir, config_id, report))
    # the configuration's score over its seeds, last: what a searcher (Optuna) compares
    tune.report({**{k: float(np.mean([f[k] for f in finals])) for k in METRICS}, "seed": -1,
                 "timesteps": int(finals[-1]["timesteps"])})  # fmt: skip


def collect(out: Path) -> dict[str, dict[str, Any]]:
    """Every run under ``out/runs``, grouped by configuration: hyperparameters, seeds, evaluations."""
    groups: dict[str, dict[str, Any]] = {}
    for params_path in sorted(out.glob(f"runs/*/{PARAMS_FILE}")):
        meta = json.loads(params_path.read_text())
        rows = read_evaluations(params_path.parent / EVAL_FILE)
        if not rows:
            continue
        group = groups.setdefault(meta["config_id"], {"hyperparams": meta["hyperparams"], "runs": {}})
        group["runs"][meta["seed"]] = rows
    return groups


def summarize(groups: dict[str, dict[str, Any]], metric: str) -> list[dict[str, Any]]:
    """One row per configuration: mean and sd over seeds of the final evaluation, best first."""
    table = []
    for config_id, group in groups.items():
        finals = [rows[-1] for rows in group["runs"].values()]
        row: dict[str, Any] = {"config": config_id, "seeds": len(finals), "hyperparams": group["hyperparams"]}
        for key in TABLE_COLUMNS + ((metric,) if metric not in TABLE_COLUMNS else ()):
            values = np.array([f[key] for f in finals])
            row[f"{key}_mean"] = float(np.nanmean(values)) if np.isfinite(values).any() else math.nan
            row[f"{key}_sd"] = float(np.nanstd(values, ddof=1)) if np.isfinite(values).sum() > 1 else 0.0
        table.append(row)
    sign = -1.0 if metric in ("return_mean", "success_rate") else 1.0
    return sorted(table, key=lambda r: sign * r[f"{metric}_mean"] if math.isfinite(r[f"{metric}_mean"]) else math.inf)


def zoo_yaml(config: TrainConfig) -> str:
    """A resolved configuration in rl-zoo3's YAML format, readable by rl-zoo3 and ``dwr-gym train --hyperparams``."""
    import yaml

    section: dict[str, Any] = {"n_envs": config.num_envs, "n_timesteps": config.total_timesteps}
    for key, value in config.algo_kwargs.items():
        if key == "policy_kwargs":
            inner = ", ".join(f"{k}={v if isinstance(v, str) and v.startswith('nn.') else repr(v)}"
                              for k, v in value.items())  # fmt: skip
            section[key] = f"dict({inner})"
        elif key == "action_noise_sigma":
            section["noise_type"], section["noise_std"] = "normal", value
        else:
            section[key] = value
    header = "# best configuration of a dwr-gym sweep" + (
        " (residual on the PTC expert: dwr-gym train only)\n" if config.residual else "\n"
    )
    if config.env_kwargs:
        section["env_kwargs"] = dict(config.env_kwargs)
    return header + yaml.safe_dump({config.env_id: section}, sort_keys=False)


def parse_resources(text: str, flag: str = "--resources-per-trial") -> dict[str, float]:
    """``cpu=1,gpu=0.5`` as Ray's resource dict (a ConfigError names ``flag``)."""
    resources: dict[str, float] = {}
    for item in text.split(","):
        key, _, value = item.partition("=")
        try:
            amount = float(value)
        except ValueError:
            amount = -1.0
        if not key or not math.isfinite(amount) or amount < 0:
            raise ConfigError(f"{flag} {text!r} is invalid: expected e.g. cpu=1 or cpu=2,gpu=0.5")
        resources[key.strip()] = amount
    return resources
