"""The tables of docs/datasets.md, from ``docs/datasets/suite.json`` and ``docs/datasets/speed.json``."""

from __future__ import annotations

from typing import Any


def _number(value: Any, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def _percent(value: Any) -> str:
    return "-" if value is None else f"{100 * value:.3g} %"


def suite_table(data: dict[str, Any]) -> str:
    """Every dataset of the suite: its size, return statistics, quality against the optimum, normalised score."""
    lines = ["| id | policy | episodes | steps | return mean (std) | in time | \\|psi_end\\| [rad] | E/opt mean | "
             "normalised score | build [s] |", "|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in data["datasets"]:
        lines.append(
            f"| `{r['dataset_id']}` | {r['what']} | {int(r['episodes']):,} | {int(r['steps']):,} | "
            f"{r['return_mean']:.2f} ({r['return_std']:.2f}) | {_percent(r['in_time'])} | "
            f"{r['heading_error_mean']:.3f} | {_number(r['energy_ratio_mean'], '.2f')} | "
            f"{_number(r['normalized_score'], '.3f')} | {r['build_seconds']:.0f} |"
        )
    nominal = next(r for r in data["datasets"] if r["name"] == "ptc-nominal")
    disturbed = next(r for r in data["datasets"] if r["name"] == "robust-pt-disturbed")
    return "\n".join(lines) + (
        f"\n\n*DWRPointStabilization-v1, seed 0 (robot i from seed i: every dataset starts from the same poses); "
        f"E/opt: energy / the optimum's on the same episode, over the episodes in time; normalised score: "
        f"(return - ref_min_score) / (ref_max_score - ref_min_score) of the mean return, with ref_max_score "
        f"{nominal['ref_max_score']:.2f} and ref_min_score {nominal['ref_min_score']:.2f} on the nominal env "
        f"({disturbed['ref_max_score']:.2f} and {disturbed['ref_min_score']:.2f} on the disturbed one); build: "
        f"collection, the optimum of each episode (solved once per start: later datasets of the same starts find "
        f"it cached) and the write, on {data['cores']} cores shared with other work (`{data['command']}`).*\n"
    )


def _made_from(policy: str) -> str:
    for prefix, method in (("bc-", "behaviour cloning"), ("td3bc-", "TD3+BC (d3rlpy)")):
        if policy.startswith(prefix):
            return f"{method} of `dwr-gym/{policy.removeprefix(prefix)}-v0`"
    return "the policy that made the data"


def baselines_table(data: dict[str, Any]) -> str:
    """The offline baselines beside the policies that made their data, on the nominal and the disturbed set."""
    rows = data["evaluation"]
    by = {(r["scenario"], r["policy"]): r for r in rows}
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    lines = ["| policy | learned from | random: in time | \\|psi_end\\| [rad] | E/opt mean | disturbed: in time | "
             "\\|psi_end\\| [rad] | energy |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for policy in policies:
        nominal, disturbed = by.get(("random", policy)), by.get(("disturbed", policy))
        cells = [f"`{policy}`", _made_from(policy)]
        cells += ["", "", ""] if nominal is None else [_percent(nominal["success_rate"]),
                                                       f"{nominal['final_heading_error_mean']:.3f}",
                                                       _number(nominal["energy_ratio_mean"], ".2f")]  # fmt: skip
        cells += ["", "", ""] if disturbed is None else [_percent(disturbed["success_rate"]),
                                                         f"{disturbed['final_heading_error_mean']:.3f}",
                                                         f"{disturbed['energy_mean']:.3f}"]  # fmt: skip
        lines.append("| " + " | ".join(cells) + " |")
    sizes = sorted({int(r["n"]) for r in rows if r["scenario"] == "disturbed"}, reverse=True)
    return "\n".join(lines) + (
        f"\n\n*`dwr-gym evaluate --scenarios random disturbed --n {data['n']}` (the `optimal` controller on the "
        f"first {sizes[-1]} of the {sizes[0]} disturbed episodes); behaviour cloning: `dwr-gym imitate --dataset ID "
        f"--epochs {data['epochs']}`; "
        + (
            f"TD3+BC: {data['td3bc_steps']:,} gradient steps of batch 256 on one CPU core (the paper's: 1,000,000); "
            if data.get("td3bc_steps")
            else ""
        )
        + "in time: arrived by T_con (within the goal tolerance, as the env counts it); E/opt: energy / the optimum's on "
        "the same episode, over the episodes in time.*\n"
    )


def speed_table(data: dict[str, Any]) -> str:
    """1 M transitions of PTC: collection, Minari's write, against the goal of 60 s."""
    verdict = "met" if data["goal_met"] else "not met"
    return (
        "| transitions | episodes | collect [s] | write [s] | total [s] | goal | load [s] |\n"
        "|---|---|---|---|---|---|---|\n"
        f"| {data['transitions']:,} | {data['episodes']:,} | {data['collect_seconds']:.1f} | "
        f"{data['write_seconds']:.1f} | **{data['total_seconds']:.1f}** | <= {data['goal_seconds']:.0f} s: {verdict} | "
        f"{data['load_seconds']:.1f} |\n\n"
        f"*`{data['command']}` on {data['cores']} cores shared with other work, Minari {data['minari']}. Minari's own "
        f"write of {data['fifth_episodes']} of these episodes took {data['fifth_minari_write_seconds']:.1f} s against "
        f"{data['fifth_our_write_seconds']:.1f} s here: Minari 0.5 recomputes the dataset's size after every episode "
        "(a walk over all its files), which `dwr-gym dataset` does once at the end.*\n"
    )


__all__ = ["baselines_table", "speed_table", "suite_table"]
