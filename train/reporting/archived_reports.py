"""The reports of answered probes whose measuring code left the suite, rendered from their archived JSON (the
benchmarks entry ``archive`` declares their blocks): ES on v1 within a budget, residual PPO on the analytic laws at
the jitted trainer's speed, `dwr-gym train`'s old defaults against its new, two commits of the env timed against
each other, `dwr-gym train`'s threads under load, ES's speed, the jitted PPO's time to the criteria, and the learning
curves of sbx's TQC on v2 beside keeping still. Each returns the block's lines."""

from __future__ import annotations

import math
import statistics
from typing import Any

T_CONS = (10.0, 20.0, 40.0, 60.0)
ES_DEVICES = 2  # the XLA CPU devices es_speed split the candidates over


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


def training_threads(results: dict[str, Any]) -> list[str]:
    """`dwr-gym train` beside busy processes, its defaults against OMP_NUM_THREADS=1 (docs/training-speed.md): rates
    per setting, the ratios and the goal."""
    fps, cores = results["median_fps"], results["cores"]
    lines = [f"{results['machine']}; {results['busy_processes']} busy processes beside each run; load average "
             f"{results['load_average_1min_at_end']} (1 min, at the end)",
             f"{len(results['rounds'])} rounds, the settings alternating; medians; each run a fresh `dwr-gym train` "
             "process, start to exit", "",
             f"{'algo':<6}{'env steps':>10}{'defaults':>11}{'OMP_NUM_THREADS=1':>19}{'ratio':>8}"
             f"{f'--threads {cores}':>14}"]  # fmt: skip
    for algo, steps in results["steps"].items():
        collapse = results["threads_cores_fps"].get(algo)
        if collapse is not None and collapse <= steps / results["reference_limit_seconds"] * 1.0001:
            collapse_text = f"< {collapse:,.1f}"  # stopped at the limit: a bound
        else:
            collapse_text = "" if collapse is None else f"{collapse:,.0f}"
        lines.append(f"{algo:<6}{steps:>10,}{fps[f'{algo} defaults']:>11,.0f}{fps[f'{algo} OMP_NUM_THREADS=1']:>19,.0f}"
                     f"{results['ratio_defaults_to_omp1'][algo]:>7.2f}x"
                     f"{collapse_text:>14}")  # fmt: skip
    return [*lines, "", *_threads_footer(results)]


def _threads_footer(results: dict[str, Any]) -> list[str]:
    """The block's last lines: what the columns are, and the goal with its verdict."""
    worst = min(results["ratio_defaults_to_omp1"].values())
    return [f"steps/s; ratio: defaults / OMP_NUM_THREADS=1, median of the per-round ratios; --threads {results['cores']}: "
            "torch's own default (before --threads), one run, stopped after "
            f"{results['reference_limit_seconds']:.0f} s "
            "('<': a bound)",
        f"the threads goal, defaults >= {results['goal']}x OMP_NUM_THREADS=1 under the same load for "
            f"PPO and SAC: {worst:.2f}x at worst, {'met' if results['met'] else 'NOT met'}"]  # fmt: skip


def es_speed(data: dict[str, Any]) -> list[str]:
    """An ES generation against the jitted PPO's updates, and on two devices against one (docs/evolution.md)."""
    s, fps, cores, ratios = data["es_settings"], data["median_steps_per_s"], data["median_cpu_per_wall"], data["ratios"]
    names = {f"es_{ES_DEVICES}_device": f"ES generation, candidates on {ES_DEVICES} devices",
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
              f"goal {ES_DEVICES} cores >= {data['goals']['two_cores_over_one']:g}x one: "
              f"{ratios['two_cores_over_one']:.2f}x, {met['two_cores_over_one']} (one device runs XLA's threads on both "
              "cores: its CPU/wall)"]  # fmt: skip
    if pinned:
        lines.append(f"2 devices over the one-core reference (*): {fps[f'es_{ES_DEVICES}_device'] / pinned['steps_per_s']:.2f}x "
                     "(* a child process pinned with sched_setaffinity, measured after the rounds above)")  # fmt: skip
    return lines


def time_to_criteria(data: dict[str, Any]) -> list[str]:
    """Five seeds of the jitted PPO under vmap until each met the criteria (docs/jax-training.md): when each did."""
    c = data["criteria"]
    lines = [data["machine"], f"load average {data['load_average_1min_at_end']} (1 min, at the end); "
             f"{data['seeds']} seeds under vmap; overrides {data['overrides'] or 'none'}",
             f"criteria on {data['evaluation_set']}: in time >= {c['in_time']:.0%}, E/opt <= {c['energy_ratio']}, "
             f"final heading <= {c['final_heading']} rad; evaluated every {data['eval_every_steps']:,} steps",
             f"compilation and first chunk: {data['compile_and_first_chunk_s']:.0f} s", "",
             f"{'seed':<6}{'reached at steps':>17}{'wall s':>9}{'CPU s':>9}{'in time':>9}{'E/opt':>7}{'heading':>9}"]  # fmt: skip
    for seed, (row, curve) in enumerate(zip(data["reached"], data["curves"], strict=True)):
        last = row or curve[-1]
        steps = f"{row['steps']:,}" if row else f"not by {last['steps']:,}"
        lines.append(f"{seed:<6}{steps:>17}{last['wall_s']:>9.0f}{last['cpu_s']:>9.0f}{last['in_time']:>9.0%}"
                     f"{last['energy_ratio'] or math.nan:>7.2f}{last['final_heading']:>9.3f}")  # fmt: skip
    first = [next((r for r in curve if r["in_time"] >= c["in_time"]), None) for curve in data["curves"]]
    lines += ["", f"in time >= {c['in_time']:.0%} alone, first reached (steps, wall s): " + "; ".join(
        f"seed {i}: {r['steps']:,}, {r['wall_s']:.0f} s" if r else f"seed {i}: not reached" for i, r in enumerate(first))]  # fmt: skip
    last = [curve[-1] for curve in data["curves"]]
    lines += ["", "at the last evaluation, median over seeds: energy "
              f"{statistics.median(r['energy'] for r in last):.2f} (optimum {last[0]['optimal_energy']:.2f}), arrival at "
              f"{statistics.median(r['arrival_fraction'] for r in last):.0%} of T_con, "
              f"{statistics.median(r['turning_share'] for r in last):.0%} of the squared commands from turning"]  # fmt: skip
    verdict = "met" if data["met"] else "NOT met"
    lines += ["", f"goal <= {data['goal_s']:.0f} s each: median {data['median_time_s']:.0f} s, {verdict}"]
    return lines


def sbx_curves(data: dict[str, Any]) -> list[str]:
    """Each seed's learning curve in brief (peak and last in-time rate) beside the return of keeping still."""
    lines = [f"{'run':<22}{'peak in time':>13}{'at env steps':>14}{'last in time':>13}{'last return':>12}"
             f"{'keeping still':>14}{'final distance':>15}{'energy':>8}"]  # fmt: skip
    for name, seed in data["seeds"].items():
        lines.append(f"{name:<22}{seed['peak_in_time']:>13.1%}{seed['peak_env_steps']:>14,}{seed['last_in_time']:>13.1%}"
                     f"{seed['last_return']:>12.2f}{seed['still_return']:>14.2f}{seed['last_final_distance']:>13.2f} m"
                     f"{seed['last_energy']:>8.2f}")  # fmt: skip
    return lines
