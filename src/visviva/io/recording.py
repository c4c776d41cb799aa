"""The recording file format (HDF5): runs written and read back.

A :class:`~visviva.simulation.recording.Recording` (the frames of a run in memory) is written
with :func:`save_recording` (one run) or :func:`write_recordings` (several runs in one file, a
comparison of methods) and read with :func:`load_recording` / :func:`read_recordings`.

File layout (format ``visviva.recording``, version 2), one HDF5 group per run::

    /                       attrs: format, format_version, visviva_version, created_utc,
                                   runs (JSON list of run names, in order)
    /<run>/                 attrs: the recording's attributes (method, dt, substeps, t0, ...);
                                   values that are not numbers or strings are stored as JSON
                                   strings under the key prefixed with "json:"
    /<run>/time             float64 (frames,), attr units = "s"
    /<run>/fields/<name>    (frames, ...) float64 or complex128, attr units, chunked per frame
    /<run>/static/<name>    arrays without a frame axis (topology, radii), attr units

The field names (``particle_position``, ``system_points``, ``edges``, ...) are those of
:mod:`visviva.simulation.recording`. Files are written to a temporary name next to the target
and renamed when complete, so a crash never leaves a truncated file under the real name.

Version 1 named a scene's drawn points ``points`` (its particles, then its systems' points)
with ``velocities``, ``alive``, ``radius`` and ``color`` over them and the particles' ``mass``;
version 2 names them as the state parts (``particle_position``, ``particle_velocity``,
``particle_alive``, ``particle_radius``, ``particle_color``, ``particle_mass``) beside the
systems' ``system_points``, ``system_velocity``, ``system_radius`` and ``system_color``. A
version-1 file is read with the new names (:func:`upgraded_names`): the first ``N`` points,
``N`` the length of ``mass`` (none without it), are the particles.
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
FORMAT_VERSION = 2


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
            return _read_runs(file, int(version))
        except _DAMAGE as exc:
            raise ModelError(
                f"{os.fspath(path)} is a damaged visviva recording ({type(exc).__name__}: "
                f"{exc}); run the simulation again to rewrite it"
            ) from None


#: What a recording file with missing or malformed parts raises while it is read.
_DAMAGE = (KeyError, ValueError, TypeError, IndexError, AttributeError, OSError)


def _read_runs(file: Any, version: int) -> dict[str, Recording]:
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
        if version == 1:
            fields, static, units = upgraded_names(fields, static, units)
        runs[name] = Recording(group["time"][()], fields, units=units, attrs=attrs, static=static)
    return runs


#: Version 1's names of the drawn points' arrays: the old name, the particles' new name and
#: the systems' points' new name (``None``: they have none).
_DRAWN_NAMES_1 = (
    ("points", "particle_position", "system_points"),
    ("velocities", "particle_velocity", "system_velocity"),
    ("alive", "particle_alive", None),
    ("radius", "particle_radius", "system_radius"),
    ("color", "particle_color", "system_color"),
)
#: Arrays of the systems' points that stay fields (the others do not change over a run).
_SYSTEM_FIELDS = ("system_points", "system_velocity")


def upgraded_names(
    fields: dict[str, np.ndarray], static: dict[str, np.ndarray], units: dict[str, str]
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, str]]:
    """The fields, static arrays and units of a version-1 recording under the names of
    version 2 (see the module docstring); other names are kept."""
    fields, static, units = dict(fields), dict(static), dict(units)
    n = 0
    if "mass" in static:
        n = static["mass"].shape[0]
        static["particle_mass"] = static.pop("mass")
        units["particle_mass"] = units.pop("mass", "kg")
    count = fields["points"].shape[1] if "points" in fields else n
    for old, own, theirs in _DRAWN_NAMES_1:
        per_frame = old in fields
        value = fields.pop(old) if per_frame else static.pop(old, None)
        unit = units.pop(old, "")
        if value is None:
            continue
        axis = 1 if per_frame else 0
        particles = value[:, :n] if per_frame else value[:n]
        systems = value[:, n:] if per_frame else value[n:]
        if value.shape[axis] != count:  # velocities of the particles alone
            systems = systems[:, :0] if per_frame else systems[:0]
        if per_frame and theirs is not None and theirs not in _SYSTEM_FIELDS:
            systems = systems[0]  # the systems' radii and colours never change
        parts = [(own, particles, per_frame)]
        if theirs is not None:
            parts.append((theirs, systems, theirs in _SYSTEM_FIELDS))
        for name, part, varying in parts:
            if part.shape[1 if varying else 0]:
                (fields if varying else static)[name] = part
                units[name] = unit
    return fields, static, units
