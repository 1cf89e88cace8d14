"""The record of what was tried: one row per lever from its archived JSON, and the tables of the answered diagnoses.

    python -m benchmarks run archive --docs

Measures nothing: the probes and the recipes that wrote these JSONs answered their question and left the suite (git
keeps them: ``git log --diff-filter=D -- benchmarks/``); this entry renders what they measured, so that no published
number loses its source. A lever's row reads the nominal set (random starts, every T_con) of its JSON's ``summary``.
"""

from __future__ import annotations

from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import NUMBER, Block, Schema, fenced, table
from train.reporting import archived_reports as reports

RUNS = "docs/rl_benchmark"
#: JSON (under docs/rl_benchmark) -> the lever it measured, in the order the levers were tried.
LEVERS: dict[str, str] = {
    "anneal.json": "jitted PPO on v1: exploration noise annealed (`anneal-N`), discount 0.9999 or 1 (`g…`)",
    "v2.json": "v2, the return that is the task: ES and jitted PPO, residual on PTC and from scratch",
    "time_scale.json": "ES on v2 with actions scaled to each episode's T_con (time-scaled) against without",
    "time_scale_long.json": "time-scaled ES at 4x the budget",
    "time_scale_30min.json": "time-scaled ES at 30 minutes a seed",
    "sbx_v1.json": "sbx's SAC, TQC and CrossQ (JAX) on v1, brief, SB3's SAC beside them",
    "sbx_v2.json": "the same on v2",
    "sbx_v2_long.json": "sbx on v2, 4x longer",
    "sbx_v2_seeds.json": "sbx on v2, five seeds",
    "sbx_v2_30min.json": "sbx on v2 at 30 minutes a seed",
    "sbx_v2_30min_tqc.json": "TQC (sbx) on v2 at 30 minutes a seed, five seeds",
    "apg.json": "APG (gradients through the env), residual on PTC",
    "apg_episodes16.json": "APG residual on PTC, 16 episodes an update",
    "apg_scratch_150M.json": "APG from scratch, 150 M env steps",
    "apg_scratch.json": "APG from scratch, 400 M env steps",
    "apg_teacher.json": "APG from an open-loop teacher (the optimum cloned)",
    "apg_teacher_time_scaled.json": "APG from the teacher, time-scaled actions",
    "apg_teacher_30min.json": "the same at 30 minutes a seed: one round of cloning against DAgger",
    "apg_clip_decay.json": "+ the state-gradient clip decaying from 16 to 4",
    "apg_near_miss.json": "+ the lesson fitted longer and the near misses clipped wider",
    "apg_hold.json": "+ the miss before T_con in the gradient (holding the goal), with and without the heading",
    "apg_hold_heading10.json": "+ the heading's error in the hold window at twice the weight (10)",
    "apg_hold_fraction.json": "+ the hold window a tenth of each episode's T_con",
    "apg_hold_bonus.json": "+ a smooth arrival bonus in the hold window, weight 10",
    "apg_hold_bonus3.json": "+ the smooth arrival bonus at weight 3",
    "constrained_200m_probe.json": "the deadline and the heading as constraints (Lagrange multipliers per T_con bin) in "
    "place of the hold weights and the near-miss clip, 200 M env steps, integral gain 1, no anti-windup",
    "constrained_560m_without_near_miss.json": "the same at 560 M env steps, integral gain 0.2, multipliers capped at "
    "100; the residual on PTC under the same constraints",
    "constrained.json": "the constraints with the near misses' clip kept (16), and with the weights' moving average "
    "exported; the residual on PTC with its gradient through the law kept where finite; PPO-Lagrangian, 8 M env steps "
    "and 30 minutes a seed",
}


def _cell(stat: dict[str, Any], scale: float = 1.0, digits: int = 2) -> str:
    """IQM [low, high] of a seed statistic; "-" where no seed measured it."""
    if stat.get("iqm") is None:
        return "-"
    if stat.get("n", 0) < 2 or stat["low"] == stat["high"]:
        return f"{stat['iqm'] * scale:.{digits}f}"
    return f"{stat['iqm'] * scale:.{digits}f} [{stat['low'] * scale:.{digits}f}, {stat['high'] * scale:.{digits}f}]"


def levers_table(runs: dict[str, Any]) -> str:
    """One row per agent of each lever's JSON (under docs/rl_benchmark): the lever, the run, its seeds and steps, and its
    nominal results: in-time share, E/opt and final heading, each the IQM over the seeds [its 95 % interval]."""
    lines = [
        "| lever | run | seeds | env steps | in time (%) | E/opt | heading (rad) | JSON |",
        "|---|---|---:|---:|---:|---:|---:|---|",
    ]
    for name, lever in LEVERS.items():
        for index, (key, agent) in enumerate(runs[name]["summary"].items()):
            nominal = agent["sets"]["random"]
            steps = agent["env_steps"]["iqm"] or 0
            first = (lever, f"`{name}`") if index == 0 else ("", "")  # a lever's later runs: its name once
            lines.append(
                f"| {first[0]} | `{key}` | {len(agent['seeds'])} | {steps / 1e6:,.1f} M "
                f"| {_cell(nominal['in_time'], 100, 1)} | {_cell(nominal['energy_ratio'])} "
                f"| {_cell(nominal['final_heading'])} | {first[1]} |"
            )
    return "\n" + "\n".join(lines) + "\n"


