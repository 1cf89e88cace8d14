"""The results tables of the README and the docs, generated from the JSON that the commands and benchmarks write.

Every generated block of a Markdown page names its producer, the suite entry that writes its JSON::

    <!-- generated: NAME by PRODUCER (python -m benchmarks run PRODUCER --docs) -->
    ...
    <!-- /generated -->

:data:`TABLES` says which JSON file and which function make table NAME; ``benchmarks/core/docs.py`` adds the
blocks the benchmarks render themselves and says which entry produces each. ::

    python -m train.reporting.doc_tables            # rewrite every table of TABLES from its JSON
    python -m train.reporting.doc_tables --check    # exit 1, naming the tables, if one disagrees with its JSON
    python -m benchmarks render [--check]           # the same for every generated block, the benchmarks' too

``tests/test_docs.py`` runs the check, so a table can not drift from the numbers it states.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from train.reporting import dataset_tables, energy_tables, incentive_tables
from train.reporting.rl_doc_tables import RL_TABLES

ROOT = Path(__file__).resolve().parents[2]
#: A generated block: its name, its producer and the command that writes its JSON, then its body.
MARKER = re.compile(
    r"^(<!-- generated: (?P<name>[\w-]+) by (?P<producer>[\w-]+) \((?P<command>[^)]*)\) -->)(?P<body>.*?)"
    r"(<!-- /generated -->)",
    re.DOTALL | re.MULTILINE,
)
#: Anything that opens a generated block at the start of a line, well formed or not, the markers of before the
#: convention included (``<!-- table: NAME -->``, ``<!-- NAME:begin -->``): a block without a producer is found by
#: this alone; the convention quoted inside a line of prose is not a block.
OPENING = re.compile(r"^<!-- (?:generated\b[^>]*|table: [\w-]+|[\w-]+:begin) -->", re.MULTILINE)

#: How the tables name the policies: the controllers of baselines and the agents shipped in train/pretrained, each by
#: the name the command line prints (an agent's label: its directory's name with hyphens); then the agents shipped
#: before, whose rows the archived JSON still holds.
POLICY_NAMES = {
    "optimal": "**optimum** (`optimal`)",
    "ptc": "PTC (16)-(19)",
    "conventional-ptc": "conventional PTC",
    "fabregas": "Fabregas [9] (1)",
    "fixed-time": "fixed-time [23]",
    "astolfi": "Astolfi",
    "pt-astolfi": "`pt-astolfi` (2)",
    "robust-pt": "`robust-pt` (3)",
    "apg-v2": "`apg-v2` (v2, reward, APG)",
    "apg-residual-ptc-v2": "`apg-residual-ptc-v2` (v2, reward, APG on PTC)",
    "ppo-jax-v1": "`ppo-jax-v1` (v1, reward, JAX)",
    "es-v1": "`es-v1` (v1, reward, ES)",
    "robust": "`robust` agent (v1)",
    "residual-ppo": "`residual-ppo` (v0)",
    "ppo": "`ppo` (v0)",
    "dagger": "`dagger` (v1)",
    "dagger-handover": "`dagger-handover` (v1)",
    "ppo-v1": "`ppo-v1` (v1, reward)",
    "residual-ppo-v1": "`residual-ppo-v1` (v1, reward, on PTC)",
    "residual-ppo-astolfi-v1": "`residual-ppo-astolfi-v1` (v1, reward, on `pt-astolfi`)",
}


def number(value: Any, fmt: str) -> str:
    """``value`` formatted, or "-" where it is missing (null in the JSON, NaN in a run)."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return format(value, fmt)


def percent(value: Any) -> str:
    return "-" if value is None else f"{100 * value:.3g} %"


def compare_table(rows: list[dict[str, Any]], sets: tuple[str, ...] = ("paper-fig5", "random")) -> str:
    """Every policy on scenario ``sets``: success, final heading error, energy, E/opt mean (worst)."""
    scenarios = [name for name in sets if any(r["scenario"] == name for r in rows)]
    rows = [r for r in rows if r["scenario"] in scenarios]
    by = {(r["scenario"], r["policy"]): r for r in rows}
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    header = ["policy"]
    for name in scenarios:
        header += [f"{name}: success", "\\|psi_end\\| [rad]", "energy", "E/opt mean (worst)"]
    lines = ["| " + " | ".join(header) + " |", "|---" * len(header) + "|"]
    for policy in policies:
        cells = [POLICY_NAMES.get(policy, f"`{policy}`")]
        for name in scenarios:
            r = by.get((name, policy))
            if r is None:
                cells += ["", "", "", ""]
                continue
            ratio = number(r["energy_ratio_mean"], ".2f")
            ratio = f"**{ratio}** ({number(r['energy_ratio_max'], '.1f')})" if ratio != "-" else "-"
            cells += [percent(r["success_rate"]), number(r["final_heading_error_mean"], ".3f"),
                      number(r["energy_mean"], ".3f"), ratio]  # fmt: skip
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n" + compare_caption(rows) + "\n"


