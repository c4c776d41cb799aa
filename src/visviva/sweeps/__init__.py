"""Sweeps: many runs of one scene with parameters varied, on any executor.

A sweep file names a base scene, the parameters to vary and how (grid, zip or random design,
:mod:`.description`, :mod:`.design`); :func:`sweep` runs every run through
:func:`~visviva.scenes.run_scene` on a process pool, in this process, or on any
:class:`concurrent.futures.Executor`, resumes where an interrupted sweep stopped, and writes a
results table (:mod:`.results`, :mod:`.results_h5`), the ``[[plots]]`` of the description
(:mod:`.plot_spec`, :mod:`.reductions`) and an index page (:mod:`.index_page`, all written by
:mod:`.reports`). A front layer like :mod:`visviva.scenes`: the physics packages
never import it.
"""

from .description import Outputs, Parameter, Sweep, SweepInfo, load_sweep, parse_sweep
from .design import SweepRun, expand, run_values
from .plot_spec import Plot
from .results_h5 import read_results_h5
from .runner import RunTask, SweepInterrupted, SweepResult, run_task, sweep

__all__ = [
    "Outputs",
    "Parameter",
    "Plot",
    "RunTask",
    "Sweep",
    "SweepInfo",
    "SweepInterrupted",
    "SweepResult",
    "SweepRun",
    "expand",
    "load_sweep",
    "parse_sweep",
    "read_results_h5",
    "run_task",
    "run_values",
    "sweep",
]
