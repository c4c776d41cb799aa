"""Simulated time in the unit that reads best: seconds for a drop, days for a year of orbits.

The video's label and the web viewer's clock both use :func:`time_unit`, chosen once from the
span a recording covers, so a number never runs to eight digits of seconds.
"""

from __future__ import annotations

__all__ = ["TIME_UNITS", "format_time", "time_unit"]

#: (name, seconds, decimals shown, largest span [s] it is chosen for), smallest unit first.
TIME_UNITS = (
    ("s", 1.0, 3, 120.0),
    ("min", 60.0, 2, 2 * 3600.0),
    ("h", 3600.0, 2, 2 * 86_400.0),
    ("days", 86_400.0, 1, 2 * 365.25 * 86_400.0),
    ("years", 365.25 * 86_400.0, 2, float("inf")),
)


def time_unit(span: float) -> tuple[str, float, int]:
    """``(name, seconds per unit, decimals)`` for times over ``span`` simulated seconds.

    Example:
        >>> time_unit(10.0), time_unit(3.2e7)
        (('s', 1.0, 3), ('days', 86400.0, 1))
    """
    for name, seconds, decimals, largest in TIME_UNITS:
        if span < largest:
            return name, seconds, decimals
    return TIME_UNITS[-1][:3]


def format_time(t: float, span: float) -> str:
    """``"t = 12.5 days"``: ``t`` [s] in the unit :func:`time_unit` picks for ``span`` [s]."""
    name, seconds, decimals = time_unit(span)
    return f"t = {t / seconds:.{decimals}f} {name}"
