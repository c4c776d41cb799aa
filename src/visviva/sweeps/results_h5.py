"""``results.h5``: the results table of a sweep as HDF5, one dataset per column.

Layout: the group ``columns`` holds one dataset of length ``runs`` per column of
``results.csv``, named as the column (a ``/`` written ``%2F`` and a ``%`` as ``%25``: HDF5 names
cannot hold a slash), with an attribute ``kind``:

* ``float``: float64 (NaN and ±inf are values as the runs gave them);
* ``int``: int64;
* ``bool``: HDF5's boolean (numpy ``bool``);
* ``text``: UTF-8 strings of variable length;
* ``json``: UTF-8 strings, each a JSON value (a vector parameter, a column of mixed kinds).

A column with missing values (a figure a failed run has not got, the ``error`` of a successful
run) also has a boolean mask of the same name in the group ``missing`` (true where missing; the
dataset holds NaN, 0, false or an empty string there). The file's attributes are the sweep's
``sweep`` (name), ``design``, ``seed``, ``runs_total`` and ``description``, its ``parameters``
(paths) and the ``columns`` in order. :func:`read_results_h5` reads it back to the rows.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from ..io.files import atomic_path
from ..io.json_values import plain_json
from .reductions import numeric

__all__ = ["read_results_h5", "write_results_h5"]

_INT64 = (-(2**63), 2**63 - 1)


def _dataset_name(column: str) -> str:
    return column.replace("%", "%25").replace("/", "%2F")


def _kind(values: Sequence[Any]) -> str:
    """The kind of a column from its present values (``float`` when there are none)."""
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return "bool"
    if any(isinstance(v, bool) for v in present):
        return "json"
    if present and all(isinstance(v, int) and _INT64[0] <= v <= _INT64[1] for v in present):
        return "int"
    numbers = [v for v in present if isinstance(v, (int, float))]
    if len(numbers) == len(present) or (numbers and all(numeric(v) is not None for v in present)):
        return "float"  # numbers, with non-finite ones as JSON spells them ("nan", "inf")
    if all(isinstance(v, str) for v in present):
        return "text"
    return "json"


def _column(values: Sequence[Any], kind: str) -> np.ndarray:
    """The dataset's values, with a neutral value where one is missing."""
    if kind == "float":
        return np.array([np.nan if v is None else numeric(v) for v in values], dtype=np.float64)
    if kind == "int":
        return np.array([0 if v is None else v for v in values], dtype=np.int64)
    if kind == "bool":
        return np.array([bool(v) for v in values], dtype=np.bool_)
    if kind == "text":
        texts = ["" if v is None else v for v in values]
    else:
        texts = ["" if v is None else json.dumps(plain_json(v)) for v in values]
    return np.array(texts, dtype=h5py.string_dtype("utf-8"))


def write_results_h5(
    path: str | os.PathLike[str],
    heading: Mapping[str, Any],
    parameters: Sequence[str],
    columns: Sequence[str],
    rows: Sequence[Mapping[str, Any]],
) -> Path:
    """Write ``rows`` to ``path`` atomically (see the module docstring); return its path.

    Args:
        path: The file to write (``results.h5``).
        heading: ``sweep`` (name), ``design``, ``seed``, ``runs_total`` and, optionally,
            ``description``: stored as attributes.
        parameters: The parameters' paths.
        columns: The columns, in order (those of ``results.csv``).
        rows: One mapping per run; a column a row lacks is missing there.
    """
    target = Path(path)
    text = h5py.string_dtype("utf-8")
    with atomic_path(target) as temporary, h5py.File(temporary, "w") as file:
        for key in ("sweep", "design", "description"):
            file.attrs.create(key, str(heading.get(key, "")), dtype=text)
        file.attrs["seed"] = np.int64(heading.get("seed", 0))
        file.attrs["runs_total"] = np.int64(heading.get("runs_total", len(rows)))
        file.attrs.create("parameters", list(parameters), dtype=text)
        file.attrs.create("columns", list(columns), dtype=text)
        data, missing = file.create_group("columns"), file.create_group("missing")
        for column in columns:
            values = [row.get(column) for row in rows]
            kind = _kind(values)
            dataset = data.create_dataset(_dataset_name(column), data=_column(values, kind))
            dataset.attrs["kind"] = kind
            absent = np.array([v is None for v in values], dtype=np.bool_)
            if absent.any():
                missing.create_dataset(_dataset_name(column), data=absent)
    return target


def read_results_h5(
    path: str | os.PathLike[str],
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Read a ``results.h5``: its attributes and one row per run with every column (``None``
    where missing), values as Python's ``float``, ``int``, ``bool``, ``str`` or JSON values."""
    with h5py.File(path, "r") as file:
        attributes = {key: _plain(value) for key, value in file.attrs.items()}
        columns = attributes["columns"]
        table: dict[str, list[Any]] = {}
        for column in columns:
            name = _dataset_name(column)
            dataset = file["columns"][name]
            kind = str(dataset.attrs["kind"])
            stored = dataset.asstr()[()] if kind in ("text", "json") else dataset[()]
            values = [json.loads(v) if kind == "json" and v else v for v in stored.tolist()]
            if name in file["missing"]:
                mask = file["missing"][name][()]
                values = [None if absent else v for v, absent in zip(values, mask, strict=True)]
            table[column] = values
        count = len(next(iter(table.values()), []))
        rows = [{column: table[column][i] for column in columns} for i in range(count)]
    return attributes, rows


def _plain(value: Any) -> Any:
    """An HDF5 attribute as plain Python: NumPy scalars unwrapped, string arrays as lists."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.generic):
        return value.item()
    return value
