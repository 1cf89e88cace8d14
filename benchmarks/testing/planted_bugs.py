"""Plant each bug of the audits (realistic slips) in a copy of the tree, run the test suite there, and record what fails.

    python -m benchmarks run planted-bugs              # every bug, one suite run each (~5 min each on 2 cores)
    python -m benchmarks run planted-bugs --bugs sinc_1_over_24
    python -m benchmarks run planted-bugs --bugs truncated_is_terminated --tests tests/test_sb3.py  # only these tests
    python -m benchmarks run planted-bugs --targeted   # each slip of TARGETED with its own tests (a minute each)

A golden or pinned record (tests/test_golden.py, the pinned v0 returns and trajectories) detects a change,
not a bug that was there when it was recorded; so each bug must also fail another test. The source tree
is never touched: each bug is planted in ``git archive HEAD`` unpacked under ``--work``. Results go to
``docs/testing/planted_bugs.json``, from which the table of docs/testing.md is rendered.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Block, Schema

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "testing" / "planted_bugs.json"
#: Tests that compare with a recorded output rather than with an independent reference.
PINNED = re.compile(r"test_golden\.py|test_v0_returns_|test_v0_defaults_are_bit_for_bit")
ADDITIVE = "        for i, item in enumerate(self.disturbances):\n            if isinstance(item, VelocityBias):"
WHEELS = "        if self.drive is not None:\n            left, right = robots.wheel_speeds"

#: bug -> (what it does, the file, the text replaced, its replacement)
BUGS: dict[str, tuple[str, str, str, str]] = {
    "ptc_u_without_p_star": (
        "PTC's u of eq. (16) without p*", "baselines/controllers.py",
        "u = p.K1 * mu * p_star * d ** (2.0 * p.beta - 1.0)  # eq. (16)",
        "u = p.K1 * mu * d ** (2.0 * p.beta - 1.0)  # eq. (16)"),
    "ptc_omega_exponent_beta": (
        "PTC's omega of eq. (18) with exponent beta instead of 2 beta - 1", "baselines/controllers.py",
        "signed_power(orientation_err, 2.0 * p.beta - 1.0)  # eq. (18)", "signed_power(orientation_err, p.beta)  # eq. (18)"),
    "sinc_1_over_24": (
        "sin(h)/h series coefficient 1/120 -> 1/24", "dwr_gym/model.py", "h2 * (1.0 / 120.0 +", "h2 * (1.0 / 24.0 +"),
    "additive_before_saturation": (
        "additive disturbances applied before the wheel saturation", "dwr_gym/disturbances.py", ADDITIVE, WHEELS),
    "optimum_ignores_episode_T_con": (
        "the reference optimum ignores each episode's own T_con", "train/evaluation/evaluate.py",
        "                params, scenario.starts, scenario.goals, scenario.T_cons, heading=optimum == \"pose\",",
        "                params, scenario.starts, scenario.goals, None, heading=optimum == \"pose\","),
    "zero_init_does_nothing": (
        "zero_init_last_layer does nothing", "train/learning/residual.py",
        '    policy = model.policy\n    if hasattr(policy, "action_net"):',
        '    return\n    policy = model.policy\n    if hasattr(policy, "action_net"):'),
    # the second test audit: behaviours no test looked at
    "distribution_ignores_seed": (
        "DisturbanceDistribution ignores its seed", "dwr_gym/randomization.py",
        "seed = self.distribution.seed", "seed = 0"),
    "command_rate_from_applied_velocities": (
        "the command-rate RMS from the applied velocities instead of the commanded", "train/evaluation/rollout.py",
        "command = np.clip(actions, -1.0, 1.0) * limits", "command = np.stack([u, w], axis=1)"),
    "truncated_is_terminated": (
        "the SB3 adapter's TimeLimit.truncated set to terminated", "dwr_gym/sb3.py",
        '"TimeLimit.truncated": bool(truncated[i] and not terminated[i]),', '"TimeLimit.truncated": bool(terminated[i]),'),
    "dagger_keeps_the_last_round": (
        "DAgger keeps only the last round's data", "train/learning/imitation/dagger.py",
        "data = concatenate([data, dagger_samples(model, config, params, rng)])",
        "data = dagger_samples(model, config, params, rng)"),
    "robust_dagger_keeps_the_last_round": (
        "robust DAgger keeps only the last round's data", "train/learning/imitation/robust_dagger.py",
        "data = concatenate([data, dagger_samples(model, config, params, rng)])",
        "data = dagger_samples(model, config, params, rng)"),
    "no_replan_out_of_the_tube": (
        "robust-pt does not re-plan when pushed out of the tube", "baselines/robust.py",
        "stray = ended | off", "stray = ended"),
    "smith_prediction_one_step_short": (
        "the Smith predictor's pose one command short", "baselines/estimation.py",
        "for lag in range(int(self.delay.max(initial=0)), 0, -1):",
        "for lag in range(int(self.delay.max(initial=0)) - 1, 0, -1):"),
    # what the benchmark publishes: a wrong set, env id, optimum or mask, an off-by-one, a flipped sign
    "v2_in_time_reached_and_left": (
        "v2's in time counts a robot at the goal before T_con that left it", "train/evaluation/rollout.py",
        "success |= ended & result.is_success & (state.step_count <= state.prescribed_steps)",
        "success |= live & result.is_success & (state.step_count <= state.prescribed_steps)"),
    "late_arrival_in_time": (
        "in time counts a late arrival", "train/evaluation/rollout.py",
        "success |= ended & result.is_success & (state.step_count <= state.prescribed_steps)",
        "success |= ended & result.is_success"),
    "heading_from_orientation_error": (
        "the final heading measured as eq. (6)'s orientation error", "train/evaluation/rollout.py",
        "final_heading = np.where(live, np.abs(result.coords.psi), final_heading)",
        "final_heading = np.where(live, np.abs(result.coords.orientation_error), final_heading)"),
    "return_after_the_end": (
        "the return keeps summing after an episode ended", "train/evaluation/rollout.py",
        "ret += np.where(live, result.reward, 0.0) * weight", "ret += result.reward * weight"),
    "energy_ratio_over_arrivals": (
        "E/opt over every arrival, not the episodes in time", "train/evaluation/rollout.py",
        "valid = self.success & np.isfinite(self.optimal_energy)",
        "valid = self.arrived & np.isfinite(self.optimal_energy)"),
    "energy_mean_of_successes": (
        "the mean energy over the episodes in time only", "train/evaluation/rollout.py",
        '"energy_mean": float(np.mean(self.energy)),', '"energy_mean": float(np.mean(self.energy[self.success])),'),
    "optimum_of_the_position": (
        "E/opt against the position optimum", "train/evaluation/evaluate.py",
        "                params, scenario.starts, scenario.goals, scenario.T_cons, heading=optimum == \"pose\",",
        "                params, scenario.starts, scenario.goals, scenario.T_cons, heading=optimum == \"position\","),
    "evaluated_on_v1_whatever_the_env": (
        "the benchmark evaluates every agent on v1", "train/evaluation/benchmark.py",
        "kwargs = env_keywords(env_id, {})", "kwargs = env_keywords(TASK_ENV_ID, {})"),
    "nominal_e_opt_from_the_whole_set": (
        "the nominal set's E/opt from its n episodes' draw, not n_optimum's", "train/evaluation/benchmark.py",
        "rows = evaluate_sets({\"agent\": policy}, [name], n_optimum, seed, kwargs",
        "rows = evaluate_sets({\"agent\": policy}, [name], n, seed, kwargs"),
    "run_evaluated_on_v1": (
        "a run is evaluated on v1 whatever its env id", "train/learning/benchmark.py",
        'env_id = config_dict.get("env_id", TASK_ENV_ID)', "env_id = TASK_ENV_ID"),
    "per_T_con_e_opt_from_nominal": (
        "the per-T_con table's E/opt cells read from the nominal set", "train/reporting/rl_benchmark.py",
        "{_cell(entry['sets'][n]['energy_ratio'], 2)}", "{_cell(entry['sets']['random']['energy_ratio'], 2)}"),
    "aggregate_reads_nominal": (
        "the aggregate of every set read from the nominal set", "train/reporting/rl_benchmark.py",
        'iqm_interval([r["sets"][s][m] for r in runs if s in r["sets"]])',
        'iqm_interval([r["sets"]["random"][m] for r in runs if s in r["sets"]])'),
    "interval_of_90_percent": (
        "the interval's percentiles 5 and 95", "train/reporting/rl_benchmark.py",
        "low, high = np.percentile(boots, [2.5, 97.5])", "low, high = np.percentile(boots, [5.0, 95.0])"),
    "iqm_cut_rounded": (
        "the IQM's quarter rounded instead of truncated", "train/reporting/rl_benchmark.py",
        "    cut = int(0.25 * samples.shape[1])", "    cut = round(0.25 * samples.shape[1])"),
    "cell_bounds_swapped": (
        "a table's interval printed high before low", "train/reporting/rl_benchmark.py",
        "[{interval['low']:.{digits}f}, {interval['high']:.{digits}f}]",
        "[{interval['high']:.{digits}f}, {interval['low']:.{digits}f}]"),
    "v2_miss_only_outside_tolerance": (
        "v2's terminal miss paid only outside the goal tolerance", "dwr_gym/core.py",
        "late = xp.where(terminated, -params.terminal_distance_weight * d, 0.0) if hold",
        "late = xp.where(terminated & (d > params.goal_tolerance), -params.terminal_distance_weight * d, 0.0) if hold"),
    "cost_one_period_late_free": ("an arrival one control period after T_con costing 0", "dwr_gym/core.py",
                                  "(step_count <= prescribed_steps)", "(step_count <= prescribed_steps + 1)"),
    "cost_every_step": ("the cost charged at every step, not once at the episode's end", "dwr_gym/core.py",
                        "xp.where(ended & xp.logical_not(in_time)", "xp.where(xp.logical_not(in_time)"),
    # the learners' conventions
    "apg_deadline_multiplier_sign": (
        "APG's deadline multiplier rewarding the distance instead of charging it", "train/learning/jitted/apg.py",
        "miss = weights[0] * after.distance + weights[1]",
        "miss = -weights[0] * after.distance + weights[1]"),
    "residual_gradient_through_undefined_law": (
        "the JAX residual's gradient through the law's undefined gain at T_con unguarded",
        "train/learning/jitted/residual.py", "self.expert_action(finite_cotangent(state.observation))",
        "self.expert_action(state.observation)"),
    "apg_hold_heading_sign": (
        "APG's hold heading term with its sign flipped", "train/learning/jitted/apg.py",
        "miss = miss + self.settings.hold_heading_weight * 2.0 * jnp.abs(jnp.sin(0.5 * after.psi))",
        "miss = miss - self.settings.hold_heading_weight * 2.0 * jnp.abs(jnp.sin(0.5 * after.psi))"),
    "apg_hold_miss_sign": (
        "APG's hold miss rewarded instead of charged", "train/learning/jitted/apg.py",
        "held = held - jnp.where(alive & last, miss / hold, 0.0)",
        "held = held + jnp.where(alive & last, miss / hold, 0.0)"),
    "residual_head_1e-2": (
        "the JAX residual's head starting at 1e-2 of its fresh kernel", "train/learning/jitted/residual.py",
        "LAST_LAYER_GAIN = 1e-3", "LAST_LAYER_GAIN = 1e-2"),
    "autoreset_wrong_fresh_episode": (
        "an ended robot takes the next fresh episode, not its own", "dwr_gym/jax_env/autoreset.py",
        "slot = (jnp.cumsum(done, dtype=jnp.int32) - 1) % self.num_resets",
        "slot = jnp.cumsum(done, dtype=jnp.int32) % self.num_resets"),
    "es_return_after_the_end": (
        "ES's return keeps summing after an episode ended", "train/learning/evolution/strategies.py",
        "returns = returns + jnp.where(alive, reward, 0.0)", "returns = returns + reward"),
}  # fmt: skip


ORACLES, LEARNERS = "tests/test_oracles.py::test_", "tests/test_oracles_learners.py::test_"
SETS = f"{ORACLES}the_benchmarks_sets_are_the_oracles_on_the_nominal_set_and_each_T_con"
EPISODES = f"{ORACLES}each_episodes_measures_are_the_oracles"
TABLES = f"{ORACLES}the_results_json_aggregate_and_tables_are_the_oracles"
#: bug -> the tests that name its module and catch it in a minute (``--targeted``; the default suite otherwise)
TARGETED: dict[str, list[str]] = {
    "v2_in_time_reached_and_left": [f"{EPISODES}[DWRPointStabilization-v2-None]"],
    "late_arrival_in_time": [f"{EPISODES}[DWRPointStabilization-v1-None]"],
    "heading_from_orientation_error": [f"{EPISODES}[DWRPointStabilization-v1-None]"],
    "return_after_the_end": [f"{EPISODES}[DWRPointStabilization-v1-None]"],
    "energy_ratio_over_arrivals": [f"{SETS}[DWRPointStabilization-v1]", TABLES],
    "energy_mean_of_successes": [f"{SETS}[DWRPointStabilization-v1]"],
    "optimum_of_the_position": [f"{SETS}[DWRPointStabilization-v1]"],
    "optimum_ignores_episode_T_con": [f"{SETS}[DWRPointStabilization-v1]"],
    "evaluated_on_v1_whatever_the_env": [f"{SETS}[DWRPointStabilization-v2]"],
    "nominal_e_opt_from_the_whole_set": [f"{SETS}[DWRPointStabilization-v1]"],
    "run_evaluated_on_v1": [
        f"{ORACLES}a_trained_entry_is_evaluated_on_its_own_env_id_and_its_json_holds_the_oracles_metrics"
    ],
    "per_T_con_e_opt_from_nominal": [TABLES],
    "aggregate_reads_nominal": [TABLES],
    "interval_of_90_percent": [f"{ORACLES}the_iqm_and_its_interval_are_the_oracles"],
    "iqm_cut_rounded": [f"{ORACLES}the_iqm_and_its_interval_are_the_oracles"],
    "cell_bounds_swapped": [TABLES],
    "v2_miss_only_outside_tolerance": [f"{ORACLES}v2s_reward_is_its_definition_term_by_term"],
    "apg_deadline_multiplier_sign": [
        "tests/test_lagrangian.py::test_the_multipliers_weigh_the_distance_and_heading_at_T_con_in_the_gradient"
    ],
    "residual_gradient_through_undefined_law": [
        "tests/test_jax_residual.py::test_apg_updates_of_a_residual_on_ptc_are_not_voided_by_the_laws_gain_at_T_con"
    ],
    "apg_hold_heading_sign": [
        f"{LEARNERS}each_apg_option_adds_the_gradient_of_its_documented_charge[hold_heading_weight]"
    ],
    "apg_hold_miss_sign": [f"{LEARNERS}each_apg_option_adds_the_gradient_of_its_documented_charge[hold_steps]"],
    "cost_one_period_late_free": ["tests/test_cost.py"],
    "cost_every_step": ["tests/test_cost.py"],
    "residual_head_1e-2": [f"{LEARNERS}the_jax_residual_starts_at_sb3s_scale_of_its_fresh_head"],
    "autoreset_wrong_fresh_episode": [f"{LEARNERS}the_autoreset_hands_the_kth_ended_robot_fresh_episode_k"],
    "es_return_after_the_end": [f"{LEARNERS}es_return_of_a_candidate_is_the_envs_own_episode_return"],
}


def plant(bug: str, work: Path) -> Path:
    """A copy of HEAD with ``bug`` planted."""
    _, path, old, new = BUGS[bug]
    root = work / bug
    if root.exists():
        shutil.rmtree(root)
    root.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "HEAD"], capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(root)], input=archive, check=True)
    text = (root / path).read_text()
    if bug == "additive_before_saturation":  # move the additive disturbances' loop in front of the wheels' block
        start, add = text.index(WHEELS), text.index(ADDITIVE)
        end = text.index("        self.last.update(commanded_linear_velocity")
        text = text[:start] + text[add:end] + text[start:add] + text[end:]
    else:
        if text.count(old) != 1:
            raise SystemExit(f"{bug}: the code to change is not in {path} (or not once): update BUGS")
        text = text.replace(old, new)
    (root / path).write_text(text)
    return root


def run_suite(root: Path, tests: list[str] | None = None) -> tuple[list[str], str]:
    """The failing tests and pytest's last line, running the default suite (or ``tests``) in ``root`` (which imports
    from there)."""
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy", "MPLBACKEND": "Agg",
           "OMP_NUM_THREADS": "1"}  # fmt: skip
    workers = "0" if tests else "2"  # a few test files: one process
    command = ["nice", "-n", "10", sys.executable, "-m", "pytest", "-n", workers, "-q", "-rf", "-p", "no:cacheprovider",
               *(tests or [])]  # fmt: skip
    output = subprocess.run(command, cwd=root, env=env, capture_output=True, text=True, check=False).stdout
    failed = sorted({line.split()[1] for line in output.splitlines() if line.startswith("FAILED ")})
    return failed, output.strip().splitlines()[-1] if output.strip() else ""


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("planted-bugs", __doc__)
    parser.add_argument("--bugs", nargs="+", choices=list(BUGS), default=list(BUGS))
    parser.add_argument("--work", type=Path, default=Path("/tmp/dwr-gym-planted"))
    parser.add_argument("--tests", nargs="+", help="run only these tests (files or node ids) instead of the suite")
    parser.add_argument("--targeted", action="store_true",
                        help="run each bug of TARGETED with its own tests (a minute each) instead of the suite")  # fmt: skip
    parser.add_argument("--docs", action="store_true", help="(the JSON is always written; renders its table)")
    args = parser.parse_args(argv)
    results = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    for bug in args.bugs:
        tests = TARGETED.get(bug, args.tests) if args.targeted else args.tests
        failed, last = run_suite(plant(bug, args.work), tests)
        independent = [test for test in failed if not PINNED.search(test)]
        results[bug] = {"description": BUGS[bug][0], "file": BUGS[bug][1], "failed": failed,
                        "failed_not_pinned": independent, "summary": last, "tests": tests or "the default suite"}  # fmt: skip
        print(f"{bug}: {len(failed)} failed, {len(independent)} of them not a golden/pinned record ({last})")
        # read again just before writing: two runs (of other bugs) may write the JSON at the same time
        results = {**(json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}), bug: results[bug]}
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps(results, indent=1) + "\n")


def table_lines(results: dict[str, Any]) -> list[str]:
    """The docs block: each bug, the tests run, how many failed and how many of those are not a pinned record."""
    lines = ["| bug | file | tests run | tests failed | of them not golden/pinned | for example |",
             "|---|---|---|---|---|---|"]  # fmt: skip
    for result in results.values():
        example = result["failed_not_pinned"][0] if result["failed_not_pinned"] else "none"
        tests = result.get("tests", "the default suite")
        run = tests if isinstance(tests, str) else ", ".join(f"`{t}`" for t in tests)
        lines.append(f"| {result['description']} | `{result['file']}` | {run} | {len(result['failed'])} | "
                     f"{len(result['failed_not_pinned'])} | `{example}` |")  # fmt: skip
    return lines


BLOCKS = (Block("planted-bugs", "docs/testing/planted_bugs.json", lambda data: "\n" + "\n".join(table_lines(data)) + "\n",
                Schema()),)  # fmt: skip
