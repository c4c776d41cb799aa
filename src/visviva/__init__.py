"""visviva: physically based animation — time integration, mechanics and simulation in one engine.

The short tour::

    import visviva as vv

    spring = vv.ode.SecondOrderProblem(lambda t, q: -q, q0=[1.0], v0=[0.0])
    solution = vv.solve(spring, method="velocity_verlet", dt=0.01, t_end=10.0)
    solution.q, solution.v, solution.t          # the recorded frames
    vv.integrators.names()                       # every method
    vv.analysis.stability_interval("rk4")        # (-2.785..., 0.0)

Subpackages and the main functions load on first use, so that ``import visviva`` (and the
``visviva`` command's ``--help``) stays fast.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._version import __version__
from .errors import (
    ModelError,
    NewtonConvergenceError,
    SimulationDiverged,
    SimulationError,
    VisvivaError,
)

if TYPE_CHECKING:
    from . import analysis, demos, integrators, io, ode, simulation, viz
    from .io import Recording
    from .simulation import Solution, simulate, solve

__all__ = [
    "ModelError",
    "NewtonConvergenceError",
    "Recording",
    "SimulationDiverged",
    "SimulationError",
    "Solution",
    "VisvivaError",
    "__version__",
    "analysis",
    "demos",
    "integrators",
    "io",
    "ode",
    "simulate",
    "simulation",
    "solve",
    "viz",
]

_SUBPACKAGES = {"analysis", "demos", "integrators", "io", "ode", "simulation", "viz"}
_FUNCTIONS = {
    "Recording": "io",
    "Solution": "simulation",
    "simulate": "simulation",
    "solve": "simulation",
}


def __getattr__(name: str) -> Any:
    if name in _SUBPACKAGES:
        return importlib.import_module(f".{name}", __name__)
    if name in _FUNCTIONS:
        return getattr(importlib.import_module(f".{_FUNCTIONS[name]}", __name__), name)
    raise AttributeError(f"module 'visviva' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