def _levers_data(root: Any = None) -> dict[str, Any]:
    import json
    from pathlib import Path

    from benchmarks.core.docs import ROOT

    base = Path(root or ROOT) / RUNS
    return {name: json.loads((base / name).read_text()) for name in LEVERS}


class _Levers(Block):
    """The levers' block reads every JSON of :data:`LEVERS` (its ``json`` names the first, which must exist)."""

    def data(self, root: Any = None) -> Any:  # type: ignore[override]
        return _levers_data(root)


LEVER_RUNS = Schema({name: dict for name in LEVERS})
#: The lever table, then the answered diagnoses' tables, each from its archived JSON by its renderer in train.reporting.
BLOCKS = (
    _Levers("what-was-tried", f"{RUNS}/{next(iter(LEVERS))}", levers_table, LEVER_RUNS),
    table("rl-levers", Schema({"seconds": NUMBER, "machine": str, "levers": dict})),
    table("rl-diagnosis", Schema({"env_id": str, "n": int, "seed": int, "energy_weight": NUMBER, "rows": list})),
    table("rl-residual", Schema({"n": int, "seed": int, "agents": dict})),
    table("rl-rushing", Schema({"n": int, "seed": int, "policies": dict})),
    table("rl-rushing-v2", Schema({"n": int, "seed": int, "policies": dict})),
    *(table(name, Schema({"out": str, "trials": list})) for name in ("rl-sweep", "rl-sweep-jax", "rl-sweep-sac", "rl-sweep-tqc")),
    table("incentives-ranking", Schema({"machine": dict})),
    table("incentives-rushing", Schema({"machine": dict})),
    table("energy-split", Schema({"split": dict, "gains": dict, "defaults": dict, "machine": dict})),
    table("law-gains", Schema({"split": dict, "gains": dict, "defaults": dict, "machine": dict})),
    table("open-loop-bound", Schema({"variants": list, "machine": dict})),
    table("apg-clone-rounds", Schema({"env_id": str, "eval_episodes": int, "rows": list, "machine": dict})),
    table("apg-clone-fit", Schema({"env_id": str, "eval_episodes": int, "rows": list, "machine": dict})),
    table("misses", Schema({"env_id": str, "seed": int, "agents": list, "machine": dict})),
    table("robust-filter-rates", Schema({"T_con": NUMBER, "seed": int, "rows": list})),
    table("prescribed-time-goal", Schema({"agents": list, "n": int, "rows": list, "verdicts": dict})),
    fenced("sbx-v2-30min-tqc-curves", "docs/rl_benchmark/sbx_v2_30min_tqc_curves.json", reports.sbx_curves,
           Schema({"run": str, "seeds": dict})),
    fenced("es-learn", "docs/jax/es_learn.json", reports.es_learn, Schema({"machine": str, "n": int, "runs": dict})),
    fenced("jax-residual-speed", "docs/jax/residual_speed.json", reports.residual_speed,
           Schema({"env_id": str, "machine": str, "median_steps_per_second": dict, "ratio_to_ppo": dict})),
    *(fenced(f"jax-residual-learn{tail}", f"docs/jax/residual_learn{tail.replace('-', '_')}.json",
             reports.residual_learn, Schema({"machine": str, "goals": dict, "runs": list}))
      for tail in ("", "-v2", "-v2-low-noise")),
    fenced("jax-residual-terms-v2", "docs/jax/residual_terms_v2.json", reports.residual_terms,
           Schema({"env_id": str, "episodes": int, "laws": dict})),
    fenced("old-vs-new", "docs/training/old_vs_new.json", reports.old_vs_new,
           Schema({"machine": str, "cap_seconds": NUMBER, "seeds": list, "env_id": str, "runs": dict})),
    table("sbx-speed", Schema({"env_id": str, "steps_timed": int, "repeats": int, "rounds": list, "summary": dict,
                               "machine": str, "load_average": NUMBER, "versions": dict})),
    fenced("training-threads", "docs/training/threads.json", reports.training_threads,
           Schema({"machine": str, "busy_processes": int, "load_average_1min_at_end": NUMBER, "steps": dict,
                   "rounds": list, "median_fps": dict, "threads_cores_fps": dict, "reference_limit_seconds": NUMBER,
                   "cores": int, "ratio_defaults_to_omp1": dict, "goal": NUMBER, "met": bool})),
    fenced("jax-time-to-criteria", "docs/jax/time_to_criteria.json", reports.time_to_criteria,
           Schema({"machine": str, "settings": dict, "seeds": int, "criteria": dict, "reached": list, "curves": list,
                   "goal_s": NUMBER, "met": bool, "median_time_s": NUMBER})),
    fenced("es-speed", "docs/jax/es_speed.json", reports.es_speed,
           Schema({"machine": str, "load_average_1min_at_end": NUMBER, "es_settings": dict,
                   "ppo_steps_per_round": int, "es_steps_per_generation": int, "compile_seconds": dict,
                   "rounds": list, "median_steps_per_s": dict, "median_cpu_per_wall": dict, "ratios": dict,
                   "goals": dict, "met": dict})),
    *(fenced(f"compare-commits-{kind}", f"docs/throughput/{path}.json", reports.compare_commits,
             Schema({"commits": list, "num_envs": int, "ratios": list, "median_ratios": list}))
      for kind, path in (("loaded", "compare_loaded"), ("quiet", "compare_quiet_one_thread"))),
)  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("archive", __doc__)
    parser.add_argument("--docs", action="store_true", help="render the blocks (the JSONs are archived: unchanged)")
    parser.parse_args(argv)
    print(levers_table(_levers_data()))
    return 0
