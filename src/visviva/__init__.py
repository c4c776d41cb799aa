"""visviva: physically based animation — time integration, mechanics and simulation in one engine.

The short tour::

    import visviva as vv

    spring = vv.ode.SecondOrderProblem(lambda t, q: -q, q0=[1.0], v0=[0.0])
    solution = vv.solve(spring, method="velocity_verlet", dt=0.01, t_end=10.0)
    solution.q, solution.v, solution.t          # the recorded frames
    vv.integrators.names()                       # every method
    vv.analysis.stability_interval("rk4")        # (-2.785..., 0.0)
"""

from . import analysis, integrators, io, ode, simulation
from ._version import __version__
from .errors import (
    ModelError,
    NewtonConvergenceError,
    SimulationDiverged,
    SimulationError,
    VisvivaError,
)
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
    "integrators",
    "io",
    "ode",
    "simulate",
    "simulation",
    "solve",
]
