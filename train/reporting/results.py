"""Rows of results as files: CSV for spreadsheets, JSON (NaN as null) for scripts and the docs' tables."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any


def json_safe(value: Any) -> Any:
    """``value`` with NaN and inf as null (bare NaN is not JSON) and numpy scalars as Python numbers."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_results(rows: list[dict[str, Any]], out_dir: str | Path, stem: str) -> list[str]:
    """Write rows as CSV and JSON into ``out_dir``; returns the paths written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, json_path = out / f"{stem}.csv", out / f"{stem}.json"
    with csv_path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    json_path.write_text(json.dumps(json_safe(rows), indent=2, allow_nan=False) + "\n")
    return [str(csv_path), str(json_path)]
