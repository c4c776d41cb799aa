"""visviva: physically based animation — time integration, mechanics and simulation in one engine.

The short tour::

    import visviva as vv

    spring = vv.ode.SecondOrderProblem(lambda t, q: -q, q0=[1.0], v0=[0.0])
    solution = vv.solve(spring, method="velocity_verlet", dt=0.01, until=10.0)
    solution.q, solution.v, solution.t          # the recorded frames
    vv.integrators.names()                       # every method
    vv.analysis.stability_interval("rk4")        # (-2.785..., 0.0)

Subpackages and the main functions load on first use, so that ``import visviva`` (and the
``visviva`` command's ``--help``) stays fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ._lazy import lazy_names
from ._version import __version__
from .errors import (
    ModelError,
    NewtonConvergenceError,
    SceneError,
    SimulationDiverged,
    SimulationError,
    VisvivaError,
)

if TYPE_CHECKING:
    from . import (
        analysis,
        cli,
        collision,
        deformables,
        demos,
        entities,
        forces,
        geometry,
        integrators,
        io,
        mechanics,
        model,
        ode,
        particles,
        rigid,
        simulation,
        studies,
        sweeps,
        viz,
    )
    from .model import Model, SceneBuilder
    from .scenes import load_model, run_scene
    from .simulation import Simulation, Solution, solve
    from .simulation.recording import Recording
    from .sweeps import load_sweep, sweep

__all__ = [
    "Model",
    "ModelError",
    "NewtonConvergenceError",
    "Recording",
    "SceneBuilder",
    "SceneError",
    "Simulation",
    "SimulationDiverged",
    "SimulationError",
    "Solution",
    "VisvivaError",
    "__version__",
    "analysis",
    "cli",
    "collision",
    "deformables",
    "demos",
    "entities",
    "forces",
    "geometry",
    "integrators",
    "io",
    "load_model",
    "load_sweep",
    "mechanics",
    "model",
    "ode",
    "particles",
    "rigid",
    "run_scene",
    "simulation",
    "solve",
    "studies",
    "sweep",
    "sweeps",
    "viz",
]

_FUNCTIONS = {
    "Model": "model",
    "SceneBuilder": "model",
    "load_model": "scenes",
    "run_scene": "scenes",
    "Recording": "simulation",
    "Simulation": "simulation",
    "Solution": "simulation",
    "solve": "simulation",
    "load_sweep": "sweeps",
    "sweep": "sweeps",
}

#: Public names that are gone, and what replaced them.
_GONE = {
    "simulate": "vv.simulate was merged into vv.solve: vv.solve(problem, method, dt=..., "
    "until=...).raise_for_status().recording is the recording it returned",
}

# Subpackages load on first use too; tests/test_surface.py checks that __all__ lists each one.
_load, __dir__ = lazy_names(__name__, __all__, _FUNCTIONS)


def __getattr__(name: str) -> Any:
    if name in _GONE:
        raise AttributeError(_GONE[name])
    return _load(name)
