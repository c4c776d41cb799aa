"""Demo ``cradle``: Newton's cradle, its impacts resolved one contact at a time and all
together (issue 27's simultaneous impacts).

Five steel balls (radius 25 mm, 0.51 kg) hang in a touching row from pivots 20 cm above
their centres; the first is raised by 30° and let go. Each ball hangs by its ``anchor``: the
point of the body 20 cm above its centre (the top of a string that is part of the ball) held
at its pivot by a stiff damped spring (k = 10⁴ N/m, c = 2 N·s/m): a pendulum, its string
stretched by ``m g / k`` = 0.5 mm at rest, where every ball starts so that the row touches
exactly. The balls are steel on steel with restitution 1 and no friction.

The same cradle is run twice:

- ``impacts="simultaneous"``: the impacts of a step are resolved together by generalized
  reflections (Smith et al. 2012): the first ball stops, the blow travels down the row in
  four rounds and the last ball swings out to 99 % of the release height while the middle
  three stay where they hang; the blow comes back, and so on. The balls meet at their
  centres, so the striker keeps its turn and the far ball leaves without one; the anchors'
  springs take the mismatch with the pendulum's swing (``I/(I + m L²)`` = 0.6 % of the
  energy from each) and their dampers spend it: each impact passes on 99.4 % of the speed
  and 98.8 % of the energy;
- ``impacts="sequential"``: the impact is one more target of the sequential-impulse sweeps
  that hold resting contacts, which share it at once: the striker bounces off the four
  touching balls as if they were one body of mass ``4m``, at ``(1 − 4)/(1 + 4) = −0.6`` of
  its speed, and the four leave together at ``2/5`` of it (heights ``0.36 h`` and ``0.16 h``).

Both are recorded (the first, ``simultaneous``, is the video's; the strings are drawn as lines
from each pivot to the top of its ball). The summary gives the height each ball reaches after
the first impact as a fraction of the release height, the balls' speeds just before and after
it (from the recorded positions), and how many of the run's impacts passed the blow to the far
end ball. The figure shows each ball's horizontal velocity and height over time.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..geometry.quaternions import quaternion_rotate
from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..simulation.recording import Recording
from ..viz.colors import distinct_colors
from ..viz.legends import shared_legend_below
from . import Demo, register_demo
from ._bodies import drawn_if_interrupted
from .catalogue import BUILTIN_DEMOS

COUNT = 5
RADIUS = 0.025  # [m]
DENSITY = 7850.0  # steel [kg/m³]
MASS = DENSITY * 4.0 / 3.0 * np.pi * RADIUS**3  # [kg]
LENGTH = 0.2  # pivot to ball centre [m]
RELEASE = np.radians(30.0)  # the first ball's angle when let go [rad]
STIFFNESS = 1e4  # of the anchors [N/m]
DAMPING = 2.0  # of the anchors [N·s/m]
G = 9.81  # [m/s²]
SAG = MASS * G / STIFFNESS  # a hanging ball's stretch of its anchor [m]
DT = 5e-4  # [s]: the anchor's stiffest mode, √(k (1/m + L²/I)) ≈ 1800 rad/s, is at ωh ≈ 0.9
RECORD_EVERY = 4  # a frame every 2 ms
PERIOD = 2.0 * np.pi * np.sqrt(LENGTH / G)  # small-swing period [s]
IMPACTS = ("simultaneous", "sequential")
STEEL = (0.72, 0.74, 0.78)
STRIKER = (0.85, 0.55, 0.35)
STRING = (0.35, 0.35, 0.35)


def pivots() -> np.ndarray:
    """Each ball's pivot [m], ``(COUNT, 3)``: a touching row along x, ``LENGTH`` above."""
    x = (np.arange(COUNT) - 0.5 * (COUNT - 1)) * 2.0 * RADIUS
    return np.stack([x, np.full(COUNT, LENGTH), np.zeros(COUNT)], axis=1)


