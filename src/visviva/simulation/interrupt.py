"""Stopping a run cleanly on Ctrl-C (SIGINT) or SIGTERM.

Inside :class:`StopOnSignal`, the first SIGINT or SIGTERM does not kill the process: it is
remembered, and the simulation loop, which polls :func:`stop_requested` after every step, ends
the run there, records that state as the last frame and raises :class:`Interrupted` carrying
the recording so far. The caller (``visviva run``, ``visviva demo``, :func:`~visviva.run_scene`)
then writes what it has, marked incomplete, and exits. A second signal, or one that arrives
while nothing polls (while a video is being written, say), raises :class:`KeyboardInterrupt`
at once, so a user is never stuck waiting.

Outside :class:`StopOnSignal` nothing changes: a Python user's Ctrl-C raises
:class:`KeyboardInterrupt` as usual.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from types import FrameType, TracebackType
from typing import Any

from .. import _stop
from ..errors import Interrupted

__all__ = ["Interrupted", "StopOnSignal", "exit_status", "stop_requested"]

#: The signals that ask a run to stop.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)

# The signal that asked the current run to stop lives in visviva._stop (set only inside a
# StopOnSignal), where the implicit solves poll it too.
# True while a loop polls stop_requested(): a first signal then waits for it.
_polled = False


def stop_requested() -> str | None:
    """Name of the signal that asked the run to stop (``"SIGINT"``), or ``None``."""
    return _stop.requested()


def exit_status(signal_name: str) -> int:
    """The shell's exit status for a process ended by ``signal_name``: 128 + its number."""
    return 128 + int(signal.Signals[signal_name])


class StopOnSignal:
    """Turn SIGINT/SIGTERM into a stop request for the duration of a job.

    Handlers are installed only in the main thread (Python allows no other); elsewhere the
    context does nothing. The previous handlers are restored on exit.

    Example:
        >>> with StopOnSignal() as stops:
        ...     with stops.polled():
        ...         pass  # run the simulation loop here
        >>> stop_requested() is None
        True
    """

    def __init__(self) -> None:
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> StopOnSignal:
        _stop.record(None)
        if threading.current_thread() is threading.main_thread():
            for number in STOP_SIGNALS:
                self._previous[number] = signal.signal(number, self._handle)
        return self

    @contextlib.contextmanager
    def polled(self) -> Iterator[None]:
        """While inside, a first signal only sets the request (a loop polls it)."""
        global _polled
        _polled = True
        try:
            yield
        finally:
            _polled = False

    @property
    def requested(self) -> str | None:
        """Name of the signal received, or ``None``."""
        return stop_requested()

    def _handle(self, number: int, frame: FrameType | None) -> None:
        first = _stop.requested() is None
        _stop.record(number)
        if not (first and _polled):
            raise KeyboardInterrupt

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        for number, handler in self._previous.items():
            signal.signal(number, handler)
        self._previous.clear()
        _stop.record(None)
