"""Sweeps on a Dask cluster: the same runs, the same numbers, and clear errors before any work.

The promises (issue 14): a sweep on Dask (`--dask`, `--scheduler`, or any client's executor)
gives per-run results bit-identical to serial and process-pool runs; a diverging run is
reported and the others finish; Ctrl-C keeps what finished and the next sweep resumes; an
unreachable scheduler is refused at once with nothing written; without Dask installed the error
says how to install it; a run whose files the caller cannot see is recorded as failed, not lost.
One LocalCluster of two workers serves the module.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from concurrent.futures import Executor, Future
from dataclasses import replace
from pathlib import Path

import distributed  # in the [test] extra: these tests run in CI, never skipped
import numpy as np
import pytest

import visviva as vv
from test_sweeps import DIVERGING, GRID, run_main, spring_sweep, write
from visviva.errors import ModelError
from visviva.io.recording import load_recording
from visviva.sweeps import SweepInterrupted, dask_executor, shared_files
from visviva.sweeps import cluster as cluster_module

#: Six runs that all succeed, with the methods of DIVERGING: the kernels a worker has
#: loaded for one sweep serve the others (loading them is most of a short run's time).
STEADY = GRID.replace("explicit_euler", "symplectic_euler")
#: Two stiffnesses × two methods; k = 1e6 N/m diverges with both (ωh = 10).
DIVERGING_FOUR = DIVERGING.replace("[10.0, 1e6, 100.0]", "[10.0, 1e6]")
#: Two stiffnesses of the spring: two short runs.
TWO_RUNS = '[[parameters]]\npath = "entities[pair].stiffness"\nvalues = [10.0, 20.0]\n'


@pytest.fixture(scope="module")
def cluster():
    """The LocalCluster of ``dask_executor(workers=2)``: its executor and scheduler address.
    Closing it must leave this process as it was: its environment, its Ctrl-C handler."""
    environment, handler = dict(os.environ), signal.getsignal(signal.SIGINT)
    with dask_executor(workers=2) as executor:
        address = executor.submit(lambda: distributed.get_worker().scheduler.address).result()
        yield executor, address
    assert dict(os.environ) == environment
    assert signal.getsignal(signal.SIGINT) is handler


@pytest.fixture(scope="module")
def client(cluster):
    """A client of that cluster, as a user with a cluster of their own would have."""
    with distributed.Client(cluster[1], set_as_default=False) as client:
        yield client


def idle(client) -> None:
    """Wait until every worker has finished what it was doing (runs cancelled by an interrupt
    go on in the background): a task queued behind them on each worker."""
    workers = list(client.scheduler_info()["workers"])
    client.gather([client.submit(time.sleep, 0, workers=[w], pure=False) for w in workers])


def closed_port() -> int:
    """A local TCP port where nothing listens."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


# ---------------------------------------------------------------- same numbers anywhere


@pytest.fixture(scope="module")
def three_ways(client, tmp_path_factory):
    """A sweep with diverging runs and recordings: serially, on a 2-process pool, on Dask
    (through a client's executor, as a user with their own cluster would)."""
    root = tmp_path_factory.mktemp("dask")
    path = write(root, spring_sweep(DIVERGING_FOUR, recordings=True))
    serial = vv.sweep(path, root / "serial", executor="serial")
    pool = vv.sweep(path, root / "pool", workers=2)
    dask = vv.sweep(path, root / "dask", executor=client.get_executor())
    return serial, pool, dask


def test_serial_pool_and_dask_runs_are_bit_identical(three_ways):
    serial, pool, dask = three_ways
    for rows in zip(serial.rows, pool.rows, dask.rows, strict=True):
        assert len({row["run"] for row in rows}) == 1
        # Every figure of the summaries but the wall time, to the last bit.
        figures = [{k: v for k, v in row.items() if k != "wall_time_s"} for row in rows]
        assert figures[0] == figures[1] == figures[2]
        recordings = [
            load_recording(result.directory / "runs" / rows[0]["run"] / "recording.h5")
            for result in three_ways
        ]
        first = recordings[0]
        assert first.frames > 1
        for other in recordings[1:]:
            assert other.frames == first.frames
            np.testing.assert_array_equal(other.time, first.time)
            assert other.fields.keys() == first.fields.keys()
            for name, values in first.fields.items():
                np.testing.assert_array_equal(other.fields[name], values, err_msg=name)
        marks = [
            json.loads((r.directory / "runs" / rows[0]["run"] / "run.json").read_text())
            for r in three_ways
        ]
        assert marks[0] == marks[1] == marks[2]


