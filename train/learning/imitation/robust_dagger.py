"""DAgger under randomised disturbances: the network of a robust prescribed-time agent.

The agent is ``robust-pt`` (:class:`baselines.robust.RobustPTController`) with a learned cruise: the network drives
on the controller's state estimate, with the estimated disturbance cancelled, until the time passes
``handover_time`` * T_con or the robot falls behind schedule; then the controller's planner (or, with ``plan=False``,
its analytic finish) takes over. This module trains the network:

1. it starts from a network cloned from minimum-energy plans (``init_from``: the hand-over network of
   ``python -m train.learning.imitation.dagger``, seed 0 of benchmarks/recipes/dagger_agents.sh) or
   from demonstrations (:func:`train.learning.imitation.dagger.demonstrations`);
2. each DAgger round, the network drives, behind the filter, from random starts and T_con in the env's range, in
   ``disturbed_fraction`` of the episodes on a robot drawn from :class:`dwr_gym.randomization.DisturbanceDistribution`
   (all seven kinds, magnitudes beyond the evaluation sets) with pose and actuation noise; from states it visits,
   the expert's plan is solved again, as ``robust-pt`` would plan it: arriving at ``plan_arrival`` * T_con, or as
   early as the limits allow once the robot is behind;
3. the learning curve evaluates the network alone (behind the filter), nominal and disturbed, after each round.

The saved run is a ``dwr-gym`` run directory whose config.yaml has a ``robust_agent`` section (the controller's
parameters): ``load_agent`` builds the controller with the network as its cruise. Needs the ``optimal`` and
``train`` extras.

    python -m train.learning.imitation.robust_dagger --run-dir runs/robust_s0 --seed 0
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from dwr_gym import core
from dwr_gym.params import EnvParams
from dwr_gym.randomization import DisturbanceDistribution
from train.env_ids import TASK_ENV_ID
from train.learning.config import TrainConfig, check_env_id, env_keywords
from train.learning.imitation.dagger import (
    DaggerConfig,
    Dataset,
    concatenate,
    demonstrations,
    fit,
    labelled_samples,
    make_model,
    solve_plans,
)


@dataclass
class RobustDaggerConfig:
    """Everything a robust DAgger run needs; written into the run's config.yaml (under ``robust_dagger``)."""

    seed: int = 0
    """Seed of the rollouts' starts and robots, the fits and the evaluation."""
    init_from: str = "runs/dagger_handover_s0"
    """A run directory whose network is the starting point, by default where seed 0 of
    benchmarks/recipes/dagger_agents.sh writes its hand-over network ('' clones ``episodes`` demonstrations first)."""
    episodes: int = 500
    """Demonstration plans (arriving at plan_arrival * T_con) fitted before the rounds; 0: none."""
    dagger_rounds: int = 4
    dagger_episodes: int = 300
    """Network rollouts per DAgger round."""
    replans_per_episode: int = 4
    """States per rollout from which the expert's plan is solved again."""
    plan_arrival: float = 0.8
    """The expert's plans arrive at this fraction of T_con (robust-pt's ``plan_arrival``)."""
    disturbed_fraction: float = 0.75
    """Share of the rollouts on a robot drawn from the disturbance distribution, with pose and actuation noise."""
    observation_noise: float = 0.01  # [m, rad]
    actuation_noise: float = 0.05
    hold_steps: int = 5
    epochs: int = 20
    batch_size: int = 2048
    learning_rate: float = 5e-4
    near_goal_weight: float = 1.0
    net_arch: list[int] = field(default_factory=lambda: [256, 256])
    workers: int = 2
    eval_episodes: int = 100
    eval_T_con: tuple[float, ...] = (10.0, 20.0, 40.0, 60.0)
    env_id: str = TASK_ENV_ID
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    distribution: dict[str, Any] = field(default_factory=dict)
    """Keywords of the DisturbanceDistribution (its defaults where left out)."""
    threads: int = 1
    """torch threads while it runs (restored afterwards; train.threads)."""


def student(model: Any, params: EnvParams) -> Any:
    """The network as it drives in deployment, without the hand-over: behind the filter that cancels disturbances."""
    from baselines.estimation import FilteredPolicy

    return FilteredPolicy(model, params.u_max, params.omega_max, params.dt, k=params.k)


def rollouts(policy: Any, params: EnvParams, config: RobustDaggerConfig, n: int, rng: np.random.Generator,
             disturbed: bool, record: bool = False) -> tuple[Any, np.ndarray, np.ndarray]:  # fmt: skip
    """Run ``policy`` from n random starts and T_con of the env, on the nominal or a randomly disturbed robot."""
    from train.evaluation.rollout import rollout

    starts = np.array([core.sample_start(rng, params) for _ in range(n)])
    T_con = np.array([core.sample_T_con(rng, params) for _ in range(n)])
    run_params, env_kwargs = params, {}
    if disturbed:
        noisy = {
            **params.as_dict(),
            "observation_noise": config.observation_noise,
            "actuation_noise": config.actuation_noise,
        }
        run_params = EnvParams.from_kwargs(**noisy)
        env_kwargs = {"disturbance_distribution": DisturbanceDistribution(**config.distribution)}
    seed = int(rng.integers(2**31))
    result = rollout(policy, run_params, starts, np.zeros((n, 3)), record=record, T_con=T_con, seed=seed,
                     env_kwargs=env_kwargs)  # fmt: skip
    return result, starts, T_con


