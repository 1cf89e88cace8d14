"""Mutation score of the test suite: mutmut over the env's mathematics, the controllers, the evaluation and learning.

    python -m benchmarks run mutation                       # every group, ~2-4 h of one core; writes the JSON
    python -m benchmarks run mutation --groups model core   # some groups only (the others keep their last results)
    python -m benchmarks run mutation --docs                # then render docs/testing.md's blocks from the JSON

Each group mutates some modules (mutmut's ``only_mutate`` globs, so a module split into several files stays
covered) and runs a fast, targeted selection of the tests on each mutant: mutmut runs, per mutant, only
the selected tests that executed the mutated function. The tests that run the command line in a subprocess
are left out (a subprocess imports the unmutated package), as are the training runs (too slow per mutant).
Each group works in its own copy of the project under ``--work`` (default ``/tmp/dwr-gym-mutation``), so
the source tree is never touched.

The score counts as killed what mutmut reports as killed or timeout, as not killed what survived or what
no selected test executes, and leaves out the mutants listed in ``benchmarks/testing/mutation_equivalent.json``
(each with the reason it is equivalent: no test can tell it from the original). Results go to
``docs/testing/mutation.json``, from which the blocks of ``docs/testing.md`` are rendered
(``python -m benchmarks render`` renders them without running mutmut).
"""

from __future__ import annotations

import json
import os
import random
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import parser_for
from benchmarks.core.docs import Block, Schema

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "testing" / "mutation.json"
EQUIVALENT = Path(__file__).with_name("mutation_equivalent.json")
COPIED = ("dwr_gym", "baselines", "train", "tests", "benchmarks", "pyproject.toml", "README.md", "docs")
#: Tests never run on mutants: subprocesses import the unmutated package; training runs take minutes per mutant.
DESELECTED = (
    "not test_cli_with and not fresh_interpreter and not spawn and not learns and not imitate and not sac_her"
    " and not end_to_end and not cloning_run"
)

