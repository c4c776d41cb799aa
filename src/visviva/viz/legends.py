"""Legends outside the data: under an axes' x label, beside it, or under a whole figure.

A legend inside the axes sits on whichever curves pass its corner, and which corner is free
changes with the run's length. Every figure the project draws puts its legends where no curve
goes; constrained layout (every figure here uses it) makes room for them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure, SubFigure
    from matplotlib.legend import Legend

__all__ = ["legend_below", "legend_beside", "shared_legend_below"]

#: Font size of legend entries [points], the demos' long-standing choice.
FONT_SIZE = 8.0
#: Space between the x label (or tick labels) and the legend's top [points].
_GAP = 3.0
#: Rough width of a character of legend text, in font sizes (DejaVu Sans averages ~0.55).
_CHARACTER_WIDTH = 0.55
#: Width of an entry besides its text, in font sizes: the handle, the pad after it and the
#: space between columns (matplotlib's defaults: 2.0, 0.8 and 2.0).
_ENTRY_EXTRA = 4.8
#: Share of a panel's width its axes may take (the rest: y tick labels and y label).
_AXES_SHARE = 0.8


def legend_below(ax: Axes, **options: Any) -> Legend | None:
    """The axes' legend, centred under its x label, in as many columns as fit its width.

    Call it after labelling the x axis: the legend is placed below the tick labels and the x
    label that exist then. ``options`` go to :meth:`~matplotlib.axes.Axes.legend` (``title``,
    ``markerscale``, ``ncols``, ``handles`` and ``labels``, ...). Returns ``None`` if nothing is
    labelled.
    """
    from matplotlib.transforms import ScaledTranslation

    labels = _labels(ax, options)
    if not labels:
        return None
    fontsize = options.pop("fontsize", FONT_SIZE)
    below_axes = ScaledTranslation(0.0, -_x_axis_depth(ax) / 72.0, ax.figure.dpi_scale_trans)
    settings = {
        "loc": "upper center",
        "bbox_to_anchor": (0.5, 0.0),
        "bbox_transform": ax.transAxes + below_axes,
        "ncols": _columns(labels, fontsize, _panel_width(ax)),
        "fontsize": fontsize,
        "frameon": False,
        "borderaxespad": 0.0,
    }
    return ax.legend(**(settings | options))


def legend_beside(ax: Axes, **options: Any) -> Legend | None:
    """The axes' legend to the right of it, top-aligned: for a tall list of entries (17
    integrators) or an axes whose x tick labels are slanted. ``options`` as for
    :func:`legend_below`."""
    if not _labels(ax, options):
        return None
    settings = {
        "loc": "upper left",
        "bbox_to_anchor": (1.02, 1.0),
        "fontsize": FONT_SIZE,
        "frameon": False,
        "borderaxespad": 0.0,
    }
    return ax.legend(**(settings | options))


def shared_legend_below(figure: Figure | SubFigure, ax: Axes, **options: Any) -> Legend | None:
    """One legend under the whole figure, of the entries of ``ax``: for panels that all draw
    the same things (exact, computed, start). ``options`` go to
    :meth:`~matplotlib.figure.Figure.legend`."""
    handles, labels = ax.get_legend_handles_labels()
    if not labels:
        return None
    fontsize = options.pop("fontsize", FONT_SIZE)
    settings = {
        "loc": "outside lower center",
        "ncols": _columns(labels, fontsize, _AXES_SHARE * 72.0 * figure.figure.get_figwidth()),
        "fontsize": fontsize,
        "frameon": False,
    }
    return figure.legend(handles, labels, **(settings | options))


def _labels(ax: Axes, options: dict[str, Any]) -> Sequence[str]:
    """The legend's entries: those given, else the axes' labelled artists."""
    if "labels" in options:
        return list(options["labels"])
    return ax.get_legend_handles_labels()[1]


def _x_axis_depth(ax: Axes) -> float:
    """How far the x axis' ticks, tick labels and label reach below the axes [points].

    Reckoned from font sizes rather than measured, which would need a renderer: a tick label
    is counted 1.35 font sizes tall (room for the superscripts of a log axis' 10⁻³), a label
    line 1.2.
    """
    tick = ax.xaxis.majorTicks[0]
    depth = _GAP
    if tick.label1.get_visible():
        depth += tick.get_tick_padding() + tick.get_pad() + 1.35 * tick.label1.get_fontsize()
    label = ax.xaxis.label
    if label.get_text() and ax.xaxis.get_label_position() == "bottom":
        lines = label.get_text().count("\n") + 1
        depth += ax.xaxis.labelpad + 1.2 * label.get_fontsize() * lines
    return depth


def _panel_width(ax: Axes) -> float:
    """The width an axes' legend may take [points]: the axes' share of its figure's width."""
    spec = ax.get_subplotspec()
    share = 1.0
    if spec is not None:
        columns = spec.get_gridspec().ncols
        share = (spec.colspan.stop - spec.colspan.start) / columns
    return _AXES_SHARE * 72.0 * ax.figure.figure.get_figwidth() * share  # root figure's width


def _columns(labels: Sequence[str], fontsize: float, width: float) -> int:
    """As many columns as entries of the longest label fit in ``width`` [points], then evened
    out (7 entries in 4 columns read as 4 + 3; 3 columns of 3 + 3 + 1 would not)."""
    longest = max(len(text) for text in labels)
    entry = fontsize * (_ENTRY_EXTRA + _CHARACTER_WIDTH * longest)
    fit = max(1, min(len(labels), int(width // entry)))
    rows = math.ceil(len(labels) / fit)
    return math.ceil(len(labels) / rows)
