"""Demo ``bottle-flip``: a flick at the bottom edge gives a bottle both momentum and spin
(seed 002: a force off the centre of mass makes a torque, and ``L = I ω``).

A 0.5 kg bottle (a solid cylinder, 7 cm across, 22 cm tall) standing upright is flicked for
1 ms at the back edge of its base. The impulse ``J`` gives ``P = J`` and, being off the
centre of mass by ``a``, ``L = a × J``: the flick is chosen so that the bottle turns once
(360°) in the time its centre of mass takes to come back to its launch height, ``T = 2 v_y /
g``: ``ω = 2π/T``, ``L = I ω``. Two other bottles of the same mass get the very same flick at
the same place: a slimmer, taller one (larger moment of inertia about the flip axis) turns
too slowly and lands short of upright, a squatter one turns too fast. In flight nothing
turns ``L``: each bottle spins at ``ω = L / I`` from the flick to the landing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry.quaternions import quaternion_matrix
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

MASS = 0.5  # [kg]
BOTTLES = {  # name: (radius, height) [m]
    "just right": (0.035, 0.22),
    "slimmer, taller": (0.03, 0.3),
    "squatter": (0.045, 0.16),
}
UP_SPEED = 3.0  # of the centre of mass after the flick [m/s]
FLICK = 0.001  # [s]: short, so that the bottle barely turns while it is pushed
DT = 1e-4  # [s]
G = 9.81  # [m/s²]


def flick(radius: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """The impulse ``J`` [N·s] and where it acts (the back edge of the base, from the centre
    of mass; the cylinder's origin is its centre) that send the "just right" bottle up at
    :data:`UP_SPEED` turning once (about −z, a forward flip) by the time it is back at its
    launch height (as if the flick were instantaneous: during it the bottle turns a little,
    the lever arm with it, and the turn at landing comes out a few degrees over)."""
    airborne = 2.0 * UP_SPEED / G  # [s]
    across = MASS * (3.0 * radius**2 + height**2) / 12.0  # cylinder, about a diameter
    spin = -2.0 * np.pi / airborne * across  # L_z [kg·m²/s]
    arm = np.array([-radius, -0.5 * height, 0.0])  # from the centre of mass
    up = MASS * UP_SPEED
    # L_z = a_x J_y − a_y J_x  ⇒  J_x = (a_x J_y − L_z) / a_y
    forward = (arm[0] * up - spin) / arm[1]
    return np.array([forward, up, 0.0]), arm


def tilt(q: np.ndarray) -> float:
    """How far the bottle has turned from upright about −z [rad], unwrapped by the caller:
    the angle of its axis (body y) in the x–y plane, measured from +y towards +x."""
    axis = quaternion_matrix(q) @ [0.0, 1.0, 0.0]
    return float(np.arctan2(axis[0], axis[1]))


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    impulse, arm = flick(*BOTTLES["just right"])
    force = impulse / FLICK
    builder = SceneBuilder(name="bottle flip")
    builder.set_world(gravity=(0.0, -G, 0.0))
    builder.set_integration(method="symplectic_euler", dt=DT, duration=duration)
    for k, (name, (radius, height)) in enumerate(BOTTLES.items()):
        builder.add_body(
            "cylinder", radius=radius, height=height, mass=MASS, name=name,
            position=(0.0, 0.5 * height, 0.4 * k), color=((0.3, 0.6, 0.9), (0.4, 0.8, 0.4),
                                                          (0.9, 0.5, 0.3))[k],
            push=[{"force": tuple(force), "point": tuple(arm), "duration": FLICK}],
        )  # fmt: skip
    model = builder.build()
    output.recordings["symplectic_euler"] = Simulation(model).record(until=duration)
    simulation = Simulation(model)
    names = list(BOTTLES)
    start = simulation.state["body_position"][:, 1].copy()
    t, angles, heights, spins = [], [], [], []
    simulation.step(round(FLICK / DT))  # the flick
    after_flick = simulation.state["body_angular_momentum"].copy()
    while simulation.time < duration - 0.5 * DT:
        t.append(simulation.time)
        angles.append([tilt(q) for q in simulation.state["body_orientation"]])
        heights.append(simulation.state["body_position"][:, 1] - start)
        q, v = simulation.raw_state.parts
        spins.append(simulation.system.kinematics.angular_velocity(q, v)[:, 2])
        simulation.step(1)
    t, heights, spins = np.array(t), np.array(heights), np.array(spins)
    turned = np.degrees(np.unwrap(np.array(angles), axis=0))  # a forward flip counts positive
    landing = {}
    for k, name in enumerate(names):
        down = np.flatnonzero((heights[1:, k] < 0.0) & (heights[:-1, k] >= 0.0))
        landing[name] = float(turned[down[0] + 1, k]) if down.size else float("nan")
    moments = {name: MASS * (3.0 * r**2 + h**2) / 12.0 for name, (r, h) in BOTTLES.items()}
    spin_error = max(
        float(np.abs(spins[:, k] - after_flick[k, 2] / moments[n]).max())
        for k, n in enumerate(names)
    )
    l_change = float(np.abs(simulation.state["body_angular_momentum"] - after_flick).max())

    figure = Figure(figsize=(12, 4.5), layout="constrained")
    turn, rise = figure.subplots(1, 2)
    for k, (name, color) in enumerate(zip(names, distinct_colors(len(names)), strict=True)):
        turn.plot(t, turned[:, k], color=color, label=f"{name}: {landing[name]:.0f}° at landing")
        rise.plot(t, heights[:, k], color=color, label=name)
    turn.axhline(360.0, color="grey", lw=0.6)
    turn.set_xlabel("t [s]")
    turn.set_ylabel("turned [°]")
    turn.set_title("Same flick, different I: ω = L / I")
    legend_below(turn)
    rise.axhline(0.0, color="grey", lw=0.6)
    rise.set_xlabel("t [s]")
    rise.set_ylabel("centre of mass above its start [m]")
    rise.set_title("The centres of mass fly the same parabola")
    output.figures["bottle_flip"] = figure
    return {
        "impulse_N_s": impulse.tolist(),
        "turned_at_landing_deg": landing,
        "moment_about_flip_axis_kg_m2": moments,
        "max_spin_error_vs_L_over_I_rad_per_s": spin_error,
        "angular_momentum_change_in_flight": l_change,
    }


register_demo(
    Demo(
        "bottle-flip",
        BUILTIN_DEMOS["bottle-flip"].summary,
        0.7,
        run,
        picture=True,
    )
)
