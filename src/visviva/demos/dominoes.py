"""Demo ``dominoes``: a row of dominoes topples in turn, and the wave's speed scales as
``√(g h)``.

Twenty dominoes 48 mm tall, 24 mm wide and 7.5 mm thick (1050 kg/m³) stand in a row, a pitch
of 0.6 of their height (28.8 mm) apart; the first is tipped forward by 15° about its front
bottom edge and let go. Domino on domino the friction is 0.3 and the restitution 0; on the
floor the friction is 0.6 (the floor's 1.2 and a domino's 0.3 by the pair rule), enough that
they tip rather than slide. Each falls onto the next and comes to lean on it; the leaning
dominoes ride on the one falling in front, and the wave settles to a steady speed within a few
dominoes (Shaw 1978; van Leeuwen 2010).

A domino has fallen when its tilt passes 45° (the moment is interpolated between recorded
frames); the wave's speed is the row's length over the time between the first and the last
falling, and, steadier, the slope of a line fitted to where and when the dominoes from the
sixth on fell. By dimensional analysis (McLachlan et al. 1983) a row of dominoes of the same
shape, spacing, friction and restitution runs at ``v = √(g h) G(d/h, ...)``: the same row
four times larger, stepped at twice the step, must run twice as fast and take twice as long.
It does to the last bit, which says that the contact stage holds no length or speed of its
own (its allowances are fractions of the bodies' sizes, its resting speed 2|g|h) and that
scaling lengths by 4 and times by 2 is exact in binary floating point. The wave also slows
as the friction between dominoes grows (the leaning dominoes slide down the one in front of
them); the row is run again with 0.1 and 0.5.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry.quaternions import quaternion_matrix
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..simulation.recording import Recording
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

COUNT = 20
HEIGHT, WIDTH, THICKNESS = 0.048, 0.024, 0.0075  # [m]
PITCH = 0.6 * HEIGHT  # [m]
DENSITY = 1050.0  # [kg/m³]
TIP = np.radians(15.0)  # the first domino's tilt [rad]
FRICTION = 0.3  # domino on domino
FLOOR = 0.6  # domino on floor, by the pair rule √(μ_floor μ_domino)
G = 9.81  # [m/s²]
DT = 1e-3  # [s] for the 48 mm dominoes; √(size) times it for others
RECORD_EVERY = 4
FALLEN = 45.0  # tilt [°] past which a domino has fallen
STEADY_FROM = 5  # the steady speed is fitted from the sixth domino on
SCALE = 4.0  # the larger row's
OTHER_FRICTIONS = (0.1, 0.5)


def scene(duration: float, scale: float = 1.0, friction: float = FRICTION) -> SceneBuilder:
    """The row, ``scale`` times the size (stepped at ``√scale`` times the step), with
    ``friction`` between dominoes."""
    h, w, t = HEIGHT * scale, WIDTH * scale, THICKNESS * scale
    builder = SceneBuilder(name="dominoes")
    builder.set_world(gravity=(0.0, -G, 0.0))
    builder.set_integration(method="symplectic_euler", dt=DT * np.sqrt(scale), duration=duration,
                            record_every=RECORD_EVERY)  # fmt: skip
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=0.0,
                         friction=FLOOR**2 / friction)  # fmt: skip
    for k in range(COUNT):
        x = k * PITCH * scale
        if k == 0:  # turned by −TIP about z around its front bottom edge (x + t/2, 0)
            c, s = np.cos(TIP), np.sin(TIP)
            centre = (x + 0.5 * t - 0.5 * t * c + 0.5 * h * s, 0.5 * t * s + 0.5 * h * c, 0.0)
            turn = (np.cos(0.5 * TIP), 0.0, 0.0, -np.sin(0.5 * TIP))
        else:
            centre, turn = (x, 0.5 * h, 0.0), (1.0, 0.0, 0.0, 0.0)
        shade = 0.25 + 0.6 * k / (COUNT - 1)
        builder.add_body("box", size=(t, h, w), density=DENSITY, position=centre,
                         orientation=turn, restitution=0.0, friction=friction,
                         color=(0.95, shade, 0.2), name=f"domino {k + 1}")  # fmt: skip
    builder.add_body_contacts()
    return builder


def tilts(recording: Recording) -> np.ndarray:
    """Each domino's tilt from upright [°] per frame, ``(frames, COUNT)``."""
    up = quaternion_matrix(recording["body_orientation"])[..., 1, 1]  # world y of body y
    return np.degrees(np.arccos(np.clip(up, -1.0, 1.0)))


