"""Streaming a run's frames into a recording file while it runs.

:class:`RecordingWriter` writes the same layout as :func:`~visviva.io.write_recordings` (format
``visviva.recording`` v2, one run), but frame by frame into resizable datasets, flushing every
``flush_every`` frames: if the process dies, the file holds every flushed frame and reads back
with :func:`~visviva.io.read_recordings` (its ``success`` attribute is then false and its
``message`` says the run did not finish). The HDF5 file is opened without SWMR/``libver``
options, so a crashed file needs no repair tool (NOTES.md).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from datetime import UTC, datetime
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from .._version import __version__
from .recording import FORMAT, FORMAT_VERSION, write_attrs

__all__ = ["RecordingWriter"]

#: Frames between flushes by default: a crash loses at most this many.
FLUSH_EVERY = 50


class RecordingWriter:
    """Appends frames to a new recording file.

    Args:
        path: File to create (replaced if it exists): write it inside a staging directory and
            move it into place when the run is complete.
        units: Unit of each field and static array.
        attrs: Run attributes known at the start (method, dt, scene text, ...).
        static: Arrays without a frame axis (radii, edges, faces).
        run: Name of the run's group.
        flush_every: Frames between flushes to disk.

    Example:
        >>> import tempfile, numpy as np, visviva as vv
        >>> path = tempfile.mkdtemp() + "/run.h5"
        >>> with RecordingWriter(path, units={"particle_position": "m"}) as writer:
        ...     for k in range(3):
        ...         writer.append(0.1 * k, {"particle_position": np.full((2, 3), float(k))})
        ...     writer.finish({"success": True})
        >>> vv.io.load_recording(path)["particle_position"].shape
        (3, 2, 3)
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        units: Mapping[str, str] | None = None,
        attrs: Mapping[str, Any] | None = None,
        static: Mapping[str, np.ndarray] | None = None,
        run: str = "run",
        flush_every: int = FLUSH_EVERY,
    ) -> None:
        import h5py

        self.path = Path(path)
        self.units = dict(units or {})
        self.flush_every = flush_every
        self.frames = 0
        self.last_time = float("nan")
        self._file = h5py.File(self.path, "w")
        self._file.attrs["format"] = FORMAT
        self._file.attrs["format_version"] = FORMAT_VERSION
        self._file.attrs["visviva_version"] = __version__
        self._file.attrs["created_utc"] = datetime.now(UTC).isoformat(timespec="seconds")
        self._file.attrs["runs"] = json.dumps([run])
        self._group = self._file.create_group(run)
        write_attrs(
            self._group,
            dict(attrs or {}) | {"success": False, "message": "the run did not finish"},
        )
        self._time = self._group.create_dataset(
            "time", (0,), dtype=np.float64, maxshape=(None,), chunks=(1024,)
        )
        self._time.attrs["units"] = "s"
        self._fields = self._group.create_group("fields")
        if static:
            group = self._group.create_group("static")
            for name, value in static.items():
                group.create_dataset(name, data=value).attrs["units"] = self.units.get(name, "")
        self._file.flush()

    def append(self, t: float, fields: Mapping[str, np.ndarray]) -> None:
        """Add one frame: its time [s] and one array per field (same shapes every frame).

        The frame counts once every array is written: an append cut short (by a signal) is
        dropped by :meth:`finish`.
        """
        self.extend([t], {name: np.asarray(value)[None] for name, value in fields.items()})

    def extend(self, times: Any, fields: Mapping[str, np.ndarray]) -> None:
        """Add ``k`` frames at once: their times [s], ``(k,)``, and one array per field with
        the frames on its first axis, ``(k, ...)`` (the shapes of :meth:`append`'s)."""
        times = np.asarray(times, dtype=np.float64)
        start, count = self.frames, times.shape[0]
        for name, values in fields.items():
            values = np.asarray(values)
            shape = values.shape[1:]
            if name not in self._fields:
                dataset = self._fields.create_dataset(
                    name,
                    (0, *shape),
                    dtype=values.dtype,
                    maxshape=(None, *shape),
                    chunks=(1, *shape) if math.prod(shape) else None,
                )
                dataset.attrs["units"] = self.units.get(name, "")
            dataset = self._fields[name]
            dataset.resize((start + count, *shape))
            dataset[start:] = values
        self._time.resize((start + count,))
        self._time[start:] = times
        self.frames += count
        if count:
            self.last_time = float(times[-1])
        if self.frames // self.flush_every > start // self.flush_every:
            self._file.flush()

    def finish(
        self, attrs: Mapping[str, Any], series: Mapping[str, np.ndarray] | None = None
    ) -> None:
        """Record the final attributes (work counters, outcome) and flush.

        Args:
            attrs: Attributes to add or replace.
            series: Fields computed after the run (such as ``energy``), one row per frame.
        """
        self._time.resize((self.frames,))
        for dataset in self._fields.values():
            dataset.resize((self.frames, *dataset.shape[1:]))
        for name, values in (series or {}).items():
            values = np.asarray(values)
            if values.shape[:1] != (self.frames,):
                raise ValueError(f"{name!r} has {values.shape[:1]} rows for {self.frames} frames")
            self._fields.create_dataset(name, data=values).attrs["units"] = self.units.get(name, "")
        write_attrs(self._group, attrs)
        self._file.flush()

    def close(self) -> None:
        """Close the file (what was appended stays readable)."""
        if self._file.id.valid:
            self._file.close()

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
