"""DAgger on minimum-energy plans: one network that drives to the full pose by any T_con.

The minimum-energy plan of :mod:`baselines.optimal` from a pose with a time left is, by the principle of
optimality, the same plan as seen from any later state on it, so the optimal command is a function of the
observation (pose relative to the goal, t / T_con, T_con). This module learns that function:

1. **Demonstrations**: plans from random starts and prescribed times (the env's ``T_con_range`` and
   ``start_distance``), each arriving at ``arrival_fraction * T_con`` so that the network has a margin
   before the deadline, sampled at every control period as (observation, normalised command) pairs.
2. **DAgger rounds**: the network drives; from states it visits, plans are solved again over the time
   left and added to the data, so it learns to recover from its own errors.

Unlike ``dwr-gym imitate`` (:mod:`train.learning.imitation.cloning`, which records the re-planning ``optimal``
controller under action noise), the labels here are whole plans solved from the states the *network*
reaches, so the data follows the student's own mistakes (Ross, Gordon, Bagnell 2011).

The network is the actor of a stable-baselines3 PPO policy, saved with a ``config.yaml`` like any
``dwr-gym train`` run: ``load_agent`` and ``dwr-gym evaluate --agents`` read it, and at run time it is
the network alone (the optimiser is only used to make the training data). Needs the ``optimal`` and
``train`` extras.

    python -m train.learning.imitation.dagger --run-dir runs/dagger_s0 --seed 0
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import multiprocessing
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym import core, model
from dwr_gym.params import EnvParams
from train.env_ids import TASK_ENV_ID, check_env_id, env_keywords
from train.learning.config import TrainConfig

#: Observations (M, 10) and normalised commands (M, 2) of demonstration samples.
Dataset = tuple[NDArray[np.float32], NDArray[np.float32]]


@dataclass
class DaggerConfig:
    """Everything a DAgger run needs; written into the run's config.yaml (under ``dagger``)."""

    seed: int = 0
    """Seed of the demonstration starts, the network initialisation and the DAgger rollouts."""
    episodes: int = 400
    """Demonstration plans from random starts."""
    dagger_rounds: int = 2
    """Rounds of rollouts by the network followed by re-planned labels."""
    dagger_episodes: int = 200
    """Network rollouts per DAgger round."""
    replans_per_episode: int = 3
    """States per DAgger rollout from which a plan is solved again."""
    arrival_fraction: float = 0.85
    """The plans arrive at this fraction of T_con: a margin for the network's errors."""
    hold_steps: int = 5
    """Control periods each planned command is held (the optimal controller's grid; < 1 % of energy)."""
    epochs: int = 40
    """Passes over the data per fit."""
    batch_size: int = 2048
    learning_rate: float = 1e-3
    near_goal_weight: float = 0.0
    """Weight each sample by (1 + near_goal_weight * 0.05 m / max(d, 1 cm)) / mean: the last centimetres
    decide arrival, where the commands are small and an unweighted loss hardly sees their errors."""
    net_arch: list[int] = field(default_factory=lambda: [256, 256])
    """Hidden layers of the actor (ReLU)."""
    workers: int = 2
    """Solver processes."""
    eval_episodes: int = 100
    """Random starts of the evaluation after each fit (the learning curve)."""
    eval_T_con: tuple[float, ...] = (10.0, 20.0, 40.0, 60.0)
    """Prescribed times [s] of the evaluation after each fit."""
    env_id: str = TASK_ENV_ID
    """The env the agent is for: DWRPointStabilization-v1 (T_con drawn per episode) or -v0 (T_con = 20 s)."""
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    """Env keywords on top of those ``env_id`` is registered with."""
    handover_expert: str = ""
    """If set (e.g. "pt-astolfi"), the trained network hands over to this analytic law for the finish
    (train.learning.imitation.handover.HandoverPolicy), with the thresholds of HANDOVER_GRID that :func:`select_handover` chooses
    on the evaluation starts (not a benchmark's)."""
    threads: int = 1
    """torch threads while it runs (restored afterwards; train.threads)."""