def expert_arrival(config: RobustDaggerConfig, T_con: float, now: float, least: float) -> float:
    """The time left [s] until robust-pt's planned arrival from a state at ``now``: plan_arrival * T_con, or, behind
    schedule, 1.1 times the least time the limits allow."""
    return max(config.plan_arrival * T_con - now, 1.1 * least, config.hold_steps * 4 * 0.05)


def dagger_samples(model: Any, config: RobustDaggerConfig, params: EnvParams, rng: np.random.Generator) -> Dataset:
    """The student drives (nominal and disturbed robots); the expert's plans from states it visits label them."""
    from baselines.optimal import least_arrival_time

    n_disturbed = round(config.disturbed_fraction * config.dagger_episodes)
    data: list[Dataset] = []
    for disturbed, n in ((True, n_disturbed), (False, config.dagger_episodes - n_disturbed)):
        if n == 0:
            continue
        result, starts, T_con = rollouts(student(model, params), params, config, n, rng, disturbed, record=True)
        traj = result.trajectory
        assert traj is not None
        poses = np.stack([traj["x"], traj["y"], traj["psi"]], axis=-1)  # (steps + 1, n, 3), goal at the origin
        ended = np.where(np.isnan(result.arrival_time), poses.shape[0] - 1, result.arrival_time / params.dt)
        jobs, meta = [], []
        for i in range(n):
            coords = core.error_coordinates(*starts[i], params.k)
            for step in rng.integers(0, max(1, round(float(ended[i]))), size=config.replans_per_episode):
                x, y, psi = (float(v) for v in poses[step, i])
                if math.hypot(x, y) <= params.goal_tolerance:
                    continue
                least = least_arrival_time((x, y, psi), params.u_max, params.omega_max, True)
                arrival = expert_arrival(config, float(T_con[i]), step * params.dt, least)
                jobs.append(((x, y, psi), arrival, params.dt, params.u_max, params.omega_max, config.hold_steps))
                meta.append((int(step), float(T_con[i]), float(coords.distance), float(coords.orientation_error)))
        for (step, T, d0, e0), plan in zip(meta, solve_plans(jobs, config.workers), strict=True):
            samples = labelled_samples(plan, step, T, d0, e0, params)
            if samples is not None:
                data.append(samples)
    return concatenate(data)


def evaluate(policy: Any, params: EnvParams, config: RobustDaggerConfig) -> dict[str, float]:
    """Success, heading and energy of ``policy`` at each evaluation T_con, nominal and on drawn robots (seed 12345)."""
    from train.evaluation.rollout import rollout

    row: dict[str, float] = {}
    for disturbed in (False, True):
        rng = np.random.default_rng(12345)
        starts = np.array([core.sample_start(rng, params) for _ in range(config.eval_episodes)])
        for T in config.eval_T_con:
            run_params, env_kwargs = params, {}
            if disturbed:
                run_params = EnvParams.from_kwargs(**{**params.as_dict(), "observation_noise": config.observation_noise,
                                                      "actuation_noise": config.actuation_noise})  # fmt: skip
                env_kwargs = {
                    "disturbance_distribution": DisturbanceDistribution(**{**config.distribution, "seed": 12345})
                }
            result = rollout(policy, run_params, starts, np.zeros_like(starts), T_con=np.full(len(starts), T),
                             seed=12345, env_kwargs=env_kwargs)  # fmt: skip
            prefix = "disturbed_" if disturbed else ""
            row[f"{prefix}success_T{int(T)}"] = float(result.success.mean())
            row[f"{prefix}heading_T{int(T)}"] = float(np.mean(result.final_heading_error))
            row[f"{prefix}energy_T{int(T)}"] = float(np.mean(result.energy))
    return row


def run(config: RobustDaggerConfig, run_dir: Path, command: list[str]) -> Path:
    """Warm start, DAgger rounds under disturbances, the hand-over; save model.zip, config.yaml, evaluations.csv.
    torch runs on ``config.threads`` threads meanwhile; the caller's count is restored afterwards."""
    from train.threads import torch_threads

    with torch_threads(config.threads):
        return _run(config, run_dir, command)


