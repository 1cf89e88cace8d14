"""The portable code paths: what ``compare`` and ``evaluate`` pin, and that the pinned kernels give the same bits when the
CPU offers less (the tables' claim: the same on any x86-64 CPU)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys

import pytest

from train.code_paths import FIXED, HWCAPS, MARK, numpy_dispatched_features, pinned, portable_environment

#: The bits of the kernels the env's step and the planners use, as a digest per function.
PROBE = """
import hashlib, json, numpy as np
rng = np.random.default_rng(0)
x, y, u = rng.normal(size=20_000) * 3, rng.normal(size=20_000) * 3, rng.uniform(-1, 1, 20_000)
fns = {"arctan2": lambda: np.arctan2(y, x), "arcsin": lambda: np.arcsin(u), "tanh": lambda: np.tanh(x),
       "sin": lambda: np.sin(10 * x), "cos": lambda: np.cos(10 * x), "exp": lambda: np.exp(x)}
print(json.dumps({k: hashlib.md5(f().tobytes()).hexdigest() for k, f in fns.items()}))
"""
x86 = pytest.mark.skipif(platform.machine().lower() not in ("x86_64", "amd64"), reason="x86-64 code paths")


def bits(env: dict[str, str]) -> dict[str, str]:
    result = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def test_portable_environment_sets_every_switch_and_keeps_other_tunables() -> None:
    env = portable_environment({"GLIBC_TUNABLES": "glibc.malloc.check=3:glibc.cpu.hwcaps=-AVX512F", "HOME": "/h"})
    assert env["HOME"] == "/h" and env[MARK] == "portable" and pinned(env) and not pinned({"HOME": "/h"})
    assert {k: env[k] for k in FIXED} == FIXED
    assert env["GLIBC_TUNABLES"].split(":") == ["glibc.malloc.check=3", HWCAPS]
    assert HWCAPS == "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX2_Usable,-FMA_Usable"
    assert env.get("NPY_DISABLE_CPU_FEATURES", "") == numpy_dispatched_features()


@x86
def test_pinned_kernels_give_the_same_bits_on_a_cpu_that_offers_less() -> None:
    """A CPU without AVX, SSE4.1 or SSE4.2 for glibc's libm (the oldest x86-64 below the pin) computes what the pinned
    paths compute here: the pin leaves nothing that depends on the CPU's features to these kernels."""
    portable = portable_environment()
    lesser = {**portable, "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-SSE4_1,-SSE4_2,-SSSE3,-AVX2_Usable,"
              "-FMA_Usable,-AVX_Usable"}  # fmt: skip
    assert bits(portable) == bits(lesser)


@x86
def test_the_pin_reaches_numpy_and_libm() -> None:
    """On a CPU with FMA or numpy kernels above its baseline, the pinned bits differ from the native ones: the switches
    are read (a switch a library ignored would leave the native bits)."""
    if not numpy_dispatched_features():
        pytest.skip("this CPU runs numpy's baseline: nothing to pin")
    native = {k: v for k, v in portable_environment().items() if k not in (*FIXED, MARK, "NPY_DISABLE_CPU_FEATURES")}
    native.pop("GLIBC_TUNABLES")
    assert bits(native) != bits(portable_environment())


def test_compare_offers_native_and_portable_code_paths() -> None:
    from train.cli import build_parser

    parser = build_parser()
    assert parser.parse_args(["compare"]).code_paths == "portable"
    assert parser.parse_args(["evaluate", "--code-paths", "native"]).code_paths == "native"
    with pytest.raises(SystemExit):
        parser.parse_args(["compare", "--code-paths", "fast"])


@pytest.mark.parametrize("choice", ["portable", "native"])
def test_the_command_line_runs_evaluate_on_the_code_paths_asked(tmp_path, choice: str) -> None:
    """``dwr-gym evaluate`` re-runs itself once on the pinned paths (or not, with ``native``) and says which it ran on."""
    env = {k: v for k, v in os.environ.items() if k != MARK}
    result = subprocess.run([sys.executable, "-m", "train.cli", "evaluate", "--controllers", "ptc", "--scenarios",
                             "paper-fig5", "--optimum", "none", "--no-progress", "--code-paths", choice, "--out",
                             str(tmp_path)], env=env, capture_output=True, text=True, check=True)  # fmt: skip
    assert f"code paths: {choice} (" in result.stdout
    assert (tmp_path / "evaluation.json").is_file()