def _solve(job: tuple[tuple[float, float, float], float, float, float, float, int]) -> Any:
    """(states, commands) of one plan on the env's grid of control periods, or None when there is none."""
    from baselines.optimal import InfeasibleArrivalTimeError, OptimalControlError, solve_minimum_energy

    start, arrival, dt, u_max, omega_max, hold = job
    try:
        plan = solve_minimum_energy(start, arrival, dt, u_max, omega_max, heading=True, hold_steps=hold)
    except (InfeasibleArrivalTimeError, OptimalControlError):
        return None
    commands = np.repeat(plan.commands, hold, axis=0)  # command of every control period
    x, y, psi = (np.repeat(plan.states[:-1, i], hold) for i in range(3))
    offset = np.tile(np.arange(hold) * dt, plan.intervals)
    # states within a held interval: the exact arc of eq. (1) from the interval's first state
    x, y, psi = model.integrate_unicycle(x, y, psi, commands[:, 0], commands[:, 1], offset, "exact", 1)
    return np.stack([x, y, psi], axis=1), commands


def solve_plans(jobs: list[Any], workers: int) -> list[Any]:
    """Solve the jobs in parallel, sorted by length so that each worker reuses its cached solvers."""
    order = sorted(range(len(jobs)), key=lambda i: jobs[i][1])
    sorted_jobs = [jobs[i] for i in order]
    if workers <= 1:
        solved = [_solve(job) for job in sorted_jobs]
    else:
        chunk = max(1, len(jobs) // (4 * workers))
        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            solved = list(pool.map(_solve, sorted_jobs, chunksize=chunk))
    results: list[Any] = [None] * len(jobs)
    for index, result in zip(order, solved, strict=True):
        results[index] = result
    return results


def observations(
    states: NDArray[np.float64], steps: NDArray[np.int64], T_con: float, d0: float, e0: float, params: EnvParams
) -> NDArray[np.float32]:
    """The env's observations at goal-frame poses ``states`` (M, 3) after ``steps`` control periods."""
    n = states.shape[0]
    state = core.TaskState.zeros(n)
    pose = (states[:, 0].copy(), states[:, 1].copy(), model.wrap_angle(states[:, 2]))
    zeros = np.zeros(n)
    core.reset_robots(state, slice(None), pose, (zeros, zeros, zeros), params, np.full(n, T_con))
    state.step_count[:] = steps
    state.initial_distance[:] = d0
    state.initial_orientation_error[:] = e0
    return core.observe(state, state.coordinates(params.k), params, core.observation_space(params))


def labelled_samples(
    plan: Any, first_step: int, T_con: float, d0: float, e0: float, params: EnvParams
) -> Dataset | None:
    """(observations, normalised commands) along a plan that starts ``first_step`` periods into an episode."""
    if plan is None:
        return None
    states, commands = plan
    keep = np.hypot(states[:, 0], states[:, 1]) <= params.arena_radius
    steps = first_step + np.arange(states.shape[0])
    obs = observations(states[keep], steps[keep], T_con, d0, e0, params)
    actions = np.clip(commands[keep] / np.array([params.u_max, params.omega_max]), -1.0, 1.0).astype(np.float32)
    return obs, actions


def demonstrations(config: DaggerConfig, params: EnvParams, rng: np.random.Generator) -> Dataset:
    """Plans from random starts and prescribed times, arriving at ``arrival_fraction`` T_con."""
    episodes = []
    for _ in range(config.episodes):
        start = core.sample_start(rng, params)
        T_con = core.sample_T_con(rng, params)
        episodes.append((start, T_con))
    jobs = [(start, config.arrival_fraction * T, params.dt, params.u_max, params.omega_max, config.hold_steps)
            for start, T in episodes]  # fmt: skip
    data = []
    for (start, T_con), plan in zip(episodes, solve_plans(jobs, config.workers), strict=True):
        coords = core.error_coordinates(*start, params.k)
        samples = labelled_samples(plan, 0, T_con, float(coords.distance), float(coords.orientation_error), params)
        if samples is not None:
            data.append(samples)
    return concatenate(data)


def concatenate(data: list[Dataset]) -> Dataset:
    """One dataset of several (an empty one when there are none)."""
    if not data:
        return np.zeros((0, len(core.OBSERVATION_NAMES)), np.float32), np.zeros((0, 2), np.float32)
    return np.concatenate([d[0] for d in data]), np.concatenate([d[1] for d in data])


def dagger_samples(policy: Any, config: DaggerConfig, params: EnvParams, rng: np.random.Generator) -> Dataset:
    """Let the network drive from random starts, then re-plan from states it visits over the time left."""
    from train.evaluation.rollout import rollout

    n = config.dagger_episodes
    starts = np.array([core.sample_start(rng, params) for _ in range(n)])
    T_con = np.array([core.sample_T_con(rng, params) for _ in range(n)])
    result = rollout(policy, params, starts, np.zeros((n, 3)), record=True, T_con=T_con)
    traj = result.trajectory
    assert traj is not None
    poses = np.stack([traj["x"], traj["y"], traj["psi"]], axis=-1)  # (steps + 1, n, 3), goal at the origin
    ended = np.where(np.isnan(result.arrival_time), poses.shape[0] - 1, result.arrival_time / params.dt)
    jobs, meta = [], []
    for i in range(n):
        length = round(float(ended[i]))
        coords = core.error_coordinates(*starts[i], params.k)
        for step in rng.integers(1, max(2, length), size=config.replans_per_episode):
            x, y, psi = poses[step, i]
            if math.hypot(x, y) <= params.goal_tolerance:
                continue
            time_left = T_con[i] - step * params.dt
            # the original target while there is time for it, else most of what is left before T_con
            arrival = config.arrival_fraction * T_con[i] - step * params.dt
            if arrival < 0.5 * time_left:
                arrival = config.arrival_fraction * time_left
            if arrival <= params.dt * config.hold_steps:
                continue
            jobs.append(((float(x), float(y), float(psi)), arrival, params.dt, params.u_max, params.omega_max,
                         config.hold_steps))  # fmt: skip
            meta.append((int(step), float(T_con[i]), float(coords.distance), float(coords.orientation_error)))
    data = []
    for (step, T, d0, e0), plan in zip(meta, solve_plans(jobs, config.workers), strict=True):
        samples = labelled_samples(plan, step, T, d0, e0, params)
        if samples is not None:
            data.append(samples)
    return concatenate(data)


def make_model(config: DaggerConfig) -> Any:
    """An untrained PPO model on the env whose actor is the network to clone into."""
    import torch
    from stable_baselines3 import PPO

    from dwr_gym.sb3 import make_sb3_vec_env

    env = make_sb3_vec_env(4, seed=config.seed, **env_keywords(config.env_id, config.env_kwargs))
    policy_kwargs = {"net_arch": {"pi": list(config.net_arch), "vf": [64, 64]}, "activation_fn": torch.nn.ReLU,
                     "log_std_init": -2.0}  # fmt: skip
    return PPO("MlpPolicy", env, seed=config.seed, device="cpu", gamma=0.999, policy_kwargs=policy_kwargs)


def fit(model: Any, data: Dataset, config: DaggerConfig, rng: np.random.Generator) -> float:
    """Regress the actor's mean action on the demonstrated commands (MSE); returns the last epoch's loss."""
    import torch

    policy = model.policy
    params = [*policy.features_extractor.parameters(), *policy.mlp_extractor.policy_net.parameters(),
              *policy.action_net.parameters()]  # fmt: skip
    optimizer = torch.optim.Adam(params, lr=config.learning_rate)
    obs = torch.as_tensor(data[0])
    target = torch.as_tensor(data[1])
    weight = 1.0 + config.near_goal_weight * 0.05 / torch.clamp(obs[:, 0], min=0.01)
    weight = (weight / weight.mean())[:, None]
    n = obs.shape[0]
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimizer, config.epochs * math.ceil(n / config.batch_size))
    loss_value = math.nan
    for _ in range(config.epochs):
        permutation = torch.as_tensor(rng.permutation(n))
        total = 0.0
        for begin in range(0, n, config.batch_size):
            index = permutation[begin : begin + config.batch_size]
            features = policy.extract_features(obs[index], policy.pi_features_extractor)
            mean = policy.action_net(policy.mlp_extractor.forward_actor(features))
            loss = torch.mean(weight[index] * (mean - target[index]) ** 2)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            schedule.step()
            total += float(loss.detach()) * index.shape[0]
        loss_value = total / n
    return loss_value