def wave(recording: Recording, scale: float = 1.0) -> dict[str, Any]:
    """When each domino fell (tilt past :data:`FALLEN`, interpolated), how many fell, and the
    wave's speed."""
    t, tilt = recording.time, tilts(recording)
    fell = np.full(COUNT, np.nan)
    for k in range(COUNT):
        past = np.flatnonzero(tilt[:, k] > FALLEN)
        if past.size and past[0] > 0:
            i = past[0]
            share = (FALLEN - tilt[i - 1, k]) / (tilt[i, k] - tilt[i - 1, k])
            fell[k] = t[i - 1] + share * (t[i] - t[i - 1])
    fallen = int(np.isfinite(fell).sum())
    where = np.arange(COUNT) * PITCH * scale
    found: dict[str, Any] = {"fallen": fallen, "fall_times_s": fell.tolist(),
                             "final_tilts_deg": tilt[-1].tolist()}  # fmt: skip
    if fallen == COUNT:
        steady = np.polyfit(fell[STEADY_FROM:], where[STEADY_FROM:], 1)[0]
        found |= {
            "first_to_last_speed_m_per_s": float(where[-1] / (fell[-1] - fell[0])),
            "steady_speed_m_per_s": float(steady),
            "steady_speed_over_sqrt_g_h": float(steady / np.sqrt(G * HEIGHT * scale)),
        }
    return found


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    recording = Simulation(scene(duration).build()).record(until=duration)
    output.recordings["dominoes"] = recording
    row = wave(recording)
    larger_time = duration * np.sqrt(SCALE)
    larger = Simulation(scene(larger_time, scale=SCALE).build()).record(until=larger_time)
    big = wave(larger, SCALE)
    others = {}
    for friction in OTHER_FRICTIONS:
        other = Simulation(scene(duration, friction=friction).build()).record(until=duration)
        others[friction] = wave(other)
    ratio = None
    if "steady_speed_m_per_s" in row and "steady_speed_m_per_s" in big:
        ratio = big["steady_speed_m_per_s"] / row["steady_speed_m_per_s"]

    figure = Figure(figsize=(12, 4.5), layout="constrained")
    topple, front = figure.subplots(1, 2)
    tilt = tilts(recording)
    for k in range(COUNT):
        topple.plot(recording.time, tilt[:, k], lw=0.9, color=(0.9, 0.25 + 0.6 * k / COUNT, 0.2))
    topple.axhline(FALLEN, color="grey", lw=0.6, ls="--")
    topple.set_xlabel("t [s]")
    topple.set_ylabel("tilt [°]")
    topple.set_title(f"{row['fallen']} of {COUNT} dominoes fall, one after another", fontsize=10)
    unit = np.sqrt(HEIGHT / G)  # [s]
    runs = [
        (f"h = {1e3 * HEIGHT:.0f} mm, μ = {FRICTION:g}", row, 1.0, "o"),
        (f"h = {1e3 * HEIGHT * SCALE:.0f} mm, μ = {FRICTION:g}", big, SCALE, "x"),
    ]
    runs += [(f"h = {1e3 * HEIGHT:.0f} mm, μ = {f:g}", others[f], 1.0, ".")
             for f in OTHER_FRICTIONS]  # fmt: skip
    for label, found, scale, marker in runs:
        fell = np.array(found["fall_times_s"])
        speed = found.get("steady_speed_over_sqrt_g_h")
        tag = "" if speed is None else f": v = {speed:.2f} √(gh)"
        front.plot(fell / (unit * np.sqrt(scale)), np.arange(COUNT) * PITCH / HEIGHT, marker,
                   label=label + tag, ms=5 if marker != "." else 7)  # fmt: skip
    front.set_xlabel("time it fell / √(h/g)")
    front.set_ylabel("position in the row / h")
    front.set_title("Where and when each fell: the larger row runs on the same line",
                    fontsize=10)  # fmt: skip
    legend_below(front)
    output.figures["dominoes"] = figure
    return {
        "domino_size_m": [HEIGHT, WIDTH, THICKNESS],
        "pitch_over_height": PITCH / HEIGHT,
        "row": row,
        f"row_{SCALE:g}_times_larger": big,
        "larger_over_smaller_steady_speed": ratio,
        "expected_ratio_sqrt_scale": float(np.sqrt(SCALE)),
        "other_frictions": {f"{f:g}": found for f, found in others.items()},
    }


register_demo(
    Demo(
        "dominoes",
        BUILTIN_DEMOS["dominoes"].summary,
        1.5,
        run,
        picture=True,
    )
)
