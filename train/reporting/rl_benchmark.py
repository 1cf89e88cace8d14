"""Aggregates of ``dwr-gym benchmark`` over seeds, as the field reports RL (Agarwal et al. 2021, rliable):
interquartile means (IQM) with 95 % stratified-bootstrap confidence intervals, learning curves (IQM and band)
against env steps and against wall-clock seconds, and the tables the docs show.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from train.evaluation.benchmark import METRICS, PER_T_CON, SETS, per_T_con_set
from train.goals import FROM_REWARD as FROM_REWARD_GOAL
from train.goals import RESIDUAL_ON_PTC

#: Every set a result may hold: the nominal and disturbed sets, then the nominal starts at each of PER_T_CON.
ALL_SETS: tuple[str, ...] = (*SETS, *(per_T_con_set(T_con) for T_con in PER_T_CON))

BOOTSTRAP_REPS = 2000
CURVE_POINTS = 40


def iqm_interval(values: list[float], seed: int = 0, reps: int = BOOTSTRAP_REPS) -> dict[str, Any]:
    """IQM of per-seed values (rliable's ``aggregate_iqm``) and its 95 % stratified-bootstrap percentile interval
    (the runs resampled with replacement, ``reps`` times, as rliable's ``StratifiedBootstrap`` does for one task;
    written here because ``rliable.library`` needs ``arch``, which does not import with pandas 3). NaN and None
    values are dropped."""
    try:
        from rliable import metrics
    except ImportError:
        raise ImportError('the RL benchmark aggregates with rliable: pip install "dwr-gym[benchmark]"') from None

    data = np.array([v for v in values if v is not None and math.isfinite(v)], dtype=np.float64)
    if data.size == 0:
        return {"iqm": None, "low": None, "high": None, "n": 0}
    point = float(metrics.aggregate_iqm(data.reshape(-1, 1)))
    rng = np.random.default_rng(seed)
    boots = trimmed_means(data[rng.integers(0, data.size, (reps, data.size))])
    low, high = np.percentile(boots, [2.5, 97.5])
    return {"iqm": point, "low": float(low), "high": float(high), "n": int(data.size)}


def trimmed_means(samples: np.ndarray) -> np.ndarray:
    """The IQM of each row, vectorised: scipy's ``trim_mean(row, 0.25)``, which rliable's ``aggregate_iqm`` is."""
    cut = int(0.25 * samples.shape[1])
    return np.sort(samples, axis=1)[:, cut : samples.shape[1] - cut].mean(axis=1)


def curve_band(curves: list[list[dict[str, float]]], x: str, y: str, seed: int = 0) -> dict[str, list[float]]:
    """IQM over seeds of ``y`` against ``x`` (each seed's curve interpolated to a common grid), with a 95 %
    bootstrap band over seeds (at most the shortest run's extent)."""
    curves = [c for c in curves if c]
    if not curves:
        return {"x": [], "iqm": [], "low": [], "high": []}
    end = min(c[-1][x] for c in curves)
    grid = np.linspace(0.0, end, CURVE_POINTS) if end > 0 else np.zeros(1)
    matrix = np.array([np.interp(grid, [r[x] for r in c], [r[y] for r in c]) for c in curves])
    rng = np.random.default_rng(seed)
    samples = matrix[rng.integers(0, len(matrix), (BOOTSTRAP_REPS, len(matrix)))]  # (reps, seeds, points)
    cut = int(0.25 * len(matrix))
    boots = np.sort(samples, axis=1)[:, cut : len(matrix) - cut].mean(axis=1)
    low, high = np.percentile(boots, [2.5, 97.5], axis=0)
    return {"x": grid.tolist(), "iqm": trimmed_means(matrix.T).tolist(), "low": low.tolist(), "high": high.tolist()}


def aggregate(results: list[dict[str, Any]]) -> dict[str, Any]:
    """{entry: {"seeds", "sets": {set: {metric: IQM interval}}, "per_seed", "curves", "seconds"}}."""
    out: dict[str, Any] = {}
    for name in dict.fromkeys(r["entry"] for r in results):
        runs = sorted((r for r in results if r["entry"] == name), key=lambda r: r["seed"])
        sets = {s: {m: iqm_interval([r["sets"][s][m] for r in runs if s in r["sets"]]) for m in METRICS}
                for s in ALL_SETS if any(s in r["sets"] for r in runs)}  # fmt: skip
        curves = [r["curve"] for r in runs]
        out[name] = {
            "seeds": [r["seed"] for r in runs],
            "learned_from": runs[0].get("learned_from", "reward"),
            "env_id": runs[0].get("env_id", "DWRPointStabilization-v1"),
            "seconds": iqm_interval([r["seconds"] for r in runs]),
            "env_steps": iqm_interval([r.get("env_steps") or math.nan for r in runs]),
            "sets": sets,
            "per_seed": {s: {m: [r["sets"][s][m] for r in runs] for m in METRICS} for s in sets},
            "curves": {
                x: {y: curve_band(curves, x, y) for y in ("in_time", "energy", "final_heading")}
                for x in ("env_steps", "wall_time")
            },
        }
    return out


def best_seed(results: list[dict[str, Any]], name: str) -> int:
    """The seed of ``name`` with the most episodes in time on the nominal set, then the lowest E/opt."""
    runs = [r for r in results if r["entry"] == name]

    def key(r: dict[str, Any]) -> tuple[float, float]:
        metrics = r["sets"]["random"]
        return (-(metrics["in_time"] or 0.0), metrics["energy_ratio"] if metrics["energy_ratio"] is not None else 1e9)

    return int(min(runs, key=key)["seed"])


def _cell(interval: dict[str, Any], digits: int) -> str:
    if interval["iqm"] is None:
        return "-"
    return f"{interval['iqm']:.{digits}f} [{interval['low']:.{digits}f}, {interval['high']:.{digits}f}]"


COLUMNS: dict[str, tuple[str, int]] = {
    "in_time": ("in time", 3),
    "energy_ratio": ("E/opt", 2),
    "final_heading": ("final heading [rad]", 2),
    "energy": ("energy", 2),
}


def table(
    summary: dict[str, Any],
    references: dict[str, Any] | None = None,
    set_name: str = "random",
    columns: tuple[str, ...] = tuple(COLUMNS),
) -> str:
    """The markdown table of one set: IQM [95 % CI] of each metric per entry (with its env steps and training
    seconds, IQM over seeds), then the reference controllers."""
    head = " | ".join(COLUMNS[c][0] for c in columns)
    lines = [f"| agent | seeds | env steps | training [s] | {head} |", "|---" * (len(columns) + 4) + "|"]
    for name, entry in summary.items():
        m = entry["sets"].get(set_name)
        if m is None:
            continue
        cells = " | ".join(_cell(m[c], COLUMNS[c][1]) for c in columns)
        steps = entry.get("env_steps", {}).get("iqm")
        steps_text = "-" if steps is None else f"{steps:,.0f}"
        lines.append(f"| {name} | {len(entry['seeds'])} | {steps_text} | {entry['seconds']['iqm']:.0f} | {cells} |")
    for name, sets in (references or {}).items():
        m = sets.get(set_name)
        if m is None:
            continue
        cells = " | ".join("-" if m[c] is None else f"{m[c]:.{COLUMNS[c][1]}f}" for c in columns)
        lines.append(f"| {name} (controller) | - | - | - | {cells} |")
    return "\n".join(lines)


FROM_REWARD = ("ppo", "ppo-jax", "ppo-jax-12m", "ppo-jax-tuned", "ppo-jax-anneal", "sac", "sac-tuned", "td3", "tqc",
               "tqc-tuned", "crossq", "es", "es-arena50")  # fmt: skip
"""The benchmark's entries of a network alone learned from the reward (the candidates of the first goal)."""
GOALS = {
    goal.name: (entries, goal.in_time, goal.energy_ratio, goal.final_heading)
    for goal, entries in ((FROM_REWARD_GOAL, FROM_REWARD), (RESIDUAL_ON_PTC, ("residual-ppo",)))
}
"""The benchmark's goals (:mod:`train.goals`): (entries, in time >=, E/opt <=, final heading <= [rad]), IQM over >= 5
seeds on nominal v1."""


def goals_table(summary: dict[str, Any]) -> str:
    """Each of the benchmark's goals, the best entry for it (most in time) and whether each figure is met."""
    lines = ["| goal | best agent | seeds | in time | E/opt | final heading [rad] | training [s] (30 min = 1,800) |",
             "|---|---|---|---|---|---|---|"]  # fmt: skip

    def verdict(value: float | None, target: float, above: bool) -> str:
        if value is None:
            return f"- (goal {'>=' if above else '<='} {target:g}): not reached"
        met = value >= target if above else value <= target
        return f"{value:.3f} ({'>=' if above else '<='} {target:g}): {'met' if met else 'not met'}"

    for goal, (names, in_time, ratio, heading) in GOALS.items():
        found = [n for n in names if n in summary and "random" in summary[n]["sets"]]
        if not found:
            continue
        best = max(found, key=lambda n: summary[n]["sets"]["random"]["in_time"]["iqm"] or 0.0)
        entry, m = summary[best], summary[best]["sets"]["random"]
        lines.append(f"| {goal} | {best} | {len(entry['seeds'])} | {verdict(m['in_time']['iqm'], in_time, True)} | "
                     f"{verdict(m['energy_ratio']['iqm'], ratio, False)} | "
                     f"{verdict(m['final_heading']['iqm'], heading, False)} | {entry['seconds']['iqm']:.0f} |")  # fmt: skip
    return "\n".join(lines)


def disturbed_table(summary: dict[str, Any], references: dict[str, Any] | None = None) -> str:
    """In-time IQM per disturbed set and entry."""
    names = [s for s in SETS if s != "random"]
    lines = ["| agent | " + " | ".join(f"{s}: in time" for s in names) + " |", "|---" * (len(names) + 1) + "|"]
    for name, entry in summary.items():
        cells = [_cell(entry["sets"][s]["in_time"], 2) if s in entry["sets"] else "-" for s in names]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    for name, sets in (references or {}).items():
        cells = [f"{sets[s]['in_time']:.2f}" if s in sets else "-" for s in names]
        lines.append(f"| {name} (controller) | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def per_T_con_table(
    summary: dict[str, Any], references: dict[str, Any] | None = None, references_env: str | None = None,
    heading: bool = False,
) -> str:  # fmt: skip
    """In time and E/opt (IQM over seeds) of each entry at each prescribed time of PER_T_CON, and with ``heading`` the
    final heading error [rad]; the references were evaluated on ``references_env`` (v1 when not recorded). (On v2 the
    deadline's violation rate, the share of episodes with ``info["cost"]`` 1, is 1 - in time.)"""
    names = [per_T_con_set(T_con) for T_con in PER_T_CON]
    measures = "in time, E/opt, heading" if heading else "in time, E/opt"
    head = " | ".join(f"{name.replace('T_con=', 'T_con ')} s: {measures}" for name in names)
    lines = [f"| agent | env | {head} |", "|---" * (len(names) + 2) + "|"]
    for entry_name, entry in summary.items():
        if not any(name in entry["sets"] for name in names):
            continue
        cells = [f"{_cell(entry['sets'][n]['in_time'], 2)}, {_cell(entry['sets'][n]['energy_ratio'], 2)}"
                 + (f", {_cell(entry['sets'][n]['final_heading'], 2)}" if heading else "")
                 if n in entry["sets"] else "-" for n in names]  # fmt: skip
        env = str(entry.get("env_id", "DWRPointStabilization-v1")).rsplit("-", 1)[-1]
        lines.append(f"| {entry_name} | {env} | " + " | ".join(cells) + " |")
    for ref_name, sets in (references or {}).items():
        cells = [f"{sets[n]['in_time']:.2f}, {'-' if sets[n]['energy_ratio'] is None else format(sets[n]['energy_ratio'], '.2f')}"
                 + (f", {sets[n]['final_heading']:.2f}" if heading else "")
                 if n in sets else "-" for n in names]  # fmt: skip
        env = (references_env or "DWRPointStabilization-v1").rsplit("-", 1)[-1]
        lines.append(f"| {ref_name} (controller) | {env} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot_curves(summary: dict[str, Any], path: Path, x: str) -> None:
    """Learning curves (IQM over seeds and its 95 % band) of the in-time rate and the energy against ``x``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for name, entry in summary.items():
        for ax, y in zip(axes, ("in_time", "energy"), strict=True):
            band = entry["curves"][x][y]
            if not band["x"]:
                continue
            line = ax.plot(band["x"], band["iqm"], label=f"{name} ({len(entry['seeds'])} seeds)")[0]
            ax.fill_between(band["x"], band["low"], band["high"], color=line.get_color(), alpha=0.2)
    axes[1].set_yscale("log")  # an untrained agent can spend hundreds of times what a trained one does
    for ax, label in zip(axes, ("in time (IQM, 95 % CI)", "energy (IQM, 95 % CI)"), strict=True):
        ax.set_xlabel("env steps" if x == "env_steps" else "wall-clock seconds (training, evaluations included)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def diagnosis_table(data: dict[str, Any]) -> str:
    """The archived table of the diagnosis: PTC with exploration noise, what the noise's energy costs."""
    lines = ["| exploration noise sigma | in time | energy | E/opt | return | noise's energy cost per s | over the "
             "episode |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in data["rows"]:
        ratio = "-" if r["energy_ratio"] is None else f"{r['energy_ratio']:.2f}"
        lines.append(f"| {r['sigma']:.2f} | {r['in_time']:.3f} | {r['energy']:.2f} | {ratio} | {r['return']:.1f} | "
                     f"{r['noise_cost_per_second']:.3f} | {r['noise_cost_per_second'] * r['episode_seconds']:.1f} |")  # fmt: skip
    lines.append(f"\n*PTC with Gaussian noise on its normalised actions, {data['n']} episodes of the benchmark's "
                 f"nominal set (seed {data['seed']}); the optimum's mean energy {data['rows'][0]['optimal_energy']:.2f}, "
                 f"i.e. a reward of {-data['energy_weight'] * data['rows'][0]['optimal_energy']:.2f}; the arrival bonus "
                 f"{data['arrival_bonus']:.0f}.*\n")  # fmt: skip
    return "\n".join(lines)


def levers_table(data: dict[str, Any]) -> str:
    """Per lever: env steps and seconds reached, the best and the last evaluation (in time, energy, heading)."""
    lines = ["| lever (one seed) | env steps | seconds | best in time (energy) | last in time | last energy | "
             "last heading [rad] |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    for lever, entry in data["levers"].items():
        rows = entry["curve"]
        best, last = max(rows, key=lambda r: r["in_time"]), rows[-1]
        lines.append(f"| {lever} | {last['env_steps']:,} | {last['wall_time']:.0f} | {best['in_time']:.2f} "
                     f"({best['energy']:.2f}) | {last['in_time']:.2f} | {last['energy']:.2f} | "
                     f"{last['final_heading']:.2f} |")  # fmt: skip
    return "\n".join(lines)


def residual_table(data: dict[str, Any]) -> str:
    """The archived residual table: each residual agent beside its expert, and where its corrections act."""
    lines = ["| policy | in time | E/opt | final heading [rad] | energy |", "|---|---|---|---|---|"]
    for name, entry in data["agents"].items():
        for label, m in ((f"{name} (residual)", entry["agent"]), (f"{entry['expert']} alone", entry["expert_alone"])):
            ratio = "-" if m["energy_ratio"] is None else f"{m['energy_ratio']:.2f}"
            lines.append(f"| {label} | {m['in_time']:.3f} | {ratio} | {m['final_heading']:.2f} | {m['energy']:.3f} |")
    lines += ["", "| residual agent | share of T_con elapsed | steps | mean abs correction of u [m/s] | of omega [rad/s] |",
              "|---|---|---|---|---|"]  # fmt: skip
    for name, entry in data["agents"].items():
        for b in entry["by_time_fraction"]:
            du = "-" if b["du"] is None else f"{b['du']:.4f}"
            dw = "-" if b["domega"] is None else f"{b['domega']:.4f}"
            lines.append(f"| {name} | {b['low']:.2f}-{b['high']:.2f} | {b['steps']:,} | {du} | {dw} |")
    return "\n".join(lines) + f"\n\n*{data['n']} episodes of the benchmark's nominal set (seed {data['seed']}).*\n"


def sweep_table(data: dict[str, Any]) -> str:
    """The trials of a ``dwr-gym sweep``: hyperparameters and final evaluation."""
    lines = ["| trial | hyperparameters | in time | return | energy |", "|---|---|---|---|---|"]
    for t in data["trials"]:
        params = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                           for k, v in json.loads(t["hyperparams"]).items())  # fmt: skip
        lines.append(f"| {t['config']} | {params} | {float(t['success_rate_mean']):.2f} | "
                     f"{float(t['return_mean_mean']):.3f} | {float(t['energy_mean_mean']):.3f} |")  # fmt: skip
    return "\n".join(lines)


def rushing_table(data: dict[str, Any]) -> str:
    """The archived rushing table: E/opt split into the price of the arrival time and the price of the motion."""
    lines = ["| policy | episodes | arrival / T_con | E/opt | timing: E_opt(t_arr) / E_opt(T_con) | "
             "motion: E / E_opt(t_arr) |", "|---|---|---|---|---|---|"]  # fmt: skip
    for name, r in data["policies"].items():
        if not r.get("episodes"):
            lines.append(f"| {name} | 0 | - | - | - | - |")
            continue
        lines.append(f"| {name} | {r['episodes']} | {r['arrival_share']:.2f} | {r['energy_ratio']:.2f} | "
                     f"{r['timing']:.2f} | {r['motion']:.2f} |")  # fmt: skip
    return "\n".join(lines) + (
        f"\n\n*{data.get('env_id', 'DWRPointStabilization-v1')}: the episodes of the benchmark's nominal set (first "
        f"{data['n']}, seed {data['seed']}) that arrive in time; geometric means over them, so that E/opt = timing x "
        "motion; optima by CasADi (the goal pose).*\n"
    )


__all__ = [
    "aggregate",
    "best_seed",
    "curve_band",
    "diagnosis_table",
    "disturbed_table",
    "iqm_interval",
    "levers_table",
    "plot_curves",
    "residual_table",
    "rushing_table",
    "sweep_table",
    "table",
]
