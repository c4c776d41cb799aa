"""What a worker does: one run of a sweep, or a batch of runs that can advance together.

A :class:`RunTask` is one run (its scene as plain data, picklable): it goes through
:func:`~visviva.scenes.run_scene` into its directory, then ``run.json`` records its index,
values, the digest of its scene, success and error. A :class:`BatchTask` holds runs whose
models share an :func:`~visviva.simulation.ensemble.ensemble_key` (a thousand pendulums from a
thousand angles, a ball on floors of fifty restitutions): they advance side by side in
batches (:func:`~visviva.simulation.ensemble.run_ensemble`, as many members at a time as
:func:`~visviva.simulation.ensemble.ensemble_capacity` allows) and each then writes exactly the
files its own run would have written, with the same numbers (see the ensemble module for
where "the same" is to round-off). A member that fails in the batch, or cannot join it, runs
alone. Every task returns one results row per run; a failure of
a run is its row's error, never an exception.
"""

from __future__ import annotations

import json
import shutil
import signal
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import VisvivaError
from ..io.files import atomic_path
from ..io.job import plain_json
from ..simulation.interrupt import Interrupted
from .results import flatten_summary

if TYPE_CHECKING:
    from ..model import Model
    from ..ode.state import State
    from ..scenes import RunFigures
    from ..simulation.ensemble import EnsembleFrame
    from ..simulation.interrupt import StopOnSignal

__all__ = ["RUN_FILE", "BatchTask", "RunTask", "finished_row", "perform", "run_batch", "run_task"]

#: A run's own record, written after its summary: what it was run with, and how it ended.
RUN_FILE = "run.json"
#: Summary entries already in the row as ``success`` and ``error``.
_OUTCOME = ("success", "message")
# In a worker of the sweep's own pool: True, and the stop signal once one arrived.
_in_pool_worker = False
_stopped_worker: str | None = None


@dataclass(frozen=True)
class RunTask:
    """What a worker needs to do one run (plain data: it travels to other processes).

    Attributes:
        index: The run's index in the design.
        name: Its directory name.
        directory: Its directory (absolute).
        scene: Its scene as plain data (validated before the sweep started).
        values: Its parameters' values, by path.
        digest: SHA-256 of ``scene``.
        formats: Extra outputs to write (mp4, html, ...).
        keep_recording: Keep ``recording.h5`` (else it is removed after the run).
    """

    index: int
    name: str
    directory: str
    scene: dict[str, Any]
    values: dict[str, Any]
    digest: str
    formats: tuple[str, ...] = ()
    keep_recording: bool = False


@dataclass(frozen=True)
class BatchTask:
    """Runs to advance together in one batched state (see the module docstring).

    Attributes:
        runs: The members, in index order.
    """

    runs: tuple[RunTask, ...]


def perform(task: RunTask | BatchTask) -> list[dict[str, Any]]:
    """Do a task; return one results row per run (see :func:`run_task`)."""
    return run_batch(task) if isinstance(task, BatchTask) else [run_task(task)]


def run_task(task: RunTask) -> dict[str, Any]:
    """Do one run; return its results row (or ``{"interrupted": signal}`` if it was stopped,
    its directory removed). Never raises for a failure of the run itself."""
    from ..model.build import build_model
    from ..model.scene import Scene
    from ..scenes import run_scene

    global _stopped_worker
    if _stopped_worker is not None:  # the queued runs of a pool told to stop do not start
        return {"index": task.index, "interrupted": _stopped_worker}
    _clear(task)
    summary: dict[str, Any] | None = None
    error: str | None = None
    try:
        model = build_model(Scene.model_validate(task.scene))
        report = run_scene(model, task.directory, formats=task.formats, force=True, progress=False)
        summary = report.summary
    except Interrupted as stop:
        return _interrupted(task, stop.signal)
    except VisvivaError as failure:  # diverged, failed to converge, an output not written
        error = str(failure)
        summary = failure.report.summary if failure.report is not None else None
    except Exception as failure:  # one broken run must not end the others
        error = f"{type(failure).__name__}: {failure}"
    if not task.keep_recording:
        (Path(task.directory) / "recording.h5").unlink(missing_ok=True)
    return _conclude(task, summary, error)


