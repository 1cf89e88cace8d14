"""What an env id's return pays for: does the optimum earn the most, and does arriving early pay?

Two measurements, each on any env id, scored with the discount the shipped hyperparameters train that id with
(``gamma`` of ``train/hyperparams/ppo.yml``: 0.999 on v1, 1 on v2):

- :func:`return_ranking`: the discounted return of each policy (the optimum, the analytic laws, the shipped
  agents) on the same episodes; the optimum should rank first.
- :func:`rushing_returns`: the minimum-energy plan to arrive at a fraction f of T_con (each deadline its own
  optimal-control problem, ``optimal`` with ``arrival_fraction`` f, re-planned every second from the observed pose,
  so it arrives under noise too), executed with Gaussian action noise of standard deviation sigma (the env's
  ``actuation_noise``, on the normalised action, the noise an exploring agent adds): the return should be highest
  at the latest arrival, whatever sigma; on v1 the early arrival pays (the RL benchmark's diagnosis, as numbers).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from train.env_ids import env_keywords

#: The controllers ranked beside the shipped agents.
CONTROLLERS = ("optimal", "ptc", "pt-astolfi")


def training_discount(env_id: str) -> float:
    """The discount PPO trains ``env_id`` with by default (its section of train/hyperparams/ppo.yml)."""
    from train.learning.hyperparams import default_hyperparams

    return float(default_hyperparams("ppo", False, env_id).get("gamma", 0.99))


def controller_policy(name: str, params: Any, **overrides: Any) -> Any:
    """An expert policy acting by the controller ``name`` (of :mod:`baselines`) in an env of ``params``."""
    from baselines import ExpertPolicy
    from baselines.registry import make_controller

    kwargs: dict[str, Any] = {}
    if name in ("optimal", "robust-pt"):
        kwargs.update(dt=params.dt, u_max=params.u_max, omega_max=params.omega_max)
    return ExpertPolicy(make_controller(name, **{**kwargs, **overrides}), params.u_max, params.omega_max)


def shipped_agents() -> dict[str, Any]:
    """{name: policy} of every agent in train/pretrained (the registered names, and the directory's name of those
    loaded by path)."""
    from train.learning.agents import PRETRAINED_DIR, load_agent, pretrained_paths

    paths = dict(pretrained_paths())
    registered = {path.resolve() for path in paths.values()}
    for path in sorted(PRETRAINED_DIR.iterdir()):  # and every other shipped agent, by its directory's name
        if (path / "model.zip").is_file() and path.resolve() not in registered:
            paths[path.name] = path
    return {name: load_agent(path)[1] for name, path in sorted(paths.items())}


def random_episodes(env_id: str, n: int, seed: int, **env_overrides: Any) -> tuple[Any, Any]:
    """The random set of ``n`` episodes (``seed``) of ``env_id`` with ``env_overrides``, and its env's params."""
    from dwr_gym.params import EnvParams
    from train.evaluation.scenarios import make_scenario

    kwargs = env_keywords(env_id, env_overrides)
    scenario = make_scenario("random", n=n, seed=seed, env_kwargs=kwargs)
    params_kwargs = {k: v for k, v in kwargs.items() if k in EnvParams.__dataclass_fields__}
    return scenario, EnvParams.from_kwargs(**params_kwargs)


