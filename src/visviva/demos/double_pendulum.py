"""Demo ``double-pendulum``: chaos from two coordinates.

Two double pendulums start 10⁻⁹ rad apart (``theta2``). Their separation grows like
``e^{λt}`` — the finite-time Lyapunov exponent ``λ`` is estimated by Benettin's method — until,
after a few seconds, the two motions have nothing in common. The video shows both pendulums
on one pivot. Energy: RK4 in ``(θ, θ̇)`` loses it slowly; implicit midpoint in Hamilton's
``(θ, p)`` keeps it bounded (symplectic), even at a ten times larger step.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..analysis.chaos import lyapunov_exponent
from ..io.job import JobOutput
from ..mechanics import classic
from ..simulation.recording import Recording
from ..simulation.solution import solve
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._bodies import drawn_if_interrupted
from .catalogue import BUILTIN_DEMOS

Q0 = np.array([2.0, 1.0])  # released from rest [rad]
DELTA = 1e-9  # initial difference in theta2 [rad]
DT = 1e-3  # [s]
#: Colours of the two pendulums' pivot and bobs: one blue, the other orange, pivots grey.
PIVOT_AND_BOBS = (
    [[0.45, 0.45, 0.45], [0.18, 0.44, 0.70], [0.18, 0.44, 0.70]],
    [[0.45, 0.45, 0.45], [0.90, 0.45, 0.10], [0.90, 0.45, 0.10]],
)


def _together(system: Any, pair: Recording) -> Recording:
    """Both pendulums in one recording: the first one's ``q`` and ``v``, six points and four
    rods, lifted above the ground."""
    q, t = pair["q"], pair.time
    points = np.concatenate([system.points(q[:, i], t) for i in range(2)], axis=1)
    points[..., 1] += 2.2
    edges = np.array(system.edges, dtype=np.int64)
    static = {
        "edges": np.concatenate([edges, edges + 3]),
        "system_color": np.array(PIVOT_AND_BOBS[0] + PIVOT_AND_BOBS[1]),
    }
    fields = {"q": q[:, 0], "v": pair["v"][:, 0], "system_points": points}
    return Recording(t, fields, units={"system_points": "m"}, attrs=pair.attrs, static=static)


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    system = classic.double_pendulum()
    output.stage("equations.txt").write_text(system.text() + "\n")
    output.stage("equations.tex").write_text(system.latex() + "\n")
    problem = system.problem(np.stack([Q0, Q0 + [0.0, DELTA]]), np.zeros((2, 2)))
    together = functools.partial(_together, system)
    with drawn_if_interrupted(together):
        pair = solve(problem, "rk4", dt=DT, until=duration, record_every=10)
    output.recordings["rk4"] = together(pair.recording)
    difference = np.concatenate([pair.q[:, 1] - pair.q[:, 0], pair.v[:, 1] - pair.v[:, 0]], axis=1)
    separation = np.linalg.norm(difference, axis=1)
    estimate = lyapunov_exponent(
        system.problem(Q0, [0.0, 0.0]), until=max(duration, 20.0), dt=2e-3, interval=0.5
    )

    canonical = solve(
        system.canonical_problem(Q0, [0.0, 0.0]), "implicit_midpoint", dt=10 * DT, until=duration
    )
    output.recordings["implicit_midpoint_qp"] = canonical.recording

    figure = Figure(figsize=(13, 4.5), layout="constrained")
    spread, running, energy = figure.subplots(1, 3)
    # The two runs by the colours the video gives them: blue starts at Q0, orange δ0 away.
    spread.semilogy(pair.t, separation, label="|Δ(θ, θ̇)| between the two runs")
    spread.semilogy(
        pair.t,
        DELTA * np.exp(estimate.exponent * pair.t),
        "k:",
        label=f"δ0 e^(λt), λ = {estimate.exponent:.2f}/s",
    )
    spread.set_xlabel("t [s]")
    spread.set_ylabel("separation")
    spread.set_title(f"Two starts {DELTA:g} rad apart in θ₂ (the video's blue and orange)")
    legend_below(spread)
    running.plot(estimate.times, estimate.running)
    running.set_xlabel("t [s]")
    running.set_ylabel("λ estimate [1/s]")
    running.set_title("Finite-time Lyapunov exponent (Benettin)")
    e0 = pair.energy[0, 0]
    energy.plot(pair.t, pair.energy[:, 0] / e0 - 1, label=f"RK4 (θ, θ̇), h = {DT} s")
    energy.plot(
        canonical.t,
        canonical.energy / e0 - 1,
        label=f"implicit midpoint (θ, p), h = {10 * DT} s",
    )
    energy.set_xlabel("t [s]")
    energy.set_ylabel("E(t)/E(0) − 1")
    energy.set_title("Energy of the first start (the video's blue pendulum)")
    legend_below(energy)
    output.figures["double_pendulum"] = figure
    visible = np.flatnonzero(separation > 0.1)
    return {
        "equations": system.text(),
        "lyapunov_exponent_per_s": estimate.exponent,
        "time_to_visible_difference_s": float(pair.t[visible[0]]) if visible.size else None,
    }


register_demo(
    Demo(
        "double-pendulum",
        BUILTIN_DEMOS["double-pendulum"].summary,
        20.0,
        run,
        picture=True,
    )
)
