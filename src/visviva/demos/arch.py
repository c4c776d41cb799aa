"""Demo ``arch``: a catenary arch of stone blocks stands with enough friction and slides
apart without (seed 000's arch).

**The arch.** Its centre line is the inverted catenary ``y = a (cosh(s/a) − cosh(x/a))``,
``a`` = 1 m, standing on the floor at ``x = ±s`` where its slope is ``sinh(s/a) = 3``: a
span of 3.64 m and a rise of 2.16 m. The line is cut into 17 voussoirs of equal length along
it (0.35 m), 0.25 m thick across it and 0.5 m deep; each joint is a plane square to the
curve, so neighbouring blocks share a face exactly (no gap, no overlap), and the two feet are
cut level with the floor. Each block is a convex mesh (a quadrilateral prism) of 2400 kg/m³,
about 105 kg. Under its own weight a uniform chain hangs as a catenary, so this arch carries
its weight along its centre line, square to every joint, with a horizontal thrust
``H = w a``, a third of the half-arch's weight ``w a sinh(s/a)``: that thrust line lies in
the middle of every block, whatever their thickness, and the joints need no friction.

**The feet** do: they stand on level ground and must resist the thrust by friction,
``μ ≥ H/V``. A thick arch can carry its weight along other thrust lines too, as long as each
crosses every joint within the block; the one of least thrust, found here by limit analysis
of the blocks (Heyman 1966: for each thrust H the crown heights at which the line crosses
every joint inside it; the least H for which some crown height serves, and the friction
each joint then needs), touches the extrados at the crown and the intrados at the haunches,
and needs ``μ* = H_min/V`` = 0.26 at the feet instead of 1/3.

**The runs.** Arches on their own slabs (box colliders), block on block and block on slab
with the same friction μ (restitution 0), symplectic Euler at h = 1/240 s, 20 sweeps:
μ = 0.6 and μ = 0.2 side by side (the recording), and μ = 0.24 … 0.3 around μ* (a second
recording). At 0.6 the arch settles by a fraction of a millimetre (its joints sink by the
contact stage's allowance) and stands, at rest to 1e-9 m/s for as long as it is run; at 0.2
the feet slide out and the keystone falls to the ground in about a second. Around the limit
the arches fall up to μ = 0.26 (in 2 s) and stand from 0.28 (settling by 2 mm): the
simulated blocks need a few per cent more friction than the limit analysis's rigid ones.

The summary gives each arch's largest block displacement, its keystone's drop, its feet's
slide and its final speed, the smallest friction at which an arch stood, the largest at which
one fell, and μ*; the figure shows the blocks with the two thrust lines and every keystone's
drop over time.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.colors import shades
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

CATENARY = 1.0  # a [m]
SLOPE = 3.0  # sinh(s/a): the centre line's slope at the feet
FOOT = CATENARY * np.arcsinh(SLOPE)  # s [m]
RISE = CATENARY * (np.cosh(FOOT / CATENARY) - 1.0)  # [m]
BLOCKS = 17
KEYSTONE = BLOCKS // 2
THICKNESS = 0.25  # across the centre line [m]
DEPTH = 0.5  # along z [m]
DENSITY = 2400.0  # [kg/m³]
G = 9.81  # [m/s²]
DT = 1.0 / 240.0  # [s]
RECORD_EVERY = 4  # 60 frames a second
FRICTIONS = (0.6, 0.2)  # the recording's arches
SWEEP = (0.24, 0.26, 0.28, 0.3)  # around the limit
SPACING = 1.5  # between arches, along z [m]
STOOD = 0.01  # an arch whose keystone dropped less than this stands [m]
STONE = ((0.78, 0.72, 0.62), (0.7, 0.64, 0.55))
KEY_COLOR = (0.85, 0.55, 0.35)


def joints() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The joints' centres on the curve, inner (intrados) and outer (extrados) ends [m],
    ``(BLOCKS + 1, 2)`` each, in the arch's plane (x, y): square to the curve, but the two
    at the feet, level with the floor."""
    half = CATENARY * SLOPE  # half the centre line's length
    x = CATENARY * np.arcsinh(np.linspace(-half, half, BLOCKS + 1) / CATENARY)
    y = CATENARY * (np.cosh(FOOT / CATENARY) - np.cosh(x / CATENARY))
    stretch = np.cosh(x / CATENARY)
    outward = np.stack([np.sinh(x / CATENARY), np.ones_like(x)], axis=1) / stretch[:, None]
    along = np.stack([np.ones_like(x), -np.sinh(x / CATENARY)], axis=1) / stretch[:, None]
    centre = np.stack([x, y], axis=1)
    inner = centre - 0.5 * THICKNESS * outward
    outer = centre + 0.5 * THICKNESS * outward
    for end in (0, BLOCKS):  # slid along the (straight) edges down to the floor
        for side in (inner, outer):
            side[end] -= side[end, 1] / along[end, 1] * along[end]
    return centre, inner, outer


