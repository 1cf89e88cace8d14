"""Env steps per second of an ES generation against the jitted PPO's, and on two cores against one.

The generation is `dwr-gym train --algo es --backend jax`'s.

    nice -n 5 python -m benchmarks run es-speed --docs     # docs/jax/es_speed.json and docs/evolution.md's block

In one process with two XLA CPU devices (``--xla_force_host_platform_device_count=2``, what `dwr-gym train --algo
es` asks for on this 2-core machine), alternating rounds so that the ratios hold on a busy machine: a generation of
the shipped ES settings (train/hyperparams/es.yml: 64 candidates x 8 episodes) with its candidates split over the
two devices, the same generation on one device, and the jitted PPO (train/hyperparams/ppo.yml: 256 robots x 64
steps, 4 epochs) on DWRPointStabilization-v1. Every ES round plays the same generation (the same state, so the same
episodes and candidates) and counts the steps its episodes took, not the steps of episodes already ended that the
batch still computes; the PPO counts its rollouts' steps, its updates included in the time. Process CPU time
beside wall time shows the cores used. Compilation is timed apart.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Schema, fenced
from benchmarks.core.record import write_json
from benchmarks.core.timing import jax_machine, jax_timed

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "jax" / "es_speed.json"
DEVICES = 2
GOALS = {"es_over_ppo": 2.0, "two_cores_over_one": 1.6}


def ask_for_devices() -> None:
    """XLA's CPU split into ``DEVICES`` devices, asked for before jax is imported (else a clear error)."""
    import sys

    if "jax" not in sys.modules:
        flag = f"--xla_force_host_platform_device_count={DEVICES}"
        os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {flag}".strip()
        return
    import jax

    if len(jax.devices()) < DEVICES:
        raise SystemExit(f"es-speed needs {DEVICES} XLA CPU devices, found {len(jax.devices())} (jax was imported "
                         "first): run it alone, python -m benchmarks run es-speed")  # fmt: skip


