"""Demo ``dzhanibekov``: the tennis-racket flip of a T-handle spun about its middle axis.

Three identical T-handles (a stem under a bar, aluminium, generated as a closed mesh whose
mass properties come from Mirtich's integrals) float with no gravity, each spun at 8 rad/s
about one of its principal axes with a 1 % nudge about the others. Euler's equations for a
free body, ``I ω' = −ω × I ω``, make a spin about the axis of the smallest or the largest
moment stable and one about the intermediate moment unstable: the middle handle turns over
again and again (Dzhanibekov's wing nut on the ISS, 1985), while ``L`` and the kinetic energy
stay what they were — ω is not conserved, the angular momentum is. The default integrator's
splitting keeps ``L`` exactly and the energy within O(h²) (:mod:`visviva.rigid.motion`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry.quaternions import quaternion_matrix
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._meshes import t_handle
from .catalogue import BUILTIN_DEMOS

DENSITY = 2700.0  # aluminium [kg/m³]
SPIN = 8.0  # [rad/s]
NUDGE = 0.01  # of the spin, about the other two axes
DT = 1.0 / 480.0  # [s]
SAMPLES_PER_SECOND = 60
AXES = ("smallest moment (x)", "intermediate moment (y)", "largest moment (z)")
#: The handles' names, written above them in the video.
NAMES = ("about x: smallest I, steady", "about y: middle I, flips", "about z: largest I, steady")
#: Each handle as the video shows it (left to right, its colour) and its spin axis' name.
HANDLES = ("left, orange", "middle, red", "right, blue")
ROLES = ("minor", "intermediate", "major")


def build_scene(duration: float) -> SceneBuilder:
    """Three T-handles side by side, each spun about one principal axis (the mesh's x, y, z
    are its principal axes: it is symmetric about the y–z and x–y planes)."""
    vertices, triangles = t_handle()
    builder = SceneBuilder(name="Dzhanibekov's T-handles")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.set_integration(method="symplectic_euler", dt=DT, duration=duration)
    for k, x in enumerate((-0.5, 0.0, 0.5)):
        spin = np.full(3, NUDGE * SPIN)
        spin[k] = SPIN
        builder.add_body(
            "mesh", vertices=vertices, triangles=triangles, density=DENSITY,
            position=(x, 0.0, 0.0), angular_velocity=spin, name=NAMES[k],
            color=((0.9, 0.6, 0.2), (0.85, 0.25, 0.2), (0.3, 0.55, 0.85))[k],
        )  # fmt: skip
    return builder


def body_spins(simulation: Simulation) -> np.ndarray:
    """Each body's angular velocity in its own axes, ``(B, 3)`` [rad/s]."""
    q, v = simulation.raw_state.parts
    world = simulation.system.kinematics.angular_velocity(q, v)
    rotation = quaternion_matrix(simulation.state["body_orientation"])
    return np.einsum("bji,bj->bi", rotation, world)


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    builder = build_scene(duration)
    model = builder.build()
    output.recordings["symplectic_euler"] = Simulation(model).record(until=duration)
    simulation = Simulation(model)
    every = round(1.0 / (SAMPLES_PER_SECOND * DT))
    samples = int(duration * SAMPLES_PER_SECOND)
    start_l = simulation.state["body_angular_momentum"].copy()
    start_e = simulation.energy()
    t, spins, energy, drift_l = [], [], [], []
    for _ in range(samples + 1):
        t.append(simulation.time)
        spins.append(body_spins(simulation))
        energy.append(simulation.energy() / start_e - 1.0)
        drift_l.append(np.abs(simulation.state["body_angular_momentum"] - start_l).max())
        simulation.step(every)
    t, spins = np.array(t), np.array(spins)
    flips = [int(np.count_nonzero(np.diff(np.sign(spins[:, k, k])))) for k in range(3)]

    figure = Figure(figsize=(13, 8), layout="constrained")
    panels = figure.subplots(2, 2).ravel()
    for k in range(3):
        for axis, style in zip(range(3), ("C0", "C1", "C2"), strict=True):
            spun = axis == k  # the spin axis' ω, whose sign changes are counted: bolder
            label = f"ω_{'xyz'[axis]}: {ROLES[axis]} axis" + (", spun" if spun else "")
            panels[k].plot(t, spins[:, k, axis], style, lw=1.4 if spun else 0.8, label=label)
        panels[k].set_title(
            f"Handle {HANDLES[k]}: spun about its {ROLES[k]} axis, of the {AXES[k]}\n"
            f"{flips[k]} sign changes",
            fontsize=10,
        )
        panels[k].set_xlabel("t [s]")
        panels[k].set_ylabel("ω in the body's axes [rad/s]")
        legend_below(panels[k])
    panels[3].plot(t, energy, label="kinetic energy / start − 1")
    panels[3].plot(t, drift_l, label="max |L − L₀| [kg m²/s]")
    panels[3].set_xlabel("t [s]")
    panels[3].set_title(f"Conserved: L exactly, energy within O(h²) (h = {DT:.4g} s)")
    legend_below(panels[3])
    output.figures["dzhanibekov"] = figure
    return {
        "principal_moments_kg_m2": model.bodies.moments[0].tolist(),
        "sign_changes_of_the_spin_axis": dict(zip(AXES, flips, strict=True)),
        "max_relative_energy_change": float(np.max(np.abs(energy))),
        "max_angular_momentum_change": float(np.max(drift_l)),
    }


register_demo(
    Demo(
        "dzhanibekov",
        BUILTIN_DEMOS["dzhanibekov"].summary,
        20.0,
        run,
        picture=True,
        labels=True,
    )
)
