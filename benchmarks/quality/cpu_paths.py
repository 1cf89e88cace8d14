"""Whether `dwr-gym compare`'s published tables depend on the CPU: compare on this CPU against compare on the oldest
x86-64 CPU, emulated by turning this one's features off.

    python -m benchmarks run compare-time --cache cold --busy 0 --out results/compare-portable
    dwr-gym compare --code-paths native --out results/compare-native        # with an empty DWR_GYM_CACHE
    nice -n 10 python -m benchmarks run compare-cpu-paths --portable results/compare-portable \
        --native results/compare-native --docs

numpy, glibc's libm, MKL and torch pick their kernels by the CPU's features (numpy's arctan2, arcsin and tanh on AVX2
and AVX-512, libm's sin, cos and arctan2 under FMA, MKL's matrix products); their results differ in the last bits,
and the closed loops and the planners' searches start from those bits. This runs ``dwr-gym compare --code-paths
native`` (an empty cache, as a fresh clone) with every feature above each library's baseline turned off: numpy's
dispatched ones (``NPY_DISABLE_CPU_FEATURES``), libm's AVX2, FMA, AVX and SSE4 variants (``GLIBC_TUNABLES``), MKL's
code path pinned (``MKL_CBWR=COMPATIBLE``), oneDNN's and torch's own kernels at their baseline (``ONEDNN_MAX_CPU_ISA``,
``ATEN_CPU_CAPABILITY=default``): what a CPU with none of them computes. Each reference run's rows are compared with
it, every cell as the docs' tables print it (success and arrival in %, heading and energy to 3 decimals, E/opt to 2
and its worst to 1): ``--portable`` (compare's default code paths, train/code_paths.py: the claim is that none differ)
and ``--native`` (this CPU's fastest kernels: what differs without the pin). Records the cells that differ in
``docs/compare/cpu_paths.json``.
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
#: A row's wall times: the only values of a row that depend on the machine's speed.
TIMINGS = ("seconds", "optimum_seconds")
#: A row's cells as the docs' tables print them (train.reporting.doc_tables): field -> format.
PRINTED = {"success_rate": "%", "arrival_rate": "%", "final_heading_error_mean": ".3f", "energy_mean": ".3f",
           "energy_ratio_mean": ".2f", "energy_ratio_max": ".1f"}  # fmt: skip


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


#: libm's CPU variants: the oldest x86-64 CPU has none of them.
LIBM_FEATURES = ("AVX2", "FMA", "AVX", "SSE4_1", "SSE4_2", "SSSE3")


def oldest_cpu_environment() -> dict[str, str]:
    """The switches that make this CPU compute as an x86-64 CPU without any feature above the libraries' baselines."""
    from train.code_paths import FIXED, numpy_dispatched_features

    return {"NPY_DISABLE_CPU_FEATURES": numpy_dispatched_features(), **FIXED,
            "GLIBC_TUNABLES": f"glibc.cpu.hwcaps={','.join(f'-{f}{s}' for f in LIBM_FEATURES for s in ('', '_Usable'))}"}  # fmt: skip


def run_changed(out: Path) -> tuple[dict[str, str], float]:
    """``dwr-gym compare --code-paths native --out OUT`` in a fresh clone's state on the oldest x86-64 CPU (emulated);
    the switches it had and its wall seconds."""
    from train.code_paths import MARK

    changed = oldest_cpu_environment()
    with tempfile.TemporaryDirectory() as tmp:
        env, began = checkout_env(DWR_GYM_CACHE=f"{tmp}/cache", **changed), time.perf_counter()
        env.pop(MARK, None)
        subprocess.run([sys.executable, "-m", "train.cli", "compare", "--code-paths", "native", "--out", str(out),
                        "--no-progress"], cwd=tmp, env=env, check=True, stdout=subprocess.DEVNULL)  # fmt: skip
    return changed, time.perf_counter() - began


def against(reference_dir: Path, changed: list[dict[str, Any]]) -> dict[str, Any]:
    """The printed cells of ``reference_dir``'s comparison.json that differ from the changed run's."""
    reference = json.loads((reference_dir / "comparison.json").read_text())
    differ = differences(reference, changed)
    ours, theirs = exact_values(reference), exact_values(changed)
    return {"rows": len(reference), "cells": len(cells(reference)), "cells_that_differ": len(differ),
            "rows_that_differ": len({k.rsplit(" / ", 1)[0] for k in differ}), "values": len(ours),
            "values_not_equal_bit_for_bit": sum(ours.get(k) != theirs.get(k) for k in ours),
            "differences": differ}  # fmt: skip


def exact_values(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Every value of the rows but the timings, by ``set / T_con / policy / field``, as written (not rounded)."""
    return {f"{r['scenario']} / {r['T_con']} / {r['policy']} / {k}": v for r in rows for k, v in r.items()
            if k not in TIMINGS}  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = parser_for("compare-cpu-paths", __doc__)
    parser.add_argument(
        "--portable", type=Path, help="a compare output folder of this CPU, compare's default code paths"
    )
    parser.add_argument("--native", type=Path, help="a compare output folder of this CPU, --code-paths native")
    parser.add_argument("--out", type=Path, help="keep the changed run's output there (default: a temporary folder)")
    parser.add_argument("--docs", action="store_true", help=f"write {JSON_PATH.relative_to(ROOT)}")
    args = parser.parse_args(argv)
    references = {name: folder for name, folder in (("portable", args.portable), ("native", args.native)) if folder}
    if not references:
        parser.error("--portable and --native are both missing: give at least one compare output folder")
    for name, folder in references.items():
        if not (folder / "comparison.json").is_file():
            parser.error(f"--{name}={folder} is invalid: expected a compare output folder with comparison.json")
    with tempfile.TemporaryDirectory() as tmp:
        out = (args.out or Path(tmp) / "changed").resolve()
        changed_env, seconds = run_changed(out)
        changed = json.loads((out / "comparison.json").read_text())
    result: dict[str, Any] = {"cpu": cpu_model(), "changed": changed_env, "wall_seconds": round(seconds, 1),
                              "load_average_1min_at_end": load_average()}  # fmt: skip
    print(f"the oldest x86-64 CPU (emulated): compare took {seconds / 60:.1f} min")
    for name, folder in references.items():
        result[name] = against(folder, changed)
        found = result[name]
        print(f"{name}: {found['cells_that_differ']} of {found['cells']} printed cells differ "
              f"({found['rows_that_differ']} of {found['rows']} rows); {found['values_not_equal_bit_for_bit']} of "
              f"{found['values']} values not bit for bit")  # fmt: skip
        for cell, (ours, theirs) in found["differences"].items():
            print(f"  {cell}: {ours} -> {theirs}")
    if args.docs:
        write_json(JSON_PATH, result)
