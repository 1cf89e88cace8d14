"""``dwr-gym imitate``: a network policy cloned from the minimum-energy planner, for any T_con, or from a dataset.

The expert is the ``optimal`` controller (:mod:`baselines.nmpc`), planning to arrive at
``arrival_fraction`` x T_con (a margin the network can use). Demonstrations come from batched
rollouts of the expert on DWRPointStabilization-v1's task (random starts 0.3-3 m away, T_con drawn per
episode in [10, 60] s), with Gaussian noise added to the executed actions while the expert's own
action is recorded (DART, Laskey et al. 2017): the expert re-plans from the perturbed poses, so the
data covers the states a slightly imperfect student visits. The policy is a stable-baselines3 PPO
``MlpPolicy`` whose action mean is fitted to the expert's actions (mean squared error), so the result
loads, evaluates and fine-tunes like any PPO agent of ``dwr-gym train``. At run time the policy is the
network alone; the optimiser is only used to make the data. With ``--dataset ID`` the demonstrations are the
observations and actions of a Minari dataset of ``dwr-gym dataset`` instead, on that dataset's env.
"""

from __future__ import annotations

import csv
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from dwr_gym import core
from dwr_gym.disturbances import split_env_kwargs
from dwr_gym.params import EnvParams
from train.env_ids import DEFAULT_ENV_ID, ENV_HELP, env_keywords
from train.learning.config import option

EVAL_FIELDS = ("epoch", "samples", "wall_time", "loss", "success_rate", "arrival_fraction_max",
               "final_heading_error_mean", "energy_mean")  # fmt: skip


@dataclass
class ImitationConfig:
    """Everything ``dwr-gym imitate`` needs; written beside the model. Each field is an option of the command."""

    env_id: str = option(DEFAULT_ENV_ID, ENV_HELP, flag="--env")
    episodes: int = option(800, "expert episodes to record")
    T_con_range: tuple[float, float] = option((10.0, 60.0), "prescribed times of the episodes [s] (v1's range)")
    start_distance: tuple[float, float] = option((0.3, 3.0), "start distances of the episodes [m] (v1's range)")
    action_noise: float = option(0.02, "std of the Gaussian noise on the executed normalised actions (DART)")
    arrival_fraction: float = option(0.9, "the expert plans to arrive at this fraction of T_con (a margin)")
    replan_tolerance: float = option(0.02, "the expert re-plans (every 2 s) when this far off its plan [m, rad]")
    epochs: int = option(60, "passes over the demonstrations")
    batch_size: int = option(4096, "samples per gradient step")
    learning_rate: float = option(1e-3, "Adam's learning rate")
    net_arch: tuple[int, ...] = option((256, 256), "hidden layer sizes of the policy network")
    seed: int = option(0, "seed of the demonstrations, the network initialisation and the batches")
    eval_episodes: int = option(200, "size of the fixed random scenario set of the learning curve")
    eval_seed: int = option(12345, "seed of that scenario set (kept apart from the training seed)")
    eval_every: int = option(10, "evaluate every this many epochs")
    threads: int = option(1, "torch threads while it runs (restored afterwards)")
    dataset: str = option("", "a Minari dataset id (dwr-gym dataset) to clone instead of recording the planner; "
                          "the dataset's env replaces --env and the ranges")  # fmt: skip


def env_kwargs(config: ImitationConfig) -> dict[str, Any]:
    """The task the student learns: the keywords of ``env_id`` (v1's by default) with the config's ranges, or
    the env of the config's dataset."""
    if config.dataset:
        from train.datasets.store import dataset_env, load_dataset

        return dataset_env(load_dataset(config.dataset, "--dataset"))[1]
    ranges = {"T_con_range": tuple(config.T_con_range), "start_distance": tuple(config.start_distance)}
    return env_keywords(config.env_id, ranges)


