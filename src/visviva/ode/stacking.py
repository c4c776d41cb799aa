"""Stacking single-system problems that share their equations into one batch.

An ensemble — the same pendulum released from a thousand angles — is one problem with a batch
axis (:mod:`visviva.ode.problems`): its systems advance side by side, each evaluation of the
equations a single call over the whole batch. :func:`stack` builds that batch from the
ensemble's members, each a problem of one system. Members may be stacked only if they share
their equations: the same function objects (``f``, or the force or acceleration, the Jacobian,
the energy), the same mass, start time, size and number type; only their initial states differ.
For Numba functions, row ``i`` of the batch then computes exactly what member ``i`` computes
alone, bit for bit: the batched evaluation applies the member's own function to its own row
(:mod:`visviva.ode.batching`) and the explicit integrators combine states entry by entry. A
NumPy function must treat rows independently, as the batch convention asks.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence

import numpy as np

from ..errors import ModelError
from .problems import FirstOrderProblem, Problem, SecondOrderProblem

__all__ = ["equations_key", "stack"]


def equations_key(problem: Problem) -> Hashable | None:
    """What members of one batch must share (see the module docstring), or ``None`` if
    ``problem`` cannot be stacked: it is a batch already, or its mass is not diagonal.

    The key holds the functions themselves, so it compares equal only within one process.
    """
    if problem.batch_size is not None:
        return None
    functions = (
        (problem.f, problem.jacobian, problem.energy)
        if isinstance(problem, FirstOrderProblem)
        else (problem.force, problem.jacobian, problem.energy)
    )
    mass: tuple[float, ...] = ()
    if isinstance(problem, SecondOrderProblem) and problem.mass is not None:
        if problem.mass.kind != "diagonal":
            return None
        diagonal = np.broadcast_to(problem.mass.values, (problem.size,))
        mass = tuple(float(x) for x in diagonal)
    dtype = (problem.y0 if isinstance(problem, FirstOrderProblem) else problem.q0).dtype
    return (
        problem.kind,
        problem.size,
        problem.t0,
        str(dtype),
        mass,
        tuple(None if f is None else (f.func, f.writes_out, f.state_arguments) for f in functions),
    )


def stack(problems: Sequence[Problem], name: str | None = None) -> Problem:
    """One problem whose batch row ``i`` is ``problems[i]`` (each of one system).

    Args:
        problems: The members, sharing their equations (:func:`equations_key`).
        name: The batch's name (default: the first member's).

    Raises:
        ModelError: No members, a member that cannot be stacked, or members whose equations
            differ (the index of the first such member is named).
    """
    if not problems:
        raise ModelError("`problems` is empty: give at least one problem to stack")
    first = problems[0]
    key = equations_key(first)
    if key is None:
        raise ModelError(
            "problem 0 cannot be stacked: it is a batch already or has a dense or sparse mass"
        )
    for index, problem in enumerate(problems[1:], start=1):
        if equations_key(problem) != key:
            raise ModelError(
                f"problem {index} does not share the equations of problem 0 (the same "
                "functions, mass, t0, size and number type); only initial states may differ"
            )
    label = first.name if name is None else name
    if isinstance(first, FirstOrderProblem):
        return FirstOrderProblem(
            first.f.func,
            np.stack([p.y0 for p in problems]),  # type: ignore[union-attr]
            first.t0,
            jacobian=None if first.jacobian is None else first.jacobian.func,
            energy=None if first.energy is None else first.energy.func,
            name=label,
        )
    q0 = np.stack([p.q0 for p in problems])  # type: ignore[union-attr]
    v0 = np.stack([p.v0 for p in problems])  # type: ignore[union-attr]
    jacobian = None if first.jacobian is None else first.jacobian.func
    energy = None if first.energy is None else first.energy.func
    if first.mass is None:
        return SecondOrderProblem(
            first.force.func, q0, v0, first.t0, jacobian=jacobian, energy=energy, name=label
        )
    return SecondOrderProblem.from_force(
        first.force.func,
        first.mass.values,
        q0,
        v0,
        first.t0,
        jacobian=jacobian,
        energy=energy,
        name=label,
    )
