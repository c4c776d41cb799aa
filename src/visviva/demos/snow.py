"""Demo ``snow``: flakes drift down in the wind and a gust, and settle on a ball and the ground.

Flakes are born in a thin box high above the ground for ``SNOWFALL`` seconds and fall at their
terminal speed ``√(mg/c)`` under quadratic drag ``F = −c|v − w|(v − w)`` in a steady wind
``w``; a vortex about a horizontal axis (air turning at ``Γ/(2πr)``, drawing the flakes along
with ``F = k(u − v)``) rolls them over like a gust. They land on a ball and on the ground, both
colliders with no bounce (restitution 0), high friction and time of impact, and stay there. The
same scene ships as ``examples/scenes/snow.toml``.

Where a flake can rest on the ball follows from Coulomb friction: the force on it at rest
(its weight, the wind's push ``c|w|w`` and the gust's ``k u``) must press it into the surface
at least ``1/μ`` times as hard as it pulls it along. In still air that is the slope ``α`` from
the top with ``tan α ≤ μ``: the ball keeps a cap of snow of half-angle ``atan μ`` and sheds the
rest; the wind widens the cap on its windward side and narrows it on the lee
(:func:`cap_in_the_wind`). The summary counts the flakes resting on the ball and on the ground
and those still moving, gives the cap's half-angle on each side against the wind's prediction,
the largest ratio of pull to push among the flakes held on the ball (at most ``μ``), and the
deepest penetration of a flake into a collider over the run.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..model.model import Model
from ..simulation.simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DURATION = 6.5  # [s]: the last flakes land about 3.5 s after the snowfall stops
DT = 0.005  # [s]
RECORD_EVERY = 6  # 33 frames per second
GRAVITY = 9.81  # [m/s²]
SNOWFALL = 3.0  # [s] of snowfall
RATE = 1200.0  # flakes per second [1/s]
CLOUD_CENTER = (-1.8, 4.0, 0.0)  # [m]: upwind of the ball, so the wind carries flakes over it
CLOUD_SIZE = (4.0, 0.2, 4.0)  # [m]
FLAKE_RADIUS = (0.025, 0.04)  # [m]
FLAKE_MASS = 1e-4  # [kg]
FLAKE_LIFETIME = 1000.0  # [s]: longer than any run, so no flake melts away
DRAG = 6.8e-4  # c [kg/m]: terminal speed √(mg/c) = 1.2 m/s
WIND = (0.5, 0.0, 0.15)  # [m/s]
GUST_CENTER = (-1.0, 2.8, 0.0)  # [m], a point on the vortex's axis
GUST_AXIS = (0.0, 0.0, 1.0)
GUST_CIRCULATION = 5.0  # Γ [m²/s]: 1 m/s at the edge of its core
GUST_CORE = 0.8  # [m]
GUST_COUPLING = 1e-4  # k [N·s/m]: the flakes take up the gust's air within m/k = 1 s
BALL_CENTER = (0.0, 1.0, 0.0)  # [m]: resting on the ground
BALL_RADIUS = 1.0  # [m]
FRICTION = 1.0  # μ on both colliders: a cap of about 45°
#: A flake slower than this counts as at rest [m/s].
REST_SPEED = 0.01
#: Flakes whose direction from the ball's axis is within 30° of the wind's count as on its
#: windward or leeward side.
SIDE_COSINE = math.cos(math.radians(30.0))
#: A flake this close to a surface (beyond touching it) counts as lying on it [m].
CONTACT_GAP = 1e-3
DESCRIPTION = (
    "3600 snowflakes fall in the wind and a rolling gust and settle on a ball and the ground "
    "(quadratic drag, vortex, colliders without bounce and with high friction)"
)


def build_scene(duration: float = DURATION) -> SceneBuilder:
    """The snowfall as a scene (``examples/scenes/snow.toml`` holds the same one)."""
    builder = SceneBuilder(name="snow", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(
        method="symplectic_euler", dt=DT, duration=duration, record_every=RECORD_EVERY
    )
    builder.add_emitter(
        name="flakes",
        rate=RATE,
        stop=SNOWFALL,
        shape="box",
        position=CLOUD_CENTER,
        extent=CLOUD_SIZE,
        direction=(0.0, -1.0, 0.0),
        spread_deg=30.0,
        speed=(0.0, 0.4),
        lifetime=FLAKE_LIFETIME,
        particle_radius=FLAKE_RADIUS,
        particle_mass=FLAKE_MASS,
        color=(0.96, 0.97, 1.0),
        seed=3,
    )
    builder.add_force("quadratic_drag", coefficient=DRAG, velocity=WIND, name="wind")
    builder.add_force(
        "vortex",
        point=GUST_CENTER,
        axis=GUST_AXIS,
        circulation=GUST_CIRCULATION,
        coefficient=GUST_COUPLING,
        core_radius=GUST_CORE,
        name="gust",
    )
    builder.add_collider(
        "sphere",
        center=BALL_CENTER,
        radius=BALL_RADIUS,
        restitution=0.0,
        friction=FRICTION,
        time_of_impact=True,
        name="ball",
    )
    builder.add_collider(
        "plane",
        point=(0.0, 0.0, 0.0),
        normal=(0.0, 1.0, 0.0),
        restitution=0.0,
        friction=FRICTION,
        time_of_impact=True,
        name="ground",
    )
    return builder


def gaps(points: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each flake's clearance [m] from the ball and from the ground: the distance from its
    centre to the surface less its radius (negative: it is inside)."""
    ball = np.linalg.norm(points - np.asarray(BALL_CENTER), axis=-1) - BALL_RADIUS - radius
    return ball, points[..., 1] - radius


