"""Tick labels that are always distinct and true: percentages with the decimals each tick needs.

A fixed number of decimals fails one way or the other: ``0`` turns the ticks of a 0.25 %
energy change into "0%", "0%", "−0%"; ``3`` clutters a plot spanning 1000 %. :class:`PercentTicks`
writes each tick with the fewest decimals that give its value exactly (to a thousandth of the
ticks' spacing): "0%", "0.25%", "0.5%", "1%", "10%"; ticks that would need more than
:data:`MAX_DECIMALS` are all written in scientific notation, ``2.5×10⁻⁶ %``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.ticker import Formatter

__all__ = ["MAX_DECIMALS", "PercentTicks", "percent_labels"]

#: Most decimals written before switching to scientific notation (0.001 % reads; 0.0001 %
#: is easier as 1×10⁻⁴ %).
MAX_DECIMALS = 3
#: A label may differ from its tick by this share of the smallest spacing between ticks.
_FAITHFUL = 1e-3


class PercentTicks(Formatter):
    """Formats fractions as percentages (0.25 → "25%"), each with the fewest decimals that
    write it exactly, or all in scientific notation if one would need too many."""

    def __init__(self) -> None:
        self._tolerance = 0.0  # [percent]: a label may be this far from its tick
        self._scientific = False

    def set_locs(self, locs: Sequence[float]) -> None:
        super().set_locs(locs)
        percents = 100.0 * np.asarray(locs, dtype=float)
        percents = np.unique(percents[np.isfinite(percents)])
        gaps = np.diff(percents)
        # A lone tick is written to a thousandth of itself (or of 1 % if it is 0).
        lone = float(np.abs(percents).max(initial=0.0)) or 1.0
        scale = gaps.min() if gaps.size else lone
        self._tolerance = _FAITHFUL * scale
        self._scientific = any(_decimals(p, self._tolerance) is None for p in percents)

    def __call__(self, x: float, pos: int | None = None) -> str:
        percent = 100.0 * x
        if abs(percent) <= self._tolerance:  # a locator's 1e-19 is 0, not "−0.00%"
            return "0%"
        if self._scientific:
            return _scientific(percent, self._tolerance)  # mathtext writes its own minus
        decimals = _decimals(percent, self._tolerance)
        return self.fix_minus(f"{percent:.{decimals or 0}f}%")


def percent_labels(fractions: Sequence[float]) -> list[str]:
    """The labels :class:`PercentTicks` gives ticks at ``fractions`` (for tests and tables)."""
    return list(PercentTicks().format_ticks(list(fractions)))


def _decimals(percent: float, tolerance: float) -> int | None:
    """The fewest decimals (up to :data:`MAX_DECIMALS`) that write ``percent`` to within
    ``tolerance``; ``None`` if more are needed."""
    for decimals in range(MAX_DECIMALS + 1):
        if abs(round(percent, decimals) - percent) <= tolerance:
            return decimals
    return None


def _scientific(percent: float, tolerance: float) -> str:
    """``percent`` as mantissa × 10^exponent with the fewest mantissa decimals (up to 15) that
    write it to within ``tolerance``."""
    for digits in range(16):
        text = f"{percent:.{digits}e}"
        if abs(float(text) - percent) <= tolerance:
            break
    mantissa, exponent = text.split("e")
    return rf"${mantissa}\times10^{{{int(exponent)}}}$%"