#: group -> (the files it mutates, as mutmut globs; the tests run on its mutants)
GROUPS: dict[str, tuple[list[str], list[str]]] = {
    "model": (["dwr_gym/model.py"],
              ["tests/test_model.py", "tests/test_paper_by_hand.py", "tests/test_golden.py", "tests/test_env.py"]),
    # with the JAX env's tests: core's array-API paths (jax arrays, traced) run only there
    "core": (["dwr_gym/core.py", "dwr_gym/state.py", "dwr_gym/observation.py"],
             ["tests/test_env.py", "tests/test_vector_env.py", "tests/test_golden.py", "tests/test_paper_by_hand.py",
              "tests/test_prescribed_time.py", "tests/test_goal_env.py", "tests/test_env_v2.py", "tests/test_jax_env.py",
              "tests/test_jax_equivalence.py::test_float64_steps_equal_the_numpy_env_to_1e_12"]),
    "disturbances": (["dwr_gym/disturbances.py"],
                     ["tests/test_robustness.py", "tests/test_paper_by_hand.py"]),
    "randomization": (["dwr_gym/randomization.py"], ["tests/test_randomization.py"]),
    "sb3": (["dwr_gym/sb3.py"], ["tests/test_sb3.py", "tests/test_integrations.py"]),
    "baselines": (["baselines/base.py", "baselines/controllers.py", "baselines/expert.py", "baselines/nmpc.py",
                   "baselines/optimal.py", "baselines/polar.py", "baselines/registry.py"],
                  ["tests/test_controllers.py", "tests/test_controller_parameters.py", "tests/test_paper_by_hand.py",
                   "tests/test_optimal.py", "tests/test_optimum_cache.py", "tests/test_planner.py",
                   "tests/test_dagger.py", "tests/test_parameter_ranges.py"]),
    "estimation": (["baselines/estimation.py"], ["tests/test_estimation.py", "tests/test_parameter_ranges.py"]),
    "robust": (["baselines/robust.py"], ["tests/test_robust.py", "tests/test_parameter_ranges.py"]),
    # the measures' modules, with the oracles of every published measure (tests/oracles.py)
    "evaluation": (["train/evaluation/rollout.py", "train/evaluation/scenarios.py", "train/evaluation/evaluate.py"],
                   ["tests/test_oracles.py", "tests/test_controllers.py", "tests/test_optimal.py",
                    "tests/test_prescribed_time.py", "tests/test_robustness.py", "tests/test_stages.py",
                    "tests/test_evaluation_stages.py", "tests/test_evaluate_edges.py", "tests/test_rollout_edges.py"]),
    "learning": (["train/learning/imitation/dagger.py", "train/learning/imitation/robust_dagger.py",
                  "train/learning/residual.py"],
                 ["tests/test_dagger.py", "tests/test_robust_dagger.py", "tests/test_residual.py",
                  *(f"tests/test_train.py::test_{name}" for name in (
                      "residual_action_arithmetic_and_clipping", "residual_wrapper_logs_expert_and_residual_parts",
                      "residual_vec_env_with_zero_residual_is_the_expert", "residual_training_starts_from_the_expert",
                      "zero_init_scales_the_last_layer_to_gain_and_zeroes_its_bias",
                      "short_training_run_of_each_algorithm[ppo-residual]"))]),
    "jax_env": (["dwr_gym/jax_env/*"], ["tests/test_jax_env.py", "tests/test_jax_equivalence.py",
                                        "tests/test_jax_autoreset.py",
                                        "tests/test_oracles_learners.py::test_the_autoreset_hands_the_kth_ended_robot_fresh_episode_k"]),
    "jax_ppo": (["train/learning/jitted/ppo.py", "train/learning/jitted/policy.py", "train/learning/jitted/export.py"],
                ["tests/test_jax_training.py"]),
    "protocol": (["train/learning/benchmark.py", "train/evaluation/benchmark.py", "train/reporting/rl_benchmark.py"],
                 ["tests/test_oracles.py", "tests/test_rl_protocol.py", "tests/test_rl_benchmark.py",
                  "tests/test_benchmark_entries.py", "tests/test_rl_benchmark_tables.py",
                  "tests/test_docs.py::test_every_generated_block_names_its_producer_and_is_what_its_json_renders"]),
    "datasets": (["train/datasets/*"], ["tests/test_datasets.py"]),
    # the first-hour tests of the optimum's cache only (the others train agents, minutes per mutant)
    "guards": (["train/threads.py", "train/evaluation/optimum.py"],
               ["tests/test_threads.py", "tests/test_optimal.py", "tests/test_optimum_cache.py",
                *(f"tests/test_first_hour_training.py::test_{name}" for name in (
                    "the_optimum_cache_keeps_what_an_interrupted_command_solved",
                    "two_commands_caching_at_once_keep_each_others_optima",
                    "the_cache_is_read_merged_and_replaced_under_one_exclusive_lock",
                    "two_commands_solving_the_same_episodes_share_the_work"))]),
}  # fmt: skip
#: Words of DESELECTED a group keeps: the learning group's subject is the tiny DAgger runs.
KEPT = {"learning": ("cloning_run",)}
#: Words a group leaves out besides: the shipped robust agent's evaluations take minutes per mutant.
EXTRA = {"robust": ("shipped",),
         # the protocol's older end-to-end run (test_rl_protocol.py trains two seeds instead), the options' trainings
         "protocol": ("trains_evaluates_and_aggregates", "tqc_and_crossq", "normalised_observations"),
         "guards": ("ctrl_c", "train_runs_on_one_thread"),
         "evaluation": ("evaluate_rows_carry_each_stage_time",),  # a command in a subprocess
         # an xfail test cannot fail a mutant; the CLI refusal runs in a subprocess; the docs block is not the code's
         "jax_env": ("v2_steps_equal",),
         "jax_ppo": ("backend_jax_refuses", "each_docs_block")}  # fmt: skip
#: Groups whose module runs code at import (dwr_gym.model builds its torch-backed functions then): mutmut imports
#: them anew for each mutant instead of forking after collection, which would keep the unmutated import.
IMPORT_PER_MUTANT = {"model"}
#: Groups whose tests run threads that do not survive a fork of the process that ran them (mutmut's stats run): XLA's
#: (jax_env, jax_ppo, core's JAX tests), a process pool's or tqdm's lock forked from it (guards, evaluation: their
#: mutants hung until their timeout, counted killed).
#: Their mutants fork from a server that never ran a test. XLA's compilation cache is shared by the mutants, which
#: then compile again only the programs their mutation changed (the cache is keyed by the program).
FORKSERVER_GROUPS = {"jax_env", "jax_ppo", "guards", "core", "evaluation"}


def deselected(group: str) -> str:
    """The ``-k`` expression of the tests a group leaves out."""
    words = [word for word in DESELECTED.split(" and not ") if word.removeprefix("not ") not in KEPT.get(group, ())]
    return " and not ".join([*words, *EXTRA.get(group, ())])


