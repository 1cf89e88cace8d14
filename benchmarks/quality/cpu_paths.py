"""Whether `dwr-gym compare`'s published tables depend on the CPU: compare run with numpy's and MKL's code paths changed.

    python -m benchmarks run compare-time --cache cold --busy 0 --out results/compare-here     # this CPU as it is
    nice -n 10 python -m benchmarks run compare-cpu-paths --reference results/compare-here --docs

A fresh clone on another x86 CPU differs from this one where numpy and MKL pick other SIMD kernels (numpy's sines and
cosines, torch's matrix products in MKL): their results differ in the last bits, and the closed loops and the planners'
searches start from those bits. This runs ``dwr-gym compare`` (an empty cache, as a fresh clone) with numpy's
dispatched code limited (``NPY_DISABLE_CPU_FEATURES``, every feature this CPU has above the baseline), MKL's code path
pinned (``MKL_CBWR=COMPATIBLE``) and torch's own kernels at their default level (``ATEN_CPU_CAPABILITY=default``), and
compares each row of its ``comparison.json`` with the reference run's, every cell as the docs' tables print it
(success and arrival in %, heading and energy to 3 decimals, E/opt to 2 and its worst to 1). It records the cells that
differ in ``docs/compare/cpu_paths.json``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.core.commands import checkout_env, parser_for
from benchmarks.core.record import cpu_model, load_average, write_json

ROOT = Path(__file__).resolve().parents[2]
JSON_PATH = ROOT / "docs" / "compare" / "cpu_paths.json"
#: A row's cells as the docs' tables print them (train.reporting.doc_tables): field -> format.
PRINTED = {"success_rate": "%", "arrival_rate": "%", "final_heading_error_mean": ".3f", "energy_mean": ".3f",
           "energy_ratio_mean": ".2f", "energy_ratio_max": ".1f"}  # fmt: skip


def numpy_features_above_baseline() -> str:
    """The dispatched numpy features this CPU has (``X86_V3 X86_V4 ...``): the ones a CPU without them would not use."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    return " ".join(name for name in __cpu_dispatch__ if __cpu_features__.get(name))


def printed(value: Any, fmt: str) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "-"
    return f"{100 * value:.3g} %" if fmt == "%" else format(value, fmt)


def cells(rows: list[dict[str, Any]]) -> dict[str, str]:
    """Every printed cell of the rows, by ``set / T_con / policy / field``."""
    return {f"{r['scenario']} / {r['T_con']} / {r['policy']} / {field}": printed(r.get(field), fmt)
            for r in rows for field, fmt in PRINTED.items()}  # fmt: skip


def differences(reference: list[dict[str, Any]], changed: list[dict[str, Any]]) -> dict[str, list[str]]:
    """The cells whose printed values differ between two runs: cell -> [reference, changed]."""
    ours, theirs = cells(reference), cells(changed)
    return {k: [ours.get(k, "absent"), theirs.get(k, "absent")] for k in sorted(set(ours) | set(theirs))
            if ours.get(k) != theirs.get(k)}  # fmt: skip


def run_changed(out: Path) -> tuple[dict[str, str], float]:
    """``dwr-gym compare --out OUT`` in a fresh clone's state with the code paths changed (the second CPU); the
    environment it had and its wall seconds."""
    changed = {"NPY_DISABLE_CPU_FEATURES": numpy_features_above_baseline(), "MKL_CBWR": "COMPATIBLE",
               "ATEN_CPU_CAPABILITY": "default"}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        env, began = checkout_env(DWR_GYM_CACHE=f"{tmp}/cache", **changed), time.perf_counter()
        subprocess.run([sys.executable, "-m", "train.cli", "compare", "--out", str(out), "--no-progress"], cwd=tmp,
                       env=env, check=True, stdout=subprocess.DEVNULL)  # fmt: skip
    return changed, time.perf_counter() - began


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("compare-cpu-paths", __doc__)
    parser.add_argument("--reference", type=Path, required=True,
                        help="a compare output folder of this CPU as it is (compare-time --out DIR)")  # fmt: skip
    parser.add_argument("--out", type=Path, help="keep the changed run's output there (default: a temporary folder)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)}")
    args = parser.parse_args(argv)
    reference_file = args.reference / "comparison.json"
    if not reference_file.is_file():
        parser.error(f"--reference={args.reference} is invalid: expected a compare output folder with comparison.json")
    reference = json.loads(reference_file.read_text())
    with tempfile.TemporaryDirectory() as tmp:
        out = (args.out or Path(tmp) / "changed").resolve()
        changed_env, seconds = run_changed(out)
        changed = json.loads((out / "comparison.json").read_text())
    differ = differences(reference, changed)
    result = {"cpu": cpu_model(), "changed": changed_env, "wall_seconds": round(seconds, 1),
              "load_average_1min_at_end": load_average(),
              "rows": len(reference), "cells": len(cells(reference)), "cells_that_differ": len(differ),
              "rows_that_differ": len({k.rsplit(" / ", 1)[0] for k in differ}), "differences": differ}  # fmt: skip
    print(f"{result['cells_that_differ']} of {result['cells']} printed cells differ ({result['rows_that_differ']} of "
          f"{result['rows']} rows); the changed run took {seconds / 60:.1f} min")  # fmt: skip
    for cell, (ours, theirs) in differ.items():
        print(f"  {cell}: {ours} -> {theirs}")
    if args.docs:
        write_json(JSON_PATH, result)
