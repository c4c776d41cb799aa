"""Demo ``pendulum``: the pendulum from K and U, its exact period and the small-angle limit.

visviva derives ``m L² θ̈ = −m g L sin θ`` from ``K = ½ m L² θ̇²`` and ``U = −m g L cos θ``
(written to ``equations.txt`` and ``equations.tex``). Released from 1 rad the swing is
visibly slower than the small-angle solution ``θ0 cos(√(g/L) t)``; its period matches
``T = 4 √(L/g) K(sin²(θ0/2))`` (complete elliptic integral) to the accuracy of RK4. The period
against amplitude, measured from simulations, follows the elliptic curve up to near π.
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

LENGTH = 1.0  # [m]
THETA0 = 1.0  # released from rest at 1 rad
DT = 1e-3  # [s]
AMPLITUDES = (0.1, 0.5, 1.0, 1.5, 2.0, 2.5, 2.9)  # [rad]


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    system = classic.pendulum(length=LENGTH)
    with drawn_if_interrupted(functools.partial(drawn_system, system)):
        solution = solve(system.problem([THETA0], [0.0]), "rk4", dt=DT, until=duration)
    output.recordings["rk4"] = drawn_system(system, solution.recording)
    output.stage("equations.txt").write_text(system.text() + "\n")
    output.stage("equations.tex").write_text(system.latex() + "\n")
    exact = classic.pendulum_period(THETA0, length=LENGTH)
    measured = classic.oscillation_period(solution.t, solution.q[:, 0], solution.v[:, 0])

    figure = Figure(figsize=(12, 5), layout="constrained")
    motion, periods = figure.subplots(1, 2)
    motion.plot(solution.t, solution.q[:, 0], label=f"θ0 = {THETA0} rad (RK4, h = {DT} s)")
    linear = classic.small_angle_pendulum(solution.t, THETA0, length=LENGTH)
    motion.plot(solution.t, linear, "--", label="small-angle θ0 cos(√(g/L) t)")
    motion.set_xlabel("t [s]")
    motion.set_ylabel("θ [rad]")
    motion.set_title("Large swings are slower than the harmonic approximation")
    legend_below(motion)
    small = 2 * math.pi * math.sqrt(LENGTH / classic.STANDARD_GRAVITY)
    curve = np.linspace(0.01, 3.0, 300)
    periods.plot(
        curve,
        [classic.pendulum_period(a, length=LENGTH) for a in curve],
        label="exact (elliptic integral)",
    )
    swing = []
    for amplitude in AMPLITUDES:
        swing_run = solve(
            system.problem([amplitude], [0.0]),
            "rk4",
            dt=DT,
            until=4 * classic.pendulum_period(amplitude, length=LENGTH) + 0.5,
        )
        swing.append(classic.oscillation_period(swing_run.t, swing_run.q[:, 0], swing_run.v[:, 0]))
    periods.plot(AMPLITUDES, swing, "o", label="measured (RK4)")
    periods.axhline(small, color="0.5", linestyle=":", label="small-angle 2π√(L/g)")
    periods.set_xlabel("amplitude θ0 [rad]")
    periods.set_ylabel("period T [s]")
    periods.set_title("Period against amplitude")
    legend_below(periods)
    output.figures["pendulum"] = figure
    return {
        "equations": system.text(),
        "period_s": {"measured": measured, "exact": exact, "small_angle": small},
        "period_relative_error": abs(measured - exact) / exact,
    }


register_demo(
    Demo(
        "pendulum",
        BUILTIN_DEMOS["pendulum"].summary,
        10.0,
        run,
        picture=True,
    )
)
