"""An executor on a Dask cluster, for :func:`~visviva.sweeps.sweep`: a local one or one at an
address.

:func:`dask_executor` connects to a running scheduler (``tcp://host:8786``) or starts a
``LocalCluster`` of worker processes on this machine, yields a
:class:`concurrent.futures.Executor` that sends each run to the cluster, and closes what it
opened on the way out (also after an error or Ctrl-C). ``sweep`` needs nothing else: any
executor will do, so a cluster made elsewhere (``dask-jobqueue`` on SLURM, say) is used through
its client's ``get_executor()`` without this module. Dask is an optional dependency
(``pip install "visviva[dask]"``), imported only when a cluster is asked for.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
from collections.abc import Iterator
from concurrent.futures import Executor
from typing import Any

from .._validation import real_number, whole_number
from ..errors import ModelError

__all__ = ["CONNECT_TIMEOUT", "dask_executor"]

#: How long [s] to wait for a scheduler at an address to answer. One on the local network
#: answers in milliseconds; the margin is for a busy scheduler or a slow link.
CONNECT_TIMEOUT = 5.0
#: The form of a scheduler address, shown when one is refused.
_ADDRESS_FORM = "tcp://host:8786"


@contextlib.contextmanager
def dask_executor(
    address: str | None = None,
    *,
    workers: int | None = None,
    timeout: float | None = None,
) -> Iterator[Executor]:
    """An executor whose tasks run on a Dask cluster, for ``sweep(..., executor=...)``.

    With ``address``, the cluster is the one whose scheduler listens there; its workers keep
    their own settings. Without it, a ``LocalCluster`` of ``workers`` processes (one thread
    each) starts on this machine, each worker given an equal share of the cores for Numba's
    parallel kernels, as the sweep's own process pool does; it is closed on exit.

    Args:
        address: The scheduler's address, ``tcp://host:8786``, or ``None`` for a local cluster.
        workers: Worker processes of the local cluster (default: every core). Refused with
            ``address``: a cluster at an address has its own workers.
        timeout: Seconds to wait for the scheduler at ``address`` to answer (default
            :data:`CONNECT_TIMEOUT`).

    Yields:
        A :class:`concurrent.futures.Executor` on the cluster.

    Raises:
        ModelError: Dask is not installed; ``workers`` given with ``address``; an address that
            is malformed or where no scheduler answers within ``timeout``. Raised before the
            executor is yielded, so nothing has run or been written.

    Example:
        >>> import visviva as vv
        >>> from visviva.sweeps import dask_executor
        >>> with dask_executor(workers=4) as executor:  # doctest: +SKIP
        ...     vv.sweep("sweep.toml", "out", executor=executor)
    """
    distributed = _import_distributed()
    timeout = real_number("timeout", CONNECT_TIMEOUT if timeout is None else timeout, positive=True)
    if address is not None and workers is not None:
        raise ModelError(
            f"`workers` sizes a local cluster; the cluster at {address} has its own workers: "
            "omit `workers` (or the address)"
        )
    if workers is not None:
        workers = whole_number("workers", workers, minimum=1)
    with contextlib.ExitStack() as stack:
        if address is None:
            # Dask's nannies set OMP/MKL/OpenBLAS thread counts in this process's environment
            # before starting workers; put it back, so that later processes started from here
            # (a process pool, say) do not inherit them.
            stack.callback(_restore_environment, dict(os.environ))
            client = stack.enter_context(_local_client(distributed, workers or os.cpu_count() or 1))
        else:
            client = stack.enter_context(_connect(distributed, address, timeout))
        # A run writes files: Dask must never answer a run from the result of an earlier one.
        yield client.get_executor(pure=False)


def _import_distributed() -> Any:
    """The ``distributed`` package, or a ModelError saying how to install it."""
    try:
        import distributed
    except ImportError as error:
        raise ModelError(
            'running a sweep on Dask needs the `distributed` package: pip install "visviva[dask]"'
        ) from error
    return distributed


def _connect(distributed: Any, address: str, timeout: float) -> Any:
    """A client of the scheduler at ``address``, or a ModelError saying what to check."""
    if not isinstance(address, str) or not address.strip():
        raise ModelError(
            f"a Dask scheduler address must be a text like {_ADDRESS_FORM} (got {address!r})"
        )
    try:
        # Checked before connecting: a Client that fails on a malformed address leaves
        # Dask's event loop in a state where the next Client in this process cannot start.
        _, port = distributed.comm.get_address_host_port(address)
    except ValueError as error:
        raise ModelError(
            f"{address!r} is not a Dask scheduler address ({error}); write it as {_ADDRESS_FORM}"
        ) from error
    try:
        return distributed.Client(address, timeout=timeout, set_as_default=False)
    except OSError as error:  # refused, unknown host, timed out (TimeoutError is an OSError)
        raise ModelError(
            f"no Dask scheduler answered at {address} within {timeout:g} s: check that "
            f"`dask scheduler` is running there, that port {port} can be reached from this "
            f"machine, and that the address has the form {_ADDRESS_FORM}"
        ) from error


@contextlib.contextmanager
def _local_client(distributed: Any, workers: int) -> Iterator[Any]:
    """A client of a new LocalCluster of ``workers`` processes; both closed on exit."""
    threads = max(1, (os.cpu_count() or 1) // workers)
    with _workers_ignore_ctrl_c():
        cluster = distributed.LocalCluster(
            n_workers=workers,
            # One run per process: run_scene records warnings process-wide, and Numba's
            # threads are shared out per process (below), as in the sweep's own pool.
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",  # a free port: never a clash with another cluster's 8787
            silence_logs=logging.ERROR,  # workers starting and stopping are not the user's news
            env={"NUMBA_NUM_THREADS": str(threads)},
        )
    try:
        with distributed.Client(cluster, set_as_default=False) as client:
            yield client
    finally:
        cluster.close()


@contextlib.contextmanager
def _workers_ignore_ctrl_c() -> Iterator[None]:
    """Ignore SIGINT while the local workers start, so that they inherit it ignored.

    Ctrl-C at the terminal reaches every process of the group. The sweep handles it here,
    in the calling process, which cancels the runs and closes the cluster; workers that got
    it too would die printing tracebacks. (A Ctrl-C while the cluster starts, a second or
    two, is ignored with them.) Outside the main thread Python cannot change handlers, and
    nothing is done.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        # None: a handler set outside Python, which cannot be put back; the default then.
        signal.signal(signal.SIGINT, signal.SIG_DFL if previous is None else previous)


def _restore_environment(saved: dict[str, str]) -> None:
    """Put ``os.environ`` back as it was when ``saved`` was taken."""
    for key in set(os.environ) - set(saved):
        del os.environ[key]
    os.environ.update(saved)
