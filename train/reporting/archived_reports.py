"""The reports of answered probes whose measuring code left the suite, rendered from their archived JSON (the
benchmarks entry ``archive`` declares their blocks): ES on v1 within a budget, residual PPO on the analytic laws at
the jitted trainer's speed, `dwr-gym train`'s old defaults against its new, and two commits of the env timed
against each other. Each returns the block's lines."""

from __future__ import annotations

import statistics
from typing import Any

T_CONS = (10.0, 20.0, 40.0, 60.0)


def es_learn(data: dict[str, Any]) -> list[str]:
    """The ES runs on v1 (docs/evolution.md): each run's nominal result and when it first reached 99 % in time."""
    lines = [data["machine"], f"nominal set: {data['n']} starts of v1 (seed 3232), E/opt on its first 50; fixed "
             f"T_con: the same starts; criteria: in time >= 99 %, E/opt <= 1.5, final heading <= 0.1 rad", "",
             f"{'run':<28}{'env steps':>12}{'wall s':>8}{'in time':>9}{'E/opt':>7}{'heading':>9}{'first 99 %':>12}"]  # fmt: skip
    for key, row in sorted(data["runs"].items()):
        m = row["nominal"]
        first = row["first_99_in_time"]
        reached = f"{first['wall_s']:.0f} s" if first else "not reached"
        ratio = f"{m['energy_ratio']:.2f}" if m["energy_ratio"] is not None else "-"
        lines.append(f"{key:<28}{row['env_steps']:>12,}{row['wall_s']:>8.0f}{m['in_time']:>9.1%}{ratio:>7}"
                     f"{m['final_heading']:>9.3f}{reached:>12}")  # fmt: skip
    lines += ["", f"{'run, at fixed T_con':<28}" + "".join(f"{f'T_con {t:g} s':>18}" for t in T_CONS),
              f"{'':<28}" + "".join(f"{'in time / heading':>18}" for _ in T_CONS)]  # fmt: skip
    for key, row in sorted(data["runs"].items()):
        cells = "".join(f"{row['per_T_con'][str(t)]['in_time']:>11.1%} / {row['per_T_con'][str(t)]['final_heading']:.2f}"
                        for t in T_CONS)  # fmt: skip
        lines.append(f"{key:<28}{cells}")
    return lines


def _number(value: Any, digits: int = 2) -> str:
    return "n/a" if value is None or value != value else f"{value:.{digits}f}"


def residual_speed(data: dict[str, Any]) -> list[str]:
    """The jitted PPO alone against it with a residual on each law, steps per CPU and wall second."""
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


def residual_learn(data: dict[str, Any]) -> list[str]:
    """A residual on each law trained for minutes, beside the law alone, and the goal for the residual on PTC."""
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
    lines += ["", f"the goal for the residual on ptc: in time >= {g['in_time']:.1%}, E/opt <= "
              f"{g['energy_ratio']}, final heading <= {g['final_heading']} rad"]  # fmt: skip
    for run in data["runs"]:
        if run["expert"] == "ptc":
            m = run["agent"]
            met = [m["in_time"] >= g["in_time"], m["energy_ratio"] is not None and m["energy_ratio"] <= g["energy_ratio"],
                   m["final_heading"] <= g["final_heading"]]  # fmt: skip
            lines.append(f"{run['env_id']}: " + ", ".join(f"{k} {'met' if ok else 'NOT met'}"
                                                           for k, ok in zip(g, met, strict=True)))  # fmt: skip
    return lines


def residual_terms(data: dict[str, Any]) -> list[str]:
    """v2's reward terms of each law alone (docs/jax-training.md)."""
    names = sorted({k for law in data["laws"].values() for k in law["terms"]})
    lines = [f"{data['env_id']}, each law alone, mean over {data['episodes']} episodes (reset seeds 0..)", "",
             f"{'law':<12}{'return':>8}" + "".join(f"{k:>10}" for k in names)
             + f"{'final d':>9}{'|e_psi|':>9}{'|psi|':>7}"]  # fmt: skip
    for name, law in data["laws"].items():
        lines.append(f"{name:<12}{law['return']:>8.2f}" + "".join(f"{law['terms'].get(k, 0.0):>10.2f}" for k in names)
                     + f"{law['final_distance']:>9.4f}{law['final_orientation_error']:>9.2f}{law['final_heading']:>7.2f}")  # fmt: skip
    return lines


def mean_sd(values: list[float], fmt: str) -> str:
    sd = statistics.stdev(values) if len(values) > 1 else 0.0
    return f"{fmt.format(statistics.fmean(values))} +- {fmt.format(sd)}"


def old_vs_new(results: dict[str, Any]) -> list[str]:
    """The docs block: per agent and setting, env steps per second and the last evaluation before the cap."""
    lines = [f"{results['machine']}; load average {results['load_average_1min_at_end']} (1 min, at the end)",
             f"{results['env_id']}, seeds {results['seeds']}, each run stopped after {results['cap_seconds']:.0f} s "
             "of wall time; mean +- sd over the seeds", "",
             f"{'agent':<14}{'defaults':<10}{'env steps/s':>18}{'steps at stop':>22}{'success at stop':>18}"
             f"{'return at stop':>20}"]  # fmt: skip
    for agent, settings in results["runs"].items():
        for setting, runs in settings.items():
            last = [r["curve"][-1] for r in runs]
            lines.append(f"{agent:<14}{setting:<10}{mean_sd([r['fps'] for r in runs], '{:,.0f}'):>18}"
                         f"{mean_sd([x['timesteps'] for x in last], '{:,.0f}'):>22}"
                         f"{mean_sd([x['success_rate'] for x in last], '{:.2f}'):>18}"
                         f"{mean_sd([x['return_mean'] for x in last], '{:.1f}'):>20}")  # fmt: skip
    for agent, settings in results["runs"].items():
        for setting, runs in settings.items():
            for r in runs:
                if r.get("stalled_seconds", 0) > 0:
                    lines.append(
                        f"{agent} {setting} seed {r['seed']}: the machine stalled {r['stalled_seconds']:.0f} s"
                    )
    for redo in results.get("redone", []):
        lines.append(f"run again: {redo['agent']} seed {redo['seed']}, old and new ({redo['why']})")
    return lines


def compare_commits(record: dict[str, Any]) -> list[str]:
    """Two commits' vector env against CartPoleVectorEnv, alternating rounds (docs/throughput.md)."""
    (old, new), load = record["commits"], record["load_processes"]
    threads = record.get("omp_num_threads")
    setting = f"OMP_NUM_THREADS={threads}" if threads else "default threads"
    lines = [f"float64 vector env at N = {record['num_envs']}, {load} busy background processes, {setting}; speed "
             "relative to CartPoleVectorEnv in the same process, per round:"]  # fmt: skip
    for commit, ratios in zip(record["commits"], record["ratios"], strict=True):
        lines.append(f"{commit:>8}: " + "  ".join(f"{r:.3f}x" for r in ratios))
    old_median, new_median = record["median_ratios"]
    lines.append(
        f"median: {old} {old_median:.3f}x, {new} {new_median:.3f}x ({new_median / old_median:.1f} times as fast)"
    )
    return lines