def test_a_run_that_diverges_on_dask_is_reported_and_the_others_finish(three_ways):
    dask = three_ways[2]
    assert (dask.ran, dask.failed) == (4, 2)
    for row in dask.rows:
        if row["entities[pair].stiffness"] == 1e6:  # ωh = 10: beyond every method's limit
            assert not row["success"] and "diverged" in row["error"]
            assert row["t_reached_s"] < 0.5
        else:
            assert row["success"] and row["error"] is None and row["t_reached_s"] == 0.5
    table = (dask.directory / "results.csv").read_text().splitlines()
    assert len(table) == 5 and table[1].startswith("0,")


# ---------------------------------------------------------------- interrupt and resume


class CtrlCAfter(Executor):
    """Sends runs to ``executor``, but the run submitted at position ``at`` is replaced by a
    Ctrl-C (KeyboardInterrupt in the waiting process) once ``after`` runs have finished."""

    def __init__(self, executor: Executor, at: int, after: int) -> None:
        self.executor, self.at, self.after = executor, at, after
        self.submitted = self.finished = 0
        self.ctrl_c: Future = Future()
        self.lock = threading.Lock()

    def submit(self, fn, /, *args, **kwargs):  # type: ignore[override]
        self.submitted += 1
        if self.submitted - 1 == self.at:
            return self.ctrl_c
        future = self.executor.submit(fn, *args, **kwargs)
        future.add_done_callback(self._count)
        return future

    def _count(self, future: Future) -> None:
        if future.cancelled():
            return
        with self.lock:
            self.finished += 1
            if self.finished == self.after:
                self.ctrl_c.set_exception(KeyboardInterrupt())


