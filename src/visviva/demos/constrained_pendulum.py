"""Demo ``constrained-pendulum``: the same pendulum in θ and as a particle on a rod.

In generalized coordinates the rod is built in: ``θ`` is all there is. As a free particle
``r = (x, y)`` the rod is a constraint force ``f^c = λ (r − c)`` with ``λ`` chosen so that
``|r − c|`` stays ``L`` (seed 001: "same as rock, but constrained"). The two descriptions trace
the same swing; the particle's rod length drifts slowly with the step unless Baumgarte
stabilisation pulls it back. The rod's tension ``|λ| L = m (g cos θ + L θ̇²)`` is plotted too.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..mechanics import classic
from ..simulation.recording import Recording
from ..simulation.solution import solve
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._bodies import drawn_if_interrupted
from .catalogue import BUILTIN_DEMOS

LENGTH = 1.0  # [m]
THETA0 = 1.2  # [rad]
DT = 0.01  # [s]
STABILIZATION = 10.0  # Baumgarte rate α [1/s]


def _drawn(recording: Recording) -> Recording:
    """The particle's recording with the pivot and the particle as points, joined by the rod."""
    q = recording["q"]
    points = np.zeros((q.shape[0], 2, 3))
    points[:, 1, :2] = q
    points[..., 1] += 1.2 * LENGTH  # swing above the video's ground plane
    return Recording(
        recording.time,
        dict(recording.fields) | {"system_points": points},
        units=dict(recording.units) | {"system_points": "m"},
        attrs=recording.attrs,
        static={"edges": np.array([[0, 1]])},
    )


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    reduced = solve(
        classic.pendulum(length=LENGTH).problem([THETA0], [0.0]), "rk4", dt=DT, until=duration
    )
    figure = Figure(figsize=(13, 4.5), layout="constrained")
    angle, drift, tension = figure.subplots(1, 3)
    angle.plot(
        reduced.t, reduced.q[:, 0], linewidth=3, alpha=0.4, label="θ (generalized coordinate)"
    )
    drifts = {}
    for alpha in (0.0, STABILIZATION):
        problem, multiplier = classic.constrained_pendulum(
            THETA0, length=LENGTH, stabilization_rate=alpha
        )
        with drawn_if_interrupted(_drawn):
            particle = solve(problem, "rk4", dt=DT, until=duration)
        label = "particle + λ(r − c)" + (f", Baumgarte α = {alpha:g}/s" if alpha else "")
        output.recordings["constrained" if alpha == 0 else "stabilized"] = _drawn(
            particle.recording
        )
        x, y = particle.q[:, 0], particle.q[:, 1]
        angle.plot(particle.t, np.arctan2(x, -y), "--", label=label)
        error = np.abs(np.hypot(x, y) - LENGTH)
        drifts["none" if alpha == 0 else f"alpha={alpha:g}"] = float(error.max())
        drift.semilogy(particle.t, np.maximum(error, 1e-17), label=label)
        tension.plot(particle.t, np.abs(multiplier(particle.q, particle.v)) * LENGTH, label=label)
    output.recordings["reduced"] = reduced.recording
    theta, omega = reduced.q[:, 0], reduced.v[:, 0]
    tension.plot(
        reduced.t,
        classic.STANDARD_GRAVITY * np.cos(theta) + LENGTH * omega**2,
        "k:",
        label="m (g cos θ + L θ̇²)",
    )
    angle.set_xlabel("t [s]")
    angle.set_ylabel("θ [rad]")
    angle.set_title("The same swing, two descriptions")
    legend_below(angle)
    drift.set_xlabel("t [s]")
    drift.set_ylabel("| |r − c| − L | [m]")
    drift.set_title(f"Rod length error, RK4, h = {DT} s")
    legend_below(drift)
    tension.set_xlabel("t [s]")
    tension.set_ylabel("|f^c| [N]")
    tension.set_title("Constraint force along the rod")
    legend_below(tension)
    output.figures["constrained_pendulum"] = figure
    return {"dt_s": DT, "max_rod_length_error_m": drifts}


register_demo(
    Demo(
        "constrained-pendulum",
        BUILTIN_DEMOS["constrained-pendulum"].summary,
        10.0,
        run,
        picture=True,
    )
)
