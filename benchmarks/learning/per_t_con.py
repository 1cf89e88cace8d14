"""Every shipped agent and the reference laws at each prescribed time on its own: T_con 10, 20, 40 and 60 s.

A rate over the drawn range hides the short deadlines (a learner 100 % in time over [10, 60] s can be 84 % at 10 s).

    python -m benchmarks run per-t-con --docs       # writes docs/rl_benchmark/per_T_con.json, renders its table

Each agent of train/pretrained/ runs on the env id it was trained on (its config.yaml; v0's agents on v1, the
task), on the benchmark's nominal starts (seed 3232) with T_con fixed to each value in turn, 100 starts each; E/opt
against the optimum of the same episode (CasADi, cached), over the episodes in time. The laws run on v1 and v2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Block, Schema
from benchmarks.core.record import report, torch_machine

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "rl_benchmark" / "per_T_con.json"
METRICS = ("in_time", "energy_ratio", "final_heading")


def shipped_agents(directory: Path) -> dict[str, Path]:
    """name -> run directory of every agent under ``directory`` (those with a model.zip), sorted by name."""
    return {path.name: path for path in sorted(directory.iterdir()) if (path / "model.zip").is_file()}


def agent_env_id(run_dir: Path) -> str:
    """The env id an agent trained on (v0's agents, trained on the paper's reward, run on the task, v1)."""
    import yaml

    from train.env_ids import PAPER_ENV_ID, TASK_ENV_ID

    config = yaml.safe_load((run_dir / "config.yaml").read_text()) if (run_dir / "config.yaml").is_file() else {}
    env_id = str((config.get("config") or {}).get("env_id", TASK_ENV_ID))
    return TASK_ENV_ID if env_id == PAPER_ENV_ID else env_id


def measure(agents: dict[str, Path], controllers: list[str], n: int) -> dict[str, Any]:
    from train.env_ids import HELD_ENV_ID, TASK_ENV_ID
    from train.evaluation.benchmark import PER_T_CON, evaluate_policy, per_T_con_set
    from train.learning.agents import load_agent

    def at_each_T_con(policy: Any, env_id: str) -> dict[str, Any]:
        sets = evaluate_policy(policy, env_id, sets=(), n_per_T_con=n, progress=True)
        return {str(T_con): {m: sets[per_T_con_set(T_con)][m] for m in METRICS} for T_con in PER_T_CON}

    rows: list[dict[str, Any]] = []
    for name, run_dir in agents.items():
        env_id = agent_env_id(run_dir)
        policy = load_agent(run_dir)[1]
        rows.append({"policy": name, "kind": "agent", "env_id": env_id, "T_con": at_each_T_con(policy, env_id)})
        print(name, env_id, rows[-1]["T_con"], flush=True)
    for name in controllers:
        for env_id in (TASK_ENV_ID, HELD_ENV_ID):
            rows.append({"policy": name, "kind": "controller", "env_id": env_id, "T_con": at_each_T_con(name, env_id)})
    return {"machine": torch_machine(), "n": n, "T_con": [float(t) for t in PER_T_CON], "rows": rows}


def render(data: dict[str, Any]) -> str:
    def cell(m: dict[str, Any]) -> str:
        ratio = "-" if m["energy_ratio"] is None else f"{m['energy_ratio']:.2f}"
        heading = "-" if m["final_heading"] is None else f"{m['final_heading']:.2f}"
        return f"{m['in_time']:.0%} / {ratio} / {heading}"

    names = [f"{t:g}" for t in data["T_con"]]
    lines = ["| policy | env | " + " | ".join(f"T_con {t} s" for t in names) + " |", "|---" * (len(names) + 2) + "|"]
    for row in data["rows"]:
        label = f"`{row['policy']}`" + (" (law)" if row["kind"] == "controller" else "")
        cells = [cell(row["T_con"][t]) if t in row["T_con"] else "-" for t in (str(float(x)) for x in data["T_con"])]
        lines.append(f"| {label} | {row['env_id'].rsplit('-', 1)[-1]} | " + " | ".join(cells) + " |")
    return (
        "\n"
        + "\n".join(lines)
        + (
            f"\n\n*Each cell: in time / E/opt (mean over the episodes in time) / final heading [rad]; {data['n']} starts "
            f"0.3-3 m of the benchmark's nominal set (seed 3232) per T_con; {data['machine']}; "
            "`python -m benchmarks run per-t-con --docs`.*\n"
        )
    )


def main(argv: list[str] | None = None) -> int:
    parser = parser_for("per-t-con", __doc__)
    parser.add_argument("--agents", nargs="*", default=None, help="run directories (default: train/pretrained/*)")
    parser.add_argument("--controllers", nargs="*", default=["ptc", "pt-astolfi"], help="laws beside them")
    parser.add_argument("--n", type=int, default=100, help="starts per T_con (default: 100)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)} (and its table)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"--n {args.n} is invalid: expected an integer >= 1")
    agents = (shipped_agents(ROOT / "train" / "pretrained") if args.agents is None
              else {Path(p).name: Path(p) for p in args.agents})  # fmt: skip
    data = measure(agents, args.controllers, args.n)
    return report([render(data)], data, JSON_PATH if args.docs else None)


BLOCKS = (Block("per-T_con-shipped", "docs/rl_benchmark/per_T_con.json", render,
                Schema({"machine": str, "n": int, "T_con": list, "rows": list})),)  # fmt: skip