def compare_caption(rows: list[dict[str, Any]]) -> str:
    """Where the table's numbers come from: the env, the sets and their sizes, the prescribed times."""
    env = rows[0].get("env_id", "DWRPointStabilization-v0")
    sets = []
    for name in dict.fromkeys(r["scenario"] for r in rows):
        r = next(r for r in rows if r["scenario"] == name)
        T = "T_con drawn per episode" if r["T_con"] is None else f"T_con = {r['T_con']:g} s"
        sets.append(f"{name} ({r['n']:.0f} episode{'s' if r['n'] != 1 else ''}, {T})")
    notes = {"fabregas": "(1) Fabregas [9] is the slow law the paper compares at T_con = 70 s (paper-fig7): it is not "
             "designed to arrive by a shorter T_con", "pt-astolfi": "(2) not from the paper: Astolfi's law on the time "
             "scale of eq. (12)", "robust-pt": "(3) not from the paper: minimum-energy re-planning to 0.8 T_con behind "
             "a Kalman filter, Astolfi's law on the time scale of eq. (12) as the finish (docs/robust.md)", "optimal": "optimum: the `optimal` controller, the least energy to the pose by T_con",
             "ppo": "(v0), (v1): the shipped agent and the env id it was trained on; reward: learned from v1's reward by RL (the v0 agents from v0's, the other v1 agents cloned from an expert)"}  # fmt: skip
    present = {r["policy"] for r in rows}
    note = "".join(f"; {text}" for name, text in notes.items() if name in present)
    return (f"\n*{env}; {', '.join(sets)}; E/opt: energy / the optimum's on the same episode, over the episodes "
            f"that arrive in time, mean (worst){note}.*")  # fmt: skip


def claims_table(data: dict[str, Any]) -> str:
    """The paper's claims, each with what was measured here and the verdict."""
    lines = ["| # | claim | measured here | verdict |", "|---|---|---|---|"]
    for c in data["claims"]:
        lines.append(f"| {c['number']} | {c['claim']} | {c['measured']} | **{c['verdict']}** |")
    return "\n".join(lines) + f"\n\n*`dwr-gym reproduce`, control period dt = {data['dt']} s.*\n"


def tolerance_table(rows: list[dict[str, Any]]) -> str:
    """The robustness sweep: the largest magnitude of each disturbance up to which each policy still arrives."""
    from train.reporting.tables import tolerance_markdown

    return tolerance_markdown(rows)


def goal_table(data: dict[str, Any]) -> str:
    """The prescribed-time goal benchmark: the agent, PTC, pt-astolfi, Astolfi and the optimum at each T_con."""
    rows = data["rows"]
    T_cons = list(dict.fromkeys(r["T_con"] for r in rows))
    lines = ["| T_con [s] | agent: success / \\|psi_end\\| [rad] / energy / E/opt | PTC | pt-astolfi (the law alone) | "
             "Astolfi | optimum: energy |", "|---|---|---|---|---|---|"]  # fmt: skip
    for T in T_cons:
        at = {("agent" if r["policy"].startswith("seed") else r["policy"]): r for r in rows if r["T_con"] == T}
        optimum = number(at["ptc"]["optimal_energy_mean"], ".3f") if "ptc" in at else ""
        cells = [goal_cell(at.get(name)) for name in ("agent", "ptc", "pt-astolfi", "astolfi")]
        lines.append(f"| {T:g} | " + " | ".join(cells) + f" | {optimum} |")
    verdicts = "; ".join(f"{text}: {verdict(by_T_con)}" for text, by_T_con in data["verdicts"].items())
    caption = f"{data['n']} random starts 0.3-3 m per T_con; agent: {', '.join(data['agents'])}. Verdicts: {verdicts}."
    return "\n".join(lines) + f"\n\n*{caption}*\n"