def starts() -> tuple[np.ndarray, np.ndarray]:
    """Each ball's centre [m] and orientation (w, x, y, z) at the start: the hanging balls at
    rest on their stretched anchors (``SAG`` below ``LENGTH``), the first swung out by
    ``RELEASE`` with its anchor stretched by ``m g cos θ / k`` (at rest, the string holds the
    weight's component along it)."""
    centres = pivots() - [0.0, LENGTH + SAG, 0.0]
    turns = np.tile([1.0, 0.0, 0.0, 0.0], (COUNT, 1))
    reach = LENGTH + SAG * np.cos(RELEASE)
    centres[0] = pivots()[0] + reach * np.array([-np.sin(RELEASE), -np.cos(RELEASE), 0.0])
    # its body y axis (to the pivot) turned by −θ about z
    turns[0] = [np.cos(-0.5 * RELEASE), 0.0, 0.0, np.sin(-0.5 * RELEASE)]
    return centres, turns


def scene(impacts: str, duration: float) -> SceneBuilder:
    """The cradle with its impacts resolved ``impacts`` (``"simultaneous"`` or
    ``"sequential"``)."""
    builder = SceneBuilder(name=f"Newton's cradle ({impacts} impacts)")
    builder.set_world(gravity=(0.0, -G, 0.0))
    builder.set_integration(method="velocity_verlet", dt=DT, duration=duration,
                            record_every=RECORD_EVERY)  # fmt: skip
    # The bar the strings hang from, its underside at the pivots (drawn; nothing reaches it).
    builder.add_collider("box", center=(0.0, 0.206, 0.0), size=(0.31, 0.012, 0.03),
                         color=(0.3, 0.3, 0.32), name="bar")  # fmt: skip
    centres, turns = starts()
    for k in range(COUNT):
        builder.add_body(
            "sphere", radius=RADIUS, density=DENSITY, position=tuple(centres[k]),
            orientation=tuple(turns[k]), restitution=1.0, friction=0.0, name=f"ball {k + 1}",
            color=STRIKER if k == 0 else STEEL,
            anchor={"point": (0.0, LENGTH, 0.0), "at": tuple(pivots()[k]),
                    "stiffness": STIFFNESS, "damping": DAMPING},
        )  # fmt: skip
    builder.add_body_contacts(impacts=impacts)
    return builder


def with_strings(recording: Recording) -> Recording:
    """``recording`` with the strings drawn: each pivot and the top of its ball as
    ``system_points``, joined by ``edges``."""
    centre = recording["body_origin"]
    frames = centre.shape[0]
    top = centre + quaternion_rotate(recording["body_orientation"], np.array([0.0, RADIUS, 0.0]))
    fixed = np.broadcast_to(pivots(), (frames, COUNT, 3))
    fields = dict(recording.fields) | {"system_points": np.concatenate([fixed, top], axis=1)}
    static = dict(recording.static) | {
        "edges": np.stack([np.arange(COUNT), COUNT + np.arange(COUNT)], axis=1),
        "system_radius": np.full(2 * COUNT, 0.0015),
        "system_color": np.tile(STRING, (2 * COUNT, 1)),
    }
    units = dict(recording.units) | {"system_points": "m", "system_radius": "m"}
    return Recording(recording.time, fields, units=units, attrs=recording.attrs, static=static)


