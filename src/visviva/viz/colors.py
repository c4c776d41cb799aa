"""Colours for figures with many lines: every line its own colour, neighbours easy to tell apart.

matplotlib's default cycle has ten colours and starts again at the eleventh line, so a figure of
17 integrators shows pairs of methods in one colour. :func:`distinct_styles` gives ``n``
different colours for any ``n`` (with line styles that set apart colours of one hue), and
:func:`shades` gives ``n`` different shades of one family, for lines whose colour already means
something (green: the arch stands, red: it falls).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["distinct_colors", "distinct_styles", "shades"]

#: Line styles, in order, for the lines past the first twenty (drawn from a colour map, whose
#: neighbouring colours are close: a change of dash sets each apart from the next).
_DASHES = ("-", "--", "-.", ":")


def distinct_styles(count: int) -> list[dict[str, Any]]:
    """``count`` pairs of ``color`` and ``linestyle`` (keyword arguments of ``Axes.plot``),
    no colour repeated.

    Up to 10: matplotlib's default colours (tab10), solid. Up to 20: those ten, then their
    light twins (tab20) dashed, so a light line is not read as its dark twin. More: colours
    sampled evenly along the *turbo* map, the dashes cycling so that neighbours differ twice.
    """
    if count <= 10:
        return [{"color": color, "linestyle": "-"} for color in _tab20()[0::2][:count]]
    if count <= 20:
        dark, light = _tab20()[0::2], _tab20()[1::2]
        return [{"color": c, "linestyle": "-"} for c in dark] + [
            {"color": c, "linestyle": "--"} for c in light[: count - 10]
        ]
    return [
        {"color": color, "linestyle": _DASHES[k % len(_DASHES)]}
        for k, color in enumerate(_along("turbo", count, 0.0, 1.0))
    ]


def distinct_colors(count: int) -> list[tuple[float, float, float]]:
    """The colours of :func:`distinct_styles` alone: ``count`` different RGB colours."""
    return [style["color"] for style in distinct_styles(count)]


def shades(count: int, family: str = "Greens") -> list[tuple[float, float, float]]:
    """``count`` different shades of one sequential colour map (``"Greens"``, ``"Reds"``,
    ``"Blues"``, ...), light to dark, none so light that it fades into a white background."""
    if count == 1:
        return _along(family, 1, 0.75, 0.75)
    return _along(family, count, 0.4, 0.95)


def _tab20() -> list[tuple[float, float, float]]:
    """tab20: ten dark colours (those of tab10, at even places) each with a light twin."""
    from matplotlib import colormaps

    return [tuple(map(float, rgb)) for rgb in colormaps["tab20"].colors]


def _along(name: str, count: int, start: float, stop: float) -> list[tuple[float, float, float]]:
    """``count`` colours evenly spaced along colour map ``name`` between ``start`` and ``stop``,
    interpolated between the map's table entries (sampling the table itself would repeat
    entries once ``count`` exceeds its 256 rows)."""
    from matplotlib import colormaps

    table = colormaps[name](np.linspace(0.0, 1.0, 256))[:, :3]
    place = np.linspace(start, stop, count) * (len(table) - 1)
    rgb = np.column_stack([np.interp(place, np.arange(len(table)), table[:, c]) for c in range(3)])
    return [tuple(map(float, row)) for row in rgb]