def measure(repeats: int, updates: int, population: int | None = None, ppo_envs: int | None = None) -> dict[str, Any]:
    import jax

    from train.learning.config import TrainConfig
    from train.learning.evolution.settings import ESSettings
    from train.learning.evolution.strategies import JaxES
    from train.learning.hyperparams import resolve_hyperparams
    from train.learning.jitted.policy import PPOSettings
    from train.learning.jitted.ppo import JaxPPO
    from train.learning.jitted.trainer import make_jax_env

    es_config = resolve_hyperparams(TrainConfig(algo="es", backend="jax"), set())
    if population is not None:
        es_config.algo_kwargs["population_size"] = population
    settings = ESSettings.from_algo_kwargs(es_config.algo_kwargs)
    env, env_params = make_jax_env(es_config)
    # on an accelerator, its one device (the host's device count is the CPU's alone)
    counts = (DEVICES, 1) if jax.default_backend() == "cpu" else (1,)
    candidates = {f"es_{n}_device": JaxES(settings, env, env_params, devices=n) for n in counts}
    ppo_config = resolve_hyperparams(TrainConfig(backend="jax", num_envs=ppo_envs), {"num_envs"} if ppo_envs else set())
    ppo_settings = PPOSettings.from_algo_kwargs(ppo_config.algo_kwargs, int(ppo_config.num_envs))
    ppo = JaxPPO(ppo_settings, *make_jax_env(ppo_config))
    runner = ppo.init(0)
    states = {name: es.init(0) for name, es in candidates.items()}  # the same state (on each one's devices)
    compile_s: dict[str, float] = {}
    runs: dict[str, Any] = {name: (lambda es=es, state=states[name]: es.generation(state))
                            for name, es in candidates.items()}  # fmt: skip
    runs["jax_ppo"] = lambda: ppo.run(runner, updates, 1e9)
    steps = {"jax_ppo": updates * ppo_settings.steps_per_update}
    for name, run in runs.items():
        compile_s[name] = round(jax_timed(run)[0], 1)
        if name != "jax_ppo":
            steps[name] = int(jax_timed(run)[2][1]["steps"])
    rounds = []
    for _ in range(repeats):
        row = {}
        for name, run in runs.items():
            wall, cpu, _ = jax_timed(run)
            row[name] = {"steps_per_s": steps[name] / wall, "cpu_per_wall": cpu / wall}
        rounds.append(row)
    median = {name: statistics.median(r[name]["steps_per_s"] for r in rounds) for name in runs}
    cores = {name: statistics.median(r[name]["cpu_per_wall"] for r in rounds) for name in runs}
    two = f"es_{DEVICES}_device"
    if two not in runs:  # an accelerator: its one device
        ratios = {"es_one_device_over_ppo": statistics.median(r["es_1_device"]["steps_per_s"] / r["jax_ppo"]["steps_per_s"]
                                                              for r in rounds)}  # fmt: skip
        return {"machine": jax_machine(), "backend": jax.default_backend(), "device": str(jax.devices()[0]),
                "es_settings": settings.as_dict(), "ppo_steps_per_round": steps["jax_ppo"],
                "ppo_num_envs": ppo_config.num_envs,
                "es_steps_per_generation": steps["es_1_device"], "compile_seconds": compile_s, "rounds": rounds,
                "median_steps_per_s": median, "median_cpu_per_wall": cores, "ratios": ratios}  # fmt: skip
    ratios = {"es_over_ppo": statistics.median(r[two]["steps_per_s"] / r["jax_ppo"]["steps_per_s"] for r in rounds),
              "es_one_device_over_ppo": statistics.median(r["es_1_device"]["steps_per_s"] / r["jax_ppo"]["steps_per_s"]
                                                          for r in rounds),
              "two_cores_over_one": statistics.median(r[two]["steps_per_s"] / r["es_1_device"]["steps_per_s"]
                                                      for r in rounds)}  # fmt: skip
    return {"machine": jax_machine(), "load_average_1min_at_end": round(os.getloadavg()[0], 2),
            "es_settings": settings.as_dict(), "ppo_steps_per_round": steps["jax_ppo"],
            "es_steps_per_generation": steps[two], "compile_seconds": compile_s, "rounds": rounds,
            "median_steps_per_s": median, "median_cpu_per_wall": cores, "ratios": ratios,
            "goals": GOALS, "met": {k: ratios[k] >= v for k, v in GOALS.items()}}  # fmt: skip


def pinned_one_core(repeats: int, updates: int) -> dict[str, float]:
    """The one-device generation's median env steps/s and CPU/wall in a child process pinned to one core (XLA's
    threads and all): the one-core reference, since a one-device generation still runs XLA's threads on both."""
    import subprocess
    import sys

    argv = [sys.executable, "-m", "benchmarks", "run", "es-speed", "--pinned-child", "--repeats", str(repeats),
            "--updates", str(updates)]  # fmt: skip
    out = subprocess.run(argv, check=True, capture_output=True, text=True, cwd=ROOT)
    data = json.loads(out.stdout.strip().splitlines()[-1])
    return {
        "steps_per_s": data["median_steps_per_s"]["es_1_device"],
        "cpu_per_wall": data["median_cpu_per_wall"]["es_1_device"],
    }