def analyse(recording: Recording) -> dict[str, Any]:
    """What the recorded cradle did at its first impact, and how many of its impacts passed the
    whole blow to the far end ball (velocities are differences of the recorded positions)."""
    t = recording.time
    x = recording["body_origin"][:, :, 0]
    y = recording["body_origin"][:, :, 1]
    v = np.gradient(x, t, axis=0)
    rest = y[0, 1]  # a hanging ball's centre
    release = float(y[0, 0] - rest)
    fastest = float(np.abs(v).max())
    # An impact: some ball's velocity jumps between two frames; one impact's frames lie
    # together, the next comes half a period later.
    jumps = np.flatnonzero(np.abs(np.diff(v, axis=0)).max(axis=1) > 0.25 * fastest)
    impacts = [int(k) for i, k in enumerate(jumps) if i == 0 or t[k] - t[jumps[i - 1]] > 0.1]
    impacts = [k for k in impacts if 2 <= k < len(t) - 3]
    summary: dict[str, Any] = {"release_height_m": release, "impacts": len(impacts)}
    if not impacts:
        return summary
    # Speeds two frames before and three after (4 to 6 ms): at the bottom of the swing they
    # barely change but by the impact.
    passed = 0
    for k in impacts:
        incoming, outgoing = np.abs(v[k - 2]), np.abs(v[k + 3])
        far = COUNT - 1 if np.argmax(incoming) == 0 else 0
        others = np.delete(outgoing, far)
        if outgoing[far] > 0.9 * incoming.max() and others.max() < 0.05 * incoming.max():
            passed += 1
    hit = impacts[0]
    # Up to the second impact: the far ball's swing out and back takes half a period.
    window = (t > t[hit]) & (t < t[hit] + 0.45 * PERIOD)
    peaks = (y[window] - rest).max(axis=0)
    moved = np.abs(x[window] - pivots()[:, 0]).max(axis=0)
    return summary | {
        "first_impact_s": float(t[hit]),
        "speeds_before_first_impact_m_per_s": v[hit - 2].tolist(),
        "speeds_after_first_impact_m_per_s": v[hit + 3].tolist(),
        "peak_height_after_first_impact_m": peaks.tolist(),
        "peak_height_over_release_height": (peaks / release).tolist(),
        "largest_swing_from_rest_after_first_impact_m": moved.tolist(),
        "impacts_passed_to_the_far_ball": passed,
    }


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    found = {}
    for impacts in IMPACTS:
        model = scene(impacts, duration).build()
        with drawn_if_interrupted(with_strings):
            recording = with_strings(Simulation(model).record(until=duration))
        output.recordings[impacts] = recording
        found[impacts] = analyse(recording)

    figure = Figure(figsize=(12, 7.5), layout="constrained")
    axes = figure.subplots(2, 2, sharex=True)
    for row, impacts in zip(axes, IMPACTS, strict=True):
        recording = output.recordings[impacts]
        t = recording.time
        x = recording["body_origin"][:, :, 0]
        y = recording["body_origin"][:, :, 1]
        v = np.gradient(x, t, axis=0)
        for k, color in enumerate(distinct_colors(COUNT)):
            row[0].plot(t, v[:, k], lw=1.0, color=color, label=f"ball {k + 1}")
            row[1].plot(t, 1e3 * (y[:, k] - y[0, 1]), lw=1.0, color=color, label=f"ball {k + 1}")
        peaks = found[impacts].get("peak_height_over_release_height")
        shares = "" if peaks is None else ", ".join(f"{p:.2f}" for p in peaks)
        row[0].set_title(f"{impacts} impacts: horizontal velocity")
        row[0].set_ylabel("v_x [m/s]")
        row[1].set_title(f"height above rest (after the first impact: {shares} of the release)",
                         fontsize=9)  # fmt: skip
        row[1].set_ylabel("height [mm]")
    for ax in axes[1]:
        ax.set_xlabel("t [s]")
    shared_legend_below(figure, axes[0, 0], ncols=COUNT)
    output.figures["cradle"] = figure
    return {
        "ball_mass_kg": MASS,
        "anchor_stiffness_N_per_m": STIFFNESS,
        "anchor_damping_N_s_per_m": DAMPING,
        "lump_prediction_height_over_release": [0.36] + [0.16] * (COUNT - 1),
        "simultaneous": found["simultaneous"],
        "sequential": found["sequential"],
    }


register_demo(
    Demo(
        "cradle",
        BUILTIN_DEMOS["cradle"].summary,
        2.0,
        run,
        picture=True,
    )
)
