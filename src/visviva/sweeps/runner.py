"""Running a sweep: every run through :func:`~visviva.scenes.run_scene`, on any executor.

Each run is an independent task (:class:`RunTask`: the scene as plain data, picklable) that
writes ``summary.json`` (and, if kept, ``recording.h5`` and the extra outputs) into
``directory/runs/<index>-<values>/``, then ``run.json`` (its index, values, the digest of its
scene, success and error). A run that fails or diverges is recorded with its error and the
others go on. With ``resume``, a run whose directory holds ``run.json`` for the same scene
digest and values, and a ``summary.json`` that was not interrupted, is not run again (a diverged
run counts as finished: the same scene diverges the same way). On Ctrl-C the runs under way stop
(their directories are removed), no new run starts, and the finished ones are kept and listed in
the results. ``results.csv`` and ``results.json`` (:mod:`.results`) are written at the end,
atomically, also after an interrupt, and then ``results.h5``, the plots and ``index.html``
(:mod:`.reports`).
"""

from __future__ import annotations

import json
import multiprocessing
import multiprocessing.context
import os
import shutil
import signal
from collections.abc import Callable
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed, wait
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any, Literal

from .._validation import whole_number
from ..errors import ModelError, VisvivaError
from ..io.files import atomic_path, check_directory
from ..io.job import plain_json
from ..simulation.interrupt import Interrupted
from ..simulation.progress import Progress
from .description import Sweep, load_sweep
from .design import SweepRun, expand
from .reports import write_reports
from .results import flatten_summary, write_results

__all__ = ["RunTask", "SweepInterrupted", "SweepResult", "run_task", "sweep"]

#: A run's own record, written after its summary: what it was run with, and how it ended.
RUN_FILE = "run.json"
#: Modules the pool's fork server imports once, so that each worker starts with them loaded.
WORKER_PRELOAD = ("visviva.sweeps.runner", "visviva.scenes", "visviva.simulation")
# In a worker of the sweep's own pool: True, and the stop signal once one arrived.
_in_pool_worker = False
_stopped_worker: str | None = None
#: Summary entries already in the row as ``success`` and ``error``.
_OUTCOME = ("success", "message")


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
class SweepResult:
    """What a sweep did.

    Attributes:
        directory: The sweep's output directory.
        rows: One row per finished run, in index order (the contents of ``results.json``).
        ran: Runs done by this call.
        skipped: Runs found finished and not run again.
        failed: Rows with ``success`` false (done now or before).
        files: ``results.csv`` and ``results.json``, then ``results.h5``, the plots' files and
            ``index.html``.
        warnings: The files that could not be written besides the table, each with its reason.
    """

    directory: Path
    rows: list[dict[str, Any]]
    ran: int
    skipped: int
    failed: int
    files: tuple[Path, ...]
    warnings: tuple[str, ...] = ()


class SweepInterrupted(Interrupted):
    """A sweep stopped by SIGINT/SIGTERM; ``result`` holds the runs finished before."""

    def __init__(self, signal_name: str, result: SweepResult, total: int) -> None:
        super().__init__(signal_name, float("nan"))
        done = len(result.rows)
        self.args = (
            f"sweep interrupted by {signal_name} with {done} of {total} runs finished "
            f"(listed in {result.files[0]}); run it again to resume",
        )
        self.result = result


