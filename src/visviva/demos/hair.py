"""Demo ``hair``: strands of hair of five lengths swing after the head turns and stops.

Five strands (Selle, Lentine & Fedkiw 2008: edge springs between neighbours, bending springs
between points two apart, torsion springs between points three apart) hang from roots on the
hairline behind a head, 8 to 16 points 4 cm apart (28 to 60 cm). Each strand's root is pinned
to the head by a handle (:mod:`visviva.particles.handles`): the head turns by
:data:`TURN_ANGLE` about the vertical through :data:`HEAD` between :data:`TURN_START` and
:data:`TURN_STOP`, speeding up and slowing down over :data:`TURN_RAMP`, and then holds still;
the strands are dragged round with it and swing after it stops. Stepped by symplectic Euler
with substeps well below the stability advisor's limit, so the swing is hardly damped by the
method.

Checks against physics:

* the roots move with the head and only with it: at every frame on the hairline circle (radius
  :data:`HAIRLINE_RADIUS` about the head's axis, at its height) to round-off, all turned by the
  same angle, bit for bit where they were before the turn, bit for bit still after it, turned
  by exactly :data:`TURN_ANGLE`;
* the strands start unstretched, so gravity loads their springs at once: a suddenly loaded
  spring overshoots to at most twice its static stretch (dampers only lower it), and the
  swing's centripetal pull adds about ``θ₀²`` of the weight at an amplitude ``θ₀``: no edge
  stretches beyond ``2 ε (1 + θ₀²)``, ``ε`` the largest static stretch. A vertical strand's
  springs all lie along it, so its statics is linear: ``K y = −m g`` with ``K`` the 1-D
  stiffness of the three families (solved exactly here);
* the swing's period at small amplitude, once the head has stopped (its offsets measured
  along the hairline's tangent at the root). A straight strand's bending and torsion springs
  lie along it and give no stiffness against a small sideways bend; each spring under tension
  ``f`` resists a sideways offset of its ends by ``f/l`` only. The strand swings like a
  hanging chain, whose slowest mode is computed exactly from the static tensions
  (:func:`chain_period`; the measured period is within :data:`PERIOD_TOLERANCE` of it). For
  reference, the strand made rigid is a compound pendulum, ``T = 2π √(I / (M g d))`` about
  its root (``2π √(2L / 3g)`` for a uniform rod of length ``L``), and a uniform chain swings
  with ``T = 4π √(L/g) / j₀,₁`` (``j₀,₁ ≈ 2.405``), 1.9 % slower than the rod: the measured
  periods lie within :data:`COMPOUND_TOLERANCE` of the compound pendulum's and grow as
  ``√L``.

Selle et al.'s altitude springs (and their ghost particles) are left out (see
:mod:`visviva.deformables.topology`).

References:
    A. Selle, M. Lentine, R. Fedkiw, "A mass spring model for hair simulation", SIGGRAPH 2008.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..analysis.advisor import largest_stable_step
from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..model.model import Model
from ..simulation.simulation import Simulation
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._deformables import GRAVITY, one_thread, spring_pairs, strain
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

DURATION = 8.0  # [s]: the turn, then four swings of the longest strand
DT = 1.0 / 60.0  # [s]
SUBSTEPS = 30  # h = 0.56 ms; the advisor's limit for these strands is 1.56 ms
METHOD = "symplectic_euler"
POINTS = (8, 10, 12, 14, 16)  # per strand, root included
SPACING = 0.04  # [m]
MASS = 5e-4  # [kg] per point
STIFFNESS = 200.0  # [N/m]: edge springs
BENDING = 20.0  # [N/m]: springs between points two apart
TORSION = 5.0  # [N/m]: springs between points three apart
DAMPING = 0.002  # [N·s/m]
HEAD = (0.0, 1.5, 0.0)  # [m]: centre of the hairline
HAIRLINE_RADIUS = 0.1  # [m]
HAIRLINE_ANGLES = (-60.0, -30.0, 0.0, 30.0, 60.0)  # [degrees] round the back of the head
TURN_ANGLE = 0.8  # [rad]: how far the head turns (46°), about the vertical through HEAD
TURN_START, TURN_STOP = 1.0, 2.2  # [s]: after gravity's first pull on the strands has rung out
TURN_RAMP = 0.4  # [s]: the head speeds up, and slows down, over this long
#: The head's angular velocity at full speed [rad/s]: each ramp gains half its length.
TURN_RATE = TURN_ANGLE / (TURN_STOP - TURN_START - TURN_RAMP)
#: The roots' largest distance from the hairline circle and from the turned positions [m]:
#: round-off of positions of order 1 m.
ROOT_TOLERANCE = 1e-12
#: The measured period may differ this much (relative) from the hanging chain's: the method's
#: error (ωh)²/24 is 1e-6, the amplitude's θ₀²/16 is 3e-4; the higher modes shift the
#: crossings that the period is read from.
PERIOD_TOLERANCE = 0.01
#: ... and from the compound pendulum's, which is 2 % stiffer than a chain of the same length.
COMPOUND_TOLERANCE = 0.05
DESCRIPTION = "five strands of hair, 28 to 60 cm, swinging after the head turns and stops"


def strand_points(count: int, angle: float) -> np.ndarray:
    """A straight vertical strand of ``count`` points [m] hanging from the hairline at
    ``angle`` [degrees] round the back of the head."""
    phi = np.radians(angle)
    root = np.array(HEAD) + HAIRLINE_RADIUS * np.array([np.sin(phi), 0.0, -np.cos(phi)])
    return root - np.outer(SPACING * np.arange(count), [0.0, 1.0, 0.0])


HEAD_TURN = {
    "pivot": HEAD,
    "axis": (0.0, 1.0, 0.0),
    "angular_velocity": TURN_RATE,
    "start": TURN_START,
    "stop": TURN_STOP,
    "ramp": TURN_RAMP,
}


def build_scene(duration: float = DURATION, head: bool = True) -> SceneBuilder:
    """The five strands, their roots on the turning head (:data:`HEAD_TURN`); with ``head``,
    the head itself, for the picture."""
    builder = SceneBuilder(name="hair", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(
        method=METHOD, dt=DT, substeps=SUBSTEPS, duration=duration, record_every=1
    )
    for index, (count, angle) in enumerate(zip(POINTS, HAIRLINE_ANGLES, strict=True)):
        builder.add_hair(
            strand_points(count, angle),
            mass=MASS,
            stiffness=STIFFNESS,
            bending=BENDING,
            torsion=TORSION,
            damping=DAMPING,
            handle=HEAD_TURN,
            radius=0.004,
            color=(0.35, 0.2, 0.1),
            name=f"strand{index}",
        )
    if head:
        # A ball inside the hairline, held at its centre by a stiff anchor: it touches nothing
        # (the scene has no contacts) and looks the same however it turns, so it need not
        # turn with the roots. It is there to be seen.
        builder.add_body(
            "sphere", radius=0.95 * HAIRLINE_RADIUS, density=1000.0, position=HEAD,
            color=(0.87, 0.72, 0.6), name="head",
            anchor={"point": (0.0, 0.0, 0.0), "at": HEAD, "stiffness": 1e5, "damping": 50.0},
        )  # fmt: skip
    return builder


def _strand_stiffness(count: int, tensions: np.ndarray | None = None) -> np.ndarray:
    """The 1-D stiffness matrix of one strand's springs along it ((count, count), [N/m]), or
    with ``tensions`` [N] per spring, the sideways stiffness ``Σ f/l`` of the stretched
    springs (their order: the edge, bending and torsion springs by first point)."""
    matrix = np.zeros((count, count))
    index = 0
    for gap, k in ((1, STIFFNESS), (2, BENDING), (3, TORSION)):
        for i in range(count - gap):
            j = i + gap
            value = k if tensions is None else tensions[index] / (gap * SPACING)
            matrix[[i, j], [i, j]] += value
            matrix[i, j] -= value
            matrix[j, i] -= value
            index += 1
    return matrix


def static_stretch(count: int) -> tuple[np.ndarray, np.ndarray]:
    """A hanging strand's exact statics: each edge's stretch ``l/L − 1`` and every spring's
    tension [N] (edge, bending, torsion), from ``K y = −m g`` with the root held."""
    stiffness = _strand_stiffness(count)
    drop = np.zeros(count)
    drop[1:] = np.linalg.solve(stiffness[1:, 1:], -MASS * GRAVITY * np.ones(count - 1))
    tensions = [
        k * (drop[i] - drop[i + gap])
        for gap, k in ((1, STIFFNESS), (2, BENDING), (3, TORSION))
        for i in range(count - gap)
    ]
    edges = (drop[:-1] - drop[1:]) / SPACING
    return edges, np.array(tensions)


def chain_period(count: int) -> float:
    """The period [s] of the slowest small sideways swing of a hanging strand: the springs
    under their static tensions ``f`` resist a sideways offset by ``f/l`` each; the root
    held."""
    _, tensions = static_stretch(count)
    sideways = _strand_stiffness(count, tensions)[1:, 1:] / MASS
    return float(2.0 * np.pi / np.sqrt(np.linalg.eigvalsh(sideways).min()))


def compound_pendulum_period(count: int) -> float:
    """The period [s] of the strand made rigid, swinging about its root by small angles:
    ``2π √(I / (M g d))`` with ``I = Σ m s²`` and ``M d = Σ m s`` over its points at ``s``
    below the root; ``2π √(2L / 3g)`` for a uniform rod of length ``L``."""
    below = SPACING * np.arange(1, count)
    return float(2.0 * np.pi * np.sqrt((below**2).sum() / (GRAVITY * below.sum())))


def measured_period(t: np.ndarray, sideways: np.ndarray) -> float:
    """Twice the mean time [s] between the zero crossings of ``sideways``, the mean sideways
    offset of a strand's points per frame (crossings found by linear interpolation)."""
    side = np.sign(sideways)
    at = np.flatnonzero(side[1:] * side[:-1] < 0)
    crossing = t[at] - sideways[at] * (t[at + 1] - t[at]) / (sideways[at + 1] - sideways[at])
    if crossing.size < 2:
        return float("nan")
    return float(2.0 * (crossing[-1] - crossing[0]) / (crossing.size - 1))


