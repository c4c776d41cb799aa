"""Demo ``top``: a spinning top on its tip precesses and nods under gravity's torque.

A solid cone (wood, 5 cm radius, 12 cm tall) stands on its apex, tilted 0.3 rad, spinning at
500 rad/s (80 turns a second) about its axis. Its apex is held at the origin by a stiff damped
spring (a ball joint by penalty: :class:`~visviva.forces.body_forces.BodyAnchor`); gravity
acts at the centre of mass, ``d = 3h/4`` above the apex, so its torque ``τ = d ŝ × M g``
turns ``L`` instead of toppling the top: ``L' = τ``. For a fast top ``L ≈ I₃ ω₃ ŝ`` and the
axis precesses about the vertical at

    Ω ≈ M g d / (I₃ ω₃),    I₃ = 3/10 M r²                                        [rad/s]

while nodding up and down (nutation) at about ``I₃ ω₃ / I₁'`` (``I₁' = 3/5 M h² + 3/20 M r²``
the moment about a horizontal axis through the apex), its tilt bounded by energy
conservation. Without the fast-top approximation, the slow steady precession at tilt θ solves
``I₁' cos θ Ω² − I₃ ω₃ Ω + M g d = 0``:

    Ω = (I₃ ω₃ − √(I₃² ω₃² − 4 I₁' M g d cos θ)) / (2 I₁' cos θ)

and a top let go without precessing nods about it. The summary holds the measured mean
precession rate against both and the tilt's range.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry.quaternions import quaternion_matrix, quaternion_multiply, quaternion_rotate
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

RADIUS, HEIGHT, DENSITY = 0.05, 0.12, 700.0  # [m], [m], wood [kg/m³]
TILT, SPIN = 0.3, 500.0  # [rad], [rad/s] (a fast top: I₃²ω² ≫ 4 I₁' M g d)
STIFFNESS, DAMPING = 2e5, 5.0  # the apex's spring [N/m] and damper [N·s/m]
DT = 1e-4  # [s]: the anchor's spring rings at √(k/M) ≈ 1000 rad/s
SAMPLES_PER_SECOND = 200
G = 9.81  # [m/s²]


def orientation() -> np.ndarray:
    """The cone upside down (apex at the bottom: a half turn about x), then tilted by
    :data:`TILT` about x."""
    flip = np.array([0.0, 1.0, 0.0, 0.0])
    tilt = np.array([np.cos(TILT / 2), np.sin(TILT / 2), 0.0, 0.0])
    return quaternion_multiply(tilt, flip)


def build_scene(duration: float) -> SceneBuilder:
    q = orientation()
    # The apex is the body point (0, h, 0); the spin is about the body's axis, −y after the
    # half turn: its world direction is R(q) (0, −1, 0), pointing up along the tilted axis.
    axis = quaternion_matrix(q) @ [0.0, -1.0, 0.0]
    apex = quaternion_matrix(q) @ [0.0, HEIGHT, 0.0]
    builder = SceneBuilder(name="spinning top")
    builder.set_world(gravity=(0.0, -G, 0.0))
    every = round(1.0 / (SAMPLES_PER_SECOND * DT))  # steps between recorded frames
    builder.set_integration(method="symplectic_euler", dt=DT, duration=duration, record_every=every)
    builder.add_body(
        "cone", radius=RADIUS, height=HEIGHT, density=DENSITY, orientation=q,
        position=-apex, angular_velocity=SPIN * axis, color=(0.75, 0.5, 0.25), name="top",
        anchor={"point": (0.0, HEIGHT, 0.0), "at": (0.0, 0.0, 0.0), "stiffness": STIFFNESS,
                "damping": DAMPING},
    )  # fmt: skip
    return builder


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    model = build_scene(duration).build()
    # One simulation, recorded SAMPLES_PER_SECOND times a second: the video and the figure.
    recording = Simulation(model).record(until=duration)
    output.recordings["symplectic_euler"] = recording
    mass = float(model.bodies.mass[0])
    # The centre of mass: the recorded origin plus the rotated body-frame offset to it.
    offset = quaternion_rotate(recording["body_orientation"][:, 0], model.bodies.center[0])
    t, centre = recording.time, recording["body_origin"][:, 0] + offset
    d = np.linalg.norm(centre, axis=1)  # the centre of mass from the apex at the origin
    tilt = np.arccos(np.clip(centre[:, 1] / d, -1.0, 1.0))
    azimuth = np.unwrap(np.arctan2(-centre[:, 2], centre[:, 0]))  # about +y
    rate = float((azimuth[-1] - azimuth[0]) / (t[-1] - t[0]))
    axial = 0.3 * mass * RADIUS**2
    weight_arm = mass * G * 0.75 * HEIGHT  # M g d [N·m]
    theory = weight_arm / (axial * SPIN)
    across = (0.6 * HEIGHT**2 + 0.15 * RADIUS**2) * mass * np.cos(TILT)  # I₁' cos θ
    spin = axial * SPIN
    steady = (spin - np.sqrt(spin**2 - 4.0 * across * weight_arm)) / (2.0 * across)

    figure = Figure(figsize=(13, 4.5), layout="constrained")
    path, nod, turn = figure.subplots(1, 3)
    path.plot(centre[:, 0], -centre[:, 2], lw=0.6)
    path.set_aspect("equal")
    path.set_xlabel("x [m]")
    path.set_ylabel("−z [m]")
    path.set_title("Centre of mass seen from above")
    nod.plot(t, np.degrees(tilt))
    nod.set_xlabel("t [s]")
    nod.set_ylabel("tilt [°]")
    nod.set_title("Nutation: the axis nods")
    turn.plot(t, azimuth - azimuth[0], label="measured")
    turn.plot(t, theory * (t - t[0]), "--", label="M g d / (I₃ ω₃)")
    turn.plot(t, steady * (t - t[0]), ":", label="steady slow precession")
    turn.set_xlabel("t [s]")
    turn.set_ylabel("azimuth [rad]")
    turn.set_title(f"Precession: {rate:.3f} rad/s (steady {steady:.3f}, fast {theory:.3f})")
    legend_below(turn)
    output.figures["top"] = figure
    return {
        "precession_rate_rad_per_s": rate,
        "gyroscopic_formula_rad_per_s": theory,
        "steady_precession_rad_per_s": float(steady),
        "tilt_range_deg": [float(np.degrees(tilt.min())), float(np.degrees(tilt.max()))],
        "apex_distance_to_centre_m": [float(d.min()), float(d.max())],
    }


register_demo(
    Demo(
        "top",
        BUILTIN_DEMOS["top"].summary,
        4.0,
        run,
        picture=True,
    )
)