def run_batch(task: BatchTask) -> list[dict[str, Any]]:
    """Do a batch of runs (see the module docstring); one results row per run, in order."""
    from ..model.build import build_model
    from ..model.scene import Scene
    from ..simulation.ensemble import ensemble_key
    from ..simulation.interrupt import StopOnSignal

    if _stopped_worker is not None:
        return [{"index": run.index, "interrupted": _stopped_worker} for run in task.runs]
    members: list[tuple[RunTask, Model]] = []
    alone: list[RunTask] = []
    for run in task.runs:
        try:
            members.append((run, build_model(Scene.model_validate(run.scene))))
        except Exception:  # run alone, which reports the problem as that run's error
            alone.append(run)
    keys = [ensemble_key(model) for _, model in members]
    if members and (keys[0] is None or any(key != keys[0] for key in keys)):
        alone += [run for run, _ in members]  # not one ensemble here after all
        members = []
    rows: dict[int, dict[str, Any]] = {}
    with StopOnSignal() as stops:
        try:
            try:
                figures, failed = _advance_together(members, stops)
            except (Interrupted, KeyboardInterrupt):
                raise
            except Exception:  # a batch that could not be made: its members run alone
                alone += [run for run, _ in members]
                members, figures, failed = [], [], set()
            for (run, model), (figure, frames) in zip(members, figures, strict=True):
                if run.index in failed:
                    alone.append(run)
                else:
                    rows[run.index] = _write_member(run, model, figure, frames)
        except (Interrupted, KeyboardInterrupt) as stop:
            name = stop.signal if isinstance(stop, Interrupted) else stops.requested or "SIGINT"
            return [rows.get(run.index) or _interrupted(run, name) for run in task.runs]
    for run in sorted(alone, key=lambda r: r.index):
        rows[run.index] = run_task(run)
    return [rows[run.index] for run in task.runs]


def _advance_together(
    members: list[tuple[RunTask, Model]], stops: StopOnSignal
) -> tuple[list[tuple[RunFigures, list[Any] | None]], set[int]]:
    """Run the members' models as one ensemble (in as many batches as
    :func:`~visviva.simulation.ensemble.ensemble_capacity` asks); each member's figures (and
    frames, if its recording is kept or made into outputs), and the indices of the members
    that failed."""
    from ..simulation.ensemble import ensemble_capacity

    done: list[tuple[RunFigures, list[Any] | None]] = []
    failed: set[int] = set()
    while len(done) < len(members):
        rest = members[len(done) :]
        chunk = rest[: ensemble_capacity([model for _, model in rest])]
        figures, lost = _advance_batch(chunk, stops)
        done += figures
        failed |= lost
    return done, failed


def _advance_batch(
    members: list[tuple[RunTask, Model]], stops: StopOnSignal
) -> tuple[list[tuple[RunFigures, list[Any] | None]], set[int]]:
    """Run the members' models as one batch (see :func:`_advance_together`)."""
    from ..simulation.ensemble import run_ensemble

    models = [model for _, model in members]
    figures = _Figures(models)
    kept: dict[int, list[Any]] = {
        i: [] for i, (run, _) in enumerate(members) if run.keep_recording or run.formats
    }
    sinks = {i: figures.recorder(i, _Frames(frames)) for i, frames in kept.items()}

    def on_frame(frame: EnsembleFrame) -> None:
        figures.see(frame)
        for k, member in enumerate(frame.members if sinks else ()):
            if member in sinks:
                energy = None if frame.energy is None else float(frame.energy[k])
                sinks[member](frame.state(k), energy)

    with stops.polled():
        result = run_ensemble(models, models[0].integration.duration, on_frame=on_frame)
    counters = {"steps": result.counters["accepted_steps"]} | result.counters
    done = []
    for i in range(len(members)):
        figure = figures.of(i)
        figure.counters = dict(counters)
        figure.wall_time_s = result.wall_time_s / len(members)
        figure.batch_size = len(members)
        done.append((figure, kept.get(i)))
    return done, {members[i][0].index for i in result.failed}


class _Figures:
    """What :class:`~visviva.scenes.RunFigures` keeps of a run, for every member of a batch
    at once: frame by frame, as arrays over the members, with the same arithmetic (a member's
    figures are those of its own run); the drawn frame of a member is made only for its last
    frame (its final coordinates) or when its recording is kept."""

    def __init__(self, models: list[Model]) -> None:
        count = len(models)
        self.models = models
        self.frames = np.zeros(count, dtype=np.int64)
        self.t_reached = np.full(count, np.nan)
        self.energy_start = np.full(count, np.nan)
        self.energy_last = np.full(count, np.nan)
        self.energy_change = np.zeros(count)
        self.has_energy = False
        self.last: EnsembleFrame | None = None  # the latest frame, copied
        self.individual: dict[int, RunFigures] = {}

    def see(self, frame: EnsembleFrame) -> None:
        members = np.asarray(frame.members, dtype=np.int64)
        self.frames[members] += 1
        self.t_reached[members] = frame.t
        if frame.energy is not None:
            self.has_energy = True
            value = np.asarray(frame.energy, dtype=np.float64)
            first = self.frames[members] == 1
            self.energy_start[members[first]] = value[first]
            self.energy_last[members] = value
            change = np.abs(value - self.energy_start[members])
            self.energy_change[members] = np.maximum(self.energy_change[members], change)
        self.last = frame.kept()

    def recorder(self, member: int, writer: Any) -> Callable[[State, Any], None]:
        """The recorder of a member whose frames are kept (its figures come from it)."""
        from ..scenes import RunFigures

        figure = self.individual[member] = RunFigures()
        return figure.recorder(self.models[member], writer)

    def of(self, member: int) -> RunFigures:
        """Member ``member``'s figures, as its own run would have them."""
        from ..scenes import RunFigures, drawn_points, final_values
        from ..simulation.frames import frame_fields

        if member in self.individual:
            return self.individual[member]
        model, fields = self.models[member], {}
        if self.last is not None and member in self.last.members:
            fields = frame_fields(model, self.last.state(self.last.members.index(member)))
        figure = RunFigures(
            t_reached=float(self.t_reached[member]),
            frames=int(self.frames[member]),
            points=drawn_points(fields),
            final=final_values(fields),
        )
        if self.has_energy:
            figure.energy_start = float(self.energy_start[member])
            figure.energy_last = float(self.energy_last[member])
            figure.energy_change = float(self.energy_change[member])
        return figure