def goal_cell(row: dict[str, Any] | None) -> str:
    """success / final heading error / energy / E/opt of one policy at one T_con."""
    if row is None:
        return ""
    return (f"{percent(row['success_rate'])} / {number(row['final_heading_error_mean'], '.3f')} / "
            f"{number(row['energy_mean'], '.3f')} / {number(row['energy_ratio_mean'], '.2f')}")  # fmt: skip


def verdict(by_T_con: dict[str, bool]) -> str:
    """'met', or 'not met at T_con ...' naming where it was missed."""
    missed = [T for T, ok in by_T_con.items() if not ok]
    return "**met**" if not missed else f"**not met** at T_con = {', '.join(missed)} s"


def robust_goal_table(data: dict[str, Any]) -> str:
    """The robust goal (``python -m benchmarks run robust-goal``): each policy on each (T_con, set), then each one's verdicts."""
    rows = data["rows"]
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    by = {(r["T_con"], r["set"], r["policy"]): r for r in rows}
    lines = ["| T_con [s] | set | " + " | ".join(POLICY_NAMES.get(p, f"`{p}`") for p in policies) + " |",
             "|---|---" + "|---" * len(policies) + "|"]  # fmt: skip
    for T, name in dict.fromkeys((r["T_con"], r["set"]) for r in rows):
        cells = []
        for policy in policies:
            r = by.get((T, name, policy))
            cells.append("" if r is None else f"{percent(r['success_rate'])} / {number(r['final_heading_error_mean'], '.2f')}"
                         f" / {number(r['energy_mean'], '.2f')} / {number(r['command_rate_rms_mean'], '.2f')}")  # fmt: skip
        lines.append(f"| {T:g} | {name} | " + " | ".join(cells) + " |")
    lines += ["", "| policy | criteria met | not met (measured, bar) |", "|---|---|---|"]
    for key, checks in data.items():
        if key.startswith("verdicts:"):
            missed = "; ".join(f"{c['criterion']}: {c['measured']:.3f}" + (f" (bar {c['bar']:.3f})" if "bar" in c else "")
                               for c in checks if not c["met"])  # fmt: skip
            lines.append(f"| {POLICY_NAMES.get(key[9:], f'`{key[9:]}`')} | {sum(c['met'] for c in checks)} / "
                         f"{len(checks)} | {missed or 'none'} |")  # fmt: skip
    caption = (
        f"Each cell: in time / mean \\|psi_end\\| [rad] / mean energy / command-rate RMS; {data['n']} starts "
        f"0.3-3 m per (T_con, set), seed {data['seed']}; `python -m benchmarks run robust-goal` ({data['seconds']} s)."
    )
    return "\n".join(lines) + f"\n\n*{caption}*\n"


def filter_rates_table(data: dict[str, Any]) -> str:
    """robust-pt's in-time rate and energy with each rate of its filter (archived: ``python -m benchmarks run archive``)."""
    kinds = list(dict.fromkeys(r["kind"] for r in data["rows"]))
    rates = list(dict.fromkeys(tuple(r["disturbance_rate"]) for r in data["rows"]))
    by = {(r["kind"], tuple(r["disturbance_rate"])): r for r in data["rows"]}
    lines = ["| `disturbance_rate` (b_u, b_omega) | " + " | ".join(kinds) + " |", "|---" * (len(kinds) + 1) + "|"]
    for rate in rates:
        cells = [f"{percent(by[(k, rate)]['success_rate'])} / {by[(k, rate)]['energy_mean']:.2f}" for k in kinds]
        lines.append(f"| ({rate[0]:g}, {rate[1]:g}) | " + " | ".join(cells) + " |")
    n = data["rows"][0]["n"]
    return (
        "\n".join(lines)
        + f"\n\n*In time / mean energy; {n} starts 0.3-3 m, T_con = {data['T_con']:g} s, seed {data['seed']}.*\n"
    )


