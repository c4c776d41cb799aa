"""The recording file format (HDF5): runs written and read back.

A :class:`~visviva.simulation.recording.Recording` (the frames of a run in memory) is written
with :func:`save_recording` (one run) or :func:`write_recordings` (several runs in one file, a
comparison of methods) and read with :func:`load_recording` / :func:`read_recordings`.

File layout (format ``visviva.recording``, version 1), one HDF5 group per run::

    /                       attrs: format, format_version, visviva_version, created_utc,
                                   runs (JSON list of run names, in order)
    /<run>/                 attrs: the recording's attributes (method, dt, substeps, t0, ...);
                                   values that are not numbers or strings are stored as JSON
                                   strings under the key prefixed with "json:"
    /<run>/time             float64 (frames,), attr units = "s"
    /<run>/fields/<name>    (frames, ...) float64 or complex128, attr units, chunked per frame
    /<run>/static/<name>    arrays without a frame axis (topology, radii), attr units

The drawable-geometry names (``points``, ``radius``, ``edges``, ...) are those of
:mod:`visviva.simulation.recording`. Files are written to a temporary name next to the target
and renamed when complete, so a crash never leaves a truncated file under the real name.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from .._validation import describe
from .._version import __version__
from ..errors import ModelError
from ..simulation.recording import Recording
from .files import atomic_path

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "load_recording",
    "read_recordings",
    "save_recording",
    "write_recordings",
]

FORMAT = "visviva.recording"
FORMAT_VERSION = 1


def save_recording(recording: Recording, path: str | os.PathLike[str], *, run: str = "run") -> Path:
    """Write ``recording`` as the only run of an HDF5 file (see the module docstring)."""
    return write_recordings(path, {run: recording})


def load_recording(path: str | os.PathLike[str], run: str | None = None) -> Recording:
    """Read one run from a recording file (the only one, or the one named ``run``)."""
    runs = read_recordings(path)
    if run is None:
        if len(runs) != 1:
            raise ModelError(
                f"{os.fspath(path)} holds {len(runs)} runs ({', '.join(runs)}); choose one "
                "with --run NAME (in Python: run=NAME)"
            )
        return next(iter(runs.values()))
    if run not in runs:
        raise ModelError(f"{os.fspath(path)} has no run {run!r}; runs: {', '.join(runs)}")
    return runs[run]


def write_recordings(path: str | os.PathLike[str], runs: Mapping[str, Recording]) -> Path:
    """Write runs to one HDF5 file atomically (temporary file, then rename).

    Args:
        path: Target file (``.h5``); its directory must exist.
        runs: Run name → recording; names must be valid HDF5 group names without ``/``.

    Returns:
        The path written.
    """
    import h5py

    target = Path(path)
    if not runs:
        raise ModelError("write_recordings() needs at least one run")
    for name in runs:
        if not name or "/" in name or name.startswith("."):
            raise ModelError(f"run name {name!r} must be non-empty, without '/' or leading '.'")
    with atomic_path(target) as temporary, h5py.File(temporary, "w") as file:
        file.attrs["format"] = FORMAT
        file.attrs["format_version"] = FORMAT_VERSION
        file.attrs["visviva_version"] = __version__
        file.attrs["created_utc"] = datetime.now(UTC).isoformat(timespec="seconds")
        file.attrs["runs"] = json.dumps(list(runs))
        for name, recording in runs.items():
            _write_run(file.create_group(name), recording)
    return target


def write_attrs(group: Any, attrs: Mapping[str, Any]) -> None:
    """Store run attributes on an HDF5 group: plain values as they are, others as JSON."""
    for key, value in attrs.items():
        for stale in (key, f"json:{key}"):
            if stale in group.attrs:
                del group.attrs[stale]
        if isinstance(value, (str, bool, int, float, np.integer, np.floating)):
            group.attrs[key] = value
        elif value is None:
            group.attrs[f"json:{key}"] = "null"
        else:
            group.attrs[f"json:{key}"] = json.dumps(value)


def _write_run(group: Any, recording: Recording) -> None:
    write_attrs(group, recording.attrs)
    time = group.create_dataset("time", data=recording.time)
    time.attrs["units"] = "s"
    fields = group.create_group("fields")
    for name, value in recording.fields.items():
        chunks = (1, *value.shape[1:]) if value.ndim > 1 and value.size else None
        dataset = fields.create_dataset(name, data=value, chunks=chunks)
        dataset.attrs["units"] = recording.units.get(name, "")
    if recording.static:
        static = group.create_group("static")
        for name, value in recording.static.items():
            static.create_dataset(name, data=value).attrs["units"] = recording.units.get(name, "")


def read_recordings(path: str | os.PathLike[str]) -> dict[str, Recording]:
    """Read every run of a recording file, in the order they were written."""
    import h5py

    source = Path(path)
    if not source.is_file():
        raise ModelError(f"recording file {os.fspath(path)!r} does not exist")
    try:
        file = h5py.File(source, "r")
    except OSError as exc:
        raise ModelError(f"{os.fspath(path)} is not an HDF5 file ({exc})") from None
    with file:
        if file.attrs.get("format") != FORMAT:
            raise ModelError(f"{os.fspath(path)} is not a visviva recording")
        version = file.attrs.get("format_version")
        if not isinstance(version, (int, np.integer)) or version < 1:
            raise ModelError(f"{os.fspath(path)} has no valid format_version (got {version!r})")
        if version > FORMAT_VERSION:
            raise ModelError(
                f"{os.fspath(path)} has recording format {version}; this visviva reads up to "
                f"{FORMAT_VERSION} (upgrade visviva)"
            )
        try:
            return _read_runs(file)
        except _DAMAGE as exc:
            raise ModelError(
                f"{os.fspath(path)} is a damaged visviva recording ({type(exc).__name__}: "
                f"{exc}); run the simulation again to rewrite it"
            ) from None


#: What a recording file with missing or malformed parts raises while it is read.
_DAMAGE = (KeyError, ValueError, TypeError, IndexError, AttributeError, OSError)


def _read_runs(file: Any) -> dict[str, Recording]:
    names = json.loads(file.attrs["runs"])
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise ValueError(f"the list of runs is {describe(names)}")
    runs = {}
    for name in names:
        group = file[name]
        attrs: dict[str, Any] = {}
        for key, value in group.attrs.items():
            if key.startswith("json:"):
                attrs[key[5:]] = json.loads(value)
            else:
                attrs[key] = value.item() if isinstance(value, np.generic) else value
        fields = {k: d[()] for k, d in group["fields"].items()}
        static = {k: d[()] for k, d in group["static"].items()} if "static" in group else {}
        units = {
            k: str(d.attrs.get("units", ""))
            for part in ("fields", "static")
            if part in group
            for k, d in group[part].items()
        }
        runs[name] = Recording(group["time"][()], fields, units=units, attrs=attrs, static=static)
    return runs
