"""The simulation loop, the adaptive driver and ``solve``."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .adaptive import DenseOutput
    from .loop import Schedule
    from .recording import Geometry, Recording
    from .simulation import Simulation, SimulationState
    from .solution import Solution, solve
    from .watch import DEFAULT_DIVERGENCE_LIMIT, DivergenceWatch

__all__ = [
    "DEFAULT_DIVERGENCE_LIMIT",
    "DenseOutput",
    "DivergenceWatch",
    "Geometry",
    "Recording",
    "Schedule",
    "Simulation",
    "SimulationState",
    "Solution",
    "solve",
]

# Names load on first use (visviva._lazy): the CLI and io need `interrupt` and `recording`
# without the loop's integrators and their Numba kernels.
__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {
        "DenseOutput": "adaptive",
        "Schedule": "loop",
        "Geometry": "recording",
        "Recording": "recording",
        "Simulation": "simulation",
        "SimulationState": "simulation",
        "Solution": "solution",
        "solve": "solution",
        "DEFAULT_DIVERGENCE_LIMIT": "watch",
        "DivergenceWatch": "watch",
    },
)
