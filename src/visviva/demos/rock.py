"""Demo ``rock``: seed 001's thrown rock, four integrators against the exact parabola.

Under a constant force the exact motion is ``x(t) = x0 + v0 t − ½ g t² ŷ``. Velocity Verlet and
RK4 reproduce it to rounding (their error terms involve derivatives of the force, which
vanish); explicit Euler's height is too high by exactly ``½ g h t`` (its position uses the
velocity at the start of each step), symplectic Euler's too low by the same.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..mechanics import classic
from ..simulation.solution import solve
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._bodies import drawn_if_interrupted, drawn_system
from .catalogue import BUILTIN_DEMOS

DT = 0.05  # step [s]
Q0 = np.array([0.0, 0.0, 0.0])  # thrown from the ground [m]
V0 = np.array([4.0, 8.0, 0.0])  # [m/s]: up 8 m/s, forward 4 m/s
METHODS = ("velocity_verlet", "rk4", "symplectic_euler", "explicit_euler")


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    system = classic.rock()
    problem = system.problem(Q0, V0)
    figure = Figure(figsize=(12, 5), layout="constrained")
    path, error = figure.subplots(1, 2)
    errors = {}
    for name, color in zip(METHODS, distinct_colors(len(METHODS)), strict=True):
        with drawn_if_interrupted(functools.partial(drawn_system, system)):
            solution = solve(problem, name, dt=DT, until=duration)
        output.recordings[name] = drawn_system(system, solution.recording)
        exact = classic.rock_trajectory(solution.t, Q0, V0)
        height_error = solution.q[:, 1] - exact[:, 1]
        errors[name] = float(np.abs(solution.q - exact).max())
        path.plot(solution.q[:, 0], solution.q[:, 1], "o-", markersize=3, color=color, label=name)
        error.plot(solution.t, height_error, color=color, label=name)
    t = np.linspace(0.0, duration, 200)
    exact = classic.rock_trajectory(t, Q0, V0)
    path.plot(exact[:, 0], exact[:, 1], color="0.3", linewidth=3, alpha=0.4, label="exact")
    path.set_xlabel("x [m]")
    path.set_ylabel("height y [m]")
    path.set_title(f"Thrown rock, h = {DT} s")
    legend_below(path)
    error.plot(t, 0.5 * classic.STANDARD_GRAVITY * DT * t, "k:", label="½ g h t (Euler, predicted)")
    error.set_xlabel("t [s]")
    error.set_ylabel("height error [m]")
    error.set_title("Constant force: Verlet and RK4 exact, Euler off by ½ g h t")
    legend_below(error)
    output.figures["rock"] = figure
    return {
        "dt_s": DT,
        "max_position_error_m": errors,
        "predicted_euler_error_m": 0.5 * classic.STANDARD_GRAVITY * DT * duration,
    }


register_demo(
    Demo(
        "rock",
        BUILTIN_DEMOS["rock"].summary,
        1.6,
        run,
        picture=True,
    )
)