def root_motion(t: np.ndarray, roots: np.ndarray) -> dict[str, Any]:
    """How the recorded ``roots`` ``(frames, strands, 3)`` [m] at times ``t`` [s] followed the
    head: the largest distance [m] from the hairline circle, the largest spread [rad] of their
    turn angles at a frame, whether they held still (bit for bit) before the turn and after it,
    and the largest error [rad] of the final turn against :data:`TURN_ANGLE`."""
    offset = roots - np.array(HEAD)
    radius = np.hypot(offset[..., 0], offset[..., 2])
    off_circle = np.maximum(np.abs(radius - HAIRLINE_RADIUS), np.abs(offset[..., 1]))
    # The angle turned (right-handed about +y) since the first frame.
    start = np.arctan2(offset[0, :, 0], offset[0, :, 2])
    turned = np.angle(np.exp(1j * (np.arctan2(offset[..., 0], offset[..., 2]) - start)))
    before, after = t < TURN_START, t >= TURN_STOP
    return {
        "off_hairline_m": float(off_circle.max()),
        "turn_spread_rad": float(np.ptp(turned, axis=1).max()),
        "still_before_turn": bool(
            np.array_equal(roots[before], np.broadcast_to(roots[0], roots[before].shape))
        ),
        "still_after_stop": bool(
            np.array_equal(roots[after], np.broadcast_to(roots[-1], roots[after].shape))
        ),
        "turn_rad": TURN_ANGLE,
        "turn_error_rad": float(np.abs(turned[-1] - TURN_ANGLE).max()),
        "tolerance_m": ROOT_TOLERANCE,
    }


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    model = build_scene(duration).build()
    simulation = Simulation(model)
    # The advisor linearizes the strands (the head, a rigid body, couples to nothing).
    strands = Simulation(build_scene(duration, head=False).build())
    advised = largest_stable_step(strands.system, strands.integrator, strands.raw_state)
    with one_thread():
        recording = simulation.record(until=duration)
    output.recordings[METHOD] = recording
    t, points = recording.time, recording["particle_position"]
    roots = points[:, model.particle_pinned]
    pairs, _ = spring_pairs(model)
    stretch = strain(model, points, pairs[np.abs(pairs[:, 1] - pairs[:, 0]) == 1])
    after = t >= TURN_STOP
    strands = []
    for group, count in zip(model.particle_groups, POINTS, strict=True):
        first = group.start
        swing = sideways(points[:, first : first + count])
        length = SPACING * (count - 1)
        strands.append(
            {
                "points": count,
                "length_m": length,
                "period_s": measured_period(t[after], swing[after].mean(axis=1)),
                "hanging_chain_period_s": chain_period(count),
                "compound_pendulum_period_s": compound_pendulum_period(count),
                "uniform_rod_period_s": float(2 * np.pi * np.sqrt(2 * length / (3 * GRAVITY))),
                "amplitude_rad": float(np.abs(swing[after, -1]).max()) / length,
                "static_stretch": float(static_stretch(count)[0].max()),
            }
        )
    largest_static = max(s["static_stretch"] for s in strands)
    amplitude = max(s["amplitude_rad"] for s in strands)
    output.figures["hair"] = _figure(model, t, points, strands)
    return {
        "method": METHOD,
        "dt": DT,
        "substeps": SUBSTEPS,
        "advisor_largest_stable_step_s": advised,
        "head_turn": HEAD_TURN,
        "roots": root_motion(t, roots),
        "largest_stretch": {
            "measured": float(stretch.max()),
            "bound_2_static_1_plus_amplitude2": 2.0 * largest_static * (1.0 + amplitude**2),
            "static": largest_static,
        },
        "strands": strands,
        "period_tolerance": PERIOD_TOLERANCE,
        "compound_tolerance": COMPOUND_TOLERANCE,
    }