def friction_ratio(model: Model, t: float, points: np.ndarray, on_ball: np.ndarray) -> np.ndarray:
    """For the flakes ``on_ball`` (a mask over every slot of ``points``, ``(N, 3)`` [m]), at
    rest on the ball: the force along the surface over the force pressing them into it, from
    the model's own forces at zero velocity (Coulomb friction holds a flake where this is at
    most μ)."""
    push = np.zeros_like(points)
    for force in model.forces:
        force.accumulate(t, points, np.zeros_like(points), push)
    push = push[on_ball]
    normal = points[on_ball] - np.asarray(BALL_CENTER)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    pressing = -np.einsum("ij,ij->i", push, normal)
    along = np.linalg.norm(push + pressing[:, None] * normal, axis=1)
    return np.divide(along, pressing, out=np.full(along.shape, np.inf), where=pressing > 0.0)


def cap_in_the_wind() -> tuple[float, float]:
    """Half-angles [degrees] of the snow cap on the ball's windward and leeward sides in the
    wind alone (the gust neglected).

    A flake at rest feels its weight and the wind's push ``f = c|w|²/m`` per mass along the
    wind; in the vertical plane of the wind, Coulomb friction holds it at slope ``α`` from the
    top while ``tan α ≤ (μ + f/g)/(1 − μ f/g)`` facing the wind and ``(μ − f/g)/(1 + μ f/g)``
    away from it.
    """
    push = DRAG * (WIND[0] ** 2 + WIND[1] ** 2 + WIND[2] ** 2) / FLAKE_MASS / GRAVITY
    windward = math.atan2(FRICTION + push, 1.0 - FRICTION * push)
    leeward = math.atan2(FRICTION - push, 1.0 + FRICTION * push)
    return math.degrees(windward), math.degrees(leeward)


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    model = build_scene(duration).build()
    simulation = Simulation(model)
    recording = simulation.record(until=duration)
    output.recordings["symplectic_euler"] = recording
    t, alive = recording.time, recording["particle_alive"]
    points, radius = recording["particle_position"], recording["particle_radius"]
    speed = np.linalg.norm(recording["particle_velocity"], axis=-1)
    resting = alive & (speed < REST_SPEED)
    born = alive.sum(axis=1)
    fraction = np.divide(resting.sum(axis=1), born, out=np.zeros(t.shape), where=born > 0)
    ball_gap, ground_gap = gaps(points, radius)
    depth = np.maximum(-ball_gap, -ground_gap) / radius
    on_ground = resting[-1] & (ground_gap[-1] < CONTACT_GAP)
    on_ball = resting[-1] & (ball_gap[-1] < CONTACT_GAP) & ~on_ground
    moving = alive[-1] & ~resting[-1]
    # Held by static friction: the contact took all of the step's velocity, to the last bit.
    held = on_ball & (speed[-1] == 0.0)
    ratio = friction_ratio(model, float(t[-1]), points[-1], held)
    offset = points[-1][on_ball] - np.asarray(BALL_CENTER)
    slope = np.degrees(np.arccos(np.clip(offset[:, 1] / np.linalg.norm(offset, axis=1), -1, 1)))
    # The sides of the ball facing into the wind and away from it, within 30° of its direction.
    across = offset[:, [0, 2]]
    wind = np.array([WIND[0], WIND[2]]) / math.hypot(WIND[0], WIND[2])
    along = across @ wind / np.maximum(np.linalg.norm(across, axis=1), 1e-300)
    windward, leeward = along < -SIDE_COSINE, along > SIDE_COSINE
    output.figures["snow"] = _figure(t, fraction, points[-1], on_ball, on_ground, moving)

    state = simulation.state
    return {
        "flakes_born": int(state["emitter_serial"].sum()),
        "flakes_dropped": int(state["emitter_dropped"].sum()),
        "resting_on_ball": int(on_ball.sum()),
        "resting_on_ground": int(on_ground.sum()),
        "still_moving": int(moving.sum()),
        "fraction_at_rest_at_end": float(fraction[-1]),
        "snow_cap_half_angle_deg": {
            "windward": float(slope[windward].max(initial=0.0)),
            "leeward": float(slope[leeward].max(initial=0.0)),
            "windward_in_the_wind_alone": cap_in_the_wind()[0],
            "leeward_in_the_wind_alone": cap_in_the_wind()[1],
            "still_air_atan_mu": math.degrees(math.atan(FRICTION)),
        },
        "max_pull_over_push_held_on_ball": float(ratio.max(initial=0.0)),
        "max_penetration_over_radius": float(depth[alive].max()) if alive.any() else None,
    }


