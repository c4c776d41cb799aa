"""Demo ``circular``: the circular-motion example of seed 004.

A particle moves on a circle of radius ``r0``: ``x' = y``, ``y' = −x``, exact solution
``(x, y) = r0 (sin t, cos t)``. The eigenvalues of the system are ``±i``: on the imaginary axis,
outside explicit Euler's stability disc — its orbit spirals *out* by ``√(1 + h²)`` per step;
backward Euler's spirals *in* by the inverse; symplectic Euler stays on a slightly squashed
closed curve; implicit midpoint keeps the radius exactly.

Written as ``q = x``, ``v = y = q'``, ``q'' = −q``, so symplectic Euler applies.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..ode.problems import SecondOrderProblem
from ..simulation.solution import solve
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

RADIUS = 1.0  # r0 [m]
DT = 0.1  # step [s]
METHODS = ("explicit_euler", "backward_euler", "symplectic_euler", "implicit_midpoint")


def circular_problem() -> SecondOrderProblem:
    """``(x, y)`` from ``(0, r0)`` with ``x' = y``, ``y' = −x``; "energy" ``½r²``."""
    return SecondOrderProblem(
        lambda t, q: -q,
        q0=[0.0],
        v0=[RADIUS],
        jacobian=lambda t, q: -np.ones(q.shape + q.shape[-1:]),
        energy=lambda t, q, v: 0.5 * (q[..., 0] ** 2 + v[..., 0] ** 2),
        name="circular motion x' = y, y' = -x",
    )


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    problem = circular_problem()
    final_radius = {}
    for name in METHODS:
        solution = solve(problem, name, dt=DT, until=duration)
        output.recordings[name] = solution.recording
        final_radius[name] = float(np.hypot(solution.q[-1, 0], solution.v[-1, 0]))

    figure = Figure(figsize=(12, 5.5), layout="constrained")
    plane, radius = figure.subplots(1, 2)
    angle = np.linspace(0, 2 * np.pi, 400)
    plane.plot(
        RADIUS * np.sin(angle), RADIUS * np.cos(angle), color="0.6", linewidth=3, label="exact"
    )
    runs = output.recordings.items()
    for (name, recording), color in zip(runs, distinct_colors(len(runs)), strict=True):
        x, y = recording["q"][:, 0], recording["v"][:, 0]
        plane.plot(x, y, linewidth=1.1, color=color, label=name)
        radius.plot(recording.time, np.hypot(x, y), linewidth=1.3, color=color, label=name)
    plane.set_aspect("equal")
    plane.set_xlabel("x [m]")
    plane.set_ylabel("y [m]")
    plane.set_title(f"Circular motion, h = {DT} s")
    legend_below(plane)
    radius.axhline(RADIUS, color="0.6", linewidth=3, label="exact")
    radius.set_yscale("log")
    radius.set_xlabel("t [s]")
    radius.set_ylabel("radius |q| [m]")
    radius.set_title("Explicit Euler spirals out, backward Euler in")
    legend_below(radius)
    output.figures["circular"] = figure
    return {
        "dt_s": DT,
        "final_radius_m": final_radius,
        # seed 004: explicit Euler's radius grows by sqrt(1 + h^2) per step, backward's shrinks.
        "predicted_radius_m": {
            "explicit_euler": RADIUS * (1 + DT**2) ** (0.5 * round(duration / DT)),
            "backward_euler": RADIUS * (1 + DT**2) ** (-0.5 * round(duration / DT)),
        },
    }


register_demo(
    Demo(
        "circular",
        BUILTIN_DEMOS["circular"].summary,
        20.0,
        run,
    )
)