def run_task(task: RunTask) -> dict[str, Any]:
    """Do one run; return its results row (or ``{"interrupted": signal}`` if it was stopped,
    its directory removed). Never raises for a failure of the run itself."""
    from ..model.build import build_model
    from ..model.scene import Scene
    from ..scenes import run_scene

    global _stopped_worker
    if _stopped_worker is not None:  # the queued runs of a pool told to stop do not start
        return {"index": task.index, "interrupted": _stopped_worker}
    directory = Path(task.directory)
    marker = directory / RUN_FILE
    marker.unlink(missing_ok=True)  # the run.json of an older run must not vouch for this one
    summary: dict[str, Any] | None = None
    error: str | None = None
    try:
        model = build_model(Scene.model_validate(task.scene))
        report = run_scene(model, directory, formats=task.formats, force=True, progress=False)
        summary = report.summary
    except Interrupted as stop:
        shutil.rmtree(directory, ignore_errors=True)
        if _in_pool_worker:
            _stopped_worker = stop.signal
        return {"index": task.index, "interrupted": stop.signal}
    except VisvivaError as failure:  # diverged, failed to converge, an output not written
        error = str(failure)
        summary = failure.report.summary if failure.report is not None else None
    except Exception as failure:  # one broken run must not end the others
        error = f"{type(failure).__name__}: {failure}"
    if not task.keep_recording:
        (directory / "recording.h5").unlink(missing_ok=True)
    info = {
        "index": task.index,
        "run": task.name,
        "values": task.values,
        "digest": task.digest,
        "success": error is None and bool(summary and summary.get("success")),
        "error": error,
    }
    directory.mkdir(parents=True, exist_ok=True)
    with atomic_path(marker) as temporary:
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


