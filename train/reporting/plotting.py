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


def legend_outside(ax: Any, below: bool = False, **kwargs: Any) -> None:
    """The legend to the right of ``ax`` (or below it), outside the plotted data."""
    place = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.2)} if below else {
        "loc": "upper left", "bbox_to_anchor": (1.02, 1.0)}  # fmt: skip
    ax.legend(borderaxespad=0.0, **place, **{"fontsize": 8, **kwargs})


def save(fig: Any, path: Path, dpi: int = 120) -> None:
    """Lay out, write (legends outside the axes included) and close a figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    pyplot().close(fig)
