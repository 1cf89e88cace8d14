"""What every figure shares: a headless pyplot, one colour and marker per policy, labelled reference lines,
legends outside the data, and byte-stable files.

A figure is saved at exactly its ``figsize`` times ``dpi`` (constrained layout makes room for the legends
outside the axes; no tight bounding box, whose size drifts with the text), without the matplotlib version in
its metadata, so the same inputs give the same bytes.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

#: A colour-blind-safe palette: Okabe and Ito's eight colours, then four of Paul Tol's (muted), yellow last
#: (it is the faintest on white).
PALETTE = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#882255", "#44AA99",
           "#999933", "#332288", "#F0E442")  # fmt: skip
MARKERS = ("o", "s", "^", "D", "v", "P", "*", "X", "<", ">", "h", "p", "d", "H")
#: Fixed places in the palette for the policies dwr-gym ships, so that each looks the same in every figure.
KNOWN_POLICIES = ("ptc", "fabregas", "astolfi", "pt-astolfi", "fixed-time", "apg-v2", "optimal", "es-v1",
                  "apg-residual-ptc-v2", "conventional-ptc", "ppo-jax-v1", "robust", "robust-pt", "residual-ppo",
                  "ppo")  # fmt: skip
#: Markers drawn along a line of many points: about this many per line, staggered between lines.
MARKS_PER_LINE = 8


def pyplot() -> Any:
    """matplotlib.pyplot on the non-interactive Agg backend, with the install hint if it is missing."""
    try:
        import matplotlib
    except ImportError as error:
        raise ImportError('matplotlib is needed for figures: pip install "dwr-gym[plots]"') from error
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: Axis labels: the quantity, then its unit in brackets ([-] where it has none).
TIME = "time t [s]"
SUCCESS = "success by T_con [fraction of episodes]"
HEADING_ERROR = "final heading error |psi - psi_d| [rad]"
ENERGY = "energy [m^2/s + rad^2/s]"


def styles(labels: Iterable[str]) -> dict[str, dict[str, Any]]:
    """A distinct colour and marker for each label: the shipped policies keep their own, others take the rest."""
    labels = list(dict.fromkeys(labels))
    places = {label: KNOWN_POLICIES.index(label) for label in labels if label in KNOWN_POLICIES}
    free = iter(i for i in range(len(PALETTE) * 4) if i not in places.values())
    for label in labels:
        if label not in places:
            places[label] = next(free)
    return {label: style(place, len(labels)) for label, place in places.items()}


def style(place: int, count: int = 1) -> dict[str, Any]:
    """The line style of palette place ``place``; past the palette the same colours repeat with dashes."""
    linestyle = ("-", "--", "-.", ":")[place // len(PALETTE) % 4]
    return {"color": PALETTE[place % len(PALETTE)], "marker": MARKERS[place % len(MARKERS)], "linestyle": linestyle,
            "markersize": 5}  # fmt: skip


def marked(style_: dict[str, Any], points: int, place: int = 0) -> dict[str, Any]:
    """``style_`` with its markers spread along a line of ``points`` points (staggered by ``place``)."""
    step = max(1, points // MARKS_PER_LINE)
    return {**style_, "markevery": (place * step // 7 % step, step)}


def reference_line(ax: Any, value: float, label: str, vertical: bool = True, **kwargs: Any) -> Any:
    """A labelled reference line (a deadline, a threshold): grey and dashed unless told otherwise."""
    options = {"color": "0.35", "linestyle": "--", "linewidth": 1.0, "label": label, "zorder": 1, **kwargs}
    return ax.axvline(value, **options) if vertical else ax.axhline(value, **options)


def figure_legend(fig: Any, title: str | None = None, **kwargs: Any) -> Any:
    """One legend for the whole figure, right of the axes (constrained layout makes room), one entry per label."""
    entries: dict[str, Any] = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    return fig.legend(list(entries.values()), list(entries), loc="outside right upper", title=title,
                      **{"fontsize": 8, **kwargs})  # fmt: skip


def legend_outside(ax: Any, below: bool = False, **kwargs: Any) -> None:
    """The legend of one axes to its right (or below it), outside the plotted data."""
    place = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.15)} if below else {
        "loc": "upper left", "bbox_to_anchor": (1.02, 1.0)}  # fmt: skip
    ax.legend(borderaxespad=0.0, **place, **{"fontsize": 8, **kwargs})


def save(fig: Any, path: Path, dpi: int = 120) -> Any:
    """Write ``fig`` at exactly its size times ``dpi``, the same bytes for the same figure; close it; return it."""
    if fig.get_layout_engine() is None:
        fig.set_layout_engine("constrained")
    fig.savefig(path, dpi=dpi, metadata={"Software": None})
    pyplot().close(fig)
    return fig
