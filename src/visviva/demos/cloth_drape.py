"""Demo ``cloth-drape``: a square of cloth falls onto a ball and drapes over it.

A 1.2 m square of 0.1 kg/m² cloth, 16 × 16 points with stiff structural springs (Choi & Ko
2002), falls from 25 cm above a ball of radius 35 cm (an impulse collider without restitution
and with Coulomb friction μ = 0.5) in still air that slows every point at the rate γ. It is
stepped by backward Euler solved as a minimization (``projected_newton``; Gast et al. 2015)
with the ball inside the solve: a point that would end inside is held on the surface with its
normal velocity filtered out of the solve (Baraff & Witkin 1998, §5), and friction enters as a
dissipation potential with the normal impulses of the previous round (Li et al. 2020).

Checks against physics:

* no point is ever inside the ball (its centre closer than the ball's radius plus its own);
* the energy never rises from one step to the next: contact and friction inside the solve keep
  the step a minimization, which only dissipates (a point stopped by the collision stage after
  the step, instead, can be moved out and gain energy: at h = 1/60 s and this fall the first
  impact does, by 2.5 mJ; at h = 1/120 s nothing is left to that stage);
* at rest the ball carries the whole cloth: the reactions at the contacts — minus the springs'
  and gravity's forces on the touching points — add up to ``M g`` upwards;
* Coulomb's law holds at every resting contact: the reaction along the surface is at most μ
  times the reaction pressing the point out (the cone of static friction).

The summary counts the resting contacts (within :data:`CONTACT_GAP` of the surface, normal
speed below the collider's resting speed) and gives the lowest one's angle from the top.

References:
    K.-J. Choi, H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
    T. F. Gast, C. Schroeder, A. Stomakhin, C. Jiang, J. M. Teran, "Optimization integrator
    for large time steps", IEEE TVCG 21 (2015).
    M. Li et al., "Incremental potential contact", ACM TOG 39(4) (2020).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._deformables import (
    GRAVITY,
    kinetic_energy,
    largest_rise,
    record_alone,
    spring_forces,
)
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulation.recording import Recording

DURATION = 3.0  # [s]: it lands at 0.2 s and is at rest (below a microjoule) by 3 s
DT = 1.0 / 120.0  # [s]
METHOD = "projected_newton"
POINTS = 16  # per side
SIZE = 1.2  # [m]
START_HEIGHT = 1.2  # [m]
AREAL_DENSITY = 0.1  # [kg/m²]
STIFFNESS = 2000.0  # [N/m]
SHEAR = 100.0  # [N/m]
BENDING = 0.05  # [N/m]
DAMPING = 0.05  # [N·s/m] along each spring
AIR = 1.0  # γ [1/s]
POINT_RADIUS = 0.01  # [m]
BALL_CENTER = (0.0, 0.6, 0.0)  # [m]
BALL_RADIUS = 0.35  # [m]
FRICTION = 0.5  # μ
#: A point this close to the ball's surface, beyond its radius, counts as touching [m]: held
#: points end half a micrometre outside, and those the cloth's tension lifts a few more.
CONTACT_GAP = 1e-4
#: A point in the ball by less than this is not counted inside [m]: round-off of the surface.
INSIDE_TOLERANCE = 1e-6
#: Contacts pressed by less than this fraction of a point's weight are left out of the friction
#: check: a cone's ratio means nothing where the normal reaction is round-off.
PRESSED = 0.05
#: A step may gain this much energy [J] and still count as not rising: the solver stops when
#: its velocity correction is below 1e-4 m/s (RMS), and a velocity off by δv changes the work of
#: the cloth's weight M g over the step by up to M g h δv (1.2 µJ here; the largest rise
#: measured is 0.7 µJ). Round-off on the 1.7 J cloth is 1e-16 J.
ENERGY_RISE_TOLERANCE = AREAL_DENSITY * SIZE * SIZE * GRAVITY * DT * 1e-4
DESCRIPTION = "a 1.2 m square of 0.1 kg/m² cloth, 16 × 16 points, falls onto a ball with friction"


def build_scene(duration: float = DURATION) -> SceneBuilder:
    """The cloth above the ball, in still air."""
    builder = SceneBuilder(name="cloth-drape", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method=METHOD, dt=DT, duration=duration, record_every=1)
    builder.add_cloth(
        (POINTS, POINTS),
        origin=(-0.5 * SIZE, START_HEIGHT, -0.5 * SIZE),
        along=(SIZE, 0.0, 0.0),
        across=(0.0, 0.0, SIZE),
        areal_density=AREAL_DENSITY,
        stiffness=STIFFNESS,
        shear=SHEAR,
        bending=BENDING,
        damping=DAMPING,
        radius=POINT_RADIUS,
        color=(0.2, 0.45, 0.8),
        name="sheet",
    )
    builder.add_force("damping", rate=AIR, name="air")
    builder.add_collider(
        "sphere",
        center=BALL_CENTER,
        radius=BALL_RADIUS,
        restitution=0.0,
        friction=FRICTION,
        name="ball",
    )
    return builder


def clearance(points: np.ndarray) -> np.ndarray:
    """Each point's distance [m] from the ball's surface less its radius (negative: inside)."""
    return np.linalg.norm(points - np.asarray(BALL_CENTER), axis=-1) - BALL_RADIUS - POINT_RADIUS


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    model, simulation, recording = record_alone(build_scene(duration), duration)
    output.recordings[METHOD] = recording
    energy, kinetic = recording["energy"], kinetic_energy(recording)
    state = simulation.state
    x, v = state["particle_position"], state["particle_velocity"]
    contacts = simulation.contacts(gap=CONTACT_GAP)
    # The ball's reaction on each touching point balances the other forces on it at rest.
    force = spring_forces(model, x, v) - AIR * model.particle_mass[:, None] * v
    force[:, 1] -= model.particle_mass * GRAVITY
    reaction = -force[contacts.particle]
    pressing = np.einsum("ij,ij->i", reaction, contacts.normal)
    along = np.linalg.norm(reaction - pressing[:, None] * contacts.normal, axis=1)
    pressed = pressing > PRESSED * model.particle_mass[contacts.particle] * GRAVITY
    ratio = along[pressed] / pressing[pressed]
    weight = float(model.particle_mass.sum()) * GRAVITY
    carried = float(reaction[:, 1].sum())
    up = contacts.normal[:, 1]
    output.figures["cloth_drape"] = _figure(recording, kinetic, contacts.normal, pressed, ratio)
    return {
        "method": METHOD,
        "dt": DT,
        "deepest_inside_ball_m": float(max(0.0, -clearance(recording["particle_position"]).min())),
        "inside_tolerance_m": INSIDE_TOLERANCE,
        "largest_energy_rise_per_step_J": largest_rise(energy),
        "energy_rise_tolerance_J": ENERGY_RISE_TOLERANCE,
        "kinetic_energy_at_end_J": float(kinetic[-1]),
        "contacts_at_rest": contacts.counts() | {"points": model.particle_count},
        "lowest_contact_from_top_deg": float(np.degrees(np.arccos(up.min()))) if up.size else None,
        "ball_carries_N": {
            "measured_upward": carried,
            "sideways": float(np.hypot(*reaction[:, [0, 2]].sum(axis=0))),
            "cloth_weight_M_g": weight,
            "relative_error": abs(carried - weight) / weight,
        },
        "friction_at_rest": {
            "pressed_contacts": int(pressed.sum()),
            "largest_along_over_pressing": float(ratio.max(initial=0.0)),
            "mu": FRICTION,
        },
    }


def _figure(
    recording: Recording,
    kinetic: np.ndarray,
    normals: np.ndarray,
    pressed: np.ndarray,
    ratio: np.ndarray,
) -> Figure:
    """Energy over time; the draped cloth from the side; friction at each resting contact."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    t, energy = recording.time, recording["energy"]
    figure = Figure(figsize=(15, 4.4), layout="constrained")
    total, side, cone = figure.subplots(1, 3)
    total.plot(t, energy, label="kinetic + springs + gravity")
    total.plot(t, kinetic, label="kinetic")
    total.set_xlabel("t [s]")
    total.set_ylabel("energy [J]")
    total.set_title("The energy never rises (contact and friction in the solve)")
    legend_below(total)
    side.add_patch(Circle(BALL_CENTER[:2], BALL_RADIUS, color="0.85", zorder=0))
    grid = recording["particle_position"][-1].reshape(POINTS, POINTS, 3)
    for row in grid:
        side.plot(row[:, 0], row[:, 1], color="C0", lw=0.6)
    side.set_aspect("equal")
    side.set_xlabel("x [m]")
    side.set_ylabel("height y [m]")
    side.set_title(f"At rest, seen from the side (t = {t[-1]:.1f} s)")
    angle = np.degrees(np.arccos(np.clip(normals[pressed, 1], -1.0, 1.0)))
    cone.plot(angle, ratio, "o", ms=4, label="resting contacts")
    cone.axhline(FRICTION, color="k", linestyle="--", label=f"μ = {FRICTION:g}")
    slope = np.linspace(0.0, min(np.degrees(np.arctan(1.2 * FRICTION)), 90.0), 50)
    cone.plot(slope, np.tan(np.radians(slope)), "k:", label="tan θ: a lone point on the ball")
    cone.set_xlabel("angle of the contact from the ball's top [°]")
    cone.set_ylabel("reaction along the surface / pressing")
    cone.set_title("Static friction: inside Coulomb's cone")
    legend_below(cone)
    return figure


register_demo(
    Demo(
        "cloth-drape",
        BUILTIN_DEMOS["cloth-drape"].summary,
        DURATION,
        run,
        picture=True,
    )
)