def mutmut_config(group: str) -> str:
    """The [tool.mutmut] table of one group."""
    globs, tests = GROUPS[group]
    table = {
        "source_paths": ["dwr_gym", "baselines", "train"],
        "only_mutate": globs,
        "also_copy": ["tests", "benchmarks", "README.md", "docs"],
        "pytest_add_cli_args_test_selection": tests,
        "pytest_add_cli_args": ["-p", "no:xdist", "-p", "no:cacheprovider", "-m", "not slow", "-k", deselected(group),
                                "-W", "ignore::DeprecationWarning"],
        "timeout_multiplier": 20.0,  # a mutant that times out counts as killed: room for a busy shared machine
        "forkserver_warmup": "none" if group in IMPORT_PER_MUTANT else "collect",
        "process_isolation": "forkserver" if group in FORKSERVER_GROUPS else "fork",
    }  # fmt: skip
    return "\n[tool.mutmut]\n" + "".join(f"{key} = {json.dumps(value)}\n" for key, value in table.items())


def prepare(group: str, work: Path) -> Path:
    """A fresh copy of the project for one group, with its mutmut configuration."""
    target = work / group
    if target.exists():
        shutil.rmtree(target)
    target.mkdir(parents=True)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".venv", "mutants", "results")
    for name in COPIED:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, target / name, ignore=ignore)
        elif source.is_file():
            shutil.copy2(source, target / name)
    pyproject = (target / "pyproject.toml").read_text()
    pyproject = re.sub(r"\n\[tool\.mutmut\].*?(?=\n\[|\Z)", "", pyproject, flags=re.S)
    (target / "pyproject.toml").write_text(pyproject + mutmut_config(group))
    return target


def refresh(group: str, target: Path) -> Path:
    """An earlier work copy of ``group`` (its mutants already generated, its test statistics taken) with the current
    tests and mutmut configuration: mutmut then maps only the new tests before testing mutants."""
    for tests in (target / "tests", target / "mutants" / "tests"):
        shutil.rmtree(tests, ignore_errors=True)
        shutil.copytree(ROOT / "tests", tests, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    for pyproject in (target / "pyproject.toml", target / "mutants" / "pyproject.toml"):
        if pyproject.is_file():
            text = re.sub(r"\n\[tool\.mutmut\].*?(?=\n\[|\Z)", "", pyproject.read_text(), flags=re.S)
            pyproject.write_text(text + mutmut_config(group))
    return target


def mutmut(directory: Path, *args: str, log: Path | None = None) -> str:
    """Run mutmut in ``directory`` under nice, one torch/BLAS thread per process."""
    command = ["nice", "-n", "10", str(Path(sys.executable).with_name("mutmut")), *args]
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg", "SDL_VIDEODRIVER": "dummy",
           "SDL_AUDIODRIVER": "dummy", "PYTHONDONTWRITEBYTECODE": "1",
           "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1",
           "JAX_COMPILATION_CACHE_DIR": str(directory.parent / f"{directory.name}-xla"),
           "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0", "JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES": "0"}  # fmt: skip
    if log is None:
        return subprocess.run(command, cwd=directory, env=env, capture_output=True, text=True, check=False).stdout
    with log.open("w") as handle:
        subprocess.run(command, cwd=directory, env=env, stdout=handle, stderr=subprocess.STDOUT, check=False)
    return ""


STATUS = {1: "killed", 3: "killed", 0: "survived", 5: "no tests", 33: "no tests", 36: "timeout", -24: "timeout",
          24: "timeout", 152: "timeout", 255: "timeout", None: "not checked", 34: "skipped"}  # fmt: skip


def collect(group: str, directory: Path, names: list[str] | None = None) -> list[dict[str, Any]]:
    """The group's mutants (only ``names`` if given): name, file, status and (unless killed) the diff."""
    mutants = []
    for meta in sorted((directory / "mutants").rglob("*.py.meta")):
        source = str(meta.relative_to(directory / "mutants"))[: -len(".meta")]
        exit_codes = json.loads(meta.read_text())["exit_code_by_key"]
        for name, code in sorted(exit_codes.items()):
            if names is None or name in names:
                mutants.append({"name": name, "file": source, "status": STATUS.get(code, "suspicious")})
    for mutant in mutants:
        if mutant["status"] not in ("killed", "timeout", "not checked"):
            mutant["diff"] = diff_lines(mutmut(directory, "show", mutant["name"]))
    return mutants


def diff_lines(show: str) -> list[str]:
    """The changed lines of ``mutmut show``'s unified diff."""
    return [line for line in show.splitlines() if line[:1] in "+-" and not line.startswith(("+++", "---"))]


