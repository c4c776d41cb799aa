"""Running a compiled computation on one thread and on two, for determinism tests."""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np


def on_one_and_two_threads(run: Callable[[], tuple[np.ndarray, ...]]) -> list[tuple]:
    """``run()``'s arrays with Numba on 1 thread, then on 2 (or as many as there are); the
    thread count is put back after."""
    threads = numba.get_num_threads()
    results = []
    try:
        for count in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(count)
            results.append(run())
    finally:
        numba.set_num_threads(threads)
    return results


def assert_same_bits(results: list[tuple]) -> None:
    """Every result's arrays equal the first's, dtype and bits."""
    for other in results[1:]:
        for a, b in zip(results[0], other, strict=True):
            assert a.dtype == b.dtype and np.array_equal(a, b)
