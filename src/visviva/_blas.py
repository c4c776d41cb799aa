"""One BLAS thread for the small dense factorizations of a step.

NumPy's OpenBLAS splits even a 300 × 300 Cholesky factorization over every core. On a quiet
machine that costs little; on a busy one its threads wait for each other: measured on a
2-core machine with one core taken by another process, 432 ms per factorization against
2.1 ms on one thread, which made a 121-point implicit cloth take 40 ms a Newton iteration
instead of 5. Our parallel loops are Numba's; the dense factorizations inside a step are small
(a multigrid's coarsest level, a named system's Newton matrix), so they run on one thread.

threadpoolctl (the scikit-learn project's tool for this) sets the BLAS library's thread
count for the length of a ``with`` block and restores it after.
"""

from __future__ import annotations

import functools
from contextlib import AbstractContextManager
from typing import Any

__all__ = ["one_blas_thread"]


@functools.cache
def _controller() -> Any:
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def one_blas_thread() -> AbstractContextManager[Any]:
    """A ``with`` block whose BLAS calls run on one thread (a few microseconds to enter)."""
    return _controller().limit(limits=1, user_api="blas")
