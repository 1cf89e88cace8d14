"""What a benchmark records beside its numbers (the machine, the libraries, the load), and its JSON."""

from __future__ import annotations

import json
import os
import platform
from pathlib import Path
from typing import Any


def torch_machine() -> str:
    """ "<arch>, <cores> cores, torch <version>": the machine line of the training benchmarks."""
    import torch

    return f"{platform.machine()}, {os.cpu_count()} cores, torch {torch.__version__}"


def cpu_model() -> str:
    """The processor's model name (Linux's /proc/cpuinfo; else what the platform module says, or "unknown")."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def load_average() -> float:
    """The 1-minute load average now, to two decimals."""
    return round(os.getloadavg()[0], 2)


def write_json(path: Path, data: Any, *, safe: bool = False) -> None:
    """``data`` as indented JSON at ``path`` (its folder made); ``safe``: NaN and inf written as null."""
    if safe:
        from train.reporting.results import json_safe

        data = json_safe(data)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1, allow_nan=not safe) + "\n")
    print(f"wrote {path}")


def report(lines: list[str], data: Any, path: Path | None) -> int:
    """Print a benchmark's report ``lines``; write ``data`` as JSON at ``path`` unless it is None (no ``--docs``)."""
    print("\n".join(lines))
    if path is not None:
        write_json(path, data)
    return 0
