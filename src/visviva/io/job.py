"""Writing a demo's (or any run's) outputs into a directory, all or nothing.

A job's files — ``recording.h5``, ``summary.json``, its figures and extra outputs — are written
into a hidden staging directory inside the target and moved into place together, so the target
never holds a partial file. A job that fails or is interrupted still moves what it finished (a
recording marked incomplete, the outputs written before the interrupt); the staging directory is
always removed, and one left by a killed process is removed by the next job in the same
directory. Files that already exist are replaced only with ``force``.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..analysis.invariants import energy_drift, max_energy_error
from ..errors import ModelError
from .files import check_directory
from .json_values import plain_json
from .recording import write_recordings

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulation.recording import Recording

__all__ = [
    "JobOutput",
    "JobReport",
    "python_warnings",
    "remove_stale_staging",
    "run_summary",
]

#: Name prefix of a job's staging directory; the job's process id follows it.
STAGING_PREFIX = ".visviva-"


def run_summary(recording: Recording) -> dict[str, Any]:
    """The per-run entry of ``summary.json``: method, step, work, energy drift, outcome.

    ``conservative`` says whether the run's energy change measures the integrator's error
    (absent when the recording does not say)."""
    attrs = recording.attrs
    keys = (
        "method",
        "dt",
        "substeps",
        "conservative",
        "steps",
        "f_evaluations",
        "jacobian_evaluations",
        "linear_solves",
        "newton_iterations",
        "krylov_iterations",
        "rejected_steps",
        "wall_time_s",
        "success",
        "message",
    )
    entry = {k: attrs[k] for k in keys if k in attrs}
    entry["energy_drift"] = energy_drift(recording)
    entry["max_energy_error"] = max_energy_error(recording)
    return entry


@dataclass(frozen=True)
class JobReport:
    """What a job wrote.

    Attributes:
        files: The files (and, for OBJ sequences, folders) now in the output directory.
        summary: The contents of ``summary.json``.
        removed_stale: Staging directories of killed jobs that were removed from the output
            directory.
    """

    files: list[Path]
    summary: dict[str, Any]
    removed_stale: list[Path] = field(default_factory=list)


def python_warnings(caught: list[warnings.WarningMessage]) -> list[dict[str, Any]]:
    """Warnings raised during a job, one entry per distinct message with its count."""
    counts: dict[tuple[str, str], int] = {}
    for warning in caught:
        key = (warning.category.__name__, str(warning.message))
        counts[key] = counts.get(key, 0) + 1
    return [
        {"kind": kind, "message": message, "count": count}
        for (kind, message), count in counts.items()
    ]


class JobOutput:
    """Collects a job's recordings, figures, files and summary, then moves them into place.

    Everything is written into a hidden staging directory inside the target
    (``.visviva-<pid>-…``) and moved into the target by :meth:`write`, so the target never holds
    a partial file. Use it as a context manager: leaving it, whether by :meth:`write` or by an
    exception, removes the staging directory.

    Args:
        directory: Output directory (created if missing).
        force: Replace output files that already exist.
    """

    def __init__(self, directory: str | os.PathLike[str], *, force: bool = False) -> None:
        self.directory = Path(directory)
        self.force = force
        self.recordings: dict[str, Recording] = {}
        self.figures: dict[str, Figure] = {}
        self.staged: list[str] = []
        self.removed_stale: list[Path] = []
        self._staging: Path | None = None

    def __enter__(self) -> JobOutput:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.discard()

    def show_first(self, run: str) -> None:
        """Make recording ``run`` the first: the one the video, viewer and exports show. A
        job adds each run to :attr:`recordings` as it finishes (so that Ctrl-C keeps it), then
        puts the one to show in front."""
        self.recordings = {run: self.recordings[run]} | self.recordings

    def planned(self) -> list[str]:
        """File names this job will write."""
        names = ["recording.h5"] if self.recordings or "recording.h5" in self.staged else []
        names.append("summary.json")
        names += [f"{name}.png" for name in self.figures]
        return names + [name for name in self.staged if name != "recording.h5"]

    def stage(self, name: str) -> Path:
        """Where to write output file ``name`` now; it moves into place with the others.

        The file counts as written as soon as it is asked for: use :meth:`writing` for one
        whose writing may be interrupted. If the process dies, what was written (a flushed
        recording) stays in the staging directory until the next job in the same directory.
        """
        self.staged.append(name)
        return self._staging_directory() / name

    @contextlib.contextmanager
    def writing(self, name: str) -> Iterator[Path]:
        """Where to write output ``name``; it joins the job only if the block completes."""
        path = self._staging_directory() / name
        try:
            yield path
        except BaseException:
            if path.is_dir():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
            raise
        self.staged.append(name)

    def discard(self) -> None:
        """Remove the staging directory and everything still in it."""
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None

    def check_target(self, names: list[str] | None = None) -> None:
        """Refuse to overwrite existing outputs without ``force`` (call before the work).

        Also removes staging directories that killed jobs left in the target (their process
        no longer exists); :attr:`removed_stale` lists them.
        """
        check_directory(self.directory, "output directory")
        self.removed_stale += remove_stale_staging(self.directory)
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

    def write(self, summary: Mapping[str, Any]) -> JobReport:
        """Write everything collected plus ``summary.json`` and move it all into place."""
        self.check_target(self.planned())
        staging = self._staging_directory()
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
                if (staging / name).is_dir() and target.is_dir():
                    shutil.rmtree(target)  # an OBJ folder replaced with --force
                os.replace(staging / name, target)
                written.append(target)
            return JobReport(written, full, list(self.removed_stale))
        finally:
            self.discard()

    def _staging_directory(self) -> Path:
        if self._staging is None:
            self.directory.mkdir(parents=True, exist_ok=True)
            self._staging = Path(
                tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}-", dir=self.directory)
            )
        return self._staging


def remove_stale_staging(directory: Path) -> list[Path]:
    """Remove staging directories in ``directory`` whose job's process no longer exists."""
    removed: list[Path] = []
    if not directory.is_dir():
        return removed
    for entry in directory.glob(f"{STAGING_PREFIX}*"):
        pid = entry.name.removeprefix(STAGING_PREFIX).partition("-")[0]
        if entry.is_dir() and pid.isdigit() and not _process_exists(int(pid)):
            shutil.rmtree(entry, ignore_errors=True)
            removed.append(entry)
    return removed


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # another user's process (or a number no process can have: keep it)
    return True
