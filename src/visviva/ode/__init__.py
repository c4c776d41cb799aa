"""Initial value problems, their states and their run-time systems.

See :mod:`visviva.ode.problems` for the two problem kinds and :mod:`visviva.ode.functions` for
the NumPy and Numba function conventions.
"""

from .mass import Mass
from .problems import FirstOrderProblem, Problem, SecondOrderProblem
from .state import Layout, PartView, State
from .system import FirstOrderSystem, SecondOrderSystem, System, WorkCounters
from .workspace import Workspace

__all__ = [
    "FirstOrderProblem",
    "FirstOrderSystem",
    "Layout",
    "Mass",
    "PartView",
    "Problem",
    "SecondOrderProblem",
    "SecondOrderSystem",
    "State",
    "System",
    "WorkCounters",
    "Workspace",
]
