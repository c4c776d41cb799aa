"""Demo ``crowd``: a room of 200 people evacuating through one door (the social-force model).

A square room of walls (thin boxes 1.2 m high, the scene's colliders, which the video and the
viewer draw: the camera sees the agents over them) with a door in its right wall; the
agents start at rest, scattered over the room without touching, and walk to an exit box just
outside the door with the social-force model of Helbing & Molnár (1995) and the parameters of
Helbing, Farkas & Vicsek (2000) (:mod:`visviva.particles.crowd`): preferred speed 1.34 m/s,
relaxation time 0.5 s, repulsion 2000 N of range 0.08 m, body force 1.2·10⁵ kg/s², sliding
friction 2.4·10⁵ kg/(m·s), masses 80 kg, radii 0.25–0.35 m. The same scene, smaller, ships as
``examples/scenes/crowd.toml``.

Figures: the agents out against time and the flow through the door [agents/s] (exits counted in
5 s windows), and a map of the density [agents/m²] in front of the door averaged over the
evacuation (the bottleneck: a dense arc forms before the door); then the same room, with fewer
agents, for four door widths: the agents out against time and the mean flow of the bulk of each
evacuation against the width (it grows with the width).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..analysis.crowds import exit_flow, exited, mean_flow
from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..simulation.simulation import Simulation
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

DURATION = 150.0  # [s]: longer than the evacuation (about 126 s)
DT = 0.005  # [s]: well below tau = 0.5 s and 2/sqrt(2k/m) = 37 ms
RECORD_EVERY = 40  # 5 frames per second
AGENTS = 200
ROOM = 14.0  # [m]: side of the square room (inside)
DOOR = 1.2  # [m]: width of the door
WALL = 0.2  # [m]: wall thickness
HEIGHT = 1.0  # [m]: agents' height (their centres')
#: [m]: walls span y = 0 to 1.2 m: above the agents' centres, so the model (discs in the XZ
#: plane at y = 1 m) sees the same walls, and low enough that the camera sees over them.
WALL_HEIGHT = 1.2
RADIUS = (0.25, 0.35)  # [m]
MASS = 80.0  # [kg]
#: The door-width study: a smaller room, the same people.
WIDTHS = (1.0, 1.4, 1.8, 2.2)  # [m]: narrower doors of this room can jam for good
STUDY_AGENTS = 60
STUDY_ROOM = 8.0  # [m]
#: Exits are counted in windows of this length [s] for the flow rate.
WINDOW = 5.0
#: The density map: cells of this size [m] over the area in front of the door.
CELL = 0.5
DESCRIPTION = "a room of people evacuating through a door (social-force model)"


def room(
    builder: SceneBuilder,
    *,
    agents: int,
    side: float,
    door: float,
    seed: int = 0,
    preferred_speed: float = 1.34,
) -> np.ndarray:
    """Add a square room (inside ``0 ≤ x ≤ side``, ``|z| ≤ side/2``) with a door of width
    ``door`` [m] in its wall at ``x = side``, ``agents`` people at rest placed at random
    without overlap, and their crowd walking to an exit box outside the door. Returns the
    agents' positions ``(agents, 3)`` [m]."""
    half, t = 0.5 * side, WALL
    y, tall = 0.5 * WALL_HEIGHT, WALL_HEIGHT
    boxes = {
        "back": ((-0.5 * t, y, 0.0), (t, tall, side + 2 * t)),
        "left": ((0.5 * side, y, -half - 0.5 * t), (side + 2 * t, tall, t)),
        "right": ((0.5 * side, y, half + 0.5 * t), (side + 2 * t, tall, t)),
    }
    jamb = half + t - 0.5 * door  # length of the front wall on either side of the door
    for name, sign in (("front_left", -1.0), ("front_right", 1.0)):
        z = sign * (0.5 * door + 0.5 * jamb)
        boxes[name] = ((side + 0.5 * t, y, z), (t, tall, jamb))
    for name, (centre, size) in boxes.items():
        builder.add_collider("box", center=centre, size=size, name=name)
    rng = np.random.default_rng(seed)
    radius = rng.uniform(*RADIUS, agents)
    points = _scatter(rng, radius, side)
    builder.add_particles(
        name="people",
        positions=points,
        mass=MASS,
        radius=radius.tolist(),
        color=(0.95, 0.75, 0.3),
    )
    exit_box = {"center": (side + t + 1.0, HEIGHT, 0.0), "size": (1.2, 2.0, door + 3.0)}
    builder.add_crowd(
        ["people"], exits=[exit_box], preferred_speed=preferred_speed, name="evacuation"
    )
    return points


def _scatter(rng: np.random.Generator, radius: np.ndarray, side: float) -> np.ndarray:
    """Non-overlapping places in the room, a margin of 0.1 m from the walls and each other."""
    placed: list[np.ndarray] = []
    for r in radius:
        for _ in range(10_000):
            p = np.array(
                [rng.uniform(r + 0.1, side - r - 0.1), rng.uniform(-1, 1) * (0.5 * side - r - 0.1)]
            )
            if all(np.hypot(*(p - q[:2])) > r + q[2] + 0.1 for q in placed):
                placed.append(np.array([p[0], p[1], r]))
                break
        else:
            raise ValueError(f"no room for {radius.shape[0]} agents in a {side} m room")
    return np.array([[x, HEIGHT, z] for x, z, _ in placed])