def _figure(
    t: np.ndarray,
    fraction: np.ndarray,
    points: np.ndarray,
    on_ball: np.ndarray,
    on_ground: np.ndarray,
    moving: np.ndarray,
) -> Figure:
    """The fraction at rest over time, and a side view of where the flakes are at the end."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    figure = Figure(figsize=(12, 4.8), layout="constrained")
    settling, side = figure.subplots(1, 2)
    settling.plot(t, fraction, label=f"at rest (speed < {REST_SPEED} m/s)")
    settling.axvline(SNOWFALL, color="0.5", linestyle=":", label="snowfall stops")
    settling.set_xlabel("t [s]")
    settling.set_ylabel("fraction of the flakes born so far")
    settling.set_ylim(0.0, 1.02)
    settling.set_title("Settling")
    legend_below(settling)
    side.add_patch(Circle(BALL_CENTER[:2], BALL_RADIUS, color="0.85", zorder=0))
    side.axhline(0.0, color="0.4")
    for chosen, color, label in (
        (on_ball, "C0", "resting on the ball"),
        (on_ground, "C2", "resting on the ground"),
        (moving, "C3", "still moving"),
    ):
        xy = points[chosen]
        side.scatter(xy[:, 0], xy[:, 1], s=1.0, color=color, label=f"{label}: {chosen.sum()}")
    reach = 1.3 * BALL_RADIUS
    angle = math.atan(FRICTION)
    for sign in (-1.0, 1.0):
        side.plot(
            [BALL_CENTER[0], BALL_CENTER[0] + sign * reach * math.sin(angle)],
            [BALL_CENTER[1], BALL_CENTER[1] + reach * math.cos(angle)],
            color="k",
            linestyle=":",
            linewidth=0.8,
        )
    side.set_aspect("equal")
    side.set_xlabel("x [m] (wind towards +x)")
    side.set_ylabel("height y [m]")
    side.set_title(f"Side view at t = {t[-1]:.1f} s (dotted: tan α = μ, still air)")
    legend_below(side, markerscale=5)
    return figure


register_demo(
    Demo(
        "snow",
        BUILTIN_DEMOS["snow"].summary,
        DURATION,
        run,
        picture=True,
    )
)