def test_ctrl_c_on_dask_keeps_the_finished_runs_and_resume_skips_them(client, tmp_path):
    path = write(tmp_path, spring_sweep(STEADY))
    out = tmp_path / "out"
    with pytest.raises(SweepInterrupted, match="of 6 runs finished") as caught:
        vv.sweep(path, out, executor=CtrlCAfter(client.get_executor(), at=5, after=2), batch=False)
    kept = caught.value.result.rows
    assert 2 <= len(kept) < 6 and all(row["success"] for row in kept)
    assert len((out / "results.csv").read_text().splitlines()) == len(kept) + 1

    idle(client)  # runs under way when Ctrl-C came may finish in the background: let them
    stamps = {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*/summary.json")}
    resumed = vv.sweep(path, out, executor=client.get_executor(), batch=False)
    assert resumed.skipped >= len(kept) and resumed.ran + resumed.skipped == 6
    assert resumed.failed == 0 and [row["index"] for row in resumed.rows] == list(range(6))
    for summary, stamp in stamps.items():  # the finished runs were not run again
        assert summary.stat().st_mtime_ns == stamp
    again = vv.sweep(path, out, executor=client.get_executor(), batch=False)
    assert (again.ran, again.skipped) == (0, 6) and again.rows == resumed.rows


# ---------------------------------------------------------------- refused before any work


def test_an_unreachable_scheduler_is_refused_quickly_and_nothing_is_written(
    tmp_path, monkeypatch, capsys
):
    address = f"tcp://127.0.0.1:{closed_port()}"
    started = time.perf_counter()
    with (
        pytest.raises(ModelError, match="no Dask scheduler answered at " + address) as caught,
        dask_executor(address, timeout=1.0),
    ):
        pass
    assert time.perf_counter() - started < 5
    assert "`dask scheduler` is running there" in str(caught.value)
    assert "tcp://host:8786" in str(caught.value)

    path = write(tmp_path, spring_sweep(STEADY))
    out = tmp_path / "out"
    monkeypatch.setattr(cluster_module, "CONNECT_TIMEOUT", 1.0)
    refusals = {
        ("--scheduler", address): f"no Dask scheduler answered at {address} within 1 s",
        ("--scheduler", "udp://host:1"): "is not a Dask scheduler address",
        ("--scheduler", address, "--workers", "2"): "drop --workers",
        ("--dask", "--serial"): "drop --dask (or --serial)",
        ("--dask", "--workers", "0"): "`workers` must be at least 1 (got 0)",
    }
    for options, message in refusals.items():
        status, _, stderr = run_main(monkeypatch, capsys, "sweep", path, "-o", out, *options)
        assert status == 2, options
        assert stderr.startswith("error: ") and stderr.count("\n") == 1, stderr
        assert message in stderr, stderr
    assert not out.exists()


def test_without_dask_the_error_says_how_to_install_it(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` fails
    with pytest.raises(ModelError, match=r'pip install "visviva\[dask\]"'), dask_executor():
        pass
    path = write(tmp_path, spring_sweep(STEADY))
    status, _, stderr = run_main(monkeypatch, capsys, "sweep", path, "-o", tmp_path / "o", "--dask")
    assert status == 2 and 'pip install "visviva[dask]"' in stderr
    assert not (tmp_path / "o").exists()
    # Dask stays optional: neither the package nor the command imports it.
    code = "import sys, visviva.sweeps, visviva.cli.main; print('distributed' in sys.modules)"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert loaded.stdout.strip() == "False", loaded.stderr


# ---------------------------------------------------------------- the command


def test_cli_runs_a_sweep_on_a_dask_scheduler(cluster, tmp_path, monkeypatch, capsys):
    path = write(tmp_path, spring_sweep(TWO_RUNS))
    out = tmp_path / "out"
    status, stdout, stderr = run_main(
        monkeypatch, capsys, "sweep", path, "-o", out, "--scheduler", cluster[1]
    )
    assert status == 0, stderr
    assert "2 runs; 2 succeeded, 0 failed" in stdout and stderr == ""
    document = json.loads((out / "results.json").read_text())
    assert [run["entities[pair].stiffness"] for run in document["runs"]] == [10.0, 20.0]
    assert [run["t_reached_s"] for run in document["runs"]] == [0.5, 0.5]
    status, stdout, _ = run_main(
        monkeypatch, capsys, "sweep", path, "-o", out, "--scheduler", cluster[1]
    )
    assert status == 0 and "2 already finished, not run again" in stdout


def test_a_local_cluster_shares_the_cores_out_between_its_workers(cluster):
    import numba

    executor, _ = cluster
    threads = {executor.submit(numba.get_num_threads).result() for _ in range(4)}
    assert threads == {max(1, (os.cpu_count() or 1) // 2)}


# ---------------------------------------------------------------- files the caller cannot see


class Elsewhere(Executor):
    """Sends runs to ``executor``, but run ``hidden`` writes where this process does not look
    (a worker's own disk) and run ``late`` is moved into place ``delay`` seconds after it
    finished (a shared file system showing new files late)."""

    def __init__(self, executor: Executor, root: Path, hidden: int, late: int) -> None:
        self.executor, self.root, self.hidden, self.late = executor, root, hidden, late
        self.delay = 0.2

    def submit(self, fn, /, task, **kwargs):  # type: ignore[override]
        if task.index not in (self.hidden, self.late):
            return self.executor.submit(fn, task)
        away = self.root / task.name
        future = self.executor.submit(fn, replace(task, directory=str(away)))
        if task.index == self.late:
            move = threading.Timer(self.delay, shutil.move, (away, task.directory))
            future.add_done_callback(lambda _: move.start())
        return future


def test_a_run_whose_files_this_machine_cannot_see_is_recorded_as_failed(
    cluster, tmp_path, monkeypatch
):
    monkeypatch.setattr(shared_files, "GRACE", 1.0)
    executor, _ = cluster
    path = write(tmp_path, spring_sweep(STEADY))
    out = tmp_path / "out"
    where = Elsewhere(executor, tmp_path / "worker-disk", hidden=1, late=5)
    result = vv.sweep(path, out, executor=where, batch=False)  # the executor moves runs
    assert (result.ran, result.failed) == (6, 1)
    hidden = result.rows[1]
    assert hidden["success"] is False
    assert hidden["error"].startswith(
        "the worker wrote run 1's files where this machine cannot see them"
    )
    assert "use an output directory on a file system shared with the workers" in hidden["error"]
    assert hidden["integration.method"] == "rk4"  # the row keeps its values
    late = result.rows[5]  # not there when it came back; moved into place while the sweep waited
    assert late["success"] and (out / "runs" / late["run"] / "run.json").exists()
    assert "cannot see them" in (out / "results.csv").read_text()
    # The next sweep runs again only the run whose files never arrived.
    again = vv.sweep(path, out, executor=executor, batch=False)
    assert (again.ran, again.skipped, again.failed) == (1, 5, 0)


class Cancelling(Executor):
    """Runs each task at once, but cancels run ``cancelled`` before it starts (as Dask does
    with the runs of a client that lost its scheduler)."""

    def __init__(self, cancelled: int) -> None:
        self.cancelled = cancelled

    def submit(self, fn, /, task, **kwargs):  # type: ignore[override]
        future: Future = Future()
        if task.index == self.cancelled:
            future.cancel()
            future.set_running_or_notify_cancel()
        else:
            future.set_result(fn(task))
        return future


def test_a_run_the_executor_cancels_is_recorded_as_failed_and_runs_on_resume(tmp_path):
    path = write(tmp_path, spring_sweep(TWO_RUNS))
    out = tmp_path / "out"
    result = vv.sweep(path, out, executor=Cancelling(cancelled=0), batch=False)
    assert (result.ran, result.failed) == (2, 1)
    assert result.rows[0]["error"].startswith("the executor cancelled the run before it finished")
    assert result.rows[1]["success"]
    assert vv.sweep(path, out, executor="serial").ran == 1
