"""Demo ``pile``: 4,096 rigid bodies of six shapes (10,000 with ``--full``) dropped into a bin
settle into a pile.

Spheres, boxes, capsules, cylinders, cones and convex rocks (the hull of fourteen random
points), a sixth of each, start on a 16 × 16 × 16 lattice 0.24 m apart (25 × 16 × 25 with
``--full``), each turned at random, and fall into a square bin 4.2 m wide (6.4 m): a floor
and four walls, planes, with restitution 0.1 and friction 0.5. Every pair goes through the
whole contact pipeline of issue 27: sweep and prune, the analytic ball and box pairs, GJK and
EPA with the clipped manifold for the rest, sequential impulses warm-started step to step,
and the split position correction (:mod:`visviva.collision.body_contacts`).

The summary gives how many bodies of each shape, the contacts at the end by Baraff's class,
the deepest overlap, the top of the pile, the fastest body, how many bodies left the bin or
fell through the floor (none should), and the kinetic energy at the end; the figure shows the
kinetic energy, the contacts and the pile's top against time. The recording holds the
bodies' surfaces for the video and the viewer (``-f mp4``, ``-f html``).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..geometry.quaternions import quaternion_rotate
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

SHAPES = ("sphere", "box", "capsule", "cylinder", "cone", "rock")
COLORS = {
    "sphere": (0.85, 0.35, 0.3),
    "box": (0.9, 0.7, 0.3),
    "capsule": (0.4, 0.7, 0.4),
    "cylinder": (0.3, 0.55, 0.85),
    "cone": (0.65, 0.45, 0.8),
    "rock": (0.6, 0.58, 0.55),
}
COLUMNS, LAYERS = 16, 16  # the lattice: 16 × 16 × 16 = 4,096 bodies, within a minute
FULL_COLUMNS = 25  # --full: 25 × 16 × 25 = 10,000 bodies (about 90 s on 2 cores)
PITCH = 0.24  # lattice spacing [m]
LOWEST = 0.3  # the lowest layer's height [m]
DENSITY = 800.0  # [kg/m³]
RESTITUTION = 0.1
FRICTION = 0.5
DT = 1.0 / 240.0
RECORD_EVERY = 8  # 30 frames a second
SEED = 27


def rock(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A convex rock about 0.15 m across: the hull of fourteen random points, as vertices
    ``(V, 3)`` [m] and outward triangles ``(T, 3)``."""
    from scipy.spatial import ConvexHull

    points = rng.normal(size=(14, 3)) * (0.07, 0.05, 0.06)
    hull = ConvexHull(points)
    vertices = points[hull.vertices]
    index = np.full(points.shape[0], -1)
    index[hull.vertices] = np.arange(hull.vertices.size)
    triangles = index[hull.simplices]
    centre = vertices.mean(axis=0)
    for k, (a, b, c) in enumerate(vertices[triangles]):
        if np.dot(np.cross(b - a, c - a), a - centre) < 0.0:
            triangles[k] = triangles[k, ::-1]
    return vertices, triangles


def scene(columns: int = COLUMNS, layers: int = LAYERS, duration: float = 2.0,
          seed: int = SEED) -> tuple[SceneBuilder, list[str]]:  # fmt: skip
    """``columns² · layers`` bodies of random shapes on a lattice over the bin; the builder
    and each body's shape."""
    rng = np.random.default_rng(seed)
    builder = SceneBuilder(name="pile")
    builder.set_integration(method="symplectic_euler", dt=DT, duration=duration,
                            record_every=RECORD_EVERY)  # fmt: skip
    half = bin_half_width(columns)
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=RESTITUTION,
                         friction=FRICTION)  # fmt: skip
    for axis in (0, 2):
        for side in (-1.0, 1.0):
            point = [0.0, 0.0, 0.0]
            normal = [0.0, 0.0, 0.0]
            point[axis], normal[axis] = side * half, -side
            builder.add_collider("plane", point=tuple(point), normal=tuple(normal),
                                 restitution=RESTITUTION, friction=FRICTION)  # fmt: skip
    vertices, triangles = rock(rng)
    kinds = []
    offset = 0.5 * (columns - 1) * PITCH
    for j in range(layers):
        for i in range(columns):
            for k in range(columns):
                kind = SHAPES[int(rng.integers(len(SHAPES)))]
                position = np.array([i * PITCH - offset, LOWEST + j * PITCH, k * PITCH - offset])
                position += rng.uniform(-0.01, 0.01, 3)
                q = rng.normal(size=4)
                common = {
                    "density": DENSITY,
                    "position": tuple(position),
                    "orientation": tuple(q / np.linalg.norm(q)),
                    "restitution": RESTITUTION,
                    "friction": FRICTION,
                    "color": COLORS[kind],
                    "name": f"{kind} {len(kinds) + 1}",
                }
                if kind == "sphere":
                    builder.add_body("sphere", radius=0.08, **common)
                elif kind == "box":
                    builder.add_body("box", size=(0.16, 0.12, 0.1), **common)
                elif kind == "capsule":
                    builder.add_body("capsule", radius=0.045, height=0.12, **common)
                elif kind == "cylinder":
                    builder.add_body("cylinder", radius=0.07, height=0.12, **common)
                elif kind == "cone":
                    builder.add_body("cone", radius=0.08, height=0.14, **common)
                else:
                    builder.add_body("mesh", vertices=vertices, triangles=triangles,
                                     collision_shape="hull", **common)  # fmt: skip
                kinds.append(kind)
    builder.add_body_contacts()
    return builder, kinds


