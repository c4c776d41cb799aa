"""A symmetric-log axis that shows where it is linear.

A symlog axis is linear within ``±linthresh`` and logarithmic beyond, so a curve crossing
``linthresh`` bends there although nothing happened to it (explicit Euler's energy growing
steadily past 1 % looks like it slows down). :func:`symlog_axis` shades the linear band, draws
dotted lines at its edges and says so in the axis label, so the kink reads as the axis'. Inside
the band it puts evenly spaced ticks when the band takes enough of the axis to hold them
(matplotlib's symlog ticks there are only 0 and the view's ends, at odd values).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import numpy as np
from matplotlib.ticker import Locator, MaxNLocator, SymmetricalLogLocator

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["LINEAR_BAND_GID", "BandTicks", "symlog_axis"]

#: ``gid`` of the shading and the edge lines of the linear band (tests look for it).
LINEAR_BAND_GID = "symlog-linear-band"
#: Most ticks inside the linear band when it fills the whole axis.
_BAND_TICKS = 8


def symlog_axis(
    ax: Axes,
    *,
    linthresh: float,
    linscale: float = 1.0,
    label: str,
    threshold_text: str | None = None,
    which: Literal["x", "y"] = "y",
) -> None:
    """Make ``which`` axis of ``ax`` symmetric-log, linear within ``±linthresh``, and mark the
    linear band: shaded, dotted at its edges, and named in the axis label.

    Args:
        ax: The axes.
        linthresh: Half-width of the linear band, in data units.
        linscale: Width of the band on the axis, in decades.
        label: The axis label; a second line says where the axis is linear.
        threshold_text: ``linthresh`` as the tick labels write it (``"1 %"``); default ``%g``.
        which: ``"x"`` or ``"y"``.
    """
    axis = ax.yaxis if which == "y" else ax.xaxis
    (ax.set_yscale if which == "y" else ax.set_xscale)(
        "symlog", linthresh=linthresh, linscale=linscale
    )
    axis.set_major_locator(BandTicks(linthresh))
    _mark_band(ax, linthresh, which)
    threshold = threshold_text or f"{linthresh:g}"
    axis.set_label_text(f"{label}\nlinear within ±{threshold} (shaded), logarithmic beyond")


class BandTicks(Locator):
    """Ticks of a symlog axis: matplotlib's at 0 and at the decades beyond the linear band
    (and at 2× and 5× them when the view reaches less than two decades beyond), and evenly
    spaced ones inside the band, as many as its share of the axis holds."""

    def __init__(self, linthresh: float) -> None:
        self.linthresh = linthresh

    def __call__(self) -> list[float]:
        low, high = self.axis.get_view_interval()
        return self.tick_values(low, high)

    def tick_values(self, vmin: float, vmax: float) -> list[float]:
        vmin, vmax = sorted((vmin, vmax))
        # Less than two decades beyond the band would hold one tick or none: add 2× and 5×.
        reach = max(abs(vmin), abs(vmax)) / self.linthresh
        subs = (1.0,) if reach >= 100 else (1.0, 2.0, 5.0)
        decades = SymmetricalLogLocator(linthresh=self.linthresh, base=10.0, subs=subs).tick_values(
            vmin, vmax
        )
        # Within the band matplotlib's ticks are the view's ends: keep 0 and the decades only.
        ticks = {float(t) for t in decades if t == 0 or abs(t) >= self.linthresh * (1 - 1e-9)}
        low, high = max(vmin, -self.linthresh), min(vmax, self.linthresh)
        bins = round(_BAND_TICKS * self._band_share(vmin, vmax, low, high))
        if high > low and bins >= 2:
            inside = MaxNLocator(nbins=bins, steps=[1, 2, 2.5, 5, 10]).tick_values(low, high)
            ticks |= {float(t) for t in inside if low <= t <= high}
        return _merged(sorted(ticks), 1e-9 * (vmax - vmin))

    def _band_share(self, vmin: float, vmax: float, low: float, high: float) -> float:
        """The share of the axis' length the band's part of the view takes."""
        if self.axis is None or vmax <= vmin:
            return 1.0
        place = self.axis.get_transform().transform(np.array([vmin, vmax, low, high]))
        return float(abs(place[3] - place[2]) / abs(place[1] - place[0]))


def _merged(ticks: list[float], tolerance: float) -> list[float]:
    """``ticks`` (sorted) without near-duplicates (closer than ``tolerance``): the band's edge
    comes from both locators, once as 0.01 and once as 0.010000000000000002."""
    kept: list[float] = []
    for tick in ticks:
        if not kept or tick - kept[-1] > tolerance:
            kept.append(tick)
    return kept


def _mark_band(ax: Axes, linthresh: float, which: str) -> None:
    """Shade ``±linthresh`` across the axes and dot its edges. Added as plain artists, which do
    not count in autoscaling: the band must not widen the view of a 0.1 % change to ±1 %."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import blended_transform_factory

    def oriented(across: float, along: float) -> tuple[float, float]:
        """A point given across the axis (axes fraction) and along it (data)."""
        return (across, along) if which == "y" else (along, across)

    transform = (
        blended_transform_factory(ax.transAxes, ax.transData)
        if which == "y"
        else blended_transform_factory(ax.transData, ax.transAxes)
    )
    band = Rectangle(oriented(0.0, -linthresh), *oriented(1.0, 2 * linthresh), transform=transform)
    band.set(facecolor="0.93", edgecolor="none", zorder=0, gid=LINEAR_BAND_GID)
    edges = LineCollection(
        [[oriented(0.0, edge), oriented(1.0, edge)] for edge in (-linthresh, linthresh)],
        transform=transform,
        colors="0.45",
        linestyles=":",
        linewidths=0.8,
        zorder=1.5,
        gid=LINEAR_BAND_GID,
    )
    ax.add_artist(band)
    ax.add_artist(edges)
