"""Residual RL on an analytic law at the jitted trainer's speed: `dwr-gym train --backend jax --residual`.

    nice -n 5 python -m benchmarks run jax-residual speed --docs                  # docs/jax/residual_speed.json
    nice -n 5 python -m benchmarks run jax-residual learn --time-limit 300 --docs # docs/jax/residual_learn.json
    nice -n 5 python -m benchmarks run jax-residual learn --env DWRPointStabilization-v2 --time-limit 300 --docs
    python -m benchmarks run jax-residual terms --env DWRPointStabilization-v2 --episodes 50 --docs

``speed``: env steps per second, updates included, of the jitted PPO alone and of the jitted residual PPO on ``ptc``
and on ``pt-astolfi`` (the law evaluated inside the compiled loop at every step), with the same settings (those of
train/hyperparams/residual_ppo.yml for the env: 256 robots, rollouts of 64 steps, 4 epochs over minibatches of
1024) in one process on one thread, in alternating rounds so that the ratios hold on a busy machine. Compilation is
timed apart.

``learn``: for each expert, `dwr-gym train --backend jax --residual --expert NAME --time-limit S` (seed 0, the
defaults of residual_ppo.yml), then the agent and its expert alone evaluated as `dwr-gym evaluate --agents RUN_DIR
--controllers NAME --scenarios random --n N --seed 3232` (the benchmark's evaluation seed): in time, E/opt (energy
over the minimum-energy plan's, mean over the episodes in time) and final heading, against the v2 goal for a
residual on PTC.
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Schema, fenced
from benchmarks.core.record import write_json
from train.goals import RESIDUAL_ON_PTC

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "jax"
EXPERTS = ("ptc", "pt-astolfi")
GOALS = {
    "in_time": RESIDUAL_ON_PTC.in_time,
    "energy_ratio": RESIDUAL_ON_PTC.energy_ratio,
    "final_heading": RESIDUAL_ON_PTC.final_heading,
}
"""The benchmark's goal for a residual on PTC (:data:`train.goals.RESIDUAL_ON_PTC`; IQM over >= 5 seeds there, one seed
here)."""
EVAL_SEED = 3232


def make_config(env_id: str, residual: bool, expert: str = "ptc", **options: Any) -> Any:
    """The resolved TrainConfig of `dwr-gym train --backend jax [--residual --expert EXPERT]` on ``env_id``."""
    from train.learning.config import TrainConfig
    from train.learning.hyperparams import resolve_hyperparams

    config = TrainConfig(backend="jax", env_id=env_id, residual=residual, expert=expert, progress=False, **options)
    config.validate()
    return resolve_hyperparams(config, set())


def timed(fn: Any, *args: Any) -> tuple[Any, float, float]:
    """``fn(*args)`` run to completion, its wall seconds and this process's CPU seconds (on one thread, the CPU time
    is the work done: what a busy shared machine leaves out of the wall time)."""
    import jax

    began, cpu = time.perf_counter(), time.process_time()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - began, time.process_time() - cpu


def machine() -> str:
    import jax

    return (f"{platform.machine()}, {os.cpu_count()} cores, jax {jax.__version__} ({jax.default_backend()}), one "
            f"thread (XLA_FLAGS={os.environ.get('XLA_FLAGS', '')!r})")  # fmt: skip


def speed(env_id: str, repeats: int, updates: int) -> dict[str, Any]:
    """Alternating rounds of the jitted PPO alone and residual on each of :data:`EXPERTS`, with one PPO setting."""
    from train.learning.jitted.policy import PPOSettings
    from train.learning.jitted.ppo import JaxPPO
    from train.learning.jitted.trainer import make_jax_env

    reference = make_config(env_id, residual=True)  # the residual's settings, for every variant
    settings = PPOSettings.from_algo_kwargs(reference.algo_kwargs, int(reference.num_envs or 0))
    variants = {"ppo": make_config(env_id, residual=False)}
    variants.update({f"residual-{name}": make_config(env_id, residual=True, expert=name) for name in EXPERTS})
    runs, compile_s = {}, {}
    for name, config in variants.items():
        ppo = JaxPPO(settings, *make_jax_env(config))
        (runner, _), compile_s[name], _ = timed(lambda p=ppo: p.run(p.init(0), 1, 1e9))
        runs[name] = [ppo, runner]
    per_round = updates * settings.steps_per_update
    rounds = []
    for index in range(repeats):
        entry: dict[str, dict[str, float]] = {"wall": {}, "cpu": {}}
        for name, run in runs.items():
            (run[1], _), wall, cpu = timed(run[0].run, run[1], updates, 1e9)
            entry["wall"][name], entry["cpu"][name] = per_round / wall, per_round / cpu
        rounds.append(entry)
        print(f"round {index + 1}/{repeats}, steps per CPU second: "
              + ", ".join(f"{k} {v:,.0f}" for k, v in entry["cpu"].items()), flush=True)  # fmt: skip
    median = {
        clock: {key: statistics.median(r[clock][key] for r in rounds) for key in runs} for clock in ("wall", "cpu")
    }
    ratios = {clock: {key: statistics.median(r[clock][key] / r[clock]["ppo"] for r in rounds) for key in runs
                      if key != "ppo"} for clock in ("wall", "cpu")}  # fmt: skip
    return {"env_id": env_id, "machine": machine(), "load_average_1min_at_end": round(os.getloadavg()[0], 2),
            "settings": settings.as_dict(), "steps_per_round": per_round, "rounds": rounds,
            "compile_seconds": {k: round(v, 1) for k, v in compile_s.items()}, "median_steps_per_second": median,
            "ratio_to_ppo": ratios}  # fmt: skip


def evaluate_run(run_dir: Path, expert: str, env_id: str, n: int) -> dict[str, Any]:
    """What `dwr-gym evaluate --agents RUN_DIR --controllers EXPERT --scenarios random --n N --seed 3232` reports:
    {"agent": metrics, "alone": the expert's metrics}."""
    from train.env_ids import env_keywords
    from train.evaluation.evaluate import evaluate_sets
    from train.learning.agents import load_agent

    label, policy = load_agent(run_dir)
    rows = evaluate_sets({label: policy, expert: expert}, ["random"], n, EVAL_SEED, env_keywords(env_id, {}),
                         optimum="pose")  # fmt: skip
    out = {}
    for row in rows:
        out["agent" if row["policy"] == label else "alone"] = {
            "in_time": row["success_rate"], "energy_ratio": row["energy_ratio_mean"],
            "final_heading": row["final_heading_error_mean"], "energy": row["energy_mean"]}  # fmt: skip
    return out


def curve_row(row: dict[str, str]) -> dict[str, float]:
    """A row of a run's evaluations.csv (its training evaluations on 100 starts) as the JSON keeps it."""
    return {"env_steps": int(row["timesteps"]), "wall_time": float(row["wall_time"]),
            "in_time": float(row["success_rate"]), "energy": float(row["energy_mean"]),
            "final_heading": float(row["final_heading_error_mean"]), "return": float(row["return_mean"])}  # fmt: skip


def learn(
    env_id: str,
    time_limit: float,
    n: int,
    out: Path,
    experts: tuple[str, ...],
    critic_warmup: int = 0,
    overrides: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Train a residual on each expert for ``time_limit`` seconds and evaluate it beside its expert."""
    import csv

    from train.learning.runs import read_state
    from train.learning.training import train

    results = []
    for expert in experts:
        run_dir = out / f"residual-ppo-jax-{expert}-{env_id}"
        config = make_config(env_id, residual=True, expert=expert, time_limit=time_limit, total_timesteps=10**9,
                             eval_freq=500_000, checkpoint_freq=500_000, run_dir=str(run_dir), overwrite=True,
                             critic_warmup=critic_warmup, hyperparam_overrides=dict(overrides or {}))  # fmt: skip
        began = time.perf_counter()
        train(config, command=["benchmarks/jax_residual.py", "learn"])
        wall = time.perf_counter() - began
        state = read_state(run_dir)
        with (run_dir / "evaluations.csv").open() as handle:
            curve = [curve_row(r) for r in csv.DictReader(handle)]
        evaluated = evaluate_run(run_dir, expert, env_id, n)
        results.append({"expert": expert, "env_id": env_id, "env_steps": state["timesteps"],
                        "train_seconds": round(wall, 1), "steps_per_second": round(state["timesteps"] / wall),
                        "gamma": config.algo_kwargs.get("gamma"), **evaluated, "curve": curve})  # fmt: skip
        print(json.dumps({k: v for k, v in results[-1].items() if k != "curve"}), flush=True)
    return {"machine": machine(), "time_limit_s": time_limit, "episodes": n, "eval_seed": EVAL_SEED,
            "critic_warmup": critic_warmup, "overrides": dict(overrides or {}), "goals": GOALS, "runs": results}  # fmt: skip


def reward_terms(env_id: str, episodes: int, experts: tuple[str, ...]) -> dict[str, Any]:
    """Each expert's return on ``env_id`` split into its named terms (``info["reward_terms"]``), mean over
    ``episodes`` episodes (reset seeds 0 ..), with the final distance, |e_psi| (eq. (6)) and |psi|: what the reward
    pays each law for, to set beside what the residual on it learned."""
    import gymnasium as gym
    import numpy as np

    import dwr_gym  # noqa: F401
    from baselines.expert import ExpertPolicy
    from baselines.registry import make_controller

    out: dict[str, Any] = {"env_id": env_id, "episodes": episodes, "laws": {}}
    for name in experts:
        env = gym.make(env_id)
        expert = ExpertPolicy.from_env(env, make_controller(name))
        sums: dict[str, float] = {}
        finals = []
        for seed in range(episodes):
            obs, _ = env.reset(seed=seed)
            done, ret = False, 0.0
            while not done:
                obs, reward, terminated, truncated, info = env.step(expert(obs))
                done, ret = terminated or truncated, ret + float(reward)
                for key, value in info["reward_terms"].items():
                    sums[key] = sums.get(key, 0.0) + float(value)
            finals.append((ret, obs[0], abs(obs[5]), abs(math.atan2(obs[4], obs[3]))))
        mean = np.mean(np.asarray(finals, dtype=np.float64), axis=0)
        out["laws"][name] = {"return": mean[0], "terms": {k: v / episodes for k, v in sums.items() if v != 0.0},
                             "final_distance": mean[1], "final_orientation_error": mean[2], "final_heading": mean[3]}  # fmt: skip
    return out


def render_terms(data: dict[str, Any]) -> list[str]:
    names = sorted({k for law in data["laws"].values() for k in law["terms"]})
    lines = [f"{data['env_id']}, each law alone, mean over {data['episodes']} episodes (reset seeds 0..)", "",
             f"{'law':<12}{'return':>8}" + "".join(f"{k:>10}" for k in names)
             + f"{'final d':>9}{'|e_psi|':>9}{'|psi|':>7}"]  # fmt: skip
    for name, law in data["laws"].items():
        lines.append(f"{name:<12}{law['return']:>8.2f}" + "".join(f"{law['terms'].get(k, 0.0):>10.2f}" for k in names)
                     + f"{law['final_distance']:>9.4f}{law['final_orientation_error']:>9.2f}{law['final_heading']:>7.2f}")  # fmt: skip
    return lines


def _number(value: Any, digits: int = 2) -> str:
    return "n/a" if value is None or value != value else f"{value:.{digits}f}"


def render_speed(data: dict[str, Any]) -> list[str]:
    fps, ratios = data["median_steps_per_second"], data["ratio_to_ppo"]
    lines = [data["machine"], f"load average {data['load_average_1min_at_end']} (1 min, at the end); {data['env_id']}; "
             f"{len(data['rounds'])} alternating rounds of {data['steps_per_round']:,} steps; medians; per CPU "
             "second (the work, on one thread) and per wall second (what a busy machine left)", "",
             f"{'--backend jax':<34}{'steps/CPU s':>12}{'/ PPO':>8}{'steps/wall s':>13}{'/ PPO':>8}"
             f"{'compilation':>13}"]  # fmt: skip
    for key in fps["cpu"]:
        name = "PPO alone" if key == "ppo" else f"--residual --expert {key.removeprefix('residual-')}"
        cpu, wall = (1.0, 1.0) if key == "ppo" else (ratios["cpu"][key], ratios["wall"][key])
        lines.append(f"{name:<34}{fps['cpu'][key]:>12,.0f}{cpu:>7.2f}x{fps['wall'][key]:>13,.0f}{wall:>7.2f}x"
                     f"{data['compile_seconds'][key]:>11.0f} s")  # fmt: skip
    return lines


def render_learn(data: dict[str, Any]) -> list[str]:
    g = data["goals"]
    lines = [data["machine"], f"seed 0, {data['time_limit_s']:.0f} s of training each (compilation and evaluations "
             f"included); {data['episodes']} random starts (seed {data['eval_seed']}) per row; critic warm-up "
             f"{data.get('critic_warmup', 0):,} steps; overrides {data.get('overrides') or 'none'}", "",
             f"{'policy':<40}{'env steps':>12}{'steps/s':>9}{'in time':>9}{'E/opt':>7}{'heading':>9}"]  # fmt: skip
    for run in data["runs"]:
        for who in ("agent", "alone"):
            m = run[who]
            if who == "agent":
                name = f"residual on {run['expert']} (gamma {run['gamma']})"
                steps, rate = f"{run['env_steps']:,}", f"{run['steps_per_second']:,}"
            else:
                name, steps, rate = f"{run['expert']} alone", "", ""
            lines.append(f"{name:<40}{steps:>12}{rate:>9}{m['in_time']:>9.1%}{_number(m['energy_ratio']):>7}"
                         f"{_number(m['final_heading'], 3):>9}")  # fmt: skip
    lines += [
        "",
        "training evaluations (100 starts of the run's own set): the return at the start, at its highest, "
        "at the end; energy and heading at each",
    ]
    for run in data["runs"]:
        curve = run["curve"]
        if "return" in curve[0]:
            best = max(curve, key=lambda r: r["return"])
            lines.append(f"  {run['expert']}: " + "; ".join(
                f"{label} {r['return']:.2f} at {r['env_steps']:,} (energy {r['energy']:.2f}, heading "
                f"{r['final_heading']:.3f})" for label, r in (("start", curve[0]), ("highest", best), ("end", curve[-1]))))  # fmt: skip
    lines += ["", f"the v2 goal for the residual on ptc: in time >= {g['in_time']:.1%}, E/opt <= "
              f"{g['energy_ratio']}, final heading <= {g['final_heading']} rad"]  # fmt: skip
    for run in data["runs"]:
        if run["expert"] == "ptc":
            m = run["agent"]
            met = [m["in_time"] >= g["in_time"], m["energy_ratio"] is not None and m["energy_ratio"] <= g["energy_ratio"],
                   m["final_heading"] <= g["final_heading"]]  # fmt: skip
            lines.append(f"{run['env_id']}: " + ", ".join(f"{k} {'met' if ok else 'NOT met'}"
                                                           for k, ok in zip(g, met, strict=True)))  # fmt: skip
    return lines


SPEED = Schema(
    {
        "env_id": str,
        "machine": str,
        "load_average_1min_at_end": (int, float),
        "steps_per_round": int,
        "rounds": list,
        "compile_seconds": dict,
        "median_steps_per_second": dict,
        "ratio_to_ppo": dict,
    }
)
LEARN = Schema(
    {"machine": str, "time_limit_s": (int, float), "episodes": int, "eval_seed": int, "goals": dict, "runs": list}
)
TERMS = Schema({"env_id": str, "episodes": int, "laws": dict})
#: The blocks of docs/jax-training.md.
BLOCKS = (fenced("jax-residual-speed", "docs/jax/residual_speed.json", render_speed, SPEED),
          fenced("jax-residual-learn", "docs/jax/residual_learn.json", render_learn, LEARN),
          fenced("jax-residual-learn-v2", "docs/jax/residual_learn_v2.json", render_learn, LEARN),
          fenced("jax-residual-learn-v2-low-noise", "docs/jax/residual_learn_v2_low_noise.json", render_learn, LEARN),
          fenced("jax-residual-terms-v2", "docs/jax/residual_terms_v2.json", render_terms, TERMS))  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("jax-residual", __doc__)
    parser.add_argument("what", nargs="?", choices=("speed", "learn", "terms"), help="the measurement to run")
    parser.add_argument("--env", default="DWRPointStabilization-v1", help="env id (default: v1)")
    parser.add_argument("--repeats", type=int, default=7, help="speed: alternating rounds (default: 7)")
    parser.add_argument("--updates", type=int, default=4, help="speed: PPO updates per round (default: 4)")
    parser.add_argument("--time-limit", type=float, default=300.0, help="learn: seconds of training per expert")
    parser.add_argument("--episodes", type=int, default=200, help="learn, terms: evaluation episodes (default: 200)")
    parser.add_argument("--experts", nargs="+", default=list(EXPERTS), help="the laws under the residual")
    parser.add_argument("--critic-warmup", type=int, default=0, help="learn: env steps of critic warm-up")
    parser.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE", help="learn: overrides")
    parser.add_argument("--name", help="the JSON's file name (default: by the measurement and the env)")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "jax-residual", help="run directories, JSON")
    parser.add_argument("--docs", action="store_true", help="also write the JSON to docs/jax/ (its blocks rendered)")
    args = parser.parse_args(argv)
    if args.what is None:
        parser.error("expected speed, learn or terms")
    # one thread for XLA (no Eigen pool) and torch, before either is imported
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "")
                               + " --xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1").strip()  # fmt: skip
    suffix = "" if args.env.endswith("v1") else "_" + args.env.split("-")[-1]
    if args.what == "speed":
        from train.learning.jitted.trainer import use_compilation_cache

        use_compilation_cache()
        data, name, lines = speed(args.env, args.repeats, args.updates), "residual_speed.json", render_speed
    elif args.what == "terms":
        data, name = reward_terms(args.env, args.episodes, tuple(args.experts)), f"residual_terms{suffix}.json"
        lines = render_terms
    else:
        from train.learning.hyperparams import parse_overrides
        from train.learning.jitted.trainer import use_compilation_cache

        use_compilation_cache()
        data = learn(args.env, args.time_limit, args.episodes, args.out, tuple(args.experts), args.critic_warmup,
                     parse_overrides(args.hyperparams))  # fmt: skip
        name, lines = f"residual_learn{suffix}.json", render_learn
    name = args.name or name
    print("\n".join(lines(data)))
    write_json(args.out / name, data)
    if args.docs:
        write_json(OUT / name, data)


if __name__ == "__main__":
    main()
