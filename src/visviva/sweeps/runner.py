"""Running a sweep: every run, alone or in a batch, on any executor.

Each run is an independent task (:class:`~visviva.sweeps.tasks.RunTask`: the scene as plain
data, picklable) that writes ``summary.json`` (and, if kept, ``recording.h5`` and the extra
outputs) into ``directory/runs/<index>-<values>/``, then ``run.json`` (its index, values, the
digest of its scene, success and error). Runs whose models are one named system with the same
equations and settings — a sweep over starting angles — are grouped into batches
(:class:`~visviva.sweeps.tasks.BatchTask`) that advance side by side in one batched state and
write exactly what each run would have written alone. A run that fails or diverges is recorded
with its error and the others go on. With ``resume``, a run whose directory holds ``run.json``
for the same scene digest and values, and a ``summary.json`` that was not interrupted, is not run
again (a diverged run counts as finished: the same scene diverges the same way). On Ctrl-C the
runs under way stop (their directories are removed), no new run starts, and the finished ones
are kept and listed in the results; on another executor (a Dask cluster) the runs not started
are cancelled and those under way are left to finish there. A run done by another executor
must leave its files where this process sees them (:mod:`.shared_files`). ``results.csv`` and
``results.json`` (:mod:`.results`) are written at the end, atomically, also after an interrupt,
and then ``results.h5``, the plots and ``index.html`` (:mod:`.reports`).
"""

from __future__ import annotations

import math
import multiprocessing
import multiprocessing.context
import os
from collections.abc import Callable, Sequence
from concurrent.futures import (
    CancelledError,
    Executor,
    Future,
    ProcessPoolExecutor,
    as_completed,
    wait,
)
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from .._validation import whole_number
from ..errors import ModelError, SimulationError
from ..io.files import check_directory
from ..simulation.interrupt import Interrupted
from ..simulation.progress import Progress
from .description import Sweep, load_sweep
from .design import SweepRun, expand
from .reports import write_reports
from .results import write_results
from .shared_files import SharedFiles
from .tasks import RUN_FILE, BatchTask, RunTask, finished_row, perform, start_worker

__all__ = ["SweepFailed", "SweepInterrupted", "SweepResult", "sweep"]

#: Modules the pool's fork server imports once, so that each worker starts with them loaded.
WORKER_PRELOAD = (
    "visviva.sweeps.tasks",
    "visviva.scenes",
    "visviva.simulation",
    "visviva.simulation.ensemble",
)
#: A batch needs at least this many runs: below it, separate runs on separate cores finish
#: sooner than one batch on one core.
MIN_BATCH = 2
#: Most runs in one batch: a batch keeps the frames of the members whose recordings are kept
#: until it ends, and more members per batch gain nothing once the per-step work is shared.
MAX_BATCH = 1024


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


class SweepFailed(SimulationError):
    """Every run of a sweep failed (raised after the results table was written, so each
    run's error can be read there).

    Attributes:
        result: The :class:`SweepResult` of the failed runs.
    """

    def __init__(self, result: SweepResult) -> None:
        first = result.rows[0]
        reason = str(first["error"]).splitlines()[0]
        total = len(result.rows)
        every = "the only run" if total == 1 else f"all {total} runs"
        super().__init__(
            f"{every} of the sweep failed; run {first['run']}: {reason} "
            f"(every run's error is in {result.files[0]})",
            t=float("nan"),
            step=None,
        )
        self.result = result


