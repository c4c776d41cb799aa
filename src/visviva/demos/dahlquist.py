"""Demo ``test-equation``: Dahlquist's test equation ``y' = λy``, ``λ = −1``, around ``h = 2``.

The exact solution decays as ``e^{−t}``. One step multiplies ``y`` by ``R(hλ)`` (seeds 000 and
004): explicit Euler's ``1 − h`` decays only for ``h < 2`` and oscillates with growing amplitude
beyond; backward Euler's ``1/(1 + h)`` decays for every ``h``; the trapezoidal rule's
``(1 − h/2)/(1 + h/2)`` decays for every ``h`` but flips sign for ``h > 2``; RK4 is stable up to
``h ≈ 2.785``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..analysis.stability import stability_function
from ..io.job import JobOutput
from ..ode.problems import FirstOrderProblem
from ..simulation.solution import solve
from ..viz.plots import plot_stability_regions
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

LAMBDA = -1.0  # eigenvalue λ [1/s]
STEPS = (0.5, 1.5, 1.9, 2.5, 3.0)  # h [s]
METHODS = ("explicit_euler", "backward_euler", "trapezoidal", "rk4")


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    problem = FirstOrderProblem(
        lambda t, y: LAMBDA * y,
        [1.0],
        jacobian=lambda t, y: np.full((1, 1), LAMBDA),
        name="test equation y' = -y",
    )
    figure = Figure(figsize=(3.0 * len(STEPS), 2.6 * len(METHODS)), layout="constrained")
    axes = figure.subplots(len(METHODS), len(STEPS), sharex=True, squeeze=False)
    exact_t = np.linspace(0.0, duration, 400)
    amplification: dict[str, dict[str, float]] = {}
    for row, name in enumerate(METHODS):
        amplification[name] = {}
        for column, h in enumerate(STEPS):
            solution = solve(problem, name, dt=h, until=duration)
            output.recordings[f"{name}_h{h:g}"] = solution.recording
            factor = float(stability_function(name, h * LAMBDA).real)
            amplification[name][f"{h:g}"] = factor
            ax = axes[row, column]
            ax.plot(exact_t, np.exp(LAMBDA * exact_t), color="0.6", linewidth=2.5)
            ax.plot(solution.t, solution.y[:, 0], "o-", markersize=3, linewidth=1)
            verdict = "stable" if abs(factor) <= 1 else "unstable"
            ax.set_title(f"{name}, h={h:g}: R={factor:.3g} ({verdict})", fontsize=9)
        axes[row, 0].set_ylabel("y")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    figure.suptitle("Test equation y' = -y: numerical (dots) vs exact e^(-t) (grey)")
    output.figures["solutions"] = figure

    regions = plot_stability_regions(METHODS, bounds=(-4.0, 3.0, -2.5, 2.5))
    for ax in regions.axes[: len(METHODS)]:
        ax.plot([h * LAMBDA for h in STEPS], [0.0] * len(STEPS), "o", color="#e6550d", markersize=4)
    regions.suptitle("Stability regions with the points hλ of the runs (orange)")
    output.figures["stability"] = regions
    return {"lambda_per_s": LAMBDA, "steps_s": list(STEPS), "amplification": amplification}


register_demo(
    Demo(
        "test-equation",
        BUILTIN_DEMOS["test-equation"].summary,
        12.0,
        run,
    )
)