def evaluate_by_T_con(policy: Any, params: EnvParams, T_cons: tuple[float, ...], n: int, seed: int) -> list[dict]:
    """Success, final heading error and energy of ``policy`` at each T_con on the same random starts."""
    from train.evaluation.rollout import rollout

    rng = np.random.default_rng(seed)
    starts = np.array([core.sample_start(rng, params) for _ in range(n)])
    rows = []
    for T in T_cons:
        result = rollout(policy, params, starts, np.zeros((n, 3)), T_con=np.full(n, T))
        rows.append({"T_con": T, "success": float(result.success.mean()),
                     "heading": float(np.mean(result.final_heading_error)), "energy": float(np.mean(result.energy))})  # fmt: skip
    return rows


#: Hand-overs tried by :func:`select_handover`: (distance [m], time fraction, speed margin) of HandoverPolicy.
HANDOVER_GRID = [(0.0, f, m) for f in (0.8, 0.85, 0.9, 1.0) for m in (0.0, 1.5, 2.0, 3.0)]


def check_handover_expert(name: str) -> None:
    """Exit with a one-line message unless ``name`` is an analytic controller."""
    from baselines.registry import CONTROLLERS

    if name not in CONTROLLERS:
        raise SystemExit(f"--handover-expert {name!r} is invalid: expected one of {', '.join(CONTROLLERS)}")


