"""The compiled path: whole runs in Numba when the user's functions are Numba functions.

When a problem's ``f`` (or acceleration/force) is an ``@njit`` function describing one system,
an explicit fixed-step method can run the entire time loop in compiled code: each thread takes
a system and advances it through all its steps while it sits in cache, calling the user's
function directly. This is what makes a batch of 10,000 double pendulums run at compiled speed.

Three pieces, each a closure compiled once per (method, user function, size) and memoized:

* an *adapter* turning the user's function (returning or filling ``out``; position-only or
  velocity-dependent; acceleration or force with a diagonal mass) into one in-place form;
* a method's *step kernel* (:class:`~visviva.integrators.base.CompiledStep`), written next to
  the method's NumPy step;
* the *runner*: the loop over systems (in parallel) and steps, with time computed from the
  integer step counter, frame recording and the divergence watch.

Arrays are copied element by element, never with slice stores (``out[:] = x``): Numba takes
seconds to compile a slice store in each new closure, against milliseconds for a loop, and these
closures are compiled afresh for every user function (first run of an RK4 problem: 6 s → 1 s).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from .._memo import Memo
from ..ode.batching import PARALLEL_MIN_SYSTEMS
from .base import CompiledStep

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from .runge_kutta import ButcherTableau

__all__ = [
    "acceleration_adapter",
    "derivative_adapter",
    "make_runner",
    "problem_key",
    "runge_kutta_step",
]

#: Compiled adapters, steps and runners by what they are built from, the most recently used
#: kept (a runner holds the step and adapters it was built from, whatever the memo drops).
_MEMO: Memo[Any] = Memo(128)


def _memoized(key: tuple[Any, ...], build: Callable[[], Any]) -> Any:
    return _MEMO.get(key, build)


def problem_key(problem: Problem) -> tuple[Any, ...] | None:
    """What a compiled kernel depends on, or ``None`` if the problem cannot be compiled.

    Compilable: the (force) function is a Numba function, and any mass is a diagonal shared by
    every system.
    """
    if problem.kind == "first_order":
        f = problem.f  # type: ignore[union-attr]
        if not f.compiled:
            return None
        return ("first_order", f.func, f.writes_out, problem.size)
    force = problem.force  # type: ignore[union-attr]
    if not force.compiled:
        return None
    mass = problem.mass  # type: ignore[union-attr]
    if mass is None:
        mass_key: tuple[Any, ...] = ()
    elif mass.kind == "diagonal" and mass.values.ndim <= 1:
        diagonal = np.broadcast_to(mass.values, (problem.size,))
        mass_key = tuple(float(x) for x in diagonal)
    else:
        return None
    return (
        "second_order",
        force.func,
        force.writes_out,
        force.state_arguments,
        problem.size,
        mass_key,
    )


def acceleration_adapter(problem: Problem) -> Callable[..., None] | None:
    """``accel(t, q, v, out)`` filling ``out`` with ``q''`` for one system, or ``None``."""
    key = problem_key(problem)
    if key is None or key[0] != "second_order":
        return None

    def build() -> Callable[..., None]:
        import numba

        func = problem.force.func  # type: ignore[union-attr]
        _, _, writes_out, state_arguments, n, mass_key = key
        has_mass = bool(mass_key)
        inverse_mass = 1.0 / np.array(mass_key if has_mass else (1.0,) * n)

        if state_arguments == 2 and writes_out:

            @numba.njit
            def raw(t, q, v, out):  # pragma: no cover - compiled
                func(t, q, v, out)
        elif state_arguments == 2:

            @numba.njit
            def raw(t, q, v, out):  # pragma: no cover - compiled
                result = func(t, q, v)
                for k in range(n):
                    out[k] = result[k]
        elif writes_out:

            @numba.njit
            def raw(t, q, v, out):  # pragma: no cover - compiled
                func(t, q, out)
        else:

            @numba.njit
            def raw(t, q, v, out):  # pragma: no cover - compiled
                result = func(t, q)
                for k in range(n):
                    out[k] = result[k]

        if not has_mass:
            return raw

        @numba.njit
        def with_mass(t, q, v, out):  # pragma: no cover - compiled
            raw(t, q, v, out)
            for k in range(n):
                out[k] *= inverse_mass[k]

        return with_mass

    return _memoized(("acceleration", *key), build)


def derivative_adapter(problem: Problem) -> Callable[..., None] | None:
    """``deriv(t, y, out)`` for the stacked one-system state, or ``None``.

    The stacked state is ``y`` for a first-order problem and ``[q, v]`` (length ``2n``) for a
    second-order one, whose derivative is ``[v, q'']``.
    """
    key = problem_key(problem)
    if key is None:
        return None

    def build() -> Callable[..., None]:
        import numba

        if key[0] == "first_order":
            func = problem.f.func  # type: ignore[union-attr]
            if key[2]:
                return func

            size = problem.size

            @numba.njit
            def first(t, y, out):  # pragma: no cover - compiled
                result = func(t, y)
                for k in range(size):
                    out[k] = result[k]

            return first

        accel = acceleration_adapter(problem)
        n = problem.size

        @numba.njit
        def second(t, y, out):  # pragma: no cover - compiled
            for k in range(n):
                out[k] = y[n + k]
            accel(t, y[:n], y[n:], out[n:])

        return second

    return _memoized(("derivative", *key), build)


def stacked_size(problem: Problem) -> int:
    """Length of the stacked one-system state: ``n`` or ``2n``."""
    return problem.size if problem.kind == "first_order" else 2 * problem.size


def runge_kutta_step(tableau: ButcherTableau, problem: Problem) -> CompiledStep | None:
    """The compiled step of an explicit Runge–Kutta tableau for ``problem``, or ``None``."""
    key = problem_key(problem)
    if key is None:
        return None

    def build() -> CompiledStep:
        import numba

        deriv = derivative_adapter(problem)
        m = stacked_size(problem)
        s = tableau.stages
        a, b, c = (np.array(x) for x in (tableau.a, tableau.b, tableau.c))

        @numba.njit
        def step(t, h, y, work, fresh):  # pragma: no cover - compiled
            # Rows 0..s-1 hold the stage rates, row s the stage state.
            stage = work[s]
            deriv(t, y, work[0])
            for i in range(1, s):
                for k in range(m):
                    total = 0.0 * y[k]
                    for j in range(i):
                        total += a[i, j] * work[j, k]
                    stage[k] = y[k] + h * total
                deriv(t + c[i] * h, stage, work[i])
            for k in range(m):
                total = 0.0 * y[k]
                for i in range(s):
                    total += b[i] * work[i, k]
                y[k] += h * total
            return s

        return CompiledStep(step, s + 1)

    return _memoized(("runge_kutta", tableau.a.tobytes(), tableau.b.tobytes(), *key), build)


def make_runner(step: CompiledStep, systems: int) -> Callable[..., None]:
    """The loop over systems and steps around a compiled step kernel (parallel for big batches).

    The returned ``run(y, work, fresh, t0, h, first, count, record_every, frames, limit,
    status, evaluations)`` advances every system of ``y`` (``(batch, m)``, in place, with
    scratch ``work`` of shape ``(batch, rows, m)``) by
    ``count`` steps of size ``h``; step ``k`` starts at ``t0 + k h`` (``k = first, first + 1,
    ...``), so time never accumulates rounding. After every ``record_every``-th step the state
    is written to ``frames[j, i]``. A system whose state leaves ``|y| ≤ limit`` (or becomes
    NaN) stops, and ``status[i]`` receives the index of the step that failed.
    """

    def build() -> Callable[..., None]:
        import numba

        kernel = step.kernel

        @numba.njit(parallel=parallel)
        def run(
            y, work, fresh, t0, h, first, count, record_every, frames, limit, status, evaluations
        ):  # pragma: no cover - compiled
            batch, m = y.shape
            for i in numba.prange(batch):
                if status[i] >= 0:
                    continue
                # Private copies: the compiler can then keep them apart from everything else,
                # which is worth ~10% against working in views of the shared arrays.
                state = y[i].copy()
                scratch = work[i].copy()
                is_fresh = fresh
                # Counted locally and stored once: neighbouring systems share cache lines.
                evaluated = 0
                for s in range(count):
                    k = first + s
                    evaluated += kernel(t0 + k * h, h, state, scratch, is_fresh)
                    is_fresh = False
                    finite = True
                    for j in range(m):
                        if not abs(state[j]) <= limit:
                            finite = False
                    if not finite:
                        status[i] = k
                        break
                    if (s + 1) % record_every == 0:
                        frame = (s + 1) // record_every - 1
                        for j in range(m):
                            frames[frame, i, j] = state[j]
                evaluations[i] += evaluated
                for j in range(m):
                    y[i, j] = state[j]
                for r in range(scratch.shape[0]):
                    for j in range(m):
                        work[i, r, j] = scratch[r, j]

        return run

    parallel = systems >= PARALLEL_MIN_SYSTEMS
    return _memoized(("runner", step, parallel), build)
