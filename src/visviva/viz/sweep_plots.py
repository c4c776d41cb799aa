"""A figure against a parameter: one line with markers per series, as a sweep's plots draw them.

The figure is built without pyplot (no global state, no display); :data:`FIGURE_SIZE` at
:data:`DPI` gives images of 825 × 550 pixels.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from typing import TYPE_CHECKING

from .colors import distinct_styles
from .legends import legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["DPI", "FIGURE_SIZE", "plot_against_parameter"]

#: Size of the figure [inches] and its resolution [pixels per inch]: 825 × 550 pixels.
FIGURE_SIZE = (7.5, 5.0)
DPI = 110
#: Characters per line of the note under the axes.
_NOTE_WIDTH = 120


def plot_against_parameter(
    lines: Sequence[tuple[str, Sequence[float], Sequence[float]]],
    *,
    x_label: str,
    y_label: str,
    title: str,
    log_x: bool = False,
    log_y: bool = False,
    x_labels: Sequence[str] | None = None,
    legend_title: str | None = None,
    note: str = "",
    joined: bool = True,
) -> Figure:
    """One line with markers per ``(label, x, y)`` of ``lines`` (markers only unless
    ``joined``: a scatter, where neighbouring points need not be close).

    Args:
        lines: Each line's legend label (empty: no legend entry), x and y values, x ascending.
        x_label: The horizontal axis' label (with its unit).
        y_label: The vertical axis' label.
        title: The figure's title.
        log_x: Logarithmic horizontal axis (every x must be positive).
        log_y: Logarithmic vertical axis (every y must be positive).
        x_labels: For an x that is not a number: the label of each position 0, 1, 2, ...
            (the lines' x are then positions).
        legend_title: Title of the legend (what the series are).
        note: Text under the axes: what was left out, and why.
        joined: Join each line's points.
    """
    from matplotlib.figure import Figure

    figure = Figure(figsize=FIGURE_SIZE, dpi=DPI, layout="constrained")
    ax = figure.subplots()
    drawn = [line for line in lines if len(line[1])]
    for (label, x, y), style in zip(drawn, distinct_styles(len(drawn)), strict=True):
        ax.plot(
            x,
            y,
            marker="o",
            markersize=4 if joined else 2.5,
            linewidth=1.3 if joined else 0.0,
            label=label or None,
            **style,
        )
    if not drawn:
        ax.text(0.5, 0.5, "nothing to plot", transform=ax.transAxes, ha="center", va="center")
    if log_x:
        ax.set_xscale("log")
    if log_y and drawn:
        ax.set_yscale("log")
    if x_labels is not None:
        crowded = len(x_labels) > 6  # slanted labels keep clear of each other
        ax.set_xticks(
            range(len(x_labels)),
            [textwrap.shorten(t, 24) for t in x_labels],
            rotation=30 if crowded else 0,
            ha="right" if crowded else "center",
        )
        ax.set_xlim(-0.5, len(x_labels) - 0.5)
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    if any(label for label, _, _ in drawn):
        # Beside, not below: slanted x tick labels reach an unknown depth under the axes.
        legend_beside(ax, title=legend_title, title_fontsize=8)
    if note:
        # A figure-level label: constrained layout makes room for it under the axis label.
        figure.supxlabel(
            textwrap.fill(note, _NOTE_WIDTH), fontsize=7, color="0.35", ha="left", x=0.01
        )
    return figure