def select_handover(model: Any, config: DaggerConfig, params: EnvParams) -> tuple[dict[str, Any], list[dict]]:
    """The hand-over of HANDOVER_GRID that, on the evaluation starts (seed 12345, not a benchmark's), arrives in
    time in >= 99 % of episodes with a mean final heading error <= 0.1 rad at every T_con and spends the least
    energy; failing that, the one that arrives in time most often. Returns it with every row tried."""
    from train.learning.imitation.handover import make_handover_policy

    tried = []
    for distance, fraction, margin in HANDOVER_GRID:
        policy = make_handover_policy(model, config.handover_expert, params, distance, fraction, margin)
        rows = evaluate_by_T_con(policy, params, config.eval_T_con, config.eval_episodes, 12345)
        tried.append({"distance": distance, "time_fraction": fraction, "speed_margin": margin,
                      "success": min(r["success"] for r in rows), "heading": max(r["heading"] for r in rows),
                      "energy": sum(r["energy"] * r["T_con"] for r in rows) / len(rows)})  # fmt: skip  # energy x T_con: each T_con alike
        print(tried[-1], flush=True)
    good = [t for t in tried if t["success"] >= 0.99 and t["heading"] <= 0.1]
    best = min(good, key=lambda t: t["energy"]) if good else max(tried, key=lambda t: (t["success"], -t["heading"]))
    chosen = {k: best[k] for k in ("distance", "time_fraction", "speed_margin")}
    selected_on = f"{config.eval_episodes} random starts per T_con in {list(config.eval_T_con)}, seed 12345"
    return {"expert": config.handover_expert, **chosen, "selected_on": selected_on}, tried


def run(config: DaggerConfig, run_dir: Path, command: list[str]) -> Path:
    """Collect, clone, run the DAgger rounds, save model.zip, config.yaml and evaluations.csv in ``run_dir``.
    torch runs on ``config.threads`` threads meanwhile; the caller's count is restored afterwards."""
    from train.threads import torch_threads

    with torch_threads(config.threads):
        return _run(config, run_dir, command)