def render(data: dict[str, Any]) -> list[str]:
    s, fps, cores, ratios = data["es_settings"], data["median_steps_per_s"], data["median_cpu_per_wall"], data["ratios"]
    names = {f"es_{DEVICES}_device": f"ES generation, candidates on {DEVICES} devices",
             "es_1_device": "ES generation, one device",
             "jax_ppo": "jitted PPO (--backend jax), updates included"}  # fmt: skip
    lines = [data["machine"], f"load average {data['load_average_1min_at_end']} (1 min, at the end); "
             f"{len(data['rounds'])} alternating rounds; medians",
             f"ES: {s['strategy']}, {s['population_size']} candidates x {s['episodes']} episodes = "
             f"{data['es_steps_per_generation']:,} env steps per generation; PPO: {data['ppo_steps_per_round']:,} per round",
             "", f"{'run':<50}{'env steps/s':>12}{'CPU/wall':>10}"]  # fmt: skip
    for key, name in names.items():
        lines.append(f"{name:<50}{fps[key]:>12,.0f}{cores[key]:>10.2f}")
    pinned = data.get("one_core")
    if pinned:
        lines.append(f"{'ES generation, one device pinned to one core (*)':<50}{pinned['steps_per_s']:>12,.0f}"
                     f"{pinned['cpu_per_wall']:>10.2f}")  # fmt: skip
    met = {k: "met" if v else "NOT met" for k, v in data["met"].items()}
    compile_s = ", ".join(f"{k} {v:.0f} s" for k, v in data["compile_seconds"].items())
    lines += ["", f"compilation (apart from the rates): {compile_s}",
              f"goal ES generation >= {data['goals']['es_over_ppo']:g}x the jitted PPO: {ratios['es_over_ppo']:.1f}x, "
              f"{met['es_over_ppo']} (one device: {ratios['es_one_device_over_ppo']:.1f}x)",
              f"goal {DEVICES} cores >= {data['goals']['two_cores_over_one']:g}x one: "
              f"{ratios['two_cores_over_one']:.2f}x, {met['two_cores_over_one']} (one device runs XLA's threads on both "
              "cores: its CPU/wall)"]  # fmt: skip
    if pinned:
        lines.append(f"2 devices over the one-core reference (*): {fps[f'es_{DEVICES}_device'] / pinned['steps_per_s']:.2f}x "
                     "(* a child process pinned with sched_setaffinity, measured after the rounds above)")  # fmt: skip
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("es-speed", __doc__)
    parser.add_argument("--repeats", type=int, default=5, help="alternating rounds (default: 5)")
    parser.add_argument("--updates", type=int, default=8, help="PPO updates per round (default: 8)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its block)")
    parser.add_argument("--no-pinned", action="store_true", help="skip the one-core reference (a pinned child process)")
    parser.add_argument("--pinned-child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--population", type=int, default=None, help="candidates per generation (default: es.yml's)")
    parser.add_argument("--ppo-envs", type=int, default=None, help="the jitted PPO's robots (default: ppo.yml's)")
    parser.add_argument("--json", default=None, metavar="PATH", help="write the measurement here (any backend)")
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.updates < 1:
        parser.error(f"--repeats {args.repeats} and --updates {args.updates}: expected both >= 1")
    if args.pinned_child:  # before jax starts its threads, which inherit the one core
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    ask_for_devices()
    data = measure(args.repeats, args.updates, args.population, args.ppo_envs)
    if args.json is not None:
        write_json(Path(args.json), data)
    if "es_2_device" not in data["median_steps_per_s"]:  # an accelerator's measurement: no CPU goals, no docs block
        print(json.dumps({k: data[k] for k in ("machine", "device", "es_settings", "median_steps_per_s", "ratios",
                                               "compile_seconds")}, indent=1))  # fmt: skip
        return 0
    if args.pinned_child:
        print(json.dumps(data))
        return 0
    if not args.no_pinned:
        data["one_core"] = pinned_one_core(args.repeats, args.updates)
    print("\n".join(render(data)))
    if args.docs:
        write_json(JSON_PATH, data)
    return 0


#: The block of docs/evolution.md.
BLOCKS = (fenced("es-speed", "docs/jax/es_speed.json", render,
                 Schema({"machine": str, "load_average_1min_at_end": NUMBER, "es_settings": dict,
                         "ppo_steps_per_round": int, "es_steps_per_generation": int, "compile_seconds": dict,
                         "rounds": list, "median_steps_per_s": dict, "median_cpu_per_wall": dict, "ratios": dict,
                         "goals": dict, "met": dict})),)  # fmt: skip