def mutant_key(mutant: dict[str, Any]) -> str:
    """A key of a mutant that survives renumbering: its file, function and changed lines."""
    function = mutant["name"].rsplit("__mutmut_", 1)[0].rsplit(".", 1)[-1]
    return f"{mutant['file']}:{function}: " + " / ".join(line.strip() for line in mutant.get("diff", []))


def score(mutants: list[dict[str, Any]], equivalent: dict[str, str]) -> dict[str, Any]:
    """Counts and the score (killed / non-equivalent) of a list of mutants."""
    counts: dict[str, int] = {}
    for mutant in mutants:
        mutant["equivalent"] = (
            equivalent.get(mutant_key(mutant)) if mutant["status"] not in ("killed", "timeout") else None
        )
        status = "equivalent" if mutant["equivalent"] else mutant["status"]
        counts[status] = counts.get(status, 0) + 1
    killed = counts.get("killed", 0) + counts.get("timeout", 0)
    relevant = len(mutants) - counts.get("equivalent", 0) - counts.get("not checked", 0)
    return {"mutants": len(mutants), **dict(sorted(counts.items())), "non_equivalent": relevant,
            "score": killed / relevant if relevant else float("nan")}  # fmt: skip


def all_names(directory: Path) -> list[str]:
    """Every mutant mutmut generated in a work copy."""
    return sorted(name for meta in (directory / "mutants").rglob("*.py.meta")
                  for name in json.loads(meta.read_text())["exit_code_by_key"])  # fmt: skip


def run(
    groups: list[str],
    work: Path,
    max_children: int,
    recheck: bool = False,
    collect_only: bool = False,
    sample: int = 0,
    seed: int = 0,
    reuse: bool = False,
) -> None:
    """Run mutmut on each group and store its mutants in the results JSON. With ``recheck``, only the mutants
    not killed in the last run are tested again, against the current tests (mutmut still generates all)."""
    for group in groups:
        began = time.perf_counter()
        log = work / f"{group}.log"
        directory = work / group if collect_only else refresh(group, work / group) if reuse else prepare(group, work)
        previous = json.loads(RESULTS.read_text())["groups"][group] if recheck else None
        names = (
            [m["name"] for m in previous["mutants"] if m["status"] not in ("killed", "timeout", "not checked")]
            if previous
            else []
        )
        print(f"{group}: mutmut in {directory} (log {log})" + (f", rechecking {len(names)}" if recheck else ""),
              flush=True)  # fmt: skip
        population = None
        if sample and not recheck and not collect_only:
            if reuse:  # the earlier copy's mutants stay; their statuses are tested afresh
                for meta in (directory / "mutants").rglob("*.py.meta"):
                    data = json.loads(meta.read_text())
                    data["exit_code_by_key"] = dict.fromkeys(data["exit_code_by_key"])
                    meta.write_text(json.dumps(data))
            # mutmut generates the mutants and maps tests to functions, then stops at the unknown name
            mutmut(directory, "run", "--max-children", str(max_children), "no_such_mutant", log=log)
            everything = all_names(directory)
            population = len(everything)
            names = sorted(random.Random(seed).sample(everything, min(sample, population)))
            print(f"{group}: a random sample of {len(names)} of its {population} mutants (seed {seed})", flush=True)
        if not collect_only:
            mutmut(directory, "run", "--max-children", str(max_children), *names, log=log)
        mutants = collect(group, directory, names if (recheck or population) else None)
        if not mutants:
            raise SystemExit(f"{group}: mutmut produced no mutants; see {log}")
        if all(m["status"] == "not checked" for m in mutants):  # e.g. a selected test that no longer exists
            raise SystemExit(f"{group}: mutmut tested no mutant (its clean test run failed?); see {log}")
        minutes = (time.perf_counter() - began) / 60.0
        if previous is not None:  # the killed mutants of the last run stand; the others take their new status
            rechecked = {m["name"]: m for m in mutants}
            mutants = [rechecked.get(m["name"], m) for m in previous["mutants"]]
            minutes += previous["minutes"]
        # read again just before writing: groups may run at the same time in separate processes
        results = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {"groups": {}}
        if previous is not None:
            population = previous.get("population")
        results["groups"][group] = {"files": GROUPS[group][0], "tests": GROUPS[group][1], "mutants": mutants,
                                    "minutes": minutes, "max_children": max_children,
                                    "population": population or len(mutants)}  # fmt: skip
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps(results, indent=1) + "\n")
        print(f"{group}: {len(mutants)} mutants in {minutes:.1f} min", flush=True)


def equivalent_mutants() -> dict[str, str]:
    """The mutants no test can tell from the original (their key -> why), from benchmarks/testing/."""
    return json.loads(EQUIVALENT.read_text()) if EQUIVALENT.is_file() else {}