def run(output: JobOutput, duration: float, columns: int = COLUMNS) -> dict[str, Any]:
    """The pile of ``columns² · LAYERS`` bodies."""
    from matplotlib.figure import Figure

    builder, kinds = scene(columns=columns, duration=duration)
    model = builder.build()
    simulation = Simulation(model)
    recording = simulation.record(until=duration)
    output.recordings["pile"] = recording
    bodies = model.bodies
    t = recording.time
    # Each frame's centres of mass, from the recorded origins and orientations.
    origin, orientation = recording["body_origin"], recording["body_orientation"]
    centre = origin + quaternion_rotate(orientation, bodies.center)
    # The recorded energy is kinetic plus gravity's m g y (the contacts store none).
    potential = -model.gravity[1] * (bodies.mass * centre[:, :, 1]).sum(axis=1)
    kinetic = recording["energy"] - potential
    fastest = np.linalg.norm(np.diff(centre, axis=0), axis=2).max(axis=1) / np.diff(t)
    x = simulation.state["body_position"]
    speed = np.linalg.norm(simulation.bodies().velocity, axis=1)
    half = bin_half_width(columns)
    outside = (x[:, 1] < 0.0) | (np.abs(x[:, 0]) > half) | (np.abs(x[:, 2]) > half)
    found = simulation.body_contacts()

    figure = Figure(figsize=(12, 4.5), layout="constrained")
    left, right = figure.subplots(1, 2)
    left.semilogy(t, np.maximum(kinetic, 1e-9), label="kinetic energy [J]")
    left.semilogy(t[1:], np.maximum(fastest, 1e-9), label="fastest centre of mass [m/s]")
    left.set_xlabel("t [s]")
    legend_below(left)
    left.set_title(f"{len(kinds):,} bodies fall into a bin and come to rest", fontsize=10)
    right.plot(t, centre[:, :, 1].max(axis=1), label="highest centre of mass")
    right.plot(t, centre[:, :, 1].mean(axis=1), label="mean height")
    right.set_xlabel("t [s]")
    right.set_ylabel("[m]")
    legend_below(right)
    right.set_title("The pile forms", fontsize=10)
    output.figures["pile"] = figure
    return {
        "bodies": len(kinds),
        "bodies_of_each_shape": {k: kinds.count(k) for k in SHAPES},
        "contacts_at_end": found.counts(),
        "deepest_overlap_at_end_m": float(max(found.depth.max(initial=0.0), 0.0)),
        "highest_centre_of_mass_at_end_m": float(x[:, 1].max()),
        "fastest_body_at_end_m_per_s": float(speed.max()),
        "kinetic_energy_at_end_J": float(kinetic[-1]),
        "kinetic_energy_at_its_peak_J": float(kinetic.max()),
        "escaped": int(outside.sum()),
    }


def bin_half_width(columns: int) -> float:
    """Half the bin's inner width [m] for a lattice of ``columns`` a side."""
    return 0.5 * columns * PITCH + 0.2


register_demo(
    Demo(
        "pile",
        BUILTIN_DEMOS["pile"].summary,
        2.0,
        run,
        picture=True,
        full=functools.partial(run, columns=FULL_COLUMNS),
    )
)
