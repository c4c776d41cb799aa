"""Reductions: the points of a ``[[plots]]`` figure, from the rows of the results table.

A plot's runs are those its ``only`` keeps (the successful ones by default); each run's y is read
as a number (``true``/``false`` as 1/0, its magnitude with ``abs_y``) and a run whose y is missing
or not finite is left out and counted. The runs sharing an x and a series value make one point:
their y reduced by ``reduce`` (``max``, ``min``, ``mean``, ``median``, or ``count``: how many
runs have a finite y), or, without ``reduce``, one point per run. Points come in series order
(first appearance in the table) and then x order: ascending numbers, or, when an x value is not
a number (a method's name, a vector), the order of first appearance, drawn as evenly spaced
labels. Pure data: nothing here draws or writes.
"""

from __future__ import annotations

import json
import math
import statistics
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from .plot_spec import Plot

__all__ = ["PlotPoints", "Point", "numeric", "reduce_plot", "shown"]

_REDUCERS: dict[str, Callable[[list[float]], float]] = {
    "max": max,
    "min": min,
    "mean": statistics.fmean,
    "median": statistics.median,
    "count": lambda values: float(len(values)),
}
#: How a non-finite float reads back from JSON (``plain_json`` writes ``"nan"``, ``"inf"``).
_NON_FINITE = ("nan", "inf", "-inf")


@dataclass(frozen=True)
class Point:
    """One point of a plot.

    Attributes:
        x: The parameter's value (as in the table).
        series: The series parameter's value, or ``None`` without a series.
        y: The (reduced) y.
        runs: The runs behind the point (with a finite y).
    """

    x: Any
    series: Any
    y: float
    runs: int


@dataclass(frozen=True)
class PlotPoints:
    """The points of one plot and what was left out of it.

    Attributes:
        plot: The plot's description.
        y_label: What y holds: ``max(|energy_drift|)``, ``integration.dt``, ...
        points: The points, by series then x.
        series: Every series value of the table, in order (also those with no point).
        x_order: Every x value of the table in drawing order (numbers ascending, else by first
            appearance).
        categorical: Whether x is drawn as evenly spaced labels (some x value is not a number).
        left_out: Runs not drawn, by reason: ``not successful``, ``no finite <y>``, ...
    """

    plot: Plot
    y_label: str
    points: tuple[Point, ...]
    series: tuple[Any, ...]
    x_order: tuple[Any, ...]
    categorical: bool
    left_out: dict[str, int] = field(default_factory=dict)

    def lines(self) -> list[tuple[Any, list[Point]]]:
        """The points of each series value that has any, in series order."""
        grouped: dict[str, list[Point]] = {}
        for point in self.points:
            grouped.setdefault(_key(point.series), []).append(point)
        return [(value, grouped[_key(value)]) for value in self.series if _key(value) in grouped]

    def empty_series(self) -> list[Any]:
        """The series values without a point."""
        drawn = {_key(point.series) for point in self.points}
        return [value for value in self.series if _key(value) not in drawn]


def numeric(value: Any) -> float | None:
    """A table value as a number: bools as 1/0, ``"nan"``/``"inf"`` (as JSON holds them) as
    floats; ``None`` for a missing value or one that is not a number."""
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str) and value in _NON_FINITE:
        return float(value)
    return None


def shown(value: Any) -> str:
    """A value as a label: ``0.01``, ``rk4``, ``[0.0, -9.81, 0.0]``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return json.dumps(list(value))
    return str(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _key(value: Any) -> str:
    """A hashable identity of a table value (lists included), kept apart by type."""
    return json.dumps(value, sort_keys=True, default=str)


def _y_label(plot: Plot) -> str:
    y = f"|{plot.y}|" if plot.abs_y else plot.y
    return f"{plot.reduce}({y})" if plot.reduce is not None else y


def reduce_plot(plot: Plot, rows: Sequence[Mapping[str, Any]]) -> PlotPoints:
    """The points of ``plot`` from the table's ``rows`` (one mapping per run, index order)."""
    series_order: dict[str, Any] = {}
    x_seen: dict[str, Any] = {}
    left_out: dict[str, int] = {}
    groups: dict[tuple[str, str], list[float]] = {}
    values: dict[tuple[str, str], tuple[Any, Any]] = {}
    for row in rows:
        x = row.get(plot.x)
        series = row.get(plot.series) if plot.series is not None else None
        series_order.setdefault(_key(series), series)
        if x is not None:
            x_seen.setdefault(_key(x), x)
        reason = _left_out(plot, row)
        if reason is None:
            y = numeric(row.get(plot.y))
            if y is None or not math.isfinite(y):
                reason = f"no finite {plot.y}"
            else:
                group = (_key(series), _key(x) if plot.reduce else f"{_key(x)}#{len(groups)}")
                groups.setdefault(group, []).append(abs(y) if plot.abs_y else y)
                values[group] = (x, series)
        if reason is not None:
            left_out[reason] = left_out.get(reason, 0) + 1
    categorical = not all(_is_number(x) for x in x_seen.values())
    x_order = list(x_seen.values())
    if not categorical:
        x_order.sort(key=lambda x: float(x))
    rank = {_key(x): position for position, x in enumerate(x_order)}
    series_rank = {key: position for position, key in enumerate(series_order)}
    points = [
        Point(
            x=values[group][0],
            series=values[group][1],
            y=_REDUCERS[plot.reduce](ys) if plot.reduce is not None else ys[0],
            runs=len(ys),
        )
        for group, ys in groups.items()
    ]
    points.sort(key=lambda p: (series_rank[_key(p.series)], rank[_key(p.x)]))
    return PlotPoints(
        plot=plot,
        y_label=_y_label(plot),
        points=tuple(points),
        series=tuple(series_order.values()),
        x_order=tuple(x_order),
        categorical=categorical,
        left_out=left_out,
    )


def _left_out(plot: Plot, row: Mapping[str, Any]) -> str | None:
    """Why ``row`` is not drawn before its y is read (``only``, a missing x), or ``None``."""
    if plot.only == "success" and not row.get("success"):
        return "not successful (only = success)"
    if plot.only == "failed" and row.get("success"):
        return "successful (only = failed)"
    if row.get(plot.x) is None:
        return f"no {plot.x}"
    return None
