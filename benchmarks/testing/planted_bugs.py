"""Plant each bug of the audits (realistic slips) in a copy of the tree, run the test suite there, and record what fails.

    python -m benchmarks run planted-bugs              # every bug, one suite run each (~5 min each on 2 cores)
    python -m benchmarks run planted-bugs --bugs sinc_1_over_24
    python -m benchmarks run planted-bugs --bugs truncated_is_terminated --tests tests/test_sb3.py  # only these tests
    python -m benchmarks run planted-bugs --targeted   # each slip with its targeted tests (a minute each)

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

#: bug -> what it does, the file, the text replaced ("old") and its replacement ("new"), and for ``--targeted`` the tests
#: that name its module and catch it in a minute ("targeted"; the default suite otherwise): a data file beside this one.
BUGS: dict[str, dict[str, Any]] = json.loads(Path(__file__).with_suffix(".json").read_text())


def plant(bug: str, work: Path) -> Path:
    """A copy of HEAD with ``bug`` planted."""
    path, old, new = (BUGS[bug][key] for key in ("file", "old", "new"))
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
                        help="run each bug with its targeted tests (a minute each) instead of the suite")  # fmt: skip
    parser.add_argument("--docs", action="store_true", help="(the JSON is always written; renders its table)")
    args = parser.parse_args(argv)
    results = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    for bug in args.bugs:
        tests = BUGS[bug].get("targeted", args.tests) if args.targeted else args.tests
        failed, last = run_suite(plant(bug, args.work), tests)
        independent = [test for test in failed if not PINNED.search(test)]
        results[bug] = {"description": BUGS[bug]["what"], "file": BUGS[bug]["file"], "failed": failed,
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
