"""Demo ``bunny-drop``: non-convex bunnies cut into convex pieces fall onto a floor and a
step, and come to rest on their own surfaces (seed 000's rigid bunny drop).

A rigid body collides as convex pieces. The bunny (a generated mesh, :func:`._meshes.bunny`,
about 1,500 triangles) is not convex — its ears stand apart from its head — so it is cut into
nearly convex pieces by CoACD (:mod:`visviva.collision.decomposition`), never silently
replaced by its hull. Three bunnies turned three ways fall from 0.5 m onto a floor and onto the
edge of a step (a box), with restitution 0.3 and friction 0.6, and come to rest. A fourth
bunny collides as its convex hull, for comparison: round and bridging the gap between its
ears, the hull rocks on the floor like a roly-poly (a rigid body rolling without slipping
loses no energy), where the pieces let the others settle on their feet and flanks.

The summary gives the pieces, each bunny's lowest surface point at rest (0 on the floor, to
within the pieces' approximation of the surface: their hulls are cut to 48 corners, which
shaves a few millimetres off a 20 cm bunny), the kinetic energy left and the contacts at the
end; the recording holds each frame's contacts, which the web viewer shows
when its *contacts* box is ticked.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..collision.decomposition import convex_decomposition
from ..geometry.quaternions import quaternion_matrix
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._meshes import bunny
from .catalogue import BUILTIN_DEMOS

DENSITY = 500.0  # [kg/m³]
DT = 1.0 / 240.0
STEP = {"center": (0.35, 0.075, 0.0), "size": (0.3, 0.15, 1.0)}  # a box on the floor [m]
HALF = float(np.sqrt(0.5))
#: name: (origin [m], orientation (w, x, y, z), collision shape, colour)
BUNNIES = {
    "upright": ((-0.3, 0.5, -0.25), (1.0, 0.0, 0.0, 0.0), "decomposition", (0.85, 0.8, 0.7)),
    "on its side": ((-0.3, 0.5, 0.25), (HALF, HALF, 0.0, 0.0), "decomposition", (0.8, 0.7, 0.6)),
    "off the step's edge": (
        (0.35, 0.6, 0.0),
        (float(np.cos(np.pi / 8)), 0.0, float(np.sin(np.pi / 8)), 0.0),
        "decomposition",
        (0.75, 0.8, 0.85),
    ),
    "as its hull": ((-0.9, 0.5, 0.0), (HALF, HALF, 0.0, 0.0), "hull", (0.7, 0.6, 0.8)),
}


def _lowest(vertices: np.ndarray, centre: np.ndarray, x: np.ndarray, q: np.ndarray) -> float:
    """The lowest point of a body's surface [m] at centre of mass ``x``, orientation ``q``."""
    world = (vertices - centre) @ quaternion_matrix(q).T + x
    return float(world[:, 1].min())


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    vertices, triangles = bunny(detail=40)
    pieces = convex_decomposition(vertices, triangles)
    builder = SceneBuilder(name="bunny drop")
    builder.set_integration(method="velocity_verlet", dt=DT, duration=duration)
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=0.3,
                         friction=0.6)  # fmt: skip
    builder.add_collider("box", **STEP, restitution=0.3, friction=0.6, color=(0.55, 0.55, 0.6))
    for name, (origin, orientation, collides, color) in BUNNIES.items():
        builder.add_body(
            "mesh", vertices=vertices, triangles=triangles, density=DENSITY, position=origin,
            orientation=orientation, collision_shape=collides, restitution=0.3, friction=0.6,
            color=color, name=name,
        )  # fmt: skip
    builder.add_body_contacts()
    model = builder.build()
    output.recordings["velocity_verlet"] = Simulation(model).record(until=duration,
                                                                    contacts=True)  # fmt: skip
    simulation = Simulation(model)
    centres = model.bodies.center
    names = list(BUNNIES)
    t, heights, energy = [], [], []
    every = 6
    for _ in range(round(duration / (every * DT)) + 1):
        t.append(simulation.time)
        state = simulation.state
        x, q = state["body_position"], state["body_orientation"]
        heights.append([_lowest(vertices, centres[b], x[b], q[b]) for b in range(len(names))])
        views = simulation.bodies()
        mass = model.bodies.mass
        kinetic = 0.5 * mass * (views.velocity**2).sum(axis=1) + 0.5 * np.einsum(
            "bi,bi->b", views.angular_velocity, state["body_angular_momentum"]
        )
        energy.append(kinetic)
        simulation.step(every)
    t, heights, energy = np.array(t), np.array(heights), np.array(energy)
    found = simulation.body_contacts()

    figure = Figure(figsize=(12, 4.5), layout="constrained")
    fall, rest = figure.subplots(1, 2)
    for k, (name, color) in enumerate(zip(names, distinct_colors(len(names)), strict=True)):
        fall.plot(t, heights[:, k], color=color, label=name)
        rest.semilogy(t, np.maximum(energy[:, k], 1e-12), color=color, label=name)
    fall.axhline(0.0, color="grey", lw=0.6)
    fall.axhline(2 * STEP["center"][1], color="grey", lw=0.6, ls=":")
    fall.set_xlabel("t [s]")
    fall.set_ylabel("lowest surface point [m]")
    fall.set_title(f"Bunnies cut into {len(pieces)} convex pieces land on their surfaces")
    legend_below(fall)
    rest.set_xlabel("t [s]")
    rest.set_ylabel("kinetic energy [J]")
    rest.set_title("Restitution 0.3, friction 0.6: they come to rest")
    output.figures["bunny_drop"] = figure
    return {
        "pieces": len(pieces),
        "piece_corners": [int(p.shape[0]) for p in pieces],
        "lowest_point_at_rest_m": {n: float(heights[-1, k]) for k, n in enumerate(names)},
        "kinetic_energy_at_rest_J": {n: float(energy[-1, k]) for k, n in enumerate(names)},
        "contacts_at_rest": found.counts(),
    }


register_demo(
    Demo(
        "bunny-drop",
        BUILTIN_DEMOS["bunny-drop"].summary,
        3.0,
        run,
        picture=True,
    )
)