def sweep(
    description: Sweep | str | os.PathLike[str],
    directory: str | os.PathLike[str],
    *,
    executor: Executor | Literal["serial"] | None = None,
    workers: int | None = None,
    resume: bool = True,
    batch: bool = True,
    progress: bool | None = None,
) -> SweepResult:
    """Run every run of a sweep into ``directory/runs/`` and tabulate the results.

    Args:
        description: A sweep file (``.toml``/``.json``) or a loaded :class:`Sweep`.
        directory: Output directory (created if missing).
        executor: Where the runs go: any :class:`concurrent.futures.Executor` (a Dask
            cluster's: :func:`~visviva.sweeps.dask_executor`, or a client's
            ``get_executor()``), ``"serial"`` for one after the other in this process, or
            ``None`` for a process pool of ``workers`` processes. The runs of another
            executor than the pool must write where this process can read: on a cluster,
            ``directory`` must be on a file system the workers share.
        workers: Processes of the default pool (default: every core).
        resume: Skip runs already finished in ``directory`` with the same scene.
        batch: Advance runs that can together in batches (one named system with the same
            equations, or particle scenes with the same entities; an explicit or symplectic
            method: :func:`~visviva.simulation.ensemble.ensemble_key`); each run's files and
            numbers are the same either way (bit for bit, or to round-off where a particle
            batch sums a force by another path: :mod:`visviva.model.replicas`).
        progress: Progress bar over runs (default: when stderr is a terminal).

    Returns:
        The rows written to ``results.csv`` and ``results.json``, and the counts.

    Raises:
        SweepError: A bad description, or runs whose scenes fail validation (all listed),
            before anything is run or written.
        ModelError: An unwritable directory or bad ``workers``, before anything is run.
        SweepInterrupted: On SIGINT/SIGTERM, after writing the results of the finished runs.
        SweepFailed: If every run failed, after writing the results (each run's error).
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
    pending: list[tuple[SweepRun, RunTask]] = []
    # Only directories listed here are read: a failed look-up of a run not yet done could be
    # cached by a network file system and hide that run's files when a worker writes them.
    present = set(os.listdir(root / "runs")) if resume else set()
    for run in runs:
        task = _task(chosen, root, run)
        found = (
            finished_row(Path(task.directory), run.digest, run.values)
            if run.name in present
            else None
        )
        if found is not None:
            rows[run.index] = found
        else:
            pending.append((run, task))
    slots = 1 if executor == "serial" else workers or os.cpu_count() or 1
    tasks = _plan(pending, slots) if batch else [task for _, task in pending]
    skipped = len(rows)
    stopped: str | None = None
    with Progress(len(runs), f"sweep {chosen.info.name}", progress) as bar:
        bar.advance(skipped)

        def collect(done: list[dict[str, Any]]) -> bool:
            nonlocal stopped
            for row in done:
                if "interrupted" in row:
                    stopped = stopped or row["interrupted"]
                else:
                    rows[row["index"]] = row
                    bar.advance(1)
            return stopped is None

        try:
            _execute(tasks, executor, workers, collect)
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
    if ordered and result.failed == len(ordered):
        raise SweepFailed(result)
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


def _plan(pending: list[tuple[SweepRun, RunTask]], slots: int) -> list[RunTask | BatchTask]:
    """The tasks for the runs to do: runs with one batch key grouped into batches of
    :data:`MIN_BATCH` to :data:`MAX_BATCH` runs, split so that each of ``slots`` workers gets
    a share, the rest alone; in the order of their first run."""
    tasks: list[RunTask | BatchTask] = []
    groups: dict[Any, list[RunTask]] = {}
    for run, task in pending:
        if run.batch_key is not None:
            groups.setdefault(run.batch_key, []).append(task)
        else:
            tasks.append(task)
    for members in groups.values():
        if len(members) < MIN_BATCH:
            tasks += members
            continue
        size = max(MIN_BATCH, min(MAX_BATCH, math.ceil(len(members) / slots)))
        for start in range(0, len(members), size):
            chunk = members[start : start + size]
            tasks += [BatchTask(tuple(chunk))] if len(chunk) >= MIN_BATCH else chunk
    return sorted(tasks, key=lambda t: t.runs[0].index if isinstance(t, BatchTask) else t.index)


def _execute(
    tasks: Sequence[RunTask | BatchTask],
    executor: Executor | Literal["serial"] | None,
    workers: int | None,
    collect: Callable[[list[dict[str, Any]]], bool],
) -> None:
    """Run ``tasks``, handing the rows of each to ``collect`` as they come; a row that says
    its run was interrupted (``collect`` returns false) stops the sweep."""
    if not tasks:
        return
    if executor == "serial":
        for task in tasks:
            if not collect(perform(task)):
                return
        return
    own = executor is None
    processes = min(workers or os.cpu_count() or 1, len(tasks))
    pool: Executor = (
        ProcessPoolExecutor(
            max_workers=processes,
            mp_context=_worker_context(),
            initializer=start_worker,
            initargs=(max(1, (os.cpu_count() or 1) // processes),),
        )
        if executor is None
        else executor
    )
    # Another executor's workers may be other machines: each run's files must be seen here.
    shared = None if own else SharedFiles(lambda row: collect([row]), RUN_FILE)
    futures: dict[Future[list[dict[str, Any]]], RunTask | BatchTask] = {}
    seen: set[Future[list[dict[str, Any]]]] = set()
    complete = False

    def take(future: Future[list[dict[str, Any]]]) -> bool:
        task = futures[future]
        done = _outcome(future, task)
        if shared is None or future.cancelled() or future.exception() is not None:
            return collect(done)  # a task that did not come back wrote no files to look for
        directories = {run.index: run.directory for run in _runs(task)}
        go_on = True
        for row in done:
            go_on = shared(row, directories[row["index"]]) and go_on
        return go_on

    try:
        try:
            for task in tasks:  # submitted inside the try: a Ctrl-C here cancels them too
                futures[pool.submit(perform, task)] = task
            for future in as_completed(futures):
                seen.add(future)
                if not take(future):
                    break
            else:
                complete = True
        finally:
            # After a stop (an interrupted row, or Ctrl-C here): cancel the runs not started
            # and keep what finished. The runs under way on the own pool got the signal too
            # and stop within a step: wait for them. Elsewhere (a cluster) they may be far
            # from done, so do not: they finish on their own, and a later sweep resumes.
            for future in futures:
                future.cancel()
            rest = [f for f in futures if f not in seen and not f.cancelled()]
            if own:
                wait(rest)
            for future in rest:
                if future.done():
                    take(future)
            if shared is not None:
                shared.settle(wait=complete)
    finally:
        if own:
            pool.shutdown(wait=True, cancel_futures=True)


def _outcome(
    future: Future[list[dict[str, Any]]], task: RunTask | BatchTask
) -> list[dict[str, Any]]:
    """The rows of a finished future; a worker that died, or a task the executor cancelled (a
    cluster that lost its scheduler), is the error of its task's runs."""
    try:
        return future.result()
    except CancelledError:
        error = "the executor cancelled the run before it finished; run the sweep again"
    except BrokenProcessPool as failure:
        error = (
            f"BrokenProcessPool: {failure} A worker process died: it was killed (out of "
            "memory?), or the script that called vv.sweep has no `if __name__ == "
            '"__main__":` guard around the call (the workers import that script)'
        )
    except Exception as failure:  # a broken worker fails its task's runs only
        error = f"{type(failure).__name__}: {failure}"
    return [
        {"index": run.index, "run": run.name, **run.values, "success": False, "error": error}
        for run in _runs(task)
    ]


def _runs(task: RunTask | BatchTask) -> tuple[RunTask, ...]:
    return task.runs if isinstance(task, BatchTask) else (task,)


def _worker_context() -> multiprocessing.context.BaseContext:
    """Workers start from a fresh "forkserver" process (where the platform has one), never
    by forking this one: a process that has used OpenMP (Numba's parallel kernels) cannot
    fork safely. The server imports the simulation modules once, so workers start warm."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(WORKER_PRELOAD))
    return context