def _finished(directory: Path, run: SweepRun) -> dict[str, Any] | None:
    """The row of a run already done in ``directory`` with the same scene, or ``None``."""
    try:
        info = json.loads((directory / RUN_FILE).read_text())
        summary = json.loads((directory / "summary.json").read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(info, dict) or not isinstance(summary, dict) or "interrupted" in summary:
        return None
    if info.get("digest") != run.digest or info.get("values") != plain_json(run.values):
        return None
    return _row(info, summary)


def sweep(
    description: Sweep | str | os.PathLike[str],
    directory: str | os.PathLike[str],
    *,
    executor: Executor | Literal["serial"] | None = None,
    workers: int | None = None,
    resume: bool = True,
    progress: bool | None = None,
) -> SweepResult:
    """Run every run of a sweep into ``directory/runs/`` and tabulate the results.

    Args:
        description: A sweep file (``.toml``/``.json``) or a loaded :class:`Sweep`.
        directory: Output directory (created if missing).
        executor: Where the runs go: any :class:`concurrent.futures.Executor` (a Dask client's
            ``get_executor()``, say), ``"serial"`` for one after the other in this process, or
            ``None`` for a process pool of ``workers`` processes.
        workers: Processes of the default pool (default: every core).
        resume: Skip runs already finished in ``directory`` with the same scene.
        progress: Progress bar over runs (default: when stderr is a terminal).

    Returns:
        The rows written to ``results.csv`` and ``results.json``, and the counts.

    Raises:
        SweepError: A bad description, or runs whose scenes fail validation (all listed),
            before anything is run or written.
        ModelError: An unwritable directory or bad ``workers``, before anything is run.
        SweepInterrupted: On SIGINT/SIGTERM, after writing the results of the finished runs.
    """
    chosen = description if isinstance(description, Sweep) else load_sweep(description)
    if workers is not None:
        workers = whole_number("workers", workers, minimum=1)
        if executor is not None:
            raise ModelError("`workers` sizes the default process pool; omit it with `executor`")
    if not (executor is None or executor == "serial" or isinstance(executor, Executor)):
        raise ModelError(
            f"`executor` must be a concurrent.futures.Executor, 'serial' or None (got {executor!r})"
        )
    runs = expand(chosen)
    root = Path(directory)
    check_directory(root, "sweep directory")
    (root / "runs").mkdir(parents=True, exist_ok=True)
    rows: dict[int, dict[str, Any]] = {}
    pending = []
    for run in runs:
        found = _finished(root / "runs" / run.name, run) if resume else None
        if found is not None:
            rows[run.index] = found
        else:
            pending.append(_task(chosen, root, run))
    skipped = len(rows)
    stopped: str | None = None
    with Progress(len(runs), f"sweep {chosen.info.name}", progress) as bar:
        bar.advance(skipped)

        def collect(row: dict[str, Any]) -> bool:
            nonlocal stopped
            if "interrupted" in row:
                stopped = stopped or row["interrupted"]
                return False
            rows[row["index"]] = row
            bar.advance(1)
            return True

        try:
            _execute(pending, executor, workers, collect)
        except KeyboardInterrupt:
            stopped = "SIGINT"
    ordered = [rows[index] for index in sorted(rows)]
    heading = {
        "sweep": chosen.info.name,
        "design": chosen.info.design,
        "seed": chosen.info.seed,
        "runs_total": len(runs),
    }
    files = write_results(root, heading, chosen.paths, ordered)
    reports = write_reports(root, chosen, heading, ordered)
    result = SweepResult(
        directory=root,
        rows=ordered,
        ran=len(rows) - skipped,
        skipped=skipped,
        failed=sum(1 for row in ordered if not row["success"]),
        files=(*files, *reports.files),
        warnings=reports.warnings,
    )
    if stopped is not None:
        raise SweepInterrupted(stopped, result, len(runs))
    return result


def _task(chosen: Sweep, root: Path, run: SweepRun) -> RunTask:
    return RunTask(
        index=run.index,
        name=run.name,
        directory=os.path.abspath(root / "runs" / run.name),
        scene=run.scene,
        values=run.values,
        digest=run.digest,
        formats=tuple(chosen.outputs.formats),
        keep_recording=chosen.outputs.recordings,
    )


def _execute(
    tasks: list[RunTask],
    executor: Executor | Literal["serial"] | None,
    workers: int | None,
    collect: Callable[[dict[str, Any]], bool],
) -> None:
    """Run ``tasks``, handing each row to ``collect`` as it comes; a row that says the run
    was interrupted (``collect`` returns false) stops the sweep."""
    if not tasks:
        return
    if executor == "serial":
        for task in tasks:
            if not collect(run_task(task)):
                return
        return
    own = executor is None
    processes = min(workers or os.cpu_count() or 1, len(tasks))
    pool: Executor = (
        ProcessPoolExecutor(
            max_workers=processes,
            mp_context=_worker_context(),
            initializer=_start_worker,
            initargs=(max(1, (os.cpu_count() or 1) // processes),),
        )
        if executor is None
        else executor
    )
    futures = {pool.submit(run_task, task): task for task in tasks}
    seen: set[Future[dict[str, Any]]] = set()
    try:
        try:
            for future in as_completed(futures):
                seen.add(future)
                if not collect(_outcome(future, futures[future])):
                    break
        finally:
            # After a stop (an interrupted row, or Ctrl-C here): cancel the runs not started,
            # wait for those under way (the signal stops them too), keep what finished.
            for future in futures:
                future.cancel()
            running = [f for f in futures if f not in seen and not f.cancelled()]
            wait(running)
            for future in running:
                collect(_outcome(future, futures[future]))
    finally:
        if own:
            pool.shutdown(wait=True, cancel_futures=True)


def _outcome(future: Future[dict[str, Any]], task: RunTask) -> dict[str, Any]:
    """The row of a finished future; a worker that died is the run's error."""
    try:
        return future.result()
    except Exception as failure:  # a broken worker fails its run only
        return {
            "index": task.index,
            "run": task.name,
            **task.values,
            "success": False,
            "error": f"{type(failure).__name__}: {failure}",
        }


def _worker_context() -> multiprocessing.context.BaseContext:
    """Workers start from a fresh "forkserver" process (where the platform has one), never
    by forking this one: a process that has used OpenMP (Numba's parallel kernels) cannot
    fork safely. The server imports the simulation modules once, so workers start warm."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(WORKER_PRELOAD))
    return context


def _start_worker(threads: int) -> None:
    """Prepare a pool worker: a share of the cores for Numba's parallel kernels (the pool
    already runs one run per core: more threads only contend, 10x slower on 2 cores), and a
    SIGINT between runs remembered so that no queued run starts after it; during a run,
    run_scene's own handler stops it cleanly (a Ctrl-C at the terminal reaches every process
    of the group)."""
    import numba

    global _in_pool_worker
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]
    _in_pool_worker = True
    signal.signal(signal.SIGINT, _remember_stop)


def _remember_stop(number: int, frame: FrameType | None) -> None:
    """A pool worker's SIGINT between runs: the runs queued to it will not start."""
    global _stopped_worker
    _stopped_worker = signal.Signals(number).name
