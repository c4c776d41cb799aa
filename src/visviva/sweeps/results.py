"""The results table of a sweep: one row per run, in ``results.csv`` and ``results.json``.

A row holds the run's index and directory name, its parameter values (one column per path),
``success`` and ``error``, then the figures of its ``summary.json`` flattened to scalar
columns: nested tables joined with dots (``counts.particles``), lists replaced by their length
(``warnings``), the list of output files left out. Both files are written atomically.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..io.files import atomic_path
from ..io.json_values import plain_json

__all__ = ["flatten_summary", "results_columns", "write_results"]

#: Summary entries that are not figures of the run (the file list, the scene's name).
_NOT_FIGURES = ("outputs", "scene")


def flatten_summary(summary: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """``summary.json`` as scalar columns: ``{"counts": {"particles": 3}}`` →
    ``{"counts.particles": 3}``; a list becomes its length."""
    flat: dict[str, Any] = {}
    for key, value in summary.items():
        if not prefix and key in _NOT_FIGURES:
            continue
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat |= flatten_summary(value, f"{name}.")
        elif isinstance(value, (list, tuple)):
            flat[name] = len(value)
        else:
            flat[name] = value
    return flat


def write_results(
    directory: Path,
    sweep: Mapping[str, Any],
    parameters: Sequence[str],
    rows: Sequence[Mapping[str, Any]],
) -> tuple[Path, Path]:
    """Write ``results.csv`` and ``results.json`` into ``directory``; return their paths.

    Args:
        directory: The sweep's output directory.
        sweep: Name, design and seed, stored at the top of the JSON file.
        parameters: The parameters' paths (their columns follow ``index`` and ``run``).
        rows: One mapping per run (see :mod:`visviva.sweeps.runner`), in index order.
    """
    columns = results_columns(parameters, rows)
    table = directory / "results.csv"
    with atomic_path(table) as temporary, temporary.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(row.get(column)) for column in columns])
    document = directory / "results.json"
    with atomic_path(document) as temporary:
        data = dict(sweep) | {"parameters": list(parameters), "runs": list(rows)}
        temporary.write_text(json.dumps(plain_json(data), indent=2, allow_nan=False) + "\n")
    return table, document


def results_columns(parameters: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The table's columns: ``index``, ``run``, the parameters, ``success``, ``error``, then
    every other key of the rows in the order first met."""
    columns = ["index", "run", *parameters, "success", "error"]
    known = set(columns)
    for row in rows:
        for key in row:
            if key not in known:
                columns.append(key)
                known.add(key)
    return columns


def _cell(value: Any) -> str:
    """A CSV cell: empty for none, ``repr`` for floats (read back to the same double)."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return json.dumps(plain_json(list(value)))
    return str(value)
