"""Demo ``oscillator``: every integrator on the undamped spring ``q'' = −ω²q``, side by side.

The exact motion keeps ``E = ½v² + ½ω²q²`` constant. Explicit Euler multiplies it by
``1 + (ωh)²`` every step and backward Euler divides it by the same factor (seed 000); the
symplectic methods keep it within ``O((ωh)^p)`` forever; the trapezoidal rule and implicit
midpoint keep it exactly; RK4 and Dormand–Prince lose a little, slowly.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..integrators import get, names
from ..io.job import JobOutput
from ..ode.problems import SecondOrderProblem
from ..simulation.solution import solve
from ..viz.plots import plot_energy, plot_phase
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

OMEGA = 2.0 * np.pi  # angular frequency [rad/s]: one oscillation per second
DT = 0.02  # step [s]: ωh ≈ 0.126


def oscillator_problem() -> SecondOrderProblem:
    """Unit mass on a spring of stiffness ω² [N/m], released from q = 1 m at rest."""

    def acceleration(t: float, q: np.ndarray) -> np.ndarray:
        return -(OMEGA**2) * q

    def jacobian(t: float, q: np.ndarray) -> np.ndarray:
        return np.full(q.shape + q.shape[-1:], -(OMEGA**2))

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        return 0.5 * v[..., 0] ** 2 + 0.5 * OMEGA**2 * q[..., 0] ** 2

    return SecondOrderProblem(
        acceleration,
        q0=[1.0],
        v0=[0.0],
        jacobian=jacobian,
        energy=energy,
        name="harmonic oscillator, omega = 2 pi rad/s",
    )


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    problem = oscillator_problem()
    every = max(1, round(duration / DT / 2000))  # keep at most ~2000 frames per method
    for name in names():
        method = get(name)
        if method.adaptive:
            solution = solve(problem, method, until=duration, rtol=1e-6, atol=1e-9)
        else:
            solution = solve(problem, method, dt=DT, until=duration, record_every=every)
        output.recordings[name] = solution.recording
    output.figures["energy"] = plot_energy(
        output.recordings, title=f"Undamped oscillator, ωh = {OMEGA * DT:.3f}: energy change"
    )
    phase_time = np.linspace(0.0, 2 * np.pi, 200)
    output.figures["phase"] = plot_phase(
        output.recordings,
        exact=(np.cos(phase_time), -OMEGA * np.sin(phase_time)),
        labels=("q [m]", "v/ω [m]"),
        velocity_scale=OMEGA,
        title=f"Phase portraits, ωh = {OMEGA * DT:.3f}: q against v/ω (exact: the unit circle)",
    )
    return {"omega_rad_per_s": OMEGA, "dt_s": DT, "omega_h": OMEGA * DT}


register_demo(
    Demo(
        "oscillator",
        BUILTIN_DEMOS["oscillator"].summary,
        10.0,
        run,
    )
)