def score_lines(results: dict[str, Any]) -> list[str]:
    """The docs block of the score: the estimate over every group, then one row per group."""
    equivalent = equivalent_mutants()
    rows, everything = [], []
    for group, data in results["groups"].items():
        summary = score(data["mutants"], equivalent)
        everything += data["mutants"]
        checked = summary["mutants"] - summary.get("not checked", 0)
        tested = f"{checked} of {data.get('population', summary['mutants'])}"
        rows.append(f"| {group} | {', '.join(f'`{f}`' for f in data['files'])} | {tested} | "
                    f"{summary.get('killed', 0) + summary.get('timeout', 0)} | {summary.get('equivalent', 0)} | "
                    f"{summary.get('survived', 0)} | {summary.get('no tests', 0)} | {100 * summary['score']:.1f} % | "
                    f"{data['minutes']:.0f} |")  # fmt: skip
    total = score(everything, equivalent)
    # each group's score stands for all of its mutants when a sample was tested: weight it by their number
    weights = {g: d.get("population", len(d["mutants"])) for g, d in results["groups"].items()}
    estimate = sum(score(d["mutants"], equivalent)["score"] * weights[g] for g, d in results["groups"].items())
    estimate /= sum(weights.values())
    return [
        f"**{100 * estimate:.1f} %** of the non-equivalent mutants of the named modules are killed, estimated as the",
        f"groups' scores weighted by their numbers of mutants ({sum(weights.values())}); of the mutants tested,",
        f"{100 * total['score']:.1f} % of the {total['non_equivalent']} non-equivalent ones are killed "
        f"({total['mutants'] - total.get('not checked', 0)} mutants tested, {total.get('equivalent', 0)} of them "
        "equivalent).",
        "",
        "| group | files | mutants tested | killed | equivalent | survived | no test runs it | score | minutes |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
    ]


def survivor_lines(results: dict[str, Any]) -> list[str]:
    """The docs block of every mutant tested and not killed that is not equivalent (the equivalent ones are listed with
    their reasons in ``mutation_equivalent.json``): its status and its change."""
    equivalent = equivalent_mutants()
    lines = ["| mutant | status | change |", "|---|---|---|"]
    for data in results["groups"].values():
        score(data["mutants"], equivalent)  # marks each mutant's "equivalent"
        for mutant in data["mutants"]:
            if mutant["status"] not in ("killed", "timeout", "not checked") and not mutant["equivalent"]:
                change = " / ".join(line.strip() for line in mutant.get("diff", [])).replace("|", "\\|")
                lines.append(f"| `{mutant['name']}` | {mutant['status']} | `{change}` |")
    return lines


def markdown(lines: Any) -> Any:
    """A block of Markdown lines (a newline, the lines, a newline) from a function of the JSON."""
    return lambda data: "\n" + "\n".join(lines(data)) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("mutation", __doc__)
    parser.add_argument("--groups", nargs="+", choices=list(GROUPS), default=list(GROUPS))
    parser.add_argument("--work", type=Path, default=Path("/tmp/dwr-gym-mutation"))
    parser.add_argument("--max-children", type=int, default=1, help="mutants tested at once (default 1 core)")
    parser.add_argument(
        "--docs", action="store_true", help="(the JSON is always written; renders docs/testing.md's blocks)"
    )
    parser.add_argument("--collect-only", action="store_true",
                        help="only read the results of an earlier (or interrupted) run from its work copy")  # fmt: skip
    parser.add_argument("--sample", type=int, default=0,
                        help="test a seeded random sample of this many mutants per group (0: all)")  # fmt: skip
    parser.add_argument("--seed", type=int, default=0, help="seed of --sample")
    parser.add_argument(
        "--reuse",
        action="store_true",
        help="keep each group's earlier work copy (its mutants and test statistics), with the current tests",
    )
    parser.add_argument("--recheck", action="store_true",
                        help="test only the mutants not killed last time, against the current tests")  # fmt: skip
    args = parser.parse_args(argv)
    if shutil.which("mutmut", path=str(Path(sys.executable).parent)) is None:
        raise SystemExit('mutmut is not installed: pip install "dwr-gym[mutation]"')
    run(args.groups, args.work, args.max_children, args.recheck, args.collect_only, args.sample, args.seed, args.reuse)


BLOCKS = (Block("mutation-score", "docs/testing/mutation.json", markdown(score_lines), Schema({"groups": dict})),
          Block("mutants-not-killed", "docs/testing/mutation.json", markdown(survivor_lines), Schema({"groups": dict})))  # fmt: skip
