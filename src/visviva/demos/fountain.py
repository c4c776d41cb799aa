"""Demo ``fountain``: a jet of water drops from a nozzle into a basin (seed 002's particles).

A disc emitter at the top of a nozzle shoots ``RATE`` drops per second upward within a cone;
each lives a lifetime drawn uniformly from ``LIFETIME``, turning from white-blue to deep blue and
growing as it falls. Gravity, light linear drag (``F = −k v``) and a basin floor that catches the
drops with little bounce and some friction. The same scene ships as
``examples/scenes/fountain.toml``.

Two numbers are checked against closed forms. With births at a constant rate and lifetimes
uniform in ``[a, b]``, the number of drops alive rises as ``rate·(t − (t − a)²/(2(b − a)))``
between ``a`` and ``b`` and stays at ``rate·(a + b)/2`` after ``b`` (Little's law). Linear drag
acts on each velocity component on its own, so the highest drop is the one launched straight up
at the top speed ``v``, and it rises to ``v/γ − (g/γ²) ln(1 + γv/g)`` with ``γ = k/m``: a few
per cent below the drag-free ``v²/(2g)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..simulation.simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

DURATION = 4.0  # [s]
DT = 0.0025  # [s]: symplectic Euler's apex is low by about v·dt/2 = 8 mm
RECORD_EVERY = 8  # 50 frames per second
GRAVITY = 9.81  # [m/s²]
NOZZLE = (0.0, 0.2, 0.0)  # centre of the nozzle's mouth [m], above the basin floor at y = 0
NOZZLE_RADIUS = 0.04  # [m]
SPREAD_DEG = 9.0  # half-angle of the jet [degrees]
SPEED = (5.6, 6.6)  # [m/s]
RATE = 2400.0  # drops per second [1/s]
LIFETIME = (1.5, 2.1)  # [s]: longer than a flight (~1.4 s), so drops run over the floor a while
DROP_RADIUS = (0.010, 0.016)  # [m]
DROP_MASS = 1e-3  # [kg]
DRAG = 1e-4  # k [N·s/m]: γ = k/m = 0.1 per second
FLOOR_RESTITUTION = 0.15
FLOOR_FRICTION = 0.3
#: White-blue at the nozzle, deep blue by the end of each drop's life: [age fraction, r, g, b].
COLOR_RAMP = [[0.0, 0.92, 0.97, 1.0], [0.4, 0.45, 0.68, 0.95], [1.0, 0.04, 0.14, 0.55]]
#: Drops leave the nozzle small and spread into larger spray: [age fraction, radius factor].
SIZE_RAMP = [[0.0, 0.6], [0.3, 1.0], [1.0, 1.3]]
DESCRIPTION = (
    "a jet of 2400 water drops per second from a nozzle, under gravity and light drag, falling "
    "into a basin"
)


def build_scene(duration: float = DURATION) -> SceneBuilder:
    """The fountain as a scene (``examples/scenes/fountain.toml`` holds the same one)."""
    builder = SceneBuilder(name="fountain", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(
        method="symplectic_euler", dt=DT, duration=duration, record_every=RECORD_EVERY
    )
    builder.add_emitter(
        name="water",
        rate=RATE,
        shape="disc",
        position=NOZZLE,
        radius=NOZZLE_RADIUS,
        normal=(0.0, 1.0, 0.0),
        direction=(0.0, 1.0, 0.0),
        spread_deg=SPREAD_DEG,
        speed=SPEED,
        lifetime=LIFETIME,
        particle_radius=DROP_RADIUS,
        particle_mass=DROP_MASS,
        color_ramp=COLOR_RAMP,
        size_ramp=SIZE_RAMP,
        seed=2,
    )
    builder.add_force("drag", coefficient=DRAG, name="air")
    builder.add_collider(
        "plane",
        point=(0.0, 0.0, 0.0),
        normal=(0.0, 1.0, 0.0),
        restitution=FLOOR_RESTITUTION,
        friction=FLOOR_FRICTION,
        name="basin",
    )
    return builder


def expected_alive(t: np.ndarray) -> np.ndarray:
    """Mean number of drops alive at ``t`` [s] for births at ``RATE`` from 0 and lifetimes
    uniform in ``LIFETIME``: ``RATE ∫₀ᵗ P(lifetime > age) d age``."""
    a, b = LIFETIME
    age = np.clip(t, 0.0, b)
    dying = np.clip(age - a, 0.0, None)
    return RATE * (age - dying**2 / (2.0 * (b - a)))


def apex_with_linear_drag(speed: float, drag_rate: float, g: float = GRAVITY) -> float:
    """Height [m] reached by a drop thrown straight up at ``speed`` [m/s] under gravity ``g``
    and linear drag of rate ``drag_rate`` γ = k/m [1/s]: ``v/γ − (g/γ²) ln(1 + γv/g)``."""
    return speed / drag_rate - g / drag_rate**2 * math.log1p(drag_rate * speed / g)


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    simulation = Simulation(build_scene(duration).build())
    recording = simulation.record(until=duration)
    output.recordings["symplectic_euler"] = recording
    t, alive = recording.time, recording["particle_alive"]
    heights = np.where(alive, recording["particle_position"][..., 1], -np.inf)
    live = alive.sum(axis=1)
    steady = t >= LIFETIME[1]
    steady_expected = RATE * 0.5 * (LIFETIME[0] + LIFETIME[1])
    rise = float(heights.max()) - NOZZLE[1]
    drag_free = SPEED[1] ** 2 / (2.0 * GRAVITY)
    with_drag = apex_with_linear_drag(SPEED[1], DRAG / DROP_MASS)

    figure = Figure(figsize=(12, 4.8), layout="constrained")
    count, side = figure.subplots(1, 2)
    count.plot(t, live, label="drops alive")
    count.plot(t, expected_alive(t), "k--", label="rate ∫ P(lifetime > age), uniform lifetimes")
    count.axhline(steady_expected, color="0.5", linestyle=":", label="rate × mean lifetime")
    count.set_xlabel("t [s]")
    count.set_ylabel("drops alive")
    count.set_title("Filling up to the steady state")
    legend_below(count)
    last = alive[-1]
    end = recording["particle_position"][-1][last]
    side.scatter(end[:, 0], end[:, 1], s=1.0, c=recording["particle_color"][-1][last])
    top = NOZZLE[1]
    side.axhline(top + drag_free, color="C3", linestyle="--", label="v²/(2g), no drag")
    side.axhline(top + with_drag, color="k", linestyle=":", label="linear drag, closed form")
    side.axhline(top + rise, color="C2", linewidth=0.8, label="highest drop (all frames)")
    side.set_aspect("equal")
    side.set_ylim(0.0, top + 1.15 * drag_free)
    side.set_xlabel("x [m]")
    side.set_ylabel("height y [m]")
    side.set_title(f"Side view at t = {t[-1]:.2f} s")
    legend_below(side)
    output.figures["fountain"] = figure

    state = simulation.state
    return {
        "drops_born": int(state["emitter_serial"].sum()),
        "drops_dropped": int(state["emitter_dropped"].sum()),
        "alive_at_end": int(live[-1]),
        "steady_state_alive_expected": steady_expected,
        "steady_state_alive_measured": float(live[steady].mean()) if steady.any() else None,
        "apex_above_nozzle_m": {
            "measured": rise,
            "linear_drag_closed_form": with_drag,
            "drag_free_v2_over_2g": drag_free,
        },
    }


register_demo(
    Demo(
        "fountain",
        BUILTIN_DEMOS["fountain"].summary,
        DURATION,
        run,
        picture=True,
    )
)
