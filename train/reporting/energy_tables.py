"""The tables of docs/what-was-tried.md's "Where the energy goes on v2", from docs/rl_benchmark/energy_split.json
(written by train/evaluation/energy_split.py; archived, rendered by ``python -m benchmarks run archive``)."""

from __future__ import annotations

from typing import Any


def split_table(data: dict[str, Any]) -> str:
    """Each policy's energy on v2, its linear and turning parts, and its share in each part of T_con."""
    split = data["split"]
    parts = int(split["parts"])
    head = [f"{i}/{parts}-{i + 1}/{parts} T_con" for i in range(parts)]
    lines = ["| policy | in time | energy | linear (u^2) | turning (omega^2) | " + " | ".join(head)
             + " | final heading [rad] |", "|---" * (6 + parts) + "|"]  # fmt: skip
    for row in split["rows"]:
        shares = " | ".join(f"{100 * share:.0f} %" for share in row["shares"])
        lines.append(f"| {row['policy']} | {row['in_time']:.2f} | {row['energy_mean']:.3f} | {row['linear_mean']:.3f} "
                     f"| {row['turning_mean']:.3f} | {shares} | {row['final_heading_mean']:.2f} |")  # fmt: skip
    lines += ["", f"Means over {split['episodes']} random episodes of {split['env_id']} (seed {split['seed']}); the "
              "energy is counted until the episode ends (T_con), its share in each part of T_con summed over them."]  # fmt: skip
    return "\n".join(lines) + "\n"


def _gains(row: dict[str, Any]) -> str:
    return ", ".join(f"{name} {value:g}" for name, value in row["gains"].items())


def gains_table(data: dict[str, Any]) -> str:
    """Per law: its default gains, and the lowest E/opt its gain grid reaches in time, without and with the heading
    goal."""
    gains = data["gains"]
    lines = ["| law | gains | which | in time | E/opt | final heading [rad] |", "|---" * 6 + "|"]
    for law, defaults in data["defaults"].items():
        mine = [row for row in gains["rows"] if row["law"] == law]
        default = next((row for row in mine if all(row["gains"].get(k) == v for k, v in defaults.items())), None)
        best = gains["best"].get(law, {})
        label = "default (the paper's)" if law == "ptc" else "default"
        chosen = ((label, default), ("lowest E/opt in time", best.get("any_heading")),
                  (f"lowest E/opt in time, heading <= {gains['heading_goal']:g} rad", best.get("heading_goal")))  # fmt: skip
        for which, row in chosen:
            if row is None:
                lines.append(f"| {law} | - | {which} | - | none in the grid | - |")
                continue
            ratio = "-" if row["energy_ratio"] is None else f"{row['energy_ratio']:.2f}"
            lines.append(f"| {law} | {_gains(row)} | {which} | {row['in_time']:.2f} | {ratio} "
                         f"| {row['final_heading']:.2f} |")  # fmt: skip
    sizes = {law: sum(row["law"] == law for row in gains["rows"]) for law in data["defaults"]}
    lines += ["", f"{gains['episodes']} random episodes of {gains['env_id']} (seed {gains['seed']}); in time: on >= "
              f"{100 * gains['in_time_goal']:g} % of them; settings tried: "
              + ", ".join(f"{law} {count}" for law, count in sizes.items()) + " (all in the JSON)."]  # fmt: skip
    return "\n".join(lines) + "\n"


def open_loop_table(data: dict[str, Any]) -> str:
    """Per law: the law alone and the best residual sequence found for each episode (and the action alone, no law)."""
    from train.evaluation.open_loop import summary

    lines = ["| actions | sequence | in time | E/opt: mean | E/opt: median | energy | final heading [rad] | heading <= "
             "0.15 rad | v2 return |", "|---" * 9 + "|"]  # fmt: skip
    for variant in data["variants"]:
        settings = variant["settings"]
        law = settings["expert"]
        label = f"residual on {law} (scale {settings['residual_scale']:g})" if law else "the action, no law"
        rows = (("the law alone", variant["law"]), ("best found per episode", variant["best"])) if law else (
            ("best found per episode", variant["best"]),)  # fmt: skip
        for which, episodes in rows:
            mean = summary(episodes)
            ratio, median = ("-" if v != v else f"{v:.2f}" for v in (mean["energy_ratio"], mean["energy_ratio_median"]))
            lines.append(f"| {label} | {which} | {mean['in_time']:.2f} | {ratio} | {median} | {mean['energy']:.3f} "
                         f"| {mean['final_heading']:.2f} | {100 * mean['heading_goal_share']:.0f} % "
                         f"| {mean['return']:.2f} |")  # fmt: skip
    first = data["variants"][0]["settings"]
    lines += ["", f"Means over {first['n']} random episodes of {first['env_id']} (seed {first['seed']}), each "
              f"optimised on its own: {first['iterations']} Adam steps of {first['learning_rate']:g} on its return; "
              "E/opt over the episodes in time, against the cached optimum of the goal pose."]  # fmt: skip
    return "\n".join(lines) + "\n"


