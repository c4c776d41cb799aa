"""The request to stop a job, where every layer can read it.

A job's :class:`~visviva.simulation.interrupt.StopOnSignal` records here which signal
(SIGINT, SIGTERM) asked it to stop. The simulation loop polls it after every step; a long
implicit solve polls it between its Newton iterations too (:func:`requested`), so that
Ctrl-C answers within an iteration rather than a whole step. Outside a job nothing is ever
recorded and polling costs a global read.
"""

from __future__ import annotations

import signal

__all__ = ["record", "requested"]

_number: int | None = None  # the signal that asked the current job to stop, or None


def record(number: int | None) -> None:
    """Remember signal ``number`` as the request to stop (``None``: no request)."""
    global _number
    _number = number


def requested() -> str | None:
    """Name of the signal that asked the job to stop (``"SIGINT"``), or ``None``."""
    return None if _number is None else signal.Signals(_number).name
