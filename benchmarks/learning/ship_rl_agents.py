"""Copy the best seed of each agent of a ``dwr-gym benchmark`` into train/pretrained/.

The best seed is the one ``benchmark.json`` names (most episodes in time on the nominal set, then the lowest
E/opt). Each shipped directory gets the run's config.yaml (its ``command`` is the ``dwr-gym train`` recipe that
``python -m benchmarks run retrain-pretrained`` runs again; ``learned_from: reward``; ``runtime``), model.zip, the observation statistics if any, evaluations.csv and
learning_curve.png.

    python -m benchmarks run ship-rl-agents results/rl-benchmark
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

from benchmarks.core.commands import parser_for

ROOT = Path(__file__).resolve().parents[2]

#: benchmark entry -> directory under train/pretrained/: the leaderboard's agents that a ``dwr-gym benchmark`` makes
#: (train.learning.agents.PRETRAINED, train.reporting.leaderboard.ROWS), each shipped where its --out holds its run.
SHIPPED = {
    "apg-hold-heading10-time-scaled-30min-v2": "apg_v2",
    "apg-residual-v2": "apg_residual_ptc_v2",
    "ppo-jax": "ppo_jax_v1",
    "es-arena50": "es_v1",
}
"""``--also`` ships more entries as ``<entry>_v1`` (or ``<entry>`` where it ends in its env version) without
registering them: load them by path."""


def plot_curve(evaluations: Path, target: Path, title: str) -> None:
    import csv

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with evaluations.open() as handle:
        rows = list(csv.DictReader(handle))
    steps = [int(r["timesteps"]) for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(7, 2.6))
    axes[0].plot(steps, [float(r["success_rate"]) for r in rows], marker="o")
    axes[0].set_ylabel("in time")
    axes[1].plot(steps, [float(r["energy_mean"]) for r in rows], marker="o")
    axes[1].set_ylabel("energy")
    for ax in axes:
        ax.set_xlabel("agent steps")
        ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(target, dpi=70)
    plt.close(fig)


def shipped_name(entry: str) -> str:
    """The directory under train/pretrained/ of a ``--also`` entry: its name with underscores, ending in its env
    version (``es-residual-v2`` -> ``es_residual_v2``, ``sac-tuned`` -> ``sac_tuned_v1``)."""
    name = entry.replace("-", "_")
    return name if name[-3:-1] == "_v" and name[-1].isdigit() else f"{name}_v1"


def portable_config(text: str, root: Path = ROOT) -> str:
    """A run's config.yaml ``text`` with the paths inside the repository ``root`` made relative to it, and so the
    absolute paths of any checkout's train/hyperparams/ (a copy of the repository the run was made in): a benchmark
    names its hyperparameter files by absolute path, which would ship this machine's directories to users."""
    text = text.replace(f"{root.as_posix().rstrip('/')}/", "")
    return re.sub(r"(?<![\w.-])/[^\s'\"]*?/(train/hyperparams/)", r"\1", text)


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("ship-rl-agents", __doc__)
    parser.add_argument("out", help="the --out of dwr-gym benchmark")
    parser.add_argument(
        "--also",
        nargs="*",
        default=[],
        help="more entries to ship, as <entry>_v1, or <entry> where it ends in its env version (-v2)",
    )
    args = parser.parse_args(argv)
    out = Path(args.out)
    # the best seeds of this --out's last report, and of the earlier runs that `--docs` merged into the docs' JSON
    docs = ROOT / "docs" / "rl_benchmark" / "benchmark.json"
    best = json.loads(docs.read_text())["best_seed"] if docs.is_file() else {}
    if (out / "benchmark.json").is_file():
        best.update(json.loads((out / "benchmark.json").read_text())["best_seed"])
    shipped = {**SHIPPED, **{name: shipped_name(name) for name in args.also}}
    for entry, directory in shipped.items():
        run = out / "runs" / f"{entry}-seed{best.get(entry)}"
        if entry not in best or not (run / "model.zip").is_file():
            print(f"not shipped: {entry} (no finished run {run})")
            continue
        seed = best[entry]
        target = ROOT / "train" / "pretrained" / directory
        shutil.rmtree(target, ignore_errors=True)
        target.mkdir(parents=True)
        (target / "config.yaml").write_text(portable_config((run / "config.yaml").read_text()))
        shutil.copy(run / "evaluations.csv", target / "evaluations.csv")
        shutil.copy(run / "model.zip", target / "model.zip")
        if (run / "model_obs_norm.npz").is_file():
            shutil.copy(run / "model_obs_norm.npz", target / "model_obs_norm.npz")
        plot_curve(run / "evaluations.csv", target / "learning_curve.png", f"{entry}, seed {seed} (dwr-gym benchmark)")
        print(f"shipped {run} as {target}")
    return 0