def record_demonstrations(
    config: ImitationConfig, progress: bool = True
) -> tuple[NDArray[np.float32], NDArray[np.float32], dict[str, float]]:
    """(observations (M, 10), expert actions (M, 2), statistics) from noisy rollouts of the optimal expert."""
    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller

    params = EnvParams.from_kwargs(**env_kwargs(config))
    rng = np.random.default_rng(config.seed)
    n = config.episodes
    starts = np.array([core.sample_start(rng, params) for _ in range(n)])
    T_cons = rng.uniform(*params.T_con_range, size=n)  # type: ignore[misc]
    controller = make_controller("optimal", dt=params.dt, u_max=params.u_max, omega_max=params.omega_max,
                                 arrival_fraction=config.arrival_fraction, replan_every=40,
                                 replan_tolerance=config.replan_tolerance)  # fmt: skip
    expert = ExpertPolicy(controller, params.u_max, params.omega_max)
    space = core.observation_space(params)
    state = core.TaskState.zeros(n)
    core.reset_robots(state, slice(None), tuple(starts.T), (np.zeros(n),) * 3, params, T_cons)  # type: ignore[arg-type]
    obs = core.observe(state, state.coordinates(params.k), params, space)
    active = np.ones(n, dtype=bool)
    success = np.zeros(n, dtype=bool)
    observations, actions = [], []
    steps: Any = range(int(state.max_steps.max()))
    if progress:
        from train.progress import Progress

        steps = Progress(steps, desc="expert demonstrations", unit="step", leave=False)
    episode_start = np.ones(n, dtype=bool)
    began = time.perf_counter()
    for _ in steps:
        action, _ = expert.predict(obs, episode_start=episode_start)
        episode_start[:] = False
        observations.append(obs[active])
        actions.append(action[active])
        executed = np.clip(action + config.action_noise * rng.standard_normal(action.shape), -1.0, 1.0)
        result = core.transition(state, np.where(active[:, None], executed, 0.0), params, space)
        success |= active & result.is_success & (state.step_count <= state.prescribed_steps)
        active &= ~(result.terminated | result.truncated)
        controller.freeze(~active)
        obs = result.observation
        if not active.any():
            break
    controller.close()
    stats = {"episodes": float(n), "expert_success_rate": float(success.mean()), "seconds": time.perf_counter() - began,
             "expert_solves": float(controller.solves), "planner_failures": float(len(controller.failures))}  # fmt: skip
    return np.concatenate(observations), np.concatenate(actions), stats


def dataset_demonstrations(
    config: ImitationConfig,
) -> tuple[NDArray[np.float32], NDArray[np.float32], dict[str, float]]:
    """(observations (M, 10), actions (M, 2), statistics) of every step of the config's dataset."""
    from train.datasets.store import load_dataset, transitions

    dataset = load_dataset(config.dataset, "--dataset")
    data = transitions(dataset)
    stats = {"episodes": float(dataset.total_episodes), "steps": float(len(data["actions"])), "seconds": 0.0}
    return data["observations"].astype(np.float32), data["actions"].astype(np.float32), stats


def imitate(config: ImitationConfig, run_dir: Path, progress: bool = True) -> Path:
    """Record demonstrations, clone them into a PPO policy, save model.zip, config.yaml and evaluations.csv.
    torch runs on ``config.threads`` threads meanwhile; the caller's count is restored afterwards."""
    from train.threads import torch_threads

    with torch_threads(config.threads):
        return _imitate(config, run_dir, progress)


