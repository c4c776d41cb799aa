"""One system, several integrators: energy behaviour, measured order and cost, side by side.

:func:`compare_methods` runs every method on the same problem at the same step for the whole
duration (energy over time), measures each method's order on a shorter span against a tight
reference (error against step size), and counts the work. The result prints a table;
:func:`visviva.viz.plots.comparison_figures` draws its two figures the notes teach from —
energy drift and convergence.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

from .._validation import real_number, whole_number
from ..analysis.invariants import energy_drift, max_energy_error
from ..errors import SimulationError
from ..integrators import get
from ..simulation.solution import solve
from .convergence import ConvergenceStudy, convergence_order

if TYPE_CHECKING:
    from ..ode.problems import Problem
    from ..simulation.recording import Recording

__all__ = ["Comparison", "MethodResult", "compare_methods"]


@dataclass(frozen=True)
class MethodResult:
    """One method's line of the comparison.

    Attributes:
        method: Method name.
        declared_order: The order the method declares.
        measured_order: Slope of error against step size (``nan`` if it could not be fitted).
        energy_drift: ``E(end)/E(0) − 1`` of the full run (``None`` without an energy).
        max_energy_error: Largest ``|E(t)/E(0) − 1|`` of the full run.
        f_evaluations: Force/derivative evaluations of the full run.
        wall_time_s: Wall time of the full run [s].
        success: The full run finished (it may diverge: explicit Euler on a stiff problem).
        message: Why it stopped, if it did not finish.
    """

    method: str
    declared_order: int
    measured_order: float
    energy_drift: float | None
    max_energy_error: float | None
    f_evaluations: int
    wall_time_s: float
    success: bool
    message: str


@dataclass(frozen=True)
class Comparison:
    """What :func:`compare_methods` returns.

    Attributes:
        results: One :class:`MethodResult` per method, in the order given.
        runs: The full runs' recordings by method (for :func:`~visviva.viz.plots.plot_energy`).
        studies: The convergence studies (for :func:`~visviva.viz.plots.plot_convergence`);
            :func:`~visviva.viz.plots.comparison_figures` draws both.
        dt: Step of the full runs [s].
        until: End of the full runs [s].
    """

    results: list[MethodResult]
    runs: dict[str, Recording]
    studies: list[ConvergenceStudy]
    dt: float
    until: float

    def table(self) -> str:
        """The results as an aligned plain-text table."""
        header = ("method", "order", "measured", "E drift", "max |ΔE/E|", "f-evals", "time [s]")
        rows = [header]
        for r in self.results:
            rows.append(
                (
                    r.method + ("" if r.success else " (failed)"),
                    str(r.declared_order),
                    f"{r.measured_order:.2f}",
                    _number(r.energy_drift),
                    _number(r.max_energy_error),
                    str(r.f_evaluations),
                    f"{r.wall_time_s:.3f}",
                )
            )
        widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
        lines = [
            "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) for row in rows
        ]
        lines.insert(1, "  ".join("-" * w for w in widths))
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """The results for ``summary.json``."""
        return {
            "dt_s": self.dt,
            "until_s": self.until,
            "methods": [asdict(r) for r in self.results],
        }


def _number(value: float | None) -> str:
    return "-" if value is None else f"{value:.2e}"


def compare_methods(
    problem: Problem,
    methods: Sequence[str],
    *,
    dt: float,
    until: float,
    convergence_until: float | None = None,
    levels: int = 6,
    record_every: int = 1,
) -> Comparison:
    """Run ``problem`` under each of ``methods`` and measure their energy, order and cost.

    Args:
        problem: Any first- or second-order problem (with an energy for the energy columns).
        methods: Integrator names.
        dt: Step of the full runs [s].
        until: End of the full runs [s] (long, to show drift).
        convergence_until: End of the order measurement [s]; default ``min(until, t0 + 1)``.
            Keep it short for chaotic systems, whose reference is only trustworthy briefly.
        levels: Step sizes in each order measurement (halved from ``(span)/8``; at least 3).
        record_every: Record every k-th step of the full runs.

    Returns:
        A :class:`Comparison`.
    """
    dt = real_number("dt", dt, positive=True, unit=" s")
    until = real_number("until", until, unit=" s")
    levels = whole_number("levels", levels, minimum=3)
    span_end = min(until, problem.t0 + 1.0) if convergence_until is None else convergence_until
    span_end = real_number("convergence_until", span_end, unit=" s")
    integrators = [get(name) for name in methods]
    results, runs, studies = [], {}, []

    for integrator in integrators:
        started = time.perf_counter()
        solution = solve(problem, integrator, dt=dt, until=until, record_every=record_every)
        elapsed = time.perf_counter() - started
        recording = solution.recording
        runs[integrator.name] = recording
        try:
            study = convergence_order(problem, integrator, until=span_end, levels=levels)
        except SimulationError:
            study = None
        if study is not None:
            studies.append(study)
        results.append(
            MethodResult(
                method=integrator.name,
                declared_order=integrator.order,
                measured_order=float("nan") if study is None else study.order,
                energy_drift=energy_drift(recording),
                max_energy_error=max_energy_error(recording),
                f_evaluations=int(recording.attrs.get("f_evaluations", 0)),
                wall_time_s=elapsed,
                success=bool(recording.attrs.get("success", True)),
                message=str(recording.attrs.get("message", "")),
            )
        )
    return Comparison(results, runs, studies, dt, until)