class _Frames:
    """A member's recorded frames kept in memory (``append(t, fields)`` like a writer)."""

    def __init__(self, store: list[Any]) -> None:
        self.store = store

    def append(self, t: float, fields: dict[str, Any]) -> None:
        self.store.append((t, {name: value.copy() for name, value in fields.items()}))


def _write_member(
    run: RunTask, model: Model, figure: RunFigures, frames: list[Any] | None
) -> dict[str, Any]:
    """Write a batch member's files, as its own run would have, and conclude it."""
    from ..io.writer import RecordingWriter
    from ..scenes import final_attrs, recording_attrs, write_run
    from ..simulation.frames import UNITS, static_fields

    seconds = model.integration.duration

    def replay(path: Path | None, stops: StopOnSignal) -> tuple[RunFigures, None]:
        if path is not None and frames is not None:
            attrs = recording_attrs(model, seconds)
            with RecordingWriter(
                path, units=UNITS, attrs=attrs, static=static_fields(model)
            ) as writer:
                if frames:
                    times = [t for t, _ in frames]
                    writer.extend(
                        times, {k: np.stack([f[k] for _, f in frames]) for k in frames[0][1]}
                    )
                writer.finish(final_attrs(figure, None, figure.wall_time_s))
        return figure, None

    _clear(run)
    try:
        report = write_run(
            model,
            run.directory,
            replay,
            seconds=seconds,
            formats=run.formats,
            force=True,
            record=frames is not None,
        )
    except VisvivaError as failure:  # an output that could not be written
        summary = failure.report.summary if failure.report is not None else None
        return _conclude(run, summary, str(failure))
    if not run.keep_recording:
        (Path(run.directory) / "recording.h5").unlink(missing_ok=True)
    return _conclude(run, report.summary, None)


def _clear(task: RunTask) -> None:
    """Remove the run.json of an older run: it must not vouch for this one."""
    (Path(task.directory) / RUN_FILE).unlink(missing_ok=True)


def _interrupted(task: RunTask, signal_name: str) -> dict[str, Any]:
    """The row of a run stopped by a signal (its directory removed); in a pool worker, the
    runs queued to it will not start."""
    global _stopped_worker
    shutil.rmtree(task.directory, ignore_errors=True)
    if _in_pool_worker:
        _stopped_worker = signal_name
    return {"index": task.index, "interrupted": signal_name}


def _conclude(task: RunTask, summary: dict[str, Any] | None, error: str | None) -> dict[str, Any]:
    """Write the run's ``run.json`` and return its results row."""
    info = {
        "index": task.index,
        "run": task.name,
        "values": task.values,
        "digest": task.digest,
        "success": error is None and bool(summary and summary.get("success")),
        "error": error,
    }
    directory = Path(task.directory)
    directory.mkdir(parents=True, exist_ok=True)
    with atomic_path(directory / RUN_FILE) as temporary:
        temporary.write_text(json.dumps(plain_json(info), indent=2, allow_nan=False) + "\n")
    return _row(info, summary)


def _row(info: dict[str, Any], summary: dict[str, Any] | None) -> dict[str, Any]:
    figures = flatten_summary({k: v for k, v in (summary or {}).items() if k not in _OUTCOME})
    return (
        {"index": info["index"], "run": info["run"]}
        | info["values"]
        | {"success": info["success"], "error": info["error"]}
        | figures
    )


def finished_row(directory: Path, digest: str, values: dict[str, Any]) -> dict[str, Any] | None:
    """The row of a run already done in ``directory`` with the same scene, or ``None``."""
    try:
        info = json.loads((directory / RUN_FILE).read_text())
        summary = json.loads((directory / "summary.json").read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(info, dict) or not isinstance(summary, dict) or "interrupted" in summary:
        return None
    if info.get("digest") != digest or info.get("values") != plain_json(values):
        return None
    return _row(info, summary)


def start_worker(threads: int) -> None:
    """Prepare a pool worker: a share of the cores for Numba's parallel kernels (the pool
    already runs one task per core: more threads only contend, 10x slower on 2 cores), and a
    SIGINT between tasks remembered so that no queued task starts after it; during a run,
    its own handler stops it cleanly (a Ctrl-C at the terminal reaches every process of the
    group)."""
    import numba

    global _in_pool_worker
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]
    _in_pool_worker = True
    signal.signal(signal.SIGINT, _remember_stop)


def _remember_stop(number: int, frame: FrameType | None) -> None:
    """A pool worker's SIGINT between tasks: the tasks queued to it will not start."""
    global _stopped_worker
    _stopped_worker = signal.Signals(number).name
