"""The simulation loop, the adaptive driver and ``solve``."""

from .adaptive import DenseOutput
from .loop import Schedule
from .recording import Geometry, Recording
from .simulation import Simulation, SimulationState
from .solve import Solution, solve
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
