"""The numerical libraries' code paths pinned to those every x86-64 CPU runs, so that ``compare``'s and ``evaluate``'s
tables are the same on any such CPU.

numpy, glibc's libm, MKL, oneDNN and torch each choose a kernel by what the CPU offers (AVX2, FMA, AVX-512): numpy's
``arctan2``, ``arcsin`` and ``tanh`` and libm's ``sin`` and ``cos`` under FMA, the networks' matrix products in MKL.
Their results differ from one kernel to the next in the last bits, and the closed loops and the planners' searches
start from those bits: on another CPU a few cells of the tables differed as printed (docs/results.md). Each library
has a switch read once, when the process starts (or when the library loads), which limits it to its baseline code:

- ``NPY_DISABLE_CPU_FEATURES``: every dispatched feature this CPU has (numpy's baseline, SSE to SSE4.2, is compiled in);
- ``GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA``: libm's SSE2 variants (the ``_Usable`` spellings for glibc < 2.33);
- ``MKL_CBWR=COMPATIBLE``: MKL's conditional numerical reproducibility, the same bits on any CPU;
- ``ONEDNN_MAX_CPU_ISA=SSE41`` and ``ATEN_CPU_CAPABILITY=default``: torch's own kernels at their default level.

So the command line re-runs ``compare`` and ``evaluate`` once, before anything is computed, in a process with these set
(:func:`pin`; ``--code-paths native`` keeps the machine's own). A Python caller of ``train.cli.main(argv)`` keeps its
process's paths: set :func:`portable_environment` before starting Python to pin them. What this does not reach: another
glibc or library version (other code, not another path), and CPUs other than x86-64.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping

#: Set in the environment of a process whose code paths are pinned (and of its children).
MARK = "DWR_GYM_CODE_PATHS"
#: ``--code-paths``: the pinned kernels (the default) or the machine's own.
CODE_PATHS = ("portable", "native")
#: libm's CPU variants off: glibc >= 2.33 names them AVX2 and FMA, older ones AVX2_Usable and FMA_Usable (an unknown
#: name is ignored).
HWCAPS = "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX2_Usable,-FMA_Usable"
FIXED = {"MKL_CBWR": "COMPATIBLE", "ONEDNN_MAX_CPU_ISA": "SSE41", "ATEN_CPU_CAPABILITY": "default"}


def numpy_dispatched_features() -> str:
    """numpy's dispatched features this CPU has, space-separated (``X86_V3 X86_V4 ...``; empty at numpy's baseline)."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    return " ".join(name for name in __cpu_dispatch__ if __cpu_features__.get(name))


def glibc_tunables(current: str | None) -> str:
    """``current`` (``GLIBC_TUNABLES``, colon-separated) with libm's CPU variants turned off, its other tunables kept."""
    kept = [t for t in (current or "").split(":") if t and not t.startswith("glibc.cpu.hwcaps=")]
    return ":".join([*kept, HWCAPS])


def portable_environment(environ: Mapping[str, str] | None = None) -> dict[str, str]:
    """``environ`` (default: this process's) with the code paths pinned to every x86-64 CPU's: the variables above set,
    overriding what was there, and :data:`MARK` set to ``portable``."""
    env = dict(os.environ if environ is None else environ)
    features = numpy_dispatched_features()
    if features:
        env["NPY_DISABLE_CPU_FEATURES"] = features
    else:
        env.pop("NPY_DISABLE_CPU_FEATURES", None)
    env["GLIBC_TUNABLES"] = glibc_tunables(env.get("GLIBC_TUNABLES"))
    return {**env, **FIXED, MARK: "portable"}


def pinned(environ: Mapping[str, str] | None = None) -> bool:
    """Whether this process (or ``environ``) already runs on the pinned code paths (marked, and the switches set)."""
    env = os.environ if environ is None else environ
    return env.get(MARK) == "portable" and all(env.get(k) == v for k, v in FIXED.items())


def describe() -> str:
    """This process's code paths in words, as ``compare`` and ``evaluate`` print them."""
    if pinned():
        return "portable (numpy, libm, MKL and torch on every x86-64 CPU's kernels: the same tables on any such CPU)"
    return "native (this CPU's fastest kernels: on another CPU a few last digits may differ; --code-paths portable)"


def pin(argv: list[str]) -> None:
    """Replace this process by ``python -m train.cli ARGV`` on the pinned code paths, unless it runs on them already
    (then return). Nothing has been computed yet: the command starts over, same arguments, same output."""
    if pinned() or os.name != "posix":  # exec replaces the process only on POSIX systems
        return
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(sys.executable, [sys.executable, "-m", "train.cli", *argv], portable_environment())


__all__ = ["CODE_PATHS", "MARK", "describe", "numpy_dispatched_features", "pin", "pinned", "portable_environment"]
