"""Sweeps: many runs of one scene with parameters varied, on any executor.

A sweep file names a base scene, the parameters to vary and how (grid, zip or random design,
:mod:`.description`, :mod:`.design`); :func:`sweep` runs every run through
:func:`~visviva.scenes.run_scene` on a process pool, in this process, or on any
:class:`concurrent.futures.Executor` — runs that share their equations, or particle scenes
with the same entities, advance together in batches (:mod:`.tasks`) — resumes where an
interrupted sweep stopped, and writes a results table
(:mod:`.results`, :mod:`.results_h5`), the ``[[plots]]`` of the description (:mod:`.plot_spec`,
:mod:`.reductions`) and an index page (:mod:`.index_page`, all written by :mod:`.reports`).
:func:`dask_executor` (:mod:`.cluster`) gives an executor on a Dask cluster, local or at an
address. A front layer like :mod:`visviva.scenes`: the physics packages never import it.
"""

from .cluster import dask_executor
from .description import Outputs, Parameter, Sweep, SweepInfo, load_sweep, parse_sweep
from .design import SweepRun, expand, run_values
from .plot_spec import Plot
from .results_h5 import read_results_h5
from .runner import SweepFailed, SweepInterrupted, SweepResult, sweep
from .tasks import BatchTask, RunTask, run_batch, run_task

__all__ = [
    "BatchTask",
    "Outputs",
    "Parameter",
    "Plot",
    "RunTask",
    "Sweep",
    "SweepFailed",
    "SweepInfo",
    "SweepInterrupted",
    "SweepResult",
    "SweepRun",
    "dask_executor",
    "expand",
    "load_sweep",
    "parse_sweep",
    "read_results_h5",
    "run_batch",
    "run_task",
    "run_values",
    "sweep",
]