def return_ranking(
    env_id: str, policies: dict[str, Any] | None = None, n: int = 200, seed: int = 4040, progress: bool = False
) -> dict[str, Any]:
    """The discounted return of each policy on ``n`` random episodes of ``env_id``: its mean, and the share of
    episodes where the optimum's return is at least the policy's. ``policies`` default: :data:`CONTROLLERS` and
    every shipped agent."""
    from train.evaluation.rollout import rollout

    scenario, params = random_episodes(env_id, n, seed)
    gamma = training_discount(env_id)
    if policies is None:
        policies = {name: controller_policy(name, params) for name in CONTROLLERS} | shipped_agents()
    returns: dict[str, np.ndarray] = {}
    for name, policy in policies.items():
        result = rollout(policy, params, scenario.starts, scenario.goals, T_con=scenario.T_cons, seed=seed,
                         discount=gamma, progress=progress, description=name)  # fmt: skip
        returns[name] = result.episode_return
    best = max(returns, key=lambda name: float(np.mean(returns[name])))
    optimum = returns.get("optimal")
    rows = [{"policy": name, "return_mean": float(np.mean(values)),
             "optimum_at_least": None if optimum is None else float(np.mean(optimum >= values - 1e-9))}
            for name, values in returns.items()]  # fmt: skip
    rows.sort(key=lambda row: -row["return_mean"])
    return {"env_id": env_id, "episodes": n, "seed": seed, "discount": gamma, "first": best, "rows": rows}


def rushing_returns(
    env_id: str,
    fractions: tuple[float, ...] = (0.3, 0.5, 0.8, 1.0),
    sigmas: tuple[float, ...] = (0.0, 0.1, 0.3),
    n: int = 20,
    seed: int = 4041,
    workers: int = 1,
    progress: bool = False,
    replan_every: int = 5,
) -> dict[str, Any]:
    """The discounted return of the minimum-energy plan to arrive at each fraction of T_con, under action noise of
    each sigma, on ``n`` random episodes of ``env_id`` (the same episodes and noise draws for every fraction), the
    plan re-made from the measured pose every ``replan_every`` control periods.

    ``latest_margin[sigma]``: the latest arrival's return minus that of the earlier arrival with the highest mean,
    episode by episode (mean and standard error): under noise the bonus at T_con is a lottery that a table of means
    alone cannot tell from an incentive."""
    from train.evaluation.rollout import rollout

    gamma = training_discount(env_id)
    rows, returns = [], {}
    for sigma in sigmas:
        scenario, params = random_episodes(env_id, n, seed, actuation_noise=sigma)
        for fraction in fractions:
            policy = controller_policy("optimal", params, arrival_fraction=fraction, workers=workers,
                                       replan_every=replan_every)  # fmt: skip
            result = rollout(policy, params, scenario.starts, scenario.goals, T_con=scenario.T_cons, seed=seed,
                             discount=gamma, progress=progress, description=f"sigma {sigma}, f {fraction}")  # fmt: skip
            policy.controller.close()
            arrived = np.isfinite(result.arrival_time)
            returns[sigma, fraction] = result.episode_return
            rows.append({
                "sigma": sigma, "fraction": fraction, "episodes": n, "replan_every": replan_every,
                "return_mean": float(np.mean(result.episode_return)),
                "return_sem": float(np.std(result.episode_return) / np.sqrt(n)),
                "in_time": float(np.mean(result.success)), "energy_mean": float(np.mean(result.energy)),
                "arrival_fraction": float(np.mean(result.arrival_time[arrived] / result.T_con[arrived]))
                if arrived.any() else None,
            })  # fmt: skip
    latest, margin = {}, {}
    for sigma in sigmas:
        mine = [row for row in rows if row["sigma"] == sigma]
        latest[str(sigma)] = max(mine, key=lambda row: row["return_mean"])["fraction"] == max(fractions)
        earlier = [row for row in mine if row["fraction"] != max(fractions)]
        if earlier:
            rival = max(earlier, key=lambda row: row["return_mean"])["fraction"]
            difference = returns[sigma, max(fractions)] - returns[sigma, rival]
            margin[str(sigma)] = {"against": rival, "mean": float(np.mean(difference)),
                                  "sem": float(np.std(difference) / np.sqrt(n))}  # fmt: skip
    return {"env_id": env_id, "episodes": n, "seed": seed, "discount": gamma, "replan_every": replan_every,
            "rows": rows, "latest_pays_most": latest, "latest_margin": margin}  # fmt: skip


__all__ = ["CONTROLLERS", "controller_policy", "random_episodes", "return_ranking", "rushing_returns", "shipped_agents",
           "training_discount"]  # fmt: skip
