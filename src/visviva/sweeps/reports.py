"""What a sweep writes beside ``results.csv`` and ``results.json``: ``results.h5``, the plots
and ``index.html``.

:func:`write_reports` is the runner's one call, after the results table is written (also after
an interrupt, with the finished runs). Each plot of the description gives ``plots/<name>.csv``
(its points: :mod:`.reductions`) and ``plots/<name>.png`` and ``.svg`` (drawn by
:func:`visviva.viz.sweep_plots.plot_against_parameter`; matplotlib is imported only when there is
a plot to draw). A plot with no point left (every run failed, say) is still written, its figure
saying so. Each file is written atomically, and a file that cannot be made (a plot that fails to
draw, a full disk) is reported as a warning in the result while the others are still written:
the results table is never lost to a figure.
"""

from __future__ import annotations

import csv
import json
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from ..entities.system.schema import System
from ..entities.system.systems import SYSTEMS
from ..io.files import atomic_path
from ..io.json_values import plain_json
from ..model.scene import Scene
from .description import Sweep
from .index_page import write_index
from .plot_spec import FIGURES, Plot
from .reductions import PlotPoints, reduce_plot, shown
from .results import results_columns
from .results_h5 import write_results_h5

__all__ = ["Reports", "write_plot", "write_reports"]

#: A unit in a field's description: ``"time step [s]"`` → ``s`` (no commas: ``[i, j]`` is not).
_UNIT = re.compile(r"\[([^\[\],]+)\]")


@dataclass(frozen=True)
class Reports:
    """The files written besides the results table, and what could not be written.

    Attributes:
        files: ``results.h5``, each plot's ``.csv``, ``.png`` and ``.svg``, ``index.html``.
        warnings: One sentence per file not written, with the reason.
    """

    files: tuple[Path, ...]
    warnings: tuple[str, ...]


def write_reports(
    directory: Path,
    sweep: Sweep,
    heading: Mapping[str, Any],
    rows: Sequence[Mapping[str, Any]],
) -> Reports:
    """Write ``results.h5``, the plots and ``index.html`` into ``directory``; never raises for
    a file that cannot be made (it is listed in ``warnings``).

    Args:
        directory: The sweep's directory.
        sweep: The sweep's description (its parameters and plots).
        heading: ``sweep`` (name), ``design``, ``seed`` and ``runs_total``.
        rows: The results table, one mapping per finished run, in index order.
    """
    heading = dict(heading) | {"description": sweep.info.description}
    files: list[Path] = []
    warnings: list[str] = []
    try:
        columns = results_columns(sweep.paths, rows)
        files.append(
            write_results_h5(directory / "results.h5", heading, sweep.paths, columns, rows)
        )
    except Exception as failure:  # the CSV and JSON tables are written: keep going
        warnings.append(f"results.h5 was not written: {_reason(failure)}")
    drawn: list[tuple[str, str]] = []
    labels = _Labels(sweep)
    for plot in sweep.plots:
        assert plot.name is not None  # named by load_sweep
        try:  # one figure must not cost the others, or the index
            points = reduce_plot(plot, rows)
            files.append(_write_table(directory / "plots", points))
            files += _write_figure(directory / "plots", points, labels)
            drawn.append((plot.name, _title(plot)))
        except Exception as failure:
            warnings.append(f"plot {plot.name!r} was not drawn: {_reason(failure)}")
    try:
        files.append(write_index(directory, heading, sweep.paths, rows, drawn, warnings))
    except Exception as failure:
        warnings.append(f"index.html was not written: {_reason(failure)}")
    return Reports(tuple(files), tuple(warnings))


def _reason(failure: Exception) -> str:
    return f"{type(failure).__name__}: {failure}".splitlines()[0]


def _title(plot: Plot) -> str:
    if plot.title:
        return plot.title
    against = f"{plot.y} against {plot.x}"
    return f"{plot.reduce} of {against}" if plot.reduce else against