def build_scene(
    duration: float = DURATION,
    *,
    agents: int = AGENTS,
    side: float = ROOM,
    door: float = DOOR,
    seed: int = 0,
) -> SceneBuilder:
    """The evacuation as a scene."""
    builder = SceneBuilder(name="crowd", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -9.81, 0.0))
    builder.set_integration(dt=DT, duration=duration, record_every=RECORD_EVERY)
    room(builder, agents=agents, side=side, door=door, seed=seed)
    return builder


def evacuate(simulation: Simulation, until: float, chunk: float = 5.0) -> None:
    """Run ``simulation`` until everyone has left or ``until`` [s]."""
    while simulation.time < until and simulation.raw_state["particle_alive"].any():
        simulation.run(min(until, simulation.time + chunk))


def density_map(points: np.ndarray, alive: np.ndarray, side: float) -> tuple[np.ndarray, ...]:
    """Agents per m² in cells of ``CELL`` in front of the door, averaged over the frames in
    which anyone is inside: ``(density (X, Z), x edges, z edges)``."""
    x_edges = np.arange(side - 5.0, side + 2.0 + 1e-9, CELL)
    z_edges = np.arange(-3.5, 3.5 + 1e-9, CELL)
    busy = alive.any(axis=1)
    total = np.zeros((x_edges.shape[0] - 1, z_edges.shape[0] - 1))
    for frame, live in zip(points[busy], alive[busy], strict=True):
        counts, _, _ = np.histogram2d(frame[live, 0], frame[live, 2], bins=(x_edges, z_edges))
        total += counts
    return total / max(1, int(busy.sum())) / CELL**2, x_edges, z_edges


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    simulation = Simulation(build_scene(duration).build())
    recording = simulation.record(until=duration)
    output.recordings["symplectic_euler"] = recording
    times = simulation.raw_state["crowd_exit_time"]
    t = recording.time
    centres, flow = exit_flow(times, WINDOW)
    density, x_edges, z_edges = density_map(
        recording["particle_position"], recording["particle_alive"], ROOM
    )

    figure = Figure(figsize=(13, 4.6), layout="constrained")
    out, rate, heat = figure.subplots(1, 3)
    out.plot(t, exited(times, t), color="C0")
    out.set_xlabel("t [s]")
    out.set_ylabel("agents out")
    out.set_title(f"{AGENTS} agents, door {DOOR} m wide")
    rate.step(centres, flow, where="mid", color="C1")
    bulk = mean_flow(times)
    rate.axhline(bulk, color="k", linestyle=":", label=f"bulk mean {bulk:.2f} agents/s")
    rate.set_xlabel("t [s]")
    rate.set_ylabel("flow through the door [agents/s]")
    rate.set_title(f"Flow rate ({WINDOW:g} s windows)")
    legend_below(rate)
    image = heat.pcolormesh(x_edges, z_edges, density.T, cmap="magma", shading="flat")
    heat.plot([ROOM, ROOM], [-3.5, -0.5 * DOOR], color="w", linewidth=3)
    heat.plot([ROOM, ROOM], [0.5 * DOOR, 3.5], color="w", linewidth=3)
    heat.set_aspect("equal")
    heat.set_xlabel("x [m]")
    heat.set_ylabel("z [m]")
    heat.set_title("Mean density before the door")
    figure.colorbar(image, ax=heat, label="agents per m²")
    output.figures["crowd"] = figure

    study: dict[str, Any] = {}
    widths = Figure(figsize=(10, 4.2), layout="constrained")
    curves, trend = widths.subplots(1, 2)
    for door, color in zip(WIDTHS, distinct_colors(len(WIDTHS)), strict=True):
        builder = build_scene(duration, agents=STUDY_AGENTS, side=STUDY_ROOM, door=door, seed=1)
        run_ = Simulation(builder.build())
        evacuate(run_, duration)
        left = run_.raw_state["crowd_exit_time"]
        grid = np.linspace(0.0, run_.time, 200)
        curves.plot(grid, exited(left, grid), color=color, label=f"{door} m")
        study[f"{door}"] = {
            "mean_flow_agents_per_s": mean_flow(left),
            "all_out_s": float(np.nanmax(left)) if np.isfinite(left).all() else None,
        }
    curves.set_xlabel("t [s]")
    curves.set_ylabel("agents out")
    curves.set_title(f"{STUDY_AGENTS} agents, {STUDY_ROOM} m room")
    legend_below(curves, title="door width")
    flows = [study[f"{w}"]["mean_flow_agents_per_s"] for w in WIDTHS]
    trend.plot(WIDTHS, flows, "o-")
    trend.set_xlabel("door width [m]")
    trend.set_ylabel("mean flow of the bulk [agents/s]")
    trend.set_title("Flow grows with the door's width")
    output.figures["door_widths"] = widths

    out_count = int(np.isfinite(times).sum())
    return {
        "agents": AGENTS,
        "agents_out": out_count,
        "all_out_s": float(np.nanmax(times)) if out_count == AGENTS else None,
        "mean_flow_agents_per_s": bulk,
        "peak_density_agents_per_m2": float(density.max()),
        "door_widths_m": study,
    }


register_demo(
    Demo(
        "crowd",
        BUILTIN_DEMOS["crowd"].summary,
        DURATION,
        run,
        picture=True,
        speed=4.0,
        color_by="speed",
    )
)