def optimal_timing_table(rows: list[dict[str, Any]]) -> str:
    """Seconds per episode of the reference optimum and of the ``optimal`` controller."""
    lines = ["| set | n | reference optimum (env grid) [s/episode] | `optimal` controller rollout [s/episode] | "
             "solves per episode | success | E/opt |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in rows:
        lines.append(f"| {r['scenario']} | {r['n']} | {r['reference_seconds_per_episode']:.3f} | "
                     f"{r['controller_seconds_per_episode']:.3f} | {r['solves_per_episode']:.2f} | "
                     f"{percent(r['success_rate'])} | {number(r['energy_ratio_mean'], '.3f')} |")  # fmt: skip
    first = rows[0]
    return "\n".join(lines) + f"\n\n*{first['workers']} worker processes on {first['cores']} cores.*\n"


def jax_env_step_table(data: dict[str, Any]) -> str:
    """``python -m benchmarks run jax-env-step``: the JAX env's step against the numpy vector env's."""
    lines = ["| step | dtype | us per step | env-steps per second | x the numpy env's | CPU us per step | "
             "x the numpy env's, CPU time |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in data["rows"]:
        case, dtype = r["case"].rsplit(", ", 1)
        lines.append(f"| {case} | {dtype} | {r['us_per_step']:,.0f} | {r['env_steps_per_second']:,.0f} | "
                     f"{r['speedup']:.2f} | {r['cpu_us_per_step']:,.0f} | {r['cpu_speedup']:.2f} |")  # fmt: skip
    return "\n".join(lines) + (
        f"\n\n*N = {data['num_envs']} robots of {data['env_id']}, {data['threads']} thread(s) for both, "
        f"{data['machine']}, jax {data['jax']} on {data['device']}; medians of {data['repeats']} interleaved "
        f"repeats; load average {data['load_average'][0]:g} before, {data['load_average'][1]:g} after.*\n"
    )


def sbx_speed_table(data: dict[str, Any]) -> str:
    """Env steps per second of sbx-rl against stable-baselines3 (archived: docs/rl_benchmark/sbx_speed.json), per algorithm."""
    names = {"sac": "SAC", "tqc": "TQC", "crossq": "CrossQ"}
    lines = ["| algorithm | SB3 (torch): env steps/s | sbx (JAX): env steps/s | sbx / SB3 |", "|---|---:|---:|---:|"]
    for algo, row in data["summary"].items():
        ratios = ", ".join(f"{ratio:.2f}" for ratio in row["ratios"])
        lines.append(f"| {names.get(algo, algo)} | {row['sb3_steps_per_s']:.0f} | {row['sbx_steps_per_s']:.0f} | "
                     f"**{row['ratio_sbx_over_sb3']:.2f}x** ({ratios}) |")  # fmt: skip
    versions = data["versions"]
    return "\n".join(lines) + (
        f"\n\n*{data['env_id']}, the settings of train/hyperparams/ (64 robots, one gradient step of 256 per step of "
        f"the 64), {data['steps_timed']} env steps timed after the warm-up and compile, one thread each; the median "
        f"of {data['repeats']} interleaved rounds (each round's ratio in brackets); {data['machine']}, load average "
        f"{data['load_average']:.1f} at the end; stable-baselines3 {versions['stable-baselines3']}, sbx-rl "
        f"{versions['sbx-rl']}, torch {versions['torch']}, jax {versions['jax']}.*\n"
    )


#: Table name -> (its JSON file, relative to the repository, and the function that makes its Markdown).
TABLES: dict[str, tuple[str, Callable[[Any], str]]] = {
    "compare": ("docs/compare/comparison.json", compare_table),
    "compare-fig7": ("docs/compare/comparison.json", lambda rows: compare_table(rows, ("paper-fig7",))),
    "claims": ("docs/reproduce/claims.json", claims_table),
    "robustness": ("docs/robustness/robustness.json", tolerance_table),
    "prescribed-time-goal": ("docs/prescribed_time/goal.json", goal_table),
    "optimal-timing": ("docs/benchmarks/optimal.json", optimal_timing_table),
    "robust-goal": ("docs/robust/goal.json", robust_goal_table),
    "robust-filter-rates": ("docs/robust/filter_rates.json", filter_rates_table),
    "robust-headline": ("docs/compare/comparison.json", lambda rows: robust_headline(rows)),
    "rl-robust": ("docs/rl_benchmark/robust_finetune.json", robust_goal_table),
    "datasets-suite": ("docs/datasets/suite.json", lambda data: dataset_tables.suite_table(data)),
    "datasets-baselines": ("docs/datasets/suite.json", lambda data: dataset_tables.baselines_table(data)),
    "datasets-speed": ("docs/datasets/speed.json", lambda data: dataset_tables.speed_table(data)),
    "jax-env-step": ("docs/jax/env_step.json", jax_env_step_table),
    "incentives-ranking": ("docs/rl_benchmark/incentives.json", lambda data: incentive_tables.ranking_table(data)),
    "incentives-rushing": ("docs/rl_benchmark/incentives.json", lambda data: incentive_tables.rushing_table(data)),
    "energy-split": ("docs/rl_benchmark/energy_split.json", lambda data: energy_tables.split_table(data)),
    "law-gains": ("docs/rl_benchmark/energy_split.json", lambda data: energy_tables.gains_table(data)),
    "open-loop-bound": ("docs/rl_benchmark/open_loop_bound.json", lambda data: energy_tables.open_loop_table(data)),
    "apg-clone-rounds": (
        "docs/rl_benchmark/apg_clone_rounds.json",
        lambda data: energy_tables.clone_rounds_table(data),
    ),
    "apg-clone-fit": (
        "docs/rl_benchmark/apg_teacher_probes/clone_fit.json",
        lambda data: energy_tables.clone_fit_table(data),
    ),
    "misses": ("docs/rl_benchmark/misses.json", lambda data: energy_tables.misses_table(data)),
    "sbx-speed": ("docs/rl_benchmark/sbx_speed.json", sbx_speed_table),
    **RL_TABLES,
}


def robust_headline(rows: list[dict[str, Any]]) -> str:
    """The robust headline of ``dwr-gym compare`` (train.reporting.robust_headline) with the tables' policy names."""
    from train.reporting.robust_headline import DISTURBED, NOMINAL, headline_table

    sets = [name for name in (NOMINAL, *DISTURBED) if any(r["scenario"] == name for r in rows)]
    sizes = {name: {int(r["n"]) for r in rows if r["scenario"] == name} for name in sets}
    counts = ", ".join(f"{name} {'/'.join(str(n) for n in sorted(sizes[name], reverse=True))}" for name in sets)
    env = rows[0].get("env_id", "DWRPointStabilization-v0")
    return headline_table(rows, POLICY_NAMES) + (
        f"\n*{env}, T_con drawn per episode, the same starts on every set; episodes per set: {counts} (the smaller "
        "number: the `optimal` controller, which re-plans with CasADi whenever pushed off its plan, on the first "
        "ones); E/opt: energy / the optimum's on the same episode, nominal.*\n"
    )


def markdown_files(root: Path = ROOT) -> list[Path]:
    """The README and every page of the docs."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md"))]


def render(name: str, root: Path = ROOT) -> str:
    """Table ``name`` from its JSON file."""
    if name not in TABLES:
        raise KeyError(f"table {name!r} is unknown: expected any of {', '.join(TABLES)}")
    path, make = TABLES[name]
    return make(json.loads((root / path).read_text()))


def table_bodies(root: Path = ROOT) -> dict[str, Callable[[], str]]:
    """Block name -> what makes its body (a newline, then the table) for every table of :data:`TABLES`."""
    return {name: functools.partial(table_body, name, root) for name in TABLES}


def table_body(name: str, root: Path = ROOT) -> str:
    """The body of table ``name``'s block: a newline, then the table."""
    return "\n" + render(name, root)


def regenerate(text: str, bodies: Mapping[str, Callable[[], str]] | None = None) -> str:
    """``text`` with every generated block that ``bodies`` makes (default: the tables) made anew."""
    bodies = table_bodies() if bodies is None else bodies

    def body(match: re.Match[str]) -> str:
        name = match.group("name")
        return match.group(1) + (bodies[name]() if name in bodies else match.group("body")) + match.group(6)

    return MARKER.sub(body, text)


def stale(root: Path = ROOT, bodies: Mapping[str, Callable[[], str]] | None = None) -> list[str]:
    """The generated blocks (as 'file: name') that ``bodies`` (default: the tables) make differently."""
    bodies = table_bodies(root) if bodies is None else bodies
    found = []
    for path in markdown_files(root):
        for match in MARKER.finditer(path.read_text()):
            name = match.group("name")
            if name in bodies and match.group("body") != bodies[name]():
                found.append(f"{path.relative_to(root)}: {name}")
    return found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if a table disagrees")
    args = parser.parse_args(argv)
    if args.check:
        found = stale()
        for item in found:
            print(f"stale table: {item} (run python -m train.reporting.doc_tables)", file=sys.stderr)
        return 1 if found else 0
    for path in markdown_files():
        text = path.read_text()
        new = regenerate(text)
        if new != text:
            path.write_text(new)
            print(f"regenerated the tables of {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