def clone_rounds_table(data: dict[str, Any]) -> str:
    """APG's cloned policy alone, before any update, per number of teacher rounds (benchmarks/learning/apg_clone_rounds)."""
    bands = list(data["rows"][0]["in_time_by_T_con"])
    lines = ["| teacher_rounds | lesson env steps | pairs | teacher's sequences in time | clone: in time | "
             + " | ".join(f"T_con {band} s" for band in bands)
             + " | return | final distance (median) [m] | final heading [rad] |",
             "|---" * (8 + len(bands)) + "|"]  # fmt: skip
    for row in data["rows"]:
        lines.append(f"| {row['rounds']} | {row['lesson_steps'] / 1e6:.0f} M | {row['pairs']:,.0f} "
                     f"| {row['teacher_in_time']:.2f} | {row['in_time']:.2f} | "
                     + " | ".join(f"{row['in_time_by_T_con'][band]:.2f}" for band in bands)
                     + f" | {row['return']:.2f} | {row['final_distance_median']:.3f} | {row['final_heading']:.2f} |")  # fmt: skip
    first = data["rows"][0]
    lines += ["", f"{first['episodes']} episodes a round, {first['iterations']} Adam steps each (seed 0); the clone's "
              f"mean action on {data['eval_episodes']} fresh episodes of {data['env_id']}, actions time-scaled by "
              f"{data['action_time_scale']:g} s; no APG update."]  # fmt: skip
    return "\n".join(lines) + "\n"


def clone_fit_table(data: dict[str, Any]) -> str:
    """APG's cloned policy alone, before any update, per length of the fit and network (apg_clone_rounds --json)."""
    lines = ["| clone_steps | network | fit's loss | clone: in time | return | final distance (median) [m] "
             "| final heading [rad] |", "|---" * 7 + "|"]  # fmt: skip
    for row in data["rows"]:
        lines.append(f"| {row['clone_steps']:,} | {'x'.join(map(str, row['net_arch']))} | {row['clone_loss']:.4f} "
                     f"| {row['in_time']:.3f} | {row['return']:.2f} | {row['final_distance_median']:.3f} "
                     f"| {row['final_heading']:.2f} |")  # fmt: skip
    first = data["rows"][0]
    lines += ["", f"One round of {first['episodes']} episodes, {first['iterations']} Adam steps each (seed 0); the "
              f"clone's mean action on {data['eval_episodes']} fresh episodes of {data['env_id']}, actions time-scaled "
              f"by {data['action_time_scale']:g} s; no APG update."]  # fmt: skip
    return "\n".join(lines) + "\n"


def misses_table(data: dict[str, Any]) -> str:
    """Per agent and T_con: in time, and where the misses end (benchmarks/learning/misses.py)."""
    lines = ["| agent | T_con [s] | in time | misses | left the arena | misses' final distance: median, largest [cm] "
             "| misses within 2 cm | misses' start distance (median) [m] |", "|---" * 8 + "|"]  # fmt: skip
    for agent in data["agents"]:
        for row in agent["rows"]:
            if row["misses"]:
                where = f"{100 * row['final_distance_median']:.2f}, {100 * row['final_distance_max']:.1f}"
                near, start = f"{100 * row['within_2cm']:.0f} %", f"{row['start_distance_median']:.2f}"
            else:
                where, near, start = "-", "-", "-"
            lines.append(f"| {agent['agent']} | {row['T_con']:g} | {100 * row['in_time']:.1f} % | {row['misses']} "
                         f"| {row['left_arena']} | {where} | {near} | {start} |")  # fmt: skip
    n = data["agents"][0]["rows"][0]["n"]
    lines += ["", f"{n} random episodes of {data['env_id']} at each T_con (seed {data['seed']}); a miss: not within "
              "the goal tolerance (1 cm) at T_con."]  # fmt: skip
    return "\n".join(lines) + "\n"


__all__ = ["clone_fit_table", "clone_rounds_table", "gains_table", "misses_table", "open_loop_table", "split_table"]