def _imitate(config: ImitationConfig, run_dir: Path, progress: bool) -> Path:
    import torch
    import yaml
    from stable_baselines3 import PPO

    from dwr_gym.sb3 import make_sb3_vec_env
    from train.evaluation.rollout import rollout
    from train.evaluation.scenarios import make_scenario
    from train.learning.config import TrainConfig
    from train.reporting.learning_curves import plot_imitation_curve

    run_dir.mkdir(parents=True, exist_ok=True)
    began = time.perf_counter()
    if config.dataset:
        observations, actions, stats = dataset_demonstrations(config)
        print(f"read {len(observations):,} steps of {stats['episodes']:.0f} episodes from {config.dataset}")
    else:
        observations, actions, stats = record_demonstrations(config, progress)
        print(f"recorded {len(observations):,} expert steps from {config.episodes} episodes in {stats['seconds']:.0f} s "
              f"(expert success {stats['expert_success_rate']:.3f})")  # fmt: skip
    torch.manual_seed(config.seed)
    kwargs = env_kwargs(config)
    model = PPO("MlpPolicy", make_sb3_vec_env(1, seed=config.seed, **kwargs), seed=config.seed, device="cpu",
                gamma=0.999, policy_kwargs={"net_arch": list(config.net_arch), "log_std_init": -2.0})  # fmt: skip
    policy = model.policy
    optimizer = torch.optim.Adam(policy.parameters(), lr=config.learning_rate)
    inputs = torch.as_tensor(observations)
    targets = torch.as_tensor(actions)
    params = EnvParams.from_kwargs(**split_env_kwargs(kwargs)[0])  # a dataset's env may have disturbances
    scenario = make_scenario("random", n=config.eval_episodes, seed=config.eval_seed, env_kwargs=kwargs)
    csv_path = run_dir / "evaluations.csv"
    with csv_path.open("w", newline="") as handle:
        csv.writer(handle).writerow(EVAL_FIELDS)
    generator = torch.Generator().manual_seed(config.seed)
    epochs: Any = range(1, config.epochs + 1)
    if progress:
        from train.progress import Progress

        epochs = Progress(epochs, desc="behaviour cloning", unit="epoch", leave=False)
    for epoch in epochs:
        order = torch.randperm(len(inputs), generator=generator)
        total = 0.0
        for batch in order.split(config.batch_size):
            mean = policy.action_net(policy.mlp_extractor.forward_actor(policy.extract_features(inputs[batch])))
            loss = torch.nn.functional.mse_loss(mean, targets[batch])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total += float(loss.detach()) * len(batch)
        if epoch % config.eval_every == 0 or epoch == config.epochs:
            summary = rollout(model, params, scenario.starts, scenario.goals, T_con=scenario.T_cons).summary()
            row = {"epoch": epoch, "samples": len(inputs), "wall_time": round(time.perf_counter() - began, 1),
                   "loss": total / len(inputs), **{k: summary[k] for k in EVAL_FIELDS[4:]}}  # fmt: skip
            with csv_path.open("a", newline="") as handle:
                csv.writer(handle).writerow([row[k] for k in EVAL_FIELDS])
    model.save(run_dir / "model.zip")
    if config.dataset:  # the dataset's env without its robot's imperfections: the agent is run on any robot
        from dwr_gym.serialization import env_kwargs_to_json
        from train.datasets.build import nominal

        ranges = env_kwargs_to_json(nominal(kwargs))
    else:
        ranges = {key: kwargs[key] for key in ("T_con_range", "start_distance")}
    train_config = TrainConfig(algo="ppo", env_id=config.env_id, env_kwargs=ranges, seed=config.seed, run_dir=str(run_dir), progress=False,
                               algo_kwargs={"policy": "MlpPolicy", "gamma": 0.999,
                                            "policy_kwargs": {"net_arch": list(config.net_arch)}})  # fmt: skip
    imitation = {**asdict(config), "net_arch": list(config.net_arch), "T_con_range": list(config.T_con_range),
                 "start_distance": list(config.start_distance)}  # fmt: skip
    data = {"config": train_config.to_dict(), "imitation": imitation,
            "demonstrations": stats, "wall_time": round(time.perf_counter() - began, 1), "learned_from": "expert",
            "runtime": []}  # fmt: skip
    (run_dir / "config.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    plot_imitation_curve(csv_path, run_dir / "learning_curve.png")
    return run_dir