def sideways(strand: np.ndarray) -> np.ndarray:
    """The offsets [m] of a strand's points from its root, ``(frames, count − 1)``, along the
    hairline's tangent at the root (the direction the head turns it) in each frame: how far
    the strand lags behind the turning head, and its swing after the head stops."""
    root = strand[:, :1]
    radial = root - np.array(HEAD)
    tangent = np.cross([0.0, 1.0, 0.0], radial)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    return np.einsum(
        "fpk,fpk->fp", strand[:, 1:] - root, np.broadcast_to(tangent, strand[:, 1:].shape)
    )


def _figure(model: Model, t: np.ndarray, points: np.ndarray, strands: list[dict]) -> Figure:
    """Each strand's swing along the hairline, and the periods against the chain and the
    rigid rod."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12, 4.6), layout="constrained")
    swing, periods = figure.subplots(1, 2)
    swing.axvspan(TURN_START, TURN_STOP, color="0.9", label="the head turns")
    colors = distinct_colors(len(strands))
    for group, strand, color in zip(model.particle_groups, strands, colors, strict=True):
        offsets = sideways(points[:, group.start : group.start + strand["points"]])
        swing.plot(t, 100 * offsets[:, -1], lw=1.0, color=color,
                   label=f"{100 * strand['length_m']:.0f} cm")  # fmt: skip
    swing.set_xlabel("t [s]")
    swing.set_ylabel("tip's offset from the root along the hairline [cm]")
    swing.set_title("The head turns, stops, and the strands swing")
    swing.margins(y=0.3)
    legend_below(swing)
    length = np.array([s["length_m"] for s in strands])
    span = np.linspace(0.9 * length.min(), 1.05 * length.max(), 50)
    periods.plot(span, 2 * np.pi * np.sqrt(2 * span / (3 * GRAVITY)), "k:",
                 label="uniform rod 2π√(2L/3g)")  # fmt: skip
    periods.plot(length, [s["compound_pendulum_period_s"] for s in strands], "^", mfc="none",
                 ms=9, label="the strand made rigid")  # fmt: skip
    periods.plot(length, [s["hanging_chain_period_s"] for s in strands], "s", mfc="none",
                 ms=9, label="hanging chain (static tensions)")  # fmt: skip
    periods.plot(length, [s["period_s"] for s in strands], "o", label="measured")
    periods.set_xlabel("strand length L [m]")
    periods.set_ylabel("period [s]")
    periods.set_title("Small swings: a chain, a little slower than a rod")
    legend_below(periods)
    return figure


register_demo(
    Demo(
        "hair",
        BUILTIN_DEMOS["hair"].summary,
        DURATION,
        run,
        picture=True,
    )
)
