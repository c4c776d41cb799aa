"""Demo ``ball-pit``: a few thousand balls dropped into a box, colliding with each other and
with its floor and walls until they settle (particle–particle collisions, issue 13).

``COUNT`` balls of radius ``RADIUS`` start as a loose, jittered block above the box, tumbling
at random, and fall under gravity; every pair of balls that touches collides
(:mod:`visviva.collision.particle_contacts`: restitution, Coulomb friction, overlaps removed)
and the box's five planes join the same solve. The scene is also
``examples/scenes/ball_pit.toml`` (fewer balls).

What the summary checks, with the physics behind each number:

* **No overlap**: the deepest overlap of any two balls, and of a ball and the floor, as a
  fraction of the radius, at the end and over the whole run (the issue asks for < 1 %).
* **Momentum**: every impulse between two balls is equal and opposite, so the balls' total
  momentum changes only by gravity and the box: while no ball touches the box yet (the first
  frames), ``P(t) = P(0) + M g t`` to round-off.
* **Support**: once the pile is at rest, the box carries its weight: the vertical impulses of
  the floor and the walls in one step add up to ``M g h`` (the walls' share, by friction, is
  Janssen's effect in a silo; the floor's normal impulses carry the rest).
* **Settling**: the kinetic energy against time (the figure) falls from the fall's to nearly
  nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..collision import ParticleContacts
from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..simulation.simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

DURATION = 1.6  # [s]
DT = 2e-3  # [s]
RECORD_EVERY = 10  # 50 frames per second
GRAVITY = 9.81  # [m/s²]
COUNT = 2000
RADIUS = 0.025  # [m]
BALL_MASS = 0.02  # [kg]: a hollow plastic ball
BOX = 0.8  # inner width of the box [m] (square floor)
SPACING = 2.3  # lattice spacing of the start block, in radii
JITTER = 0.1  # random offset of each start position, in radii
TUMBLE = 0.3  # standard deviation of each start velocity component [m/s]
RESTITUTION = 0.4
FRICTION = 0.3
ITERATIONS = 20
#: Five colours, one per particle entity.
COLORS = [(0.93, 0.26, 0.21), (0.99, 0.76, 0.05), (0.20, 0.66, 0.33), (0.13, 0.47, 0.85),
          (0.62, 0.32, 0.76)]  # fmt: skip
DESCRIPTION = (
    "a few thousand balls dropped into a box: collisions between balls and with the box, "
    "settling into a pile"
)


def start_positions(count: int, radius: float, box: float, seed: int = 1) -> np.ndarray:
    """``(count, 3)`` start centres [m]: a jittered square lattice three radii clear of the
    box's walls, layer above layer from two diameters up."""
    rng = np.random.default_rng(seed)
    spacing = SPACING * radius
    side = int((box - 6.0 * radius) / spacing) + 1
    layers = -(-count // (side * side))
    axis = (np.arange(side) - (side - 1) / 2.0) * spacing
    x, y, z = np.meshgrid(axis, 4.0 * radius + np.arange(layers) * spacing, axis, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    points = points[np.lexsort((points[:, 2], points[:, 0], points[:, 1]))][:count]
    return points + rng.uniform(-JITTER, JITTER, points.shape) * radius


def build_scene(
    count: int = COUNT,
    radius: float = RADIUS,
    box: float = BOX,
    duration: float = DURATION,
    iterations: int = ITERATIONS,
) -> SceneBuilder:
    """The ball pit as a scene: the balls in five coloured entities, the box's floor and four
    walls, and the balls' collisions."""
    rng = np.random.default_rng(2)
    builder = SceneBuilder(name="ball-pit", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(
        method="symplectic_euler", dt=DT, duration=duration, record_every=RECORD_EVERY
    )
    points = start_positions(count, radius, box)
    velocities = rng.normal(0.0, TUMBLE, points.shape)
    for k, color in enumerate(COLORS):
        if points[k :: len(COLORS)].shape[0]:
            builder.add_particles(
                points[k :: len(COLORS)].tolist(),
                velocities=velocities[k :: len(COLORS)].tolist(),
                mass=BALL_MASS,
                radius=radius,
                color=color,
                name=f"balls{k}",
            )
    e, mu = RESTITUTION, FRICTION
    builder.add_collider(
        "plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=e, friction=mu, name="floor"
    )
    for axis, side in ((0, 1.0), (0, -1.0), (2, 1.0), (2, -1.0)):
        point, normal = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        point[axis], normal[axis] = -side * box / 2.0, side
        builder.add_collider("plane", point=point, normal=normal, restitution=e, friction=mu)
    builder.add_particle_collisions(
        restitution=e, friction=mu, iterations=iterations, name="balls collide"
    )
    return builder


def contact_stage(simulation: Simulation) -> ParticleContacts:
    """The simulation's particle–particle contact stage."""
    return next(s for s in simulation.model.stages if isinstance(s, ParticleContacts))


def pit_measures(simulation: Simulation) -> dict[str, float]:
    """The deepest ball–ball and ball–floor overlaps of the current state [in radii] and the
    floor's share of the pile's weight in the last step (1 at rest)."""
    state = simulation.state
    stage = contact_stage(simulation)
    radius = state["particle_radius"]
    contacts = stage.pair_contacts(state)
    pairs = float(contacts.depth.max() / radius.max()) if len(contacts) else 0.0
    floor = float(np.max(radius - state["particle_position"][:, 1]) / radius.max())
    last = stage.solved(simulation.system.workspace)
    if last is None:
        raise ValueError("the simulation has not taken a step yet")
    box = last.second < 0
    on_floor = box & (last.collider == 0)
    weight = float(np.sum(simulation.model.particle_mass)) * GRAVITY * simulation.dt
    # Vertical impulse of the box on the balls in the last step: normal and friction parts.
    lift = last.normal_impulse[box] * last.ny[box] + last.tangent_impulse[box, 1]
    return {
        "ball_overlap_over_radius": max(pairs, 0.0),
        "floor_overlap_over_radius": max(floor, 0.0),
        "floor_normal_impulse_over_weight": float(last.normal_impulse[on_floor].sum() / weight),
        "box_vertical_impulse_over_weight": float(lift.sum() / weight),
        "contacts": float(last.first.shape[0]),
    }


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    model = build_scene(duration=duration).build()
    simulation = Simulation(model)
    mass = np.asarray(model.particle_mass)
    recording = simulation.record(until=duration)
    output.recordings["symplectic_euler"] = recording
    t = recording.time
    v = recording["particle_velocity"]
    x = recording["particle_position"]
    kinetic = 0.5 * np.einsum("i,fij,fij->f", mass, v, v)
    # While every ball is clear of the box (two radii from each plane), only gravity changes
    # the balls' momentum: by M g t, to round-off.
    clear = np.minimum(x[..., 1], BOX / 2.0 - np.abs(x[..., [0, 2]]).max(axis=-1)).min(axis=1)
    falling = np.cumprod(clear > 2.0 * RADIUS).astype(bool)
    momentum = np.einsum("i,fij->fj", mass, v)
    expected = momentum[0] + np.outer(t, [0.0, -GRAVITY * mass.sum(), 0.0])
    drift = float(np.abs(momentum[falling] - expected[falling]).max(initial=0.0))
    scale = float(mass.sum() * (GRAVITY * t[falling].max() + TUMBLE)) if falling.any() else 0.0
    deepest_floor = max(0.0, float((RADIUS - x[..., 1]).max() / RADIUS))
    end = pit_measures(simulation)

    figure = Figure(figsize=(12, 4.8), layout="constrained")
    energy, side = figure.subplots(1, 2)
    energy.semilogy(t, np.maximum(kinetic, 1e-12), label="kinetic energy of the balls")
    energy.set_xlabel("t [s]")
    energy.set_ylabel("kinetic energy [J]")
    energy.set_title(f"{mass.shape[0]} balls settling")
    legend_below(energy)
    # The cut through the middle of the box (the plane z = 0): each ball it crosses is a disc
    # of radius √(r² − z²); two discs overlap only where their balls do.
    from matplotlib.collections import EllipseCollection

    last = x[-1]
    cut = np.abs(last[:, 2]) < RADIUS
    widths = 2.0 * np.sqrt(RADIUS**2 - last[cut, 2] ** 2)
    colors = (
        np.asarray(recording.static["particle_color"])[cut]
        if "particle_color" in recording.static
        else None
    )
    side.add_collection(
        EllipseCollection(
            widths, widths, 0.0, units="xy", offsets=last[cut][:, :2],
            offset_transform=side.transData, facecolors=colors, edgecolors="0.2",
            linewidths=0.3,
        )
    )  # fmt: skip
    side.plot([-BOX / 2, -BOX / 2, BOX / 2, BOX / 2], [0.9, 0.0, 0.0, 0.9], color="k")
    side.set_xlim(-0.55 * BOX, 0.55 * BOX)
    side.set_ylim(-0.02, max(0.9, float(last[:, 1].max()) + 2.0 * RADIUS))
    side.set_aspect("equal")
    side.set_xlabel("x [m]")
    side.set_ylabel("height y [m]")
    side.set_title(f"Cut through the middle of the box, t = {t[-1]:.2f} s")
    output.figures["ball_pit"] = figure

    return {
        "balls": int(mass.shape[0]),
        "radius_m": RADIUS,
        "overlap_at_end_over_radius": {
            "ball_ball": end["ball_overlap_over_radius"],
            "ball_floor": end["floor_overlap_over_radius"],
        },
        "deepest_floor_overlap_recorded_over_radius": deepest_floor,
        "momentum_in_free_fall": {
            "largest_error_kg_m_per_s": drift,
            "relative": drift / scale if scale > 0.0 else 0.0,
            "frames": int(falling.sum()),
        },
        "support_at_end": {
            "floor_normal_impulse_over_weight": end["floor_normal_impulse_over_weight"],
            "box_vertical_impulse_over_weight": end["box_vertical_impulse_over_weight"],
        },
        "kinetic_energy_J": {
            "start": float(kinetic[0]),
            "peak": float(kinetic.max()),
            "end": float(kinetic[-1]),
        },
        "contacts_at_end": int(end["contacts"]),
    }


register_demo(
    Demo(
        "ball-pit",
        BUILTIN_DEMOS["ball-pit"].summary,
        DURATION,
        run,
        picture=True,
    )
)