def _run(config: RobustDaggerConfig, run_dir: Path, command: list[str]) -> Path:
    import torch
    from stable_baselines3 import PPO

    from train.learning.runs import MODEL_FILE

    if (run_dir / MODEL_FILE).exists():
        raise SystemExit(f"--run-dir {str(run_dir)!r} already holds a trained model: choose another")
    DisturbanceDistribution(**config.distribution)  # a bad keyword fails here, before any work
    run_dir.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(config.seed)
    params = EnvParams.from_kwargs(**env_keywords(config.env_id, config.env_kwargs))
    rng = np.random.default_rng(config.seed)
    began = time.time()
    plain = DaggerConfig(seed=config.seed, episodes=config.episodes, arrival_fraction=config.plan_arrival,
                         hold_steps=config.hold_steps, epochs=config.epochs, batch_size=config.batch_size,
                         learning_rate=config.learning_rate, near_goal_weight=config.near_goal_weight,
                         net_arch=list(config.net_arch), workers=config.workers, env_id=config.env_id,
                         env_kwargs=dict(config.env_kwargs))  # fmt: skip
    model = PPO.load(Path(config.init_from) / MODEL_FILE, device="cpu") if config.init_from else make_model(plain)
    data = demonstrations(plain, params, rng) if config.episodes else concatenate([])
    if config.episodes:
        fit(model, data, plain, rng)
    curve = [{"round": 0, "samples": len(data[0]), "wall_time": round(time.time() - began, 1), "loss": math.nan,
              **evaluate(student(model, params), params, config)}]  # fmt: skip
    print(curve[-1], flush=True)
    save(model, curve, config, run_dir, command)
    for round_ in range(1, config.dagger_rounds + 1):
        data = concatenate([data, dagger_samples(model, config, params, rng)])
        loss = fit(model, data, plain, rng)
        curve.append({"round": round_, "samples": len(data[0]), "wall_time": round(time.time() - began, 1),
                      "loss": loss, **evaluate(student(model, params), params, config)})  # fmt: skip
        print(curve[-1], flush=True)
        save(model, curve, config, run_dir, command)  # after every round: an interrupted run keeps its last model
    print(f"trained in {time.time() - began:.0f} s on {len(data[0])} samples; saved {run_dir / MODEL_FILE}")
    return run_dir


def save(
    model: Any, curve: list[dict[str, Any]], config: RobustDaggerConfig, run_dir: Path, command: list[str]
) -> None:
    """The run directory as a loadable agent: model.zip, config.yaml (with the robust_agent section), evaluations.csv."""
    import csv

    from train.learning.runs import EVAL_FILE, MODEL_FILE, save_config

    model.save(run_dir / MODEL_FILE)
    extra: dict[str, Any] = {"robust_dagger": dataclasses.asdict(config), "command": command,
                             "robust_agent": {"plan_arrival": config.plan_arrival}, "learned_from": "expert",
                             "runtime": ["planner", "finish"]}  # fmt: skip
    train_config = TrainConfig(algo="ppo", total_timesteps=1, num_envs=4, seed=config.seed, env_id=config.env_id,
                               env_kwargs=dict(config.env_kwargs), run_dir=str(run_dir), progress=False)  # fmt: skip
    save_config(train_config, run_dir, extra)
    with (run_dir / EVAL_FILE).open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(curve[-1]))
        writer.writeheader()
        writer.writerows(curve)
    plot_curves(curve, config.eval_T_con, run_dir)


def plot_curves(curve: list[dict[str, Any]], T_cons: Any, run_dir: Path) -> None:
    """The learning curves (the network alone, as the DAgger rounds evaluate it), nominal and disturbed."""
    from train.reporting.learning_curves import plot_dagger_curve

    T_cons = tuple(float(T) for T in T_cons)
    plot_dagger_curve(curve, T_cons, run_dir / "learning_curve.png",
                      title="Robust DAgger, the network alone: fixed evaluation starts 0.3-3 m away, nominal")  # fmt: skip
    plot_dagger_curve(curve, T_cons, run_dir / "learning_curve_disturbed.png", prefix="disturbed_",
                      title="Robust DAgger, the network alone: the same starts under randomised disturbances")  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    from train.learning.runs import MODEL_FILE

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--run-dir", required=True)
    for f in dataclasses.fields(RobustDaggerConfig):
        if f.type in ("int", "float", "str"):
            kind = {"int": int, "float": float, "str": str}[f.type]  # type: ignore[index]
            flag = "--env" if f.name == "env_id" else f"--{f.name.replace('_', '-')}"
            parser.add_argument(flag, dest=f.name, type=kind, default=f.default)
    args = parser.parse_args(argv)
    values = {k: v for k, v in vars(args).items() if k != "run_dir"}
    try:
        values["env_id"] = check_env_id(values["env_id"])
    except ValueError as error:
        parser.error(str(error))
    init_from = values["init_from"]
    if init_from and not (Path(init_from) / MODEL_FILE).is_file():  # answered before the hours of planning
        parser.error(f"--init-from {init_from!r} is invalid: no {MODEL_FILE} in it; train the hand-over network first "
                     f"(python -m train.learning.imitation.dagger --run-dir {init_from} ..., as benchmarks/recipes/"
                     "dagger_agents.sh does) or pass --init-from '' to clone demonstrations")  # fmt: skip
    run(RobustDaggerConfig(**values), Path(args.run_dir),
        ["python", "-m", "train.learning.imitation.robust_dagger", *(argv or sys.argv[1:])])  # fmt: skip


if __name__ == "__main__":
    main()
