"""The two matplotlib chores shared by ``reproduce`` and ``compare``: a headless pyplot, and saving a figure."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def pyplot() -> Any:
    """matplotlib.pyplot on the non-interactive Agg backend, with the install hint if it is missing."""
    try:
        import matplotlib
    except ImportError as error:
        raise ImportError('matplotlib is needed for figures: pip install "dwr-gym[plots]"') from error
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig: Any, path: Path, dpi: int = 120) -> None:
    """Lay out, write and close a figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)
