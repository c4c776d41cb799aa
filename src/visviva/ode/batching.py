"""Compiled loops that apply a one-system Numba function to every system of a batch.

A Numba function written for one system (``y`` of shape ``(n,)``) is wrapped here into a
parallel loop over the leading batch axis, so the rest of visviva can treat it exactly like a
NumPy function that takes the whole batch. The loops are closures over the user's function, so
they compile once per function per process (Numba cannot cache a function that calls a
dispatcher it receives at run time). Results are stored element by element: a slice store
costs Numba seconds of compilation in every closure that contains one.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .._memo import Memo
from .functions import UserFunction

__all__ = ["batched"]


#: Batches at least this large run on all cores; smaller ones on one (a parallel loop costs
#: more to start than a handful of systems take, and on a busy machine 10x more).
PARALLEL_MIN_SYSTEMS = 64

#: Built wrappers by (user function, its form, result kind): every problem made from the same
#: Numba function reuses one compiled loop instead of compiling its own (~0.5 s each); the most
#: recently used are kept.
_WRAPPERS: Memo[Callable[..., Any]] = Memo(64)


def batched(function: UserFunction, result: str) -> Callable[..., Any]:
    """Return ``call(t, *states) -> result`` over a batch for a one-system Numba function.

    Args:
        function: A compiled user function (``function.compiled`` is true).
        result: What one call returns per system: ``"array"`` (same shape as the first state,
            e.g. a derivative), ``"matrix"`` (an ``(n, n)`` Jacobian), ``"pair"`` (two
            ``(n, n)`` Jacobians) or ``"scalar"`` (an energy).

    Returns:
        A Python callable taking ``t`` and one or two arrays of shape ``(batch, n)`` and
        returning the stacked results: ``(batch, n)``, ``(batch, n, n)``, a pair of those, or
        ``(batch,)``.
    """
    key = (function.func, function.state_arguments, function.writes_out, result)
    return _WRAPPERS.get(key, lambda: _build(function, result))


class _Split:
    """A loop over the systems of a batch (``loop(t, states..., outputs...)`` with ``prange``),
    compiled on first use in two forms: parallel for batches of at least
    :data:`PARALLEL_MIN_SYSTEMS` systems, serial for smaller ones. Both compute every system
    the same way, so the choice never changes a result."""

    def __init__(self, loop: Callable[..., None]) -> None:
        import numba

        self._parallel = numba.njit(parallel=True)(loop)
        self._serial = numba.njit(loop)

    def __call__(self, t: float, first: np.ndarray, *rest: Any) -> None:
        big = first.shape[0] >= PARALLEL_MIN_SYSTEMS
        (self._parallel if big else self._serial)(t, first, *rest)


def _build(function: UserFunction, result: str) -> Callable[..., Any]:
    import numba

    func = function.func
    two = function.state_arguments == 2
    writes_out = function.writes_out

    if result == "array":
        if writes_out:
            if two:

                @_Split
                def loop_out2(t, a, b, out):  # pragma: no cover - compiled
                    for i in numba.prange(a.shape[0]):
                        func(t, a[i], b[i], out[i])

                kernel: Any = loop_out2
            else:

                @_Split
                def loop_out1(t, a, out):  # pragma: no cover - compiled
                    for i in numba.prange(a.shape[0]):
                        func(t, a[i], out[i])

                kernel = loop_out1
        elif two:

            @_Split
            def loop_ret2(t, a, b, out):  # pragma: no cover - compiled
                for i in numba.prange(a.shape[0]):
                    result = func(t, a[i], b[i])
                    for k in range(a.shape[1]):
                        out[i, k] = result[k]

            kernel = loop_ret2
        else:

            @_Split
            def loop_ret1(t, a, out):  # pragma: no cover - compiled
                for i in numba.prange(a.shape[0]):
                    result = func(t, a[i])
                    for k in range(a.shape[1]):
                        out[i, k] = result[k]

            kernel = loop_ret1

        def call_array(t: float, *states: np.ndarray) -> np.ndarray:
            out = np.empty_like(states[0])
            kernel(t, *states, out)
            return out

        return call_array

    if result == "matrix":

        @_Split
        def loop_matrix(t, a, out):  # pragma: no cover - compiled
            for i in numba.prange(a.shape[0]):
                matrix = func(t, a[i])
                for r in range(a.shape[1]):
                    for c in range(a.shape[1]):
                        out[i, r, c] = matrix[r, c]

        def call_matrix(t: float, a: np.ndarray) -> np.ndarray:
            out = np.empty(a.shape + a.shape[-1:], dtype=a.dtype)
            loop_matrix(t, a, out)
            return out

        return call_matrix

    if result == "pair":

        @_Split
        def loop_pair(t, a, b, out_q, out_v):  # pragma: no cover - compiled
            for i in numba.prange(a.shape[0]):
                jq, jv = func(t, a[i], b[i])
                for r in range(a.shape[1]):
                    for c in range(a.shape[1]):
                        out_q[i, r, c] = jq[r, c]
                        out_v[i, r, c] = jv[r, c]

        def call_pair(t: float, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            out_q = np.empty(a.shape + a.shape[-1:], dtype=a.dtype)
            out_v = np.empty_like(out_q)
            loop_pair(t, a, b, out_q, out_v)
            return out_q, out_v

        return call_pair

    if result == "scalar":
        if two:

            @_Split
            def loop_scalar2(t, a, b, out):  # pragma: no cover - compiled
                for i in numba.prange(a.shape[0]):
                    out[i] = func(t, a[i], b[i])

            scalar_kernel: Any = loop_scalar2
        else:

            @_Split
            def loop_scalar1(t, a, out):  # pragma: no cover - compiled
                for i in numba.prange(a.shape[0]):
                    out[i] = func(t, a[i])

            scalar_kernel = loop_scalar1

        def call_scalar(t: float, *states: np.ndarray) -> np.ndarray:
            out = np.empty(states[0].shape[0])
            scalar_kernel(t, *states, out)
            return out

        return call_scalar

    raise ValueError(f"unknown result kind {result!r}")
