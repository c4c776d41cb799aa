"""Demo ``spring-pendulum``: a bob on a spring, swinging and bouncing in ``(r, θ)``.

``K = ½ m (ṙ² + r² θ̇²)``, ``U = ½ k (r − L₀)² − m g r cos θ``. With the spring's frequency
near twice the swing's the two motions trade energy back and forth (the elastic pendulum's
autoparametric resonance); the total stays constant, which RK4 at h = 1 ms keeps to ~10⁻⁹.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..mechanics import classic
from ..simulation.solution import solve
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._bodies import drawn_if_interrupted, drawn_system
from .catalogue import BUILTIN_DEMOS

MASS, REST = 1.0, 1.0  # [kg], [m]
G = classic.STANDARD_GRAVITY
# ω_spring = 2 ω_swing: k/m = 4 g / (L₀ + m g / k)  ⇒  k = 3 m g / L₀
STIFFNESS = 3.0 * MASS * G / REST
DT = 1e-3  # [s]


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    system = classic.spring_pendulum(mass=MASS, stiffness=STIFFNESS, rest_length=REST)
    hanging = REST + MASS * G / STIFFNESS  # equilibrium length [m]
    with drawn_if_interrupted(functools.partial(drawn_system, system)):
        solution = solve(
            system.problem([hanging + 0.05, 0.3], [0.0, 0.0]),
            "rk4",
            dt=DT,
            until=duration,
            record_every=10,
        )
    output.recordings["rk4"] = drawn_system(system, solution.recording)
    r, theta = solution.q[:, 0], solution.q[:, 1]
    rdot, omega = solution.v[:, 0], solution.v[:, 1]
    spring = 0.5 * STIFFNESS * (r - REST) ** 2
    gravity = -MASS * G * r * np.cos(theta)
    radial = 0.5 * MASS * rdot**2
    swing = 0.5 * MASS * r**2 * omega**2

    figure = Figure(figsize=(13, 4.5), layout="constrained")
    path, exchange, total = figure.subplots(1, 3)
    path.plot(r * np.sin(theta), -r * np.cos(theta), linewidth=0.6)
    path.set_aspect("equal")
    path.set_xlabel("x [m]")
    path.set_ylabel("y [m]")
    path.set_title("Path of the bob")
    # The energy of each mode about the hanging equilibrium.
    stretch = radial + 0.5 * STIFFNESS * (r - hanging) ** 2
    exchange.plot(solution.t, stretch, label="spring mode")
    exchange.plot(solution.t, swing + MASS * G * hanging * (1 - np.cos(theta)), label="swing mode")
    exchange.set_xlabel("t [s]")
    exchange.set_ylabel("energy [J]")
    exchange.set_title("ω_spring = 2 ω_swing: the modes trade energy")
    legend_below(exchange)
    e = spring + gravity + radial + swing
    total.plot(solution.t, e / e[0] - 1)
    total.set_xlabel("t [s]")
    total.set_ylabel("E(t)/E(0) − 1")
    total.set_title(f"Total energy, RK4, h = {DT} s")
    output.figures["spring_pendulum"] = figure
    return {
        "stiffness_N_per_m": STIFFNESS,
        "swing_period_s": 2 * math.pi * math.sqrt(hanging / G),
        "energy_drift": float(e[-1] / e[0] - 1),
    }


register_demo(
    Demo(
        "spring-pendulum",
        BUILTIN_DEMOS["spring-pendulum"].summary,
        30.0,
        run,
        picture=True,
    )
)
