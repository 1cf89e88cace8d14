"""Ship which guess wins each planner plan of `dwr-gym compare`'s defaults (baselines/plan_hints.npz), or check it.

    python -m benchmarks run ship-plan-hints            # compare's whole search, its winners written to the file
    python -m benchmarks run ship-plan-hints --check    # the same search, every winner compared with the shipped one
    python -m benchmarks run ship-plan-hints --merge    # the check, then this machine's winners added to the file

Runs ``dwr-gym compare`` with its defaults as a user would, in a fresh process, with every plan solved by the whole
search of its guesses (no plan store: ``DWR_GYM_PLAN_CACHE=0``; no hints: ``DWR_GYM_PLAN_HINTS=0``), each solving
process writing the winner of every search of more than one guess (``DWR_GYM_PLAN_HINTS_RECORD``). The file records
the solver's digest (:func:`baselines.plan_hints.solver_digest`): a changed solver reads none of it until this runs
again (tests/test_plan_hints.py says so). About 8 minutes on 2 cores.

Why ``--merge``: a hint is keyed by its job to 10 significant digits (:func:`baselines.plan_hints.hint_key`), which
holds across CPUs for the laws' planners, but the jobs of the ``robust`` agent's planner start from poses its float32
torch network steered there, whose outputs differ in the 7th digit between CPUs (MKL picks its kernels by processor).
So the winners recorded on one machine name few of that agent's searches on another. ``--merge`` checks every winner
both machines met and keeps the union: the file then serves each machine it was recorded on.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

from benchmarks.core.commands import checkout_env, dwr_gym, parser_for

if TYPE_CHECKING:
    from baselines.plan_hints import Hint


def recorded_winners() -> dict[bytes, Hint]:
    """The winner of every whole search ``dwr-gym compare`` solves with its defaults, by key prefix."""
    from baselines.plan_hints import RECORD, SWITCH, read_recorded

    with tempfile.TemporaryDirectory() as tmp:
        record = Path(tmp) / "winners"
        record.mkdir()
        env = checkout_env(DWR_GYM_PLAN_CACHE="0", **{SWITCH: "0", RECORD: str(record)})
        dwr_gym(["compare", "--no-progress", "--out", f"{tmp}/out"], cwd=tmp, env=env)
        return read_recorded(record)


def check(shipped: dict[bytes, Hint], recorded: dict[bytes, Hint]) -> list[str]:
    """What differs between the shipped winners and those just recorded (empty: the file is right)."""
    wrong = [key.hex() for key in recorded if key in shipped and shipped[key] != recorded[key]]
    missing, extra = recorded.keys() - shipped.keys(), shipped.keys() - recorded.keys()
    lines = [f"{key}: shipped guess {shipped[bytes.fromhex(key)]}, the search keeps {recorded[bytes.fromhex(key)]}"
             for key in wrong]  # fmt: skip
    if missing:
        lines.append(f"{len(missing)} searches have no shipped hint (they search every guess: slower, not wrong)")
    if extra:
        lines.append(f"{len(extra)} shipped hints name no search compare solves now")
    return lines


def main(argv: list[str] | None = None) -> None:
    import casadi

    from baselines.plan_hints import HINTS_PATH, read_hints, solver_digest, write_hints

    parser = parser_for("ship-plan-hints", __doc__)
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true", help="compare with the shipped file instead of writing it")
    mode.add_argument("--merge", action="store_true",
                      help="compare with the shipped file, then write it with this machine's winners added")  # fmt: skip
    args = parser.parse_args(argv)
    recorded = recorded_winners()
    if not args.check and not args.merge:
        write_hints(HINTS_PATH, solver_digest(), casadi.__version__, recorded)
        print(f"wrote {HINTS_PATH.name}: {len(recorded)} plans' winning guesses ({HINTS_PATH.stat().st_size:,} bytes)")
        return
    solver, _, shipped = read_hints(HINTS_PATH)
    lines = [] if solver == solver_digest() else [f"recorded with solver {solver}, this one is {solver_digest()}"]
    lines += check(shipped, recorded)
    for line in lines:
        print(line)
    wrong = any(": shipped guess" in line or line.startswith("recorded with") for line in lines)
    print(f"{len(recorded)} searches, {len(shipped)} shipped hints: {'WRONG' if wrong else 'every shipped hint right'}")
    if wrong:
        sys.exit(1)
    if args.merge:
        merged = {**shipped, **recorded}
        write_hints(HINTS_PATH, solver_digest(), casadi.__version__, merged)
        print(f"wrote {HINTS_PATH.name}: {len(merged)} plans' winning guesses, {len(merged) - len(shipped)} of them "
              f"new ({HINTS_PATH.stat().st_size:,} bytes)")  # fmt: skip
