"""The tables of docs/rl-v2.md's incentives section, from docs/rl_benchmark/incentives.json
(``benchmarks/incentives.py``, train/evaluation/incentives.py)."""

from __future__ import annotations

from typing import Any


def _env_ids(data: dict[str, Any], part: str) -> list[str]:
    return [key for key, value in data.items() if isinstance(value, dict) and part in value]


def ranking_table(data: dict[str, Any]) -> str:
    """Mean discounted return of each policy on each env id, with the share of episodes the optimum beats it in."""
    env_ids = _env_ids(data, "ranking")
    by_env = {env: {row["policy"]: row for row in data[env]["ranking"]["rows"]} for env in env_ids}
    policies = list(dict.fromkeys(row["policy"] for env in env_ids for row in data[env]["ranking"]["rows"]))
    head = [f"{env.rsplit('-', 1)[1]} return (gamma {data[env]['ranking']['discount']:g})" for env in env_ids]
    head += [f"{env.rsplit('-', 1)[1]}: optimum >= it" for env in env_ids]
    lines = ["| policy | " + " | ".join(head) + " |", "|---" * (1 + len(head)) + "|"]
    for policy in policies:
        cells = []
        for env in env_ids:
            row = by_env[env].get(policy)
            rank = list(by_env[env]).index(policy) + 1 if row else None
            cells.append("-" if row is None else f"{row['return_mean']:.2f} ({rank})")
        for env in env_ids:
            row = by_env[env].get(policy)
            share = None if row is None else row["optimum_at_least"]
            cells.append("-" if share is None or policy == "optimal" else f"{100 * share:.0f} %")
        lines.append(f"| {policy} | " + " | ".join(cells) + " |")
    episodes = {data[env]["ranking"]["episodes"] for env in env_ids}
    lines.append("")
    lines.append(f"Mean discounted return over {', '.join(map(str, sorted(episodes)))} random episodes (rank in "
                 "brackets); first: " + ", ".join(f"{env.rsplit('-', 1)[1]} `{data[env]['ranking']['first']}`"
                                                  for env in env_ids) + ".")  # fmt: skip
    return "\n".join(lines) + "\n"


def rushing_table(data: dict[str, Any]) -> str:
    """Mean discounted return of the minimum-energy plan to arrive at each fraction of T_con, per noise sigma."""
    env_ids = _env_ids(data, "rushing")
    lines = ["| env | sigma | " + " | ".join(f"arrive at {f:g} T_con" for f in _fractions(data, env_ids))
             + " | latest pays most | latest - the best earlier, episode by episode | episodes, re-planned every |",
             ""]  # fmt: skip
    lines[1] = "|---" * (5 + len(_fractions(data, env_ids))) + "|"
    for env in env_ids:
        rushing = data[env]["rushing"]
        for sigma in dict.fromkeys(row["sigma"] for row in rushing["rows"]):
            rows = {row["fraction"]: row for row in rushing["rows"] if row["sigma"] == sigma}
            cells = [f"{rows[f]['return_mean']:.2f} ± {rows[f]['return_sem']:.2f} ({100 * rows[f]['in_time']:.0f} %)"
                     if f in rows else "-" for f in _fractions(data, env_ids)]  # fmt: skip
            verdict = "yes" if rushing["latest_pays_most"].get(str(sigma)) else "**no**"
            margin = rushing.get("latest_margin", {}).get(str(sigma))
            paired = f"{margin['mean']:+.2f} ± {margin['sem']:.2f} (vs {margin['against']:g})" if margin else "-"
            first = next(iter(rows.values()))
            # (20 control periods: the runs before the interval was an option)
            run = (f"{first.get('episodes', rushing['episodes'])}, "
                   f"{first.get('replan_every', rushing.get('replan_every', 20))} control periods")  # fmt: skip
            lines.append(f"| {env.rsplit('-', 1)[1]} (gamma {rushing['discount']:g}) | {sigma:g} | " + " | ".join(cells)
                         + f" | {verdict} | {paired} | {run} |")  # fmt: skip
    lines.append("")
    lines.append(
        "Mean discounted return ± its standard error over a row's random episodes (in time in brackets), the same "
        "episodes and noise draws in every cell of a row, the plans re-made from the measured pose at the row's "
        "interval; the paired column compares each episode's latest arrival with the same episode's earlier arrival "
        "of the highest mean."
    )
    return "\n".join(lines) + "\n"


def _fractions(data: dict[str, Any], env_ids: list[str]) -> list[float]:
    return sorted({row["fraction"] for env in env_ids for row in data[env]["rushing"]["rows"]})


__all__ = ["ranking_table", "rushing_table"]
