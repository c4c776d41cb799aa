"""``[[plots]]`` of a sweep file: a figure of the results drawn against a parameter.

Each plot names its horizontal axis ``x`` (a parameter path of the sweep), its vertical axis
``y`` (a figure of the results table, such as ``max_energy_error``, or a parameter path), and
optionally a ``series`` (a parameter path: one line per value) and a ``reduce`` that combines the
runs sharing an x and a series into one point. :func:`plot_problems` checks the plots against
the sweep's parameters when the file is loaded (the runs have not run yet, so a figure is known
by name: the fixed figures of every run's ``summary.json``, or a nested one such as
``counts.particles`` whose presence is only known afterwards); :func:`named` gives each plot its
file name and its paths as the table's columns. Drawing is :mod:`.reports`' work.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Annotated, Literal

from pydantic import Field

from .._registry import did_you_mean
from ..entities.fields import Strict

__all__ = ["FIGURES", "NESTED_FIGURES", "Plot", "named", "plot_problems"]

#: The numeric figures of every run's row, with their units ("" for a pure number). ``success``
#: and ``complete`` count as 1 and 0 (``reduce = "mean"`` of ``success``: the fraction that
#: succeeded); ``warnings`` is the number of a run's warnings.
FIGURES: dict[str, str] = {
    "index": "",
    "success": "",
    "complete": "",
    "dt": "s",
    "duration_s": "s",
    "t_reached_s": "s",
    "steps": "",
    "energy_drift": "",
    "max_energy_error": "",
    "energy_tolerance": "",
    "wall_time_s": "s",
    "warnings": "",
}
#: Tables of ``summary.json`` whose entries depend on the scene (``counts.particles``,
#: ``emitters.<name>.births``, a system's ``final.generalized_position[1]``): accepted by name,
#: found or not once the runs are done.
NESTED_FIGURES = ("counts.", "emitters.", "final.")
#: Columns of the table that hold text, not numbers.
_TEXT_COLUMNS = ("method", "run", "error", "interrupted")

Reduce = Literal["max", "min", "mean", "median", "count"]
Only = Literal["all", "success", "failed"]
ColumnName = Annotated[str, Field(strict=True, min_length=1, max_length=500)]
Flag = Annotated[bool, Field(strict=True)]
#: A plot's file stem: letters, digits and ``_ . = + -``, not starting with a dot or a dash.
PlotName = Annotated[
    str,
    Field(strict=True, min_length=1, max_length=100, pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.=+-]*$"),
]


class Plot(Strict):
    """``[[plots]]``: one figure of the results against a parameter.

    ``plots/<name>.png`` (and ``.svg``) draws one line with markers per ``series`` value;
    ``plots/<name>.csv`` holds its points: x, series, y (reduced) and the number of runs behind
    each point. Runs whose y is missing or not finite are left out and counted in a note.
    """

    x: ColumnName = Field(description="parameter path on the horizontal axis")
    y: ColumnName = Field(
        description="figure of the results (energy_drift, max_energy_error, steps, "
        "t_reached_s, wall_time_s, ...) or a parameter path, on the vertical axis"
    )
    series: ColumnName | None = Field(None, description="parameter path: one line per value")
    reduce: Reduce | None = Field(
        None,
        description="how the runs sharing an x and a series make one point: max, min, mean, "
        "median or count (of the runs with a finite y); without it each run is a point",
    )
    only: Only = Field("success", description="the runs drawn: success (default), failed or all")
    log_x: Flag = Field(False, description="logarithmic horizontal axis")
    log_y: Flag = Field(False, description="logarithmic vertical axis")
    abs_y: Flag = Field(False, description="draw |y| (a signed figure such as energy_drift)")
    lines: Flag = Field(
        True, description="join the points of a series (false: points only, for scatter)"
    )
    title: Annotated[str, Field(strict=True, max_length=200)] | None = Field(
        None, description="the figure's title (default: what is drawn against what)"
    )
    name: PlotName | None = Field(
        None, description="file stem under plots/ (default: from y, reduce and x)"
    )


def _same(path: str) -> str:
    """A path compared without its spaces, as the sweep compares its parameter paths."""
    return path.replace(" ", "")


def _find(path: str, paths: Sequence[str]) -> int | None:
    """The index of the parameter path ``path`` among ``paths``, or ``None``."""
    wanted = _same(path)
    return next((i for i, p in enumerate(paths) if _same(p) == wanted), None)


def plot_problems(
    plots: Sequence[Plot],
    paths: Sequence[str],
    values: Sequence[list[object] | None],
    counts: Sequence[int | None],
    design: str,
) -> list[tuple[int, str, str]]:
    """Every problem of the plots as ``(plot index, key, message)``.

    Args:
        plots: The ``[[plots]]`` tables.
        paths: The sweep's parameter paths, in the file's order.
        values: Each parameter's ``values`` list (``None`` for a range: numbers).
        counts: Each parameter's number of values in a grid or zip design (``None`` in a
            random design).
        design: The sweep's design (``grid``, ``zip`` or ``random``).
    """
    problems: list[tuple[int, str, str]] = []
    explicit = [plot.name for plot in plots if plot.name is not None]
    for index, plot in enumerate(plots):
        found = _one_plot(plot, paths, values, counts, design)
        if plot.name is not None and explicit.count(plot.name) > 1:
            found.append(
                ("name", f"the name {plot.name!r} is given to several plots; give each its own")
            )
        problems += [(index, key, message) for key, message in found]
    return problems


def _one_plot(
    plot: Plot,
    paths: Sequence[str],
    values: Sequence[list[object] | None],
    counts: Sequence[int | None],
    design: str,
) -> list[tuple[str, str]]:
    """The problems of one plot as ``(key, message)`` (see :func:`plot_problems`)."""
    problems: list[tuple[str, str]] = []
    listed = ", ".join(paths)
    found: dict[str, int] = {}
    for key in ("x", "series"):
        path = getattr(plot, key)
        position = None if path is None else _find(path, paths)
        if position is not None:
            found[key] = position
        elif path is not None:
            problems.append(
                (
                    key,
                    f"`{key}` must be one of the sweep's parameter paths (got {path!r})."
                    f"{did_you_mean(path, paths)} Parameters: {listed}",
                )
            )
    if "x" in found and found.get("series") == found["x"]:
        problems.append(("series", "`series` and `x` are the same parameter; choose another"))
    y = _find(plot.y, paths)
    if y is not None:
        found["y"] = y
    elif plot.y in _TEXT_COLUMNS:
        problems.append(
            (
                "y",
                f"`y` is drawn as a number, and {plot.y!r} is a text; give it as `series` "
                "to draw one line per value",
            )
        )
    elif plot.y not in FIGURES and not plot.y.startswith(NESTED_FIGURES):
        problems.append(
            (
                "y",
                f"`y` must be a figure of the results or a parameter path (got {plot.y!r})."
                f"{did_you_mean(plot.y, [*FIGURES, *paths])} Figures: {', '.join(FIGURES)}, "
                f"counts.<what>, final.<coordinate>; parameters: {listed}",
            )
        )
    for key, log in (("x", plot.log_x), ("y", plot.log_y)):
        if key in found and (message := _axis_problem(key, log, values[found[key]])):
            problems.append((key, message))
    if plot.reduce is None and design == "grid" and "x" in found:
        shared = [
            f"{paths[i]} ({counts[i]} values)"
            for i in range(len(paths))
            if i not in (found["x"], found.get("series")) and (counts[i] or 1) > 1
        ]
        if shared:
            problems.append(
                (
                    "reduce",
                    "several runs share each x and series, differing in "
                    f"{', '.join(shared)}; give `reduce` (max, min, mean, median or count) to "
                    "combine them, or make that parameter the `series`",
                )
            )
    return problems


def _axis_problem(key: str, log: bool, values: list[object] | None) -> str | None:
    """Why the values of the parameter on axis ``key`` cannot be drawn as asked, or ``None``."""
    if values is None:  # a range: finite numbers, positive if it is a log_range
        return None
    numbers = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if len(numbers) < len(values):
        if key == "y":
            return (
                "`y` is drawn as a number, and this parameter takes other values; give it as "
                "`series` to draw one line per value"
            )
        if log:
            return (
                "`log_x` needs numbers, and this parameter takes other values (drawn as evenly "
                "spaced labels); drop `log_x`"
            )
    elif log and min(numbers) <= 0:
        return f"`log_{key}` needs positive values, and this parameter takes {min(numbers)!r}"
    return None


def named(plots: Sequence[Plot], paths: Sequence[str]) -> tuple[Plot, ...]:
    """The plots ready to draw: ``x``, ``series`` and a parameter ``y`` written as the sweep's
    parameter path (the table's column: ``integration. dt`` → ``integration.dt``), and a
    ``name`` each: the given one, else ``<reduce>_<y>_vs_<x>`` from the paths' last fields
    (``max_dt_vs_stiffness``), with ``-2``, ``-3``... where names repeat."""
    taken = {plot.name for plot in plots if plot.name is not None}
    result = []
    for plot in plots:
        update: dict[str, str] = {}
        for key in ("x", "series", "y"):
            path = getattr(plot, key)
            position = None if path is None else _find(path, paths)
            if position is not None:
                update[key] = paths[position]
        if plot.name is None:
            stem = "_".join(
                part
                for part in (plot.reduce, _field(plot.y), "vs", _field(plot.x))
                if part is not None
            )
            stem = re.sub(r"[^A-Za-z0-9_.=+-]+", "-", stem).strip("-.")[:90] or "plot"
            name, number = stem, 1
            while name in taken:
                number += 1
                name = f"{stem}-{number}"
            taken.add(name)
            update["name"] = name
        result.append(plot.model_copy(update=update))
    return tuple(result)


def _field(path: str) -> str:
    """The last field of a path: ``entities[0].stiffness`` → ``stiffness``."""
    return re.sub(r"\[[^\]]*\]", "", path).split(".")[-1].strip() or path