class _Labels:
    """Axis labels: a figure's or a parameter's name with its unit where one is known (from the
    scene field's description, or a named system's parameter table)."""

    def __init__(self, sweep: Sweep) -> None:
        self.keys = dict(zip(sweep.paths, sweep.keys, strict=True))
        self.base = sweep.base
        self._scene: Scene | None = None

    def __call__(self, column: str) -> str:
        unit = FIGURES.get(column) if column not in self.keys else self._unit(self.keys[column])
        return f"{column} [{unit}]" if unit else column

    def _unit(self, keys: tuple[str | int, ...]) -> str | None:
        if self._scene is None:
            self._scene = Scene.model_validate(self.base)
        node: Any = self._scene
        unit = None
        for key in keys:
            if isinstance(node, BaseModel) and isinstance(key, str):
                described = type(node).model_fields[key].description or ""
                found = _UNIT.search(described)
                unit = found.group(1).strip() if found else None
                if isinstance(node, System) and key == "parameters":
                    table = SYSTEMS[node.system].parameters
                    return table[str(keys[-1])].unit if str(keys[-1]) in table else None
                node = getattr(node, key)
            elif isinstance(node, (list, tuple)) and isinstance(key, int):
                node = node[key]  # an entity, or a vector's component (the vector's unit)
            else:
                return None
        return unit


def write_plot(
    folder: Path,
    plot: Plot,
    rows: Sequence[Mapping[str, Any]],
    label: Callable[[str], str] = str,
) -> tuple[Path, ...]:
    """Write ``plot``'s table (``<name>.csv``) and figure (``<name>.png``, ``.svg``) into
    ``folder``; return their paths.

    Args:
        folder: The sweep's ``plots`` directory (created if missing).
        plot: The plot, with its ``name``.
        rows: The results table.
        label: Gives an axis label (with its unit) for a column name.
    """
    points = reduce_plot(plot, rows)
    return (_write_table(folder, points), *_write_figure(folder, points, label))


def _write_table(folder: Path, points: PlotPoints) -> Path:
    """``<name>.csv``: x, the series value (with a series), y and the runs behind each point."""
    plot = points.plot
    folder.mkdir(parents=True, exist_ok=True)
    table = folder / f"{plot.name}.csv"
    with atomic_path(table) as temporary, temporary.open("w", newline="") as handle:
        writer = csv.writer(handle)
        series = [plot.series] if plot.series is not None else []
        writer.writerow([plot.x, *series, points.y_label, "runs"])
        for point in points.points:
            chosen = [_csv(point.series)] if plot.series is not None else []
            writer.writerow([_csv(point.x), *chosen, repr(point.y), point.runs])
    return table


def _write_figure(
    folder: Path, points: PlotPoints, label: Callable[[str], str]
) -> tuple[Path, Path]:
    """``<name>.png`` and ``<name>.svg``."""
    figure = _figure(points, label)
    images = []
    for suffix in (".png", ".svg"):
        image = folder / f"{points.plot.name}{suffix}"
        with atomic_path(image) as temporary:
            figure.savefig(temporary, format=suffix[1:])
        images.append(image)
    return images[0], images[1]


def _csv(value: Any) -> str:
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return json.dumps(plain_json(list(value)))
    return shown(value)


def _figure(points: PlotPoints, label: Callable[[str], str]) -> Any:
    """The figure of ``points``: one line per series value, points off a log axis left out."""
    from ..viz.sweep_plots import plot_against_parameter

    plot = points.plot
    position = {json.dumps(x, default=str): i for i, x in enumerate(points.x_order)}
    lines = []
    off_axis = 0
    for value, members in points.lines():
        xs, ys = [], []
        for point in members:
            x = position[json.dumps(point.x, default=str)] if points.categorical else point.x
            if (plot.log_x and not x > 0) or (plot.log_y and not point.y > 0):
                off_axis += 1  # a log axis has no place for zero or less
                continue
            xs.append(float(x))
            ys.append(point.y)
        text = f"{shown(value)}" if plot.series is not None else ""
        lines.append((text, xs, ys))
    notes = [f"{count} runs left out: {reason}" for reason, count in points.left_out.items()]
    if off_axis:
        hint = " (abs_y = true draws |y|)" if plot.log_y and not plot.abs_y else ""
        notes.append(f"{off_axis} points ≤ 0 left out of the log axis{hint}")
    empty = points.empty_series()
    if plot.series is not None and empty:
        notes.append(f"no point for {plot.series} = {', '.join(shown(v) for v in empty)}")
    y_label = label(plot.y)
    if plot.reduce == "count":
        y_label = f"runs with a finite {plot.y}"
    elif plot.reduce is not None or plot.abs_y:
        y_label = points.y_label + y_label[len(plot.y) :]
    return plot_against_parameter(
        lines,
        x_label=label(plot.x),
        y_label=y_label,
        title=_title(plot),
        log_x=plot.log_x,
        log_y=plot.log_y,
        x_labels=[shown(x) for x in points.x_order] if points.categorical else None,
        legend_title=plot.series,
        note="; ".join(notes),
        joined=plot.lines,
    )
