"""Flow through exits, counted from the times agents leave (``crowd_exit_time``).

The flow through a door is the number of agents passing it per second. With the exit times
``t_k`` of the agents (NaN: still inside), :func:`exit_flow` gives the flow in windows of
``window`` seconds and :func:`mean_flow` the mean flow of the bulk of an evacuation: the
agents between the ``low`` and ``high`` fractions of those who left, over the time between
(``(high − low) n / (t_high − t_low)``), which leaves out the first few (who did not queue) and
the stragglers.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validation import real_number
from ..errors import ModelError

__all__ = ["exit_flow", "exited", "mean_flow"]


def _times(exit_times: Any) -> np.ndarray:
    times = np.asarray(exit_times, dtype=np.float64)
    if times.ndim != 1:
        raise ModelError(f"`exit_times` must be one time per agent, shape (n,) (got {times.shape})")
    return np.sort(times[~np.isnan(times)])


def exited(exit_times: Any, t: Any) -> np.ndarray:
    """How many agents have left by each time of ``t`` [s] (exit time ≤ t)."""
    times = _times(exit_times)
    return np.searchsorted(times, np.asarray(t, dtype=np.float64), side="right")


def exit_flow(exit_times: Any, window: float) -> tuple[np.ndarray, np.ndarray]:
    """The flow [agents/s] in consecutive windows of ``window`` [s] from 0 to the last exit.

    Returns:
        ``(centres, flow)``: the windows' middle times [s] and the agents leaving per second
        in each, shape ``(W,)`` each (empty if nobody left).
    """
    window = real_number("window", window, positive=True, unit=" s")
    times = _times(exit_times)
    if not times.shape[0]:
        return np.zeros(0), np.zeros(0)
    edges = np.arange(0.0, times[-1] + window, window)
    if edges.shape[0] < 2:
        edges = np.array([0.0, window])
    counts, _ = np.histogram(times, bins=edges)
    return 0.5 * (edges[:-1] + edges[1:]), counts / window


def mean_flow(exit_times: Any, low: float = 0.1, high: float = 0.9) -> float:
    """Mean flow [agents/s] of the agents between fractions ``low`` and ``high`` of those who
    left (see the module docstring); NaN if fewer than two left or they left at once."""
    if not 0.0 <= low < high <= 1.0:
        raise ModelError(f"`low` and `high` must satisfy 0 <= low < high <= 1 (got {low}, {high})")
    times = _times(exit_times)
    n = times.shape[0]
    first, last = round(low * (n - 1)), round(high * (n - 1))
    if n < 2 or last <= first or times[last] <= times[first]:
        return math.nan
    return (last - first) / float(times[last] - times[first])
