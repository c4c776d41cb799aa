"""Demo ``galaxy``: two disk galaxies collide (Toomre & Toomre 1972).

Each galaxy is a central mass with a self-gravitating disk of stars on near-circular orbits;
the two fall towards each other on a parabolic orbit and pass within ``PERICENTER``. Tidal
forces pull out a bridge and long tails, as in the Toomres' models of interacting galaxies.
Softened gravity (N-body units, G = 1) from the Barnes–Hut tree at opening angle ``THETA``,
velocity Verlet. The summary gives the tree's force error against direct summation in the
starting configuration and the change of the total energy (the tree's forces are not exactly
the gradient of any potential, so the energy wanders at about their error).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..mechanics import colliding_disks, tree_force_error
from ..simulation.solution import solve
from . import Demo, register_demo
from ._bodies import body_states, drawn_bodies, drawn_if_interrupted
from .catalogue import BUILTIN_DEMOS

BODIES_PER_DISK = 3000
DISK_MASS = 0.2  # of each disk, against a central mass of 1
RADIUS = 1.0  # [m], N-body units
PERICENTER = 1.5
SEPARATION = 6.0
SOFTENING = 0.05
DT = 0.01
THETA = 0.5  # Barnes–Hut opening angle


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    bodies = colliding_disks(
        BODIES_PER_DISK,
        central_mass=1.0,
        disk_mass=DISK_MASS,
        radius=RADIUS,
        separation=SEPARATION,
        pericenter=PERICENTER,
        G=1.0,
        softening=SOFTENING,
        seed=1,
    )
    problem = bodies.problem(
        softening=SOFTENING, method="barnes_hut", theta=THETA, name="colliding galaxies"
    )
    with drawn_if_interrupted(drawn_bodies):
        solution = solve(problem, "velocity_verlet", dt=DT, until=duration, record_every=5)
    output.recordings["velocity_verlet"] = drawn_bodies(solution.recording)
    x, _ = body_states(solution.recording)
    figure = Figure(figsize=(14, 3.8), layout="constrained")
    panels = figure.subplots(1, 4, sharex=True, sharey=True)
    for panel, frame in zip(panels, np.linspace(0, x.shape[0] - 1, 4).astype(int), strict=True):
        panel.scatter(x[frame, :, 0], x[frame, :, 2], s=0.3, color="navy")
        panel.set_aspect("equal")
        panel.set_title(f"t = {solution.t[frame]:.1f}")
        panel.set_xlabel("x")
    panels[0].set_ylabel("z")
    output.figures["galaxy"] = figure
    # The centres fall in on a parabolic orbit, so the total energy is near zero: measure its
    # change against the initial kinetic energy instead of against itself.
    change = np.abs(solution.energy - solution.energy[0]).max()
    tree = tree_force_error(
        bodies.positions, bodies.masses, G=1.0, softening=SOFTENING, theta=THETA
    )
    return {
        "bodies": bodies.count,
        "barnes_hut_force_error": {"theta": THETA, "median": tree.median, "p99": tree.p99},
        "dt": DT,
        "max_energy_change_over_initial_kinetic": float(change / bodies.kinetic_energy()),
    }


register_demo(
    Demo(
        "galaxy",
        BUILTIN_DEMOS["galaxy"].summary,
        15.0,
        run,
        picture=True,
    )
)
