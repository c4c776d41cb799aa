"""Demo ``cloth-hang``: a square of cloth held at two corners falls, swings and comes to rest.

A 1 m square of 0.1 kg/m² cloth, 20 × 20 points with the structural, shear and bend springs of
Choi & Ko (2002), starts horizontal and is held at the two corners of one edge (seeds 001 and
004). Still air slows every point at the rate ``γ`` (mass-proportional damping ``F = −γ m v``,
the same as a drag in proportion to each point's area, the cloth's density being uniform), so
the swing dies out within seconds. The springs are stiff for such light points (symplectic
Euler would need steps below 0.3 ms); the cloth is stepped at h = 1/60 s by backward Euler
solved as an energy minimization (``projected_newton``: Gast et al. 2015; Baraff & Witkin 1998).

Two checks against physics:

* backward Euler only dissipates: with springs, gravity and dampers the step minimizes the
  incremental potential, whose value bounds the new energy by the old, so the total energy
  (kinetic + springs + gravity) never rises from one step to the next (to the solver's
  tolerance, far below :data:`ENERGY_RISE_TOLERANCE`);
* at rest nothing but the pins holds the cloth up: the springs pull the two pinned points
  down by exactly the weight of every other point (the springs' forces sum to zero, so their
  pull on the pins is minus their pull on the free points, which balances those points'
  weight), and the pins carry their own weight besides: the whole ``M g``.

The figure shows the energy over the run and the sag profile at rest: the top edge between the
pins (which sags by the stretch of its springs) and the bottom edge.

References:
    K.-J. Choi, H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
    T. F. Gast, C. Schroeder, A. Stomakhin, C. Jiang, J. M. Teran, "Optimization integrator
    for large time steps", IEEE TVCG 21 (2015).
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
    load_on_pins,
    record_alone,
    strain,
    stretch_pairs,
)
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulation.recording import Recording

DURATION = 8.0  # [s]: the swing has died out (kinetic energy below a microjoule)
DT = 1.0 / 60.0  # [s]
METHOD = "projected_newton"
POINTS = 20  # per side
SIZE = 1.0  # [m]
HEIGHT = 1.5  # [m]: the pinned edge
AREAL_DENSITY = 0.1  # [kg/m²]
STIFFNESS = 1000.0  # [N/m]
SHEAR = 50.0  # [N/m]
BENDING = 0.05  # [N/m]: real cloth bends easily
DAMPING = 0.02  # [N·s/m] along each spring
AIR = 1.5  # γ [1/s]
PINNED = (0, POINTS - 1)  # the two corners of the first row
#: A step may gain this much energy [J] and still count as not rising: the solver stops when
#: its velocity correction is below 1e-4 m/s RMS, which moves the energy of a 1 J cloth by
#: far less; round-off on 1 J is 1e-16 J.
ENERGY_RISE_TOLERANCE = 1e-9
DESCRIPTION = "a 1 m square of 0.1 kg/m² cloth, 20 × 20 points, held at two corners, in still air"


def build_scene(duration: float = DURATION) -> SceneBuilder:
    """The cloth, its two pins and the air (the cloth of ``examples/scenes/cloth_hang.toml``
    with air to bring it to rest)."""
    builder = SceneBuilder(name="cloth-hang", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method=METHOD, dt=DT, duration=duration, record_every=1)
    builder.add_cloth(
        (POINTS, POINTS),
        origin=(-0.5 * SIZE, HEIGHT, 0.0),
        along=(SIZE, 0.0, 0.0),
        across=(0.0, 0.0, SIZE),
        areal_density=AREAL_DENSITY,
        stiffness=STIFFNESS,
        shear=SHEAR,
        bending=BENDING,
        damping=DAMPING,
        pinned=list(PINNED),
        radius=0.01,
        color=(0.85, 0.25, 0.2),
        name="sheet",
    )
    builder.add_force("damping", rate=AIR, name="air")
    return builder


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    model, simulation, recording = record_alone(build_scene(duration), duration)
    output.recordings[METHOD] = recording
    energy, kinetic = recording["energy"], kinetic_energy(recording)
    state = simulation.state
    x, v = state["particle_position"], state["particle_velocity"]
    pull = load_on_pins(model, x, v)
    pinned = model.particle_pinned
    free_weight = float(model.particle_mass[~pinned].sum()) * GRAVITY
    pin_weight = float(model.particle_mass[pinned].sum()) * GRAVITY
    held = -float(pull[1]) + pin_weight  # the pins' own weight hangs on them too
    weight = float(model.particle_mass.sum()) * GRAVITY
    grid = x.reshape(POINTS, POINTS, 3)  # [row j, column i]
    output.figures["cloth_hang"] = _figure(recording, kinetic, grid)
    return {
        "method": METHOD,
        "dt": DT,
        "kinetic_energy_at_end_J": float(kinetic[-1]),
        "energy_J": {"start": float(energy[0]), "end": float(energy[-1])},
        "largest_energy_rise_per_step_J": largest_rise(energy),
        "energy_rise_tolerance_J": ENERGY_RISE_TOLERANCE,
        "load_on_pins_N": {
            "springs_pull_down": -float(pull[1]),
            "free_points_weight": free_weight,
            "springs_pull_sideways": float(np.hypot(pull[0], pull[2])),
            "held_with_pins_own_weight": held,
            "cloth_weight_M_g": weight,
            "relative_error": abs(held - weight) / weight,
        },
        "sag_at_rest_m": {
            "top_edge_middle": HEIGHT - float(grid[0, POINTS // 2, 1]),
            "lowest_point": HEIGHT - float(x[:, 1].min()),
        },
        "largest_stretch_at_rest": float(strain(model, x, stretch_pairs(model)).max()),
        "pins_moved_m": float(np.abs(x[pinned] - model.particle_position[pinned]).max()),
    }


def _figure(recording: Recording, kinetic: np.ndarray, grid: np.ndarray) -> Figure:
    """Energy over time; the top edge's sag and the cloth seen from the front, at rest."""
    from matplotlib.figure import Figure

    t, energy = recording.time, recording["energy"]
    figure = Figure(figsize=(16, 4.2), layout="constrained")
    total, moving, profile, front = figure.subplots(1, 4)
    total.plot(t, energy, label="kinetic + springs + gravity")
    total.set_xlabel("t [s]")
    total.set_ylabel("energy [J]")
    total.set_title("Backward Euler: the energy never rises")
    legend_below(total)
    moving.semilogy(t[1:], np.maximum(kinetic[1:], 1e-16), color="C1")
    moving.set_xlabel("t [s]")
    moving.set_ylabel("kinetic energy [J]")
    moving.set_title(f"The swing dies out in still air (γ = {AIR:g}/s)")
    top = grid[0]
    profile.plot(top[:, 0], 1e3 * (top[:, 1] - HEIGHT), "o-", ms=3)
    profile.set_xlabel("x [m]")
    profile.set_ylabel("height of the top edge [mm]")
    profile.set_title("Sag of the top edge between the pins, at rest")
    for row in range(grid.shape[0]):
        front.plot(grid[row, :, 0], grid[row, :, 1], color="C3", lw=0.6)
    for column in range(grid.shape[1]):
        front.plot(grid[:, column, 0], grid[:, column, 1], color="C3", lw=0.6)
    front.plot(top[[0, -1], 0], top[[0, -1], 1], "ko", ms=5, label="pins")
    front.set_aspect("equal")
    front.set_xlabel("x [m]")
    front.set_ylabel("height y [m]")
    front.set_title("At rest, seen from the front")
    legend_below(front)
    return figure


register_demo(
    Demo(
        "cloth-hang",
        BUILTIN_DEMOS["cloth-hang"].summary,
        DURATION,
        run,
        picture=True,
    )
)
