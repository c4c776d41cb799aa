"""Demo ``kepler``: two bodies on an ellipse of eccentricity 0.5, against Kepler's solution.

The exact motion follows from Kepler's equation ``M = E − e sin E`` (solved by Newton's
method). Leapfrog/velocity Verlet at 1000 steps per orbit keeps the energy error bounded
(oscillating at O(h²), largest at periapsis) and the angular momentum to rounding (a central
force and a symplectic, time-reversible method); RK4 is far more accurate per orbit but its
energy drifts slowly; explicit Euler spirals outwards.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..analysis.invariants import angular_momentum
from ..io.job import JobOutput
from ..mechanics import kepler_orbit
from ..simulation.solution import solve
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._bodies import body_states, drawn_bodies, drawn_if_interrupted
from .catalogue import BUILTIN_DEMOS

ECCENTRICITY = 0.5
MASSES = (1.0, 0.1)  # [kg], with G = 1 (N-body units)
STEPS_PER_ORBIT = 1000
METHODS = ("velocity_verlet", "rk4", "explicit_euler")
#: The heavier body orange, the lighter blue.
COLORS = np.array([[0.90, 0.45, 0.10], [0.18, 0.44, 0.70]])
#: Kepler's third law with G = 1: T = 2π √(a³ / (m1 + m2)) for a = 1 [s].
PERIOD = 2 * np.pi / np.sqrt(sum(MASSES))


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    orbit = kepler_orbit(1.0, ECCENTRICITY, masses=MASSES, G=1.0)
    dt = orbit.period / STEPS_PER_ORBIT
    problem = orbit.bodies().problem()
    masses = np.array(MASSES)
    figure = Figure(figsize=(13, 4.5), layout="constrained")
    path, energy, momentum = figure.subplots(1, 3)
    exact_path = orbit.positions(np.linspace(0.0, orbit.period, 400))
    path.plot(
        exact_path[:, 1, 0],
        exact_path[:, 1, 2],
        color="0.3",
        linewidth=4,
        alpha=0.3,
        label="Kepler ellipse",
    )
    figures = {}
    for name, color in zip(METHODS, distinct_colors(len(METHODS)), strict=True):
        draw = functools.partial(drawn_bodies, color=COLORS)
        with drawn_if_interrupted(draw):
            solution = solve(problem, name, dt=dt, until=duration, record_every=10)
        output.recordings[name] = draw(solution.recording)
        x, v = body_states(solution.recording)
        relative_energy = solution.energy / orbit.energy - 1.0
        spin = angular_momentum(masses, x, v)[:, 1]
        relative_spin = spin / spin[0] - 1.0
        error = np.abs(x - orbit.positions(solution.t)).max(axis=(1, 2))
        figures[name] = {
            "max_energy_error": float(np.abs(relative_energy).max()),
            "max_angular_momentum_error": float(np.abs(relative_spin).max()),
            "final_position_error_m": float(error[-1]),
        }
        path.plot(x[:, 1, 0], x[:, 1, 2], linewidth=0.8, color=color, label=name)
        orbits = solution.t / orbit.period
        energy.semilogy(orbits, np.maximum(np.abs(relative_energy), 1e-17), color=color, label=name)
        momentum.semilogy(orbits, np.maximum(np.abs(relative_spin), 1e-17), color=color, label=name)
    path.set_aspect("equal")
    path.set_xlabel("x [m]")
    path.set_ylabel("z [m]")
    path.set_title(f"Lighter body, e = {ECCENTRICITY}, {STEPS_PER_ORBIT} steps per orbit")
    legend_below(path)
    energy.set_xlabel("orbits")
    energy.set_ylabel("|E/E_Kepler − 1|")
    energy.set_title("Energy")
    legend_below(energy)
    momentum.set_xlabel("orbits")
    momentum.set_ylabel("|L/L0 − 1|")
    momentum.set_title("Angular momentum")
    legend_below(momentum)
    output.figures["kepler"] = figure
    return {"period_s": orbit.period, "dt_s": dt, "methods": figures}


register_demo(
    Demo(
        "kepler",
        BUILTIN_DEMOS["kepler"].summary,
        60.0,
        run,
        picture=True,
        trail=PERIOD,  # the whole ellipse behind each body
    )
)
