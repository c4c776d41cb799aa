"""Demo ``jelly``: a cube of jelly dropped onto the floor lands, squashes, wobbles and rests.

A 30 cm cube of 200 kg/m³ jelly, a 6 × 6 × 6 lattice of points joined by structural,
face-diagonal and body-diagonal springs (seed 004's volumetric soft body; the diagonals keep it
from folding flat), falls from 50 cm onto a floor with friction and a little restitution. The
same scene ships as ``examples/scenes/jelly.toml``: symplectic Euler with 20 substeps per
frame, below the stability advisor's limit.

Checks against physics:

* it falls freely until it touches the floor, at ``√(2 h / g)`` for the drop ``h`` of its
  lowest points;
* no point is ever below the floor (its centre closer than its radius);
* at rest it keeps its shape and is squashed by its own weight, by about what linear
  elasticity of its springs says: with ``K`` the springs' stiffness at rest (``k u uᵀ`` for
  each spring along ``u``) and the weights ``f``, the small displacements solve ``K u = f``
  with the bottom face on the floor. Friction decides whether the bottom face may spread: held
  where it landed, the cube is stiffer; sliding freely, softer. The top face's mean drop lies
  between the two (:func:`linear_compression`), and its height is ``r + size − δ``;
* the energy the drop gave it is gone — to the impact (restitution 0.2) and the springs'
  dampers: the energy at the end is the static energy of the squashed cube at rest
  (gravity's ``Σ m g y`` plus the springs' ``½ uᵀ K u``), within a tenth of what the
  compression takes off the undeformed cube's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..model.model import Model
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._deformables import (
    GRAVITY,
    kinetic_energy,
    record_alone,
    spring_pairs,
    springs_of,
    strain,
)
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DURATION = 3.0  # [s]
DT = 1.0 / 60.0  # [s]
SUBSTEPS = 20  # h ≈ 0.83 ms, below the advisor's 1.3 ms for these springs
POINTS = 6  # per edge
SIZE = 0.3  # [m]
DROP = 0.5  # [m]: height of the cube's lowest points' centres
DENSITY = 200.0  # [kg/m³]
STIFFNESS = 2000.0  # [N/m] (face and body diagonals the same)
DAMPING = 0.5  # [N·s/m]
RADIUS = 0.01  # [m]
FRICTION = 0.6
RESTITUTION = 0.2
#: A point this far below the floor (beyond its radius) still counts as on it [m].
FLOOR_TOLERANCE = 1e-9
DESCRIPTION = "a 30 cm cube of 200 kg/m³ jelly dropped from 50 cm onto a floor with friction"


def build_scene(duration: float = DURATION) -> SceneBuilder:
    """The jelly cube above the floor (``examples/scenes/jelly.toml`` holds the same one)."""
    builder = SceneBuilder(name="jelly", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method="symplectic_euler", dt=DT, duration=duration, substeps=SUBSTEPS)
    builder.add_soft_lattice(
        (POINTS, POINTS, POINTS),
        origin=(-0.5 * SIZE, DROP, -0.5 * SIZE),
        size=(SIZE, SIZE, SIZE),
        density=DENSITY,
        stiffness=STIFFNESS,
        damping=DAMPING,
        radius=RADIUS,
        color=(0.3, 0.8, 0.35),
        name="jelly",
    )
    builder.add_collider("plane", friction=FRICTION, restitution=RESTITUTION, name="floor")
    return builder


def layer(model: Model) -> np.ndarray:
    """Each point's layer from the bottom, ``j`` of its lattice index ``(k·ny + j)·nx + i``."""
    return (np.arange(model.particle_count) // POINTS) % POINTS


def stiffness_at_rest(model: Model) -> np.ndarray:
    """The springs' stiffness matrix [N/m] at rest, ``(3N, 3N)``: ``k u uᵀ`` per spring."""
    count = model.particle_count
    blocks = np.zeros((count, count, 3, 3))  # [row particle, column particle, row, column]
    x = model.particle_position
    for springs in springs_of(model):
        i, j = springs.pairs.T
        u = x[j] - x[i]
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        block = springs.stiffness[:, None, None] * u[:, :, None] * u[:, None, :]
        for a, b, sign in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
            np.add.at(blocks, (a, b), sign * block)
    return blocks.transpose(0, 2, 1, 3).reshape(3 * count, 3 * count)


def linear_compression(model: Model, *, sliding: bool) -> tuple[float, np.ndarray]:
    """The top face's mean drop [m] under the cube's weight in linear elasticity, and every
    point's displacement ``(N, 3)`` [m], the bottom face resting on the floor: held where it
    is, or (``sliding``) free to slide along it (one corner then holds the cube in place and a
    second its turn about the vertical: the load is symmetric, so they carry nothing)."""
    count = model.particle_count
    bottom = layer(model) == 0
    free = np.ones((count, 3), dtype=bool)
    free[bottom, 1] = False
    if sliding:
        free[0, [0, 2]] = False  # a corner of the bottom face
        free[POINTS - 1, 2] = False  # the next corner along x
    else:
        free[bottom] = False
    load = np.zeros((count, 3))
    load[:, 1] = -model.particle_mass * GRAVITY
    mask = free.ravel()
    matrix = stiffness_at_rest(model)
    displacement = np.zeros(3 * count)
    displacement[mask] = np.linalg.solve(matrix[np.ix_(mask, mask)], load.ravel()[mask])
    u = displacement.reshape(count, 3)
    return float(-u[layer(model) == POINTS - 1, 1].mean()), u


def static_energy(model: Model, u: np.ndarray) -> float:
    """Gravity's and the springs' energy [J] of the cube at rest on the floor, displaced by
    ``u`` ``(N, 3)`` [m] from its undeformed shape with the bottom at ``y = r``."""
    height = model.particle_position[:, 1] - DROP + RADIUS + u[:, 1]
    elastic = 0.5 * u.ravel() @ stiffness_at_rest(model) @ u.ravel()
    return float(GRAVITY * model.particle_mass @ height + elastic)


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    model, _, recording = record_alone(build_scene(duration), duration)
    output.recordings["symplectic_euler"] = recording
    t, points, energy = recording.time, recording["particle_position"], recording["energy"]
    clearance = points[..., 1] - RADIUS
    lowest = clearance.min(axis=1)
    touched = np.flatnonzero(lowest <= 1e-6)
    top = layer(model) == POINTS - 1
    bottom = layer(model) == 0
    height = points[:, top, 1].mean(axis=1) - points[:, bottom, 1].mean(axis=1)
    held, _ = linear_compression(model, sliding=False)
    sliding, u = linear_compression(model, sliding=True)
    at_rest = points[-1]
    pairs, _ = spring_pairs(model)
    measured = RADIUS + SIZE - float(at_rest[top, 1].mean())
    output.figures["jelly"] = _figure(t, lowest, height, energy, kinetic_energy(recording))
    return {
        "method": "symplectic_euler",
        "dt": DT,
        "substeps": SUBSTEPS,
        "lowest_below_floor_m": float(max(0.0, -lowest.min())),
        "floor_tolerance_m": FLOOR_TOLERANCE,
        "first_touch_s": {
            "measured": float(t[touched[0]]) if touched.size else None,
            "free_fall_sqrt_2h_over_g": float(np.sqrt(2.0 * (DROP - RADIUS) / GRAVITY)),
            "frame_s": DT,
        },
        "cube_height_m": {"smallest": float(height.min()), "undeformed": SIZE},
        "kinetic_energy_at_end_J": float(kinetic_energy(recording)[-1]),
        "compression_at_rest_m": {
            "measured": measured,
            "linear_bottom_held": held,
            "linear_bottom_sliding": sliding,
        },
        "top_height_at_rest_m": {
            "measured": float(at_rest[top, 1].mean()),
            "size_plus_radius_minus_compression": RADIUS + SIZE - sliding,
        },
        "largest_stretch_at_rest": float(np.abs(strain(model, at_rest, pairs)).max()),
        "energy_J": {
            "start": float(energy[0]),
            "end": float(energy[-1]),
            "at_rest_linear_elasticity": static_energy(model, u),
            "undeformed_on_the_floor": static_energy(model, np.zeros_like(u)),
        },
    }


def _figure(
    t: np.ndarray,
    lowest: np.ndarray,
    height: np.ndarray,
    energy: np.ndarray,
    kinetic: np.ndarray,
) -> Figure:
    """The fall and the bounce; the cube's height (its squash); the energy going."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(14, 4.4), layout="constrained")
    fall, squash, spent = figure.subplots(1, 3)
    fall.plot(t, lowest, label="lowest point's clearance")
    fall.plot(t, np.maximum(DROP - RADIUS - 0.5 * GRAVITY * t**2, 0.0), "k--", lw=0.8,
              label="free fall")  # fmt: skip
    fall.set_xlabel("t [s]")
    fall.set_ylabel("height above the floor [m]")
    fall.set_title("It falls, lands and bounces a little")
    legend_below(fall)
    squash.plot(t, 100 * height, color="C2")
    squash.axhline(100 * SIZE, color="0.5", linestyle=":", label="undeformed")
    squash.set_xlabel("t [s]")
    squash.set_ylabel("top face above the bottom face [cm]")
    squash.set_title("Squash on impact, wobble, rest")
    legend_below(squash)
    spent.plot(t, energy, label="total")
    spent.plot(t, kinetic, label="kinetic")
    spent.set_xlabel("t [s]")
    spent.set_ylabel("energy [J]")
    spent.set_title("The drop's energy goes to impacts and dampers")
    legend_below(spent)
    return figure


register_demo(
    Demo(
        "jelly",
        BUILTIN_DEMOS["jelly"].summary,
        DURATION,
        run,
        picture=True,
    )
)