def _run(config: DaggerConfig, run_dir: Path, command: list[str]) -> Path:
    import csv

    import torch

    from train.learning.runs import EVAL_FILE, MODEL_FILE, save_config
    from train.reporting.learning_curves import plot_dagger_curve

    if config.handover_expert:
        check_handover_expert(config.handover_expert)
    if (run_dir / MODEL_FILE).exists():
        raise SystemExit(f"--run-dir {str(run_dir)!r} already holds a trained model: choose another")
    run_dir.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(config.seed)
    params = EnvParams.from_kwargs(**env_keywords(config.env_id, config.env_kwargs))
    rng = np.random.default_rng(config.seed)
    began = time.time()
    model = make_model(config)
    data = demonstrations(config, params, rng)
    curve = []
    for round_ in range(config.dagger_rounds + 1):
        loss = fit(model, data, config, rng)
        rows = evaluate_by_T_con(model, params, config.eval_T_con, config.eval_episodes, 12345)
        curve.append({"round": round_, "samples": len(data[0]), "wall_time": round(time.time() - began, 1),
                      "loss": loss, **{f"{k}_T{int(r['T_con'])}": r[k] for r in rows for k in ("success", "heading", "energy")}})  # fmt: skip
        print(curve[-1], flush=True)
        if round_ < config.dagger_rounds:
            data = concatenate([data, dagger_samples(model, config, params, rng)])
    model.save(run_dir / MODEL_FILE)
    extra: dict[str, Any] = {"dagger": dataclasses.asdict(config), "command": command, "learned_from": "expert",
                             "runtime": []}  # fmt: skip
    if config.handover_expert:
        extra["handover"], tried = select_handover(model, config, params)
        extra["handover_tried"] = tried
        extra["runtime"] = [f"handover: {extra['handover']['expert']}"]
        print(f"hand-over: {extra['handover']}", flush=True)
    train_config = TrainConfig(algo="ppo", total_timesteps=1, num_envs=4, seed=config.seed,
                               env_id=config.env_id, env_kwargs=dict(config.env_kwargs), run_dir=str(run_dir), progress=False)  # fmt: skip
    save_config(train_config, run_dir, extra)
    with (run_dir / EVAL_FILE).open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(curve[0]))
        writer.writeheader()
        writer.writerows(curve)
    plot_dagger_curve(curve, config.eval_T_con, run_dir / "learning_curve.png")
    print(f"cloned in {time.time() - began:.0f} s from {len(data[0])} samples; saved {run_dir / MODEL_FILE}")
    return run_dir


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--run-dir", required=True)
    for f in dataclasses.fields(DaggerConfig):
        if f.type in ("int", "float", "str"):
            kind = {"int": int, "float": float, "str": str}[f.type]  # type: ignore[index]
            flag = "--env" if f.name == "env_id" else f"--{f.name.replace('_', '-')}"
            parser.add_argument(flag, dest=f.name, type=kind, default=f.default)
    parser.add_argument("--handover-only", action="store_true",
                        help="only choose the hand-over of an existing run (needs --handover-expert) and save it in "
                             "its config.yaml")  # fmt: skip
    args = parser.parse_args(argv)
    values = {k: v for k, v in vars(args).items() if k not in ("run_dir", "handover_only")}
    try:
        values["env_id"] = check_env_id(values["env_id"])
    except ValueError as error:
        parser.error(str(error))
    if args.handover_only:
        add_handover(Path(args.run_dir), args.handover_expert, args.eval_episodes)
        return
    run(
        DaggerConfig(**values),
        Path(args.run_dir),
        ["python", "-m", "train.learning.imitation.dagger", *(argv or sys.argv[1:])],
    )


def add_handover(run_dir: Path, expert: str, eval_episodes: int) -> None:
    """Choose the hand-over of a trained run (:func:`select_handover`) and write it into its config.yaml."""
    from stable_baselines3 import PPO

    from train.learning.agents import load_extra
    from train.learning.runs import MODEL_FILE, load_config, save_config

    check_handover_expert(expert)
    if not (run_dir / MODEL_FILE).is_file():
        raise SystemExit(f"--run-dir {str(run_dir)!r} holds no {MODEL_FILE}: train it first")
    train_config, extra = load_config(run_dir), load_extra(run_dir)
    config = DaggerConfig(**{**extra.get("dagger", {}), "handover_expert": expert, "eval_episodes": eval_episodes})
    params = train_config.env_params()
    model = PPO.load(run_dir / MODEL_FILE, device="cpu")
    extra["handover"], extra["handover_tried"] = select_handover(model, config, params)
    extra["learned_from"], extra["runtime"] = "expert", [f"handover: {extra['handover']['expert']}"]
    extra.pop("config", None)
    extra.pop("dwr_gym_version", None)
    save_config(train_config, run_dir, extra)
    print(f"hand-over: {extra['handover']}; saved in {run_dir / 'config.yaml'}")


if __name__ == "__main__":
    main()
