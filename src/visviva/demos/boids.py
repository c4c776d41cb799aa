"""Demo ``boids``: 10,000 birds, starting with random headings, form a flock that flows around
an obstacle on its way to a goal (Reynolds' boids, :mod:`visviva.particles.boids`).

The birds start in a box, each with a random velocity (so the flock's polarisation
``Φ = |Σ v/|v|| / N`` starts near ``1/√N``); they see flockmates within ``RADIUS`` in a field of
view of ``FOV_DEG`` degrees, keep ``SEPARATION`` apart, align and cohere, and seek a ``GOAL`` behind
a sphere, which they avoid from their look-ahead distance (2V²/A) on (and which, as an impulse
collider, would also bounce a bird that touched it). World gravity is off: the birds' lift is
not modelled. The same scene, with fewer birds, ships as ``examples/scenes/boids.toml``.

Summary: Φ over time (it rises to above 0.9 as the flock forms), the nearest-neighbour
distance (against the separation distance), the closest approach to the obstacle's surface and
how many birds got past it. Figure ``boids.png``: Φ against time, and the flock seen from above.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..particles.boids import polarisation
from ..simulation.simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

BIRDS = 10_000
DURATION = 20.0  # [s]
DT = 0.05  # [s]
RECORD_EVERY = 4  # 5 frames per second of simulated time
START = (-30.0, 12.0, 0.0)  # centre of the box the birds start in [m]
BOX = (24.0, 8.0, 24.0)  # its edges [m]: about 12 flockmates within RADIUS at the start
SPEED_JITTER = 3.0  # standard deviation of each starting velocity component [m/s]
RADIUS = 2.5  # [m]
SEPARATION = 1.0  # [m]
FOV_DEG = 270.0  # [degrees]
MAX_SPEED = 6.0  # [m/s]
MIN_SPEED = 2.0  # [m/s]
MAX_ACCELERATION = 12.0  # [m/s²]: look-ahead 2V²/A = 6 m
SEPARATION_WEIGHT, ALIGNMENT_WEIGHT, COHESION_WEIGHT = 8.0, 2.0, 1.0  # [1/s]
GOAL = (45.0, 12.0, 0.0)  # [m]
GOAL_WEIGHT = 0.6  # [1/s]
OBSTACLE = (0.0, 12.0, 0.0)  # centre [m]
OBSTACLE_RADIUS = 6.0  # [m]
DESCRIPTION = (
    "10,000 birds with random headings form a flock that flows around a sphere on its way to "
    "a goal (Reynolds' boids)"
)


def build_scene(birds: int = BIRDS, duration: float = DURATION) -> SceneBuilder:
    """The flock as a scene (``examples/scenes/boids.toml`` holds a smaller one)."""
    builder = SceneBuilder(name="boids", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.set_integration(
        method="symplectic_euler", dt=DT, duration=duration, record_every=RECORD_EVERY
    )
    builder.add_particle_cloud(
        name="birds",
        count=birds,
        center=START,
        size=BOX,
        velocity_jitter=SPEED_JITTER,
        radius=0.15,
        color=(0.15, 0.15, 0.2),
        seed=13,
    )
    builder.add_collider(
        "sphere", center=OBSTACLE, radius=OBSTACLE_RADIUS, restitution=0.2, name="obstacle"
    )
    builder.add_boids(
        ["birds"],
        radius=RADIUS,
        separation=SEPARATION,
        fov_deg=FOV_DEG,
        max_speed=MAX_SPEED,
        min_speed=MIN_SPEED,
        max_acceleration=MAX_ACCELERATION,
        goal=GOAL,
        goal_weight=GOAL_WEIGHT,
        separation_weight=SEPARATION_WEIGHT,
        alignment_weight=ALIGNMENT_WEIGHT,
        cohesion_weight=COHESION_WEIGHT,
        name="flock",
    )
    return builder


def nearest_distances(points: np.ndarray) -> np.ndarray:
    """Each point's distance to its nearest other point [m] (SciPy's k-d tree)."""
    from scipy.spatial import cKDTree

    return cKDTree(points).query(points, k=2)[0][:, 1]


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    simulation = Simulation(build_scene(duration=duration).build())
    recording = simulation.record(until=duration)
    output.recordings["symplectic_euler"] = recording
    t, x, v = recording.time, recording["particle_position"], recording["particle_velocity"]
    phi = np.array([polarisation(frame) for frame in v])
    gap = np.linalg.norm(x - np.asarray(OBSTACLE), axis=2) - OBSTACLE_RADIUS
    nearest = nearest_distances(x[-1])
    formed = np.flatnonzero(phi > 0.9)

    figure = Figure(figsize=(12, 4.8), layout="constrained")
    left, right = figure.subplots(1, 2)
    left.plot(t, phi, label="polarisation Φ = |Σ v/|v|| / N")
    left.axhline(1.0 / np.sqrt(BIRDS), color="0.5", linestyle=":", label="1/√N (random headings)")
    left.axhline(0.9, color="C3", linestyle="--", linewidth=0.8, label="0.9")
    left.set_ylim(0.0, 1.02)
    left.set_xlabel("t [s]")
    left.set_ylabel("Φ")
    left.set_title(f"{BIRDS:,} birds line up")
    legend_below(left)
    for k, shade in ((0, "0.75"), (len(t) // 2, "C1"), (len(t) - 1, "C0")):
        right.scatter(x[k, :, 0], x[k, :, 2], s=0.2, color=shade, label=f"t = {t[k]:.0f} s")
    circle = np.linspace(0.0, 2.0 * np.pi, 200)
    right.fill(
        OBSTACLE[0] + OBSTACLE_RADIUS * np.cos(circle),
        OBSTACLE[2] + OBSTACLE_RADIUS * np.sin(circle),
        color="0.3",
        label="obstacle",
    )
    right.plot(GOAL[0], GOAL[2], "k*", markersize=12, label="goal")
    right.set_aspect("equal")
    right.set_xlabel("x [m]")
    right.set_ylabel("z [m]")
    right.set_title("Seen from above")
    legend = legend_below(right)
    for handle in legend.legend_handles[:3]:  # the three frames' dots, enlarged
        handle.set_sizes([12.0])
    output.figures["boids"] = figure

    return {
        "birds": BIRDS,
        "polarisation": {
            "start": float(phi[0]),
            "end": float(phi[-1]),
            "max": float(phi.max()),
            "first_above_0.9_s": float(t[formed[0]]) if formed.size else None,
            "random_headings_1_over_sqrt_n": 1.0 / np.sqrt(BIRDS),
        },
        "nearest_neighbour_m": {
            "separation": SEPARATION,
            "min": float(nearest.min()),
            "median": float(np.median(nearest)),
        },
        "closest_to_obstacle_surface_m": float(gap.min()),
        "past_the_obstacle": float((x[-1, :, 0] > OBSTACLE[0] + OBSTACLE_RADIUS).mean()),
        "speed_m_s": {"min": float(np.linalg.norm(v[-1], axis=1).min()), "max_speed": MAX_SPEED},
    }


register_demo(
    Demo(
        "boids",
        BUILTIN_DEMOS["boids"].summary,
        DURATION,
        run,
        picture=True,
        speed=2.0,
        color_by="speed",
    )
)