def outlines() -> list[np.ndarray]:
    """Each block's outline (x, y) [m], counter-clockwise, ``(4, 2)``."""
    _, inner, outer = joints()
    shapes = []
    for k in range(BLOCKS):
        corners = np.array([inner[k], inner[k + 1], outer[k + 1], outer[k]])
        if _area(corners) < 0.0:
            corners = corners[::-1]
        shapes.append(corners)
    return shapes


def _area(polygon: np.ndarray) -> float:
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float((x * np.roll(y, -1) - np.roll(x, -1) * y).sum())


def _centroid(polygon: np.ndarray) -> np.ndarray:
    x, y = polygon[:, 0], polygon[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * cross.sum()
    return np.array([((x + np.roll(x, -1)) * cross).sum(), ((y + np.roll(y, -1)) * cross).sum()]
                    ) / (6.0 * area)  # fmt: skip


def prism(outline: np.ndarray, depth: float) -> tuple[np.ndarray, np.ndarray]:
    """A counter-clockwise outline (x, y) extruded over ``±depth/2`` along z: vertices and
    triangles (counter-clockwise seen from outside)."""
    n = outline.shape[0]
    vertices = np.concatenate([np.column_stack([outline, np.full(n, z)])
                               for z in (-0.5 * depth, 0.5 * depth)])  # fmt: skip
    triangles = []
    for k in range(1, n - 1):
        triangles.append((0, k + 1, k))  # the back face, seen from −z
        triangles.append((n, n + k, n + k + 1))
    for k in range(n):
        j = (k + 1) % n
        triangles.extend([(k, j, n + j), (k, n + j, n + k)])
    return vertices, np.array(triangles)


def voussoirs() -> list[tuple[np.ndarray, float, np.ndarray, np.ndarray]]:
    """Each block's centroid (x, y) [m], turn about z [rad] (its chord's direction), and its
    mesh in its own axes (origin at the centroid): vertices and triangles."""
    centre, _, _ = joints()
    blocks = []
    for k, outline in enumerate(outlines()):
        middle = _centroid(outline)
        chord = centre[k + 1] - centre[k]
        turn = float(np.arctan2(chord[1], chord[0]))
        c, s = np.cos(turn), np.sin(turn)
        local = (outline - middle) @ np.array([[c, -s], [s, c]])  # Rᵀ (p − c)
        vertices, triangles = prism(local, DEPTH)
        blocks.append((middle, turn, vertices, triangles))
    return blocks


def scene(frictions: tuple[float, ...], duration: float) -> SceneBuilder:
    """Arches side by side along −z, one per friction, each on a slab of its friction."""
    builder = SceneBuilder(name="catenary arches")
    builder.set_world(gravity=(0.0, -G, 0.0))
    builder.set_integration(method="symplectic_euler", dt=DT, duration=duration,
                            record_every=RECORD_EVERY)  # fmt: skip
    blocks = voussoirs()
    for m, friction in enumerate(frictions):
        z = 0.0 - SPACING * m
        builder.add_collider("box", center=(0.0, -0.1, z), size=(10.0, 0.2, 0.9 * SPACING),
                             restitution=0.0, friction=friction, color=(0.45, 0.5, 0.4),
                             name=f"slab, μ = {friction:g}")  # fmt: skip
        for k, (middle, turn, vertices, triangles) in enumerate(blocks):
            builder.add_body(
                "mesh", vertices=vertices.tolist(), triangles=triangles.tolist(),
                density=DENSITY, position=(float(middle[0]), float(middle[1]), z),
                orientation=(float(np.cos(0.5 * turn)), 0.0, 0.0, float(np.sin(0.5 * turn))),
                restitution=0.0, friction=friction,
                color=KEY_COLOR if k == KEYSTONE else STONE[k % 2],
                name=f"μ = {friction:g}, block {k + 1}",
            )  # fmt: skip
    builder.add_body_contacts()
    return builder


def limit_analysis() -> dict[str, Any]:
    """The thrust lines the right half of the arch can carry its weight along (the left is
    its mirror image): crossing the crown's vertical section horizontally at height ``y_c``
    with thrust ``H``, and every joint within the block. Returns the least and most thrust
    [N] and, over the feasible thrusts, the least friction that every joint (the foot
    included) can hold the line with, ``μ*``; the least-thrust line and the line nearest the
    centre line, each as the points where it crosses the crown and the joints."""
    shapes = outlines()
    _, inner, outer = joints()
    key = shapes[KEYSTONE]
    # The keystone's right half, clipped at x = 0.
    right = []
    for p, q in zip(key, np.roll(key, -1, axis=0), strict=True):
        if p[0] >= 0.0:
            right.append(p)
        if (p[0] >= 0.0) != (q[0] >= 0.0):
            right.append(p + p[0] / (p[0] - q[0]) * (q - p))
    pieces = [np.array(right)] + shapes[KEYSTONE + 1 :]
    area = np.array([abs(_area(p)) for p in pieces])
    weight = DENSITY * DEPTH * G * area  # [N]
    where = np.array([_centroid(p)[0] for p in pieces])
    crown = np.array(right)[np.isclose(np.array(right)[:, 0], 0.0)][:, 1]
    low, high = crown.min(), crown.max()
    # Joint j of the right half: between piece j and j + 1; the last is the foot.
    rows = range(KEYSTONE + 1, BLOCKS + 1)
    start, span = inner[rows], outer[rows] - inner[rows]
    loads = np.cumsum(weight)  # (J,)
    moments = np.cumsum(weight * where)
    thrusts = np.linspace(0.05, 1.5, 20001) * loads[-1]

    def crossing(thrust: np.ndarray, height: np.ndarray) -> np.ndarray:
        """Where the line crosses each joint, 0 at the intrados and 1 at the extrados."""
        a = moments - loads * start[:, 0] - thrust[..., None] * start[:, 1]
        b = thrust[..., None] * span[:, 1] + loads * span[:, 0]
        return (a + thrust[..., None] * height[..., None]) / b

    # For each thrust the crown heights that keep every crossing in [0, 1]: an interval.
    ends = np.stack([crossing(thrusts, np.full_like(thrusts, y)) for y in (low, high)])
    slope = (ends[1] - ends[0]) / (high - low)  # d(crossing)/d(height), (H, J)
    with np.errstate(divide="ignore", invalid="ignore"):
        first = np.where(slope > 0, -ends[0] / slope, (1.0 - ends[0]) / slope) + low
        last = np.where(slope > 0, (1.0 - ends[0]) / slope, -ends[0] / slope) + low
    bottom = np.maximum(first.max(axis=1), low)
    top = np.minimum(last.min(axis=1), high)
    feasible = bottom <= top
    # The friction each joint needs to turn the force (H, −W) onto it.
    along = span / np.linalg.norm(span, axis=1)[:, None]
    force_x, force_y = thrusts[:, None], -loads[None, :]
    tangential = np.abs(force_x * along[:, 0] + force_y * along[:, 1])
    normal = np.abs(force_x * along[:, 1] - force_y * along[:, 0])
    needed = (tangential / normal).max(axis=1)
    best = int(np.argmin(np.where(feasible, needed, np.inf)))
    least = int(np.argmax(feasible))
    # The line nearest the centre line: the feasible thrust and crown height whose crossings
    # stray least from the middle of the joints.
    heights = np.linspace(low, high, 401)
    candidates = thrusts[feasible]
    candidates = candidates[np.linspace(0, candidates.size - 1, 401).astype(int)]
    stray = np.abs(crossing(candidates[:, None], heights[None, :]) - 0.5).max(axis=2)
    h_index, y_index = np.unravel_index(int(np.argmin(stray)), stray.shape)

    def line(thrust: float, height: float) -> np.ndarray:
        """Where the line crosses the crown's section and each joint (Moseley's line of
        resistance), (x, y) [m]."""
        u = crossing(np.array(thrust), np.array(height))
        return np.concatenate([[[0.0, height]], start + u[:, None] * span])

    central = candidates[h_index]
    return {
        "half_weight_N": float(loads[-1]),
        "least_thrust_N": float(thrusts[least]),
        "most_thrust_N": float(thrusts[feasible][-1]),
        "centre_line_thrust_N": float(loads[-1] / SLOPE),
        "critical_friction": float(needed[best]),
        "least_thrust_friction_at_foot": float(thrusts[least] / loads[-1]),
        "least_thrust_line": line(float(thrusts[least]), float(bottom[least])),
        "central_line": line(float(central), float(heights[y_index])),
        "central_line_stray_from_middle": float(stray[h_index, y_index]),
    }


def watch(recording: Any, count: int) -> list[dict[str, Any]]:
    """Per arch of a recording: its largest block displacement, its keystone's drop (over
    time and at the end) and its feet's slide [m], and its fastest block's speed over the
    last frame [m/s]."""
    origin = recording["body_origin"]
    found = []
    for m in range(count):
        arch = origin[:, m * BLOCKS : (m + 1) * BLOCKS]
        moved = np.linalg.norm(arch - arch[0], axis=2)
        drop = arch[0, KEYSTONE, 1] - arch[:, KEYSTONE, 1]
        slide = np.abs(arch[:, [0, BLOCKS - 1], 0] - arch[0, [0, BLOCKS - 1], 0]).max(axis=1)
        last = np.linalg.norm(arch[-1] - arch[-2], axis=1) / (
            recording.time[-1] - recording.time[-2]
        )
        found.append({
            "largest_displacement_m": float(moved.max()),
            "keystone_drop_m": float(drop[-1]),
            "largest_keystone_drop_m": float(drop.max()),
            "feet_slide_m": float(slide[-1]),
            "final_speed_m_per_s": float(last.max()),
            "stands": bool(drop.max() < STOOD),
            "_drop": drop,
        })  # fmt: skip
    return found


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    limits = limit_analysis()
    arches: dict[float, dict[str, Any]] = {}
    times = {}
    for name, frictions in (("friction_0.6_and_0.2", FRICTIONS), ("friction_sweep", SWEEP)):
        recording = Simulation(scene(frictions, duration).build()).record(until=duration)
        output.recordings[name] = recording
        for friction, found in zip(frictions, watch(recording, len(frictions)), strict=True):
            arches[friction] = found
            times[friction] = recording.time
    stood = [f for f, found in arches.items() if found["stands"]]
    fell = [f for f, found in arches.items() if not found["stands"]]

    figure = Figure(figsize=(13, 5), layout="constrained")
    elevation, drops = figure.subplots(1, 2, width_ratios=(1.1, 1.0))
    from matplotlib.patches import Polygon

    for k, outline in enumerate(outlines()):
        color = KEY_COLOR if k == KEYSTONE else STONE[k % 2]
        elevation.add_patch(Polygon(outline, closed=True, fc=color, ec="k", lw=0.6))
    for key, label, style in (
        ("central_line", "thrust line nearest the centre", "b-"),
        ("least_thrust_line", f"least thrust: μ ≥ {limits['critical_friction']:.3f} at the feet",
         "r--"),
    ):  # fmt: skip
        line = limits[key]
        both = np.concatenate([line[::-1] * [-1.0, 1.0], line])
        elevation.plot(both[:, 0], both[:, 1], style, lw=1.2, label=label)
    elevation.axhline(0.0, color="k", lw=0.8)
    elevation.set_aspect("equal")
    elevation.set_xlabel("x [m]")
    elevation.set_ylabel("y [m]")
    elevation.set_title(f"{BLOCKS} voussoirs on the catenary, joints square to it", fontsize=10)
    legend_below(elevation)
    # Green: it stands, red: it falls; within each, a shade of its own for each μ.
    colors = {}
    for stands, family in ((True, "Greens"), (False, "Reds")):
        chosen = sorted(f for f in arches if arches[f]["stands"] == stands)
        colors |= dict(zip(chosen, shades(len(chosen), family), strict=True))
    for friction in sorted(arches, reverse=True):
        drop = arches[friction]["_drop"]
        drops.semilogy(
            times[friction],
            np.maximum(drop, 1e-6),
            label=f"μ = {friction:g}",
            color=colors[friction],
            lw=1.8 if friction in FRICTIONS else 1.0,  # the recording's arches: bold
        )
    drops.axhline(STOOD, color="grey", lw=0.6, ls="--")
    drops.set_xlabel("t [s]")
    drops.set_ylabel("keystone's drop [m]")
    drops.set_title(f"Stands from μ = {min(stood, default=float('nan')):g}, falls up to "
                    f"μ = {max(fell, default=float('nan')):g} (limit analysis: "
                    f"{limits['critical_friction']:.3f})", fontsize=10)  # fmt: skip
    legend_below(drops)
    output.figures["arch"] = figure
    for found in arches.values():
        del found["_drop"]
    return {
        "span_m": 2.0 * FOOT,
        "rise_m": RISE,
        "blocks": BLOCKS,
        "block_mass_kg": [float(DENSITY * DEPTH * abs(_area(o))) for o in outlines()],
        "thickness_m": THICKNESS,
        "largest_joint_gap_or_overlap_m": joint_mismatch(),
        "limit_analysis": {k: v for k, v in limits.items() if not k.endswith("line")},
        "arches": {f"{f:g}": found for f, found in sorted(arches.items())},
        "smallest_friction_that_stood": min(stood, default=None),
        "largest_friction_that_fell": max(fell, default=None),
    }


def joint_mismatch() -> float:
    """The largest distance [m] between a joint's corners as the two blocks meeting there
    have them (0 to round-off: neighbours share their joint faces)."""
    worst = 0.0
    blocks = voussoirs()
    placed = []
    for middle, turn, vertices, _ in blocks:
        c, s = np.cos(turn), np.sin(turn)
        placed.append(vertices[:, :2] @ np.array([[c, s], [-s, c]]) + middle)
    for k in range(BLOCKS - 1):
        ours, theirs = placed[k], placed[k + 1]
        gaps = np.linalg.norm(ours[:, None] - theirs[None], axis=2).min(axis=1)
        shared = np.sort(gaps)[:4]  # the joint's corners, two on each face
        worst = max(worst, float(shared.max()))
    return worst


register_demo(
    Demo(
        "arch",
        BUILTIN_DEMOS["arch"].summary,
        4.0,
        run,
        picture=True,
    )
)
