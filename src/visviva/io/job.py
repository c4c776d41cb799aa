"""Writing a demo's (or any run's) outputs into a directory, all or nothing.

A job's files — ``recording.h5``, ``summary.json`` and its figures — are written into a hidden
staging directory next to the target and moved into place only when every one of them has been
written, so an interrupted or failed job leaves no partial file behind. Files that already exist
are replaced only with ``force``.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..analysis.invariants import energy_drift, max_energy_error
from ..errors import ModelError
from .recording import write_recordings

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .recording import Recording

__all__ = ["JobOutput", "plain_json", "run_summary"]


def run_summary(recording: Recording) -> dict[str, Any]:
    """The per-run entry of ``summary.json``: method, step, work, energy drift, outcome."""
    attrs = recording.attrs
    keys = (
        "method",
        "dt",
        "substeps",
        "steps",
        "f_evaluations",
        "jacobian_evaluations",
        "linear_solves",
        "newton_iterations",
        "rejected_steps",
        "wall_time_s",
        "success",
        "message",
    )
    entry = {k: attrs[k] for k in keys if k in attrs}
    entry["energy_drift"] = energy_drift(recording)
    entry["max_energy_error"] = max_energy_error(recording)
    return entry


class JobOutput:
    """Collects a job's recordings, figures and summary, then writes them at once.

    Args:
        directory: Output directory (created if missing).
        force: Replace output files that already exist.
    """

    def __init__(self, directory: str | os.PathLike[str], *, force: bool = False) -> None:
        self.directory = Path(directory)
        self.force = force
        self.recordings: dict[str, Recording] = {}
        self.figures: dict[str, Figure] = {}
        self.summary: dict[str, Any] = {}
        self.staged: list[str] = []
        self._staging: Path | None = None

    def planned(self) -> list[str]:
        """File names this job will write."""
        names = ["summary.json"]
        if self.recordings:
            names.insert(0, "recording.h5")
        return names + [f"{name}.png" for name in self.figures] + self.staged

    def stage(self, name: str) -> Path:
        """Where to write output file ``name`` now; it moves into place with the others.

        The staging directory is a hidden directory inside the target, so if the process dies
        the files written so far (a flushed recording) survive there.
        """
        if self._staging is None:
            self.directory.mkdir(parents=True, exist_ok=True)
            self._staging = Path(tempfile.mkdtemp(prefix=".visviva-", dir=self.directory))
        self.staged.append(name)
        return self._staging / name

    def discard(self) -> None:
        """Remove everything staged (the job failed before writing its outputs)."""
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None

    def check_target(self, names: list[str] | None = None) -> None:
        """Refuse to overwrite existing outputs without ``force`` (call before the work)."""
        if self.directory.exists() and not self.directory.is_dir():
            raise ModelError(
                f"output path {os.fspath(self.directory)!r} is a file, not a directory"
            )
        if self.force:
            return
        existing = [
            n for n in (names or ["recording.h5", "summary.json"]) if (self.directory / n).exists()
        ]
        if existing:
            raise ModelError(
                f"{os.fspath(self.directory)} already holds {', '.join(existing)}; "
                "pass --force to replace them or choose another directory"
            )

    def write(self, summary: Mapping[str, Any]) -> list[Path]:
        """Write everything collected plus ``summary.json``; return the paths written."""
        self.check_target(self.planned())
        self.directory.mkdir(parents=True, exist_ok=True)
        if self._staging is None:
            self._staging = Path(tempfile.mkdtemp(prefix=".visviva-", dir=self.directory))
        staging = self._staging
        try:
            if self.recordings:
                write_recordings(staging / "recording.h5", self.recordings)
            for name, figure in self.figures.items():
                figure.savefig(staging / f"{name}.png", dpi=110)
            full = dict(summary) | {"outputs": self.planned()}
            text = json.dumps(plain_json(full), indent=2, allow_nan=False)
            (staging / "summary.json").write_text(text + "\n")
            written = []
            for name in self.planned():
                target = self.directory / name
                os.replace(staging / name, target)
                written.append(target)
            return written
        finally:
            self.discard()


def plain_json(value: Any) -> Any:
    """``value`` as plain JSON: NumPy scalars unwrapped, non-finite floats as strings."""
    import math

    import numpy as np

    if isinstance(value, Mapping):
        return {str(k): plain_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain_json(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
