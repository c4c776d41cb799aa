"""Demo ``billiards``: a break, its impacts resolved one contact at a time and all together
(issue 27's simultaneous impacts).

Fifteen balls (radius 28.575 mm, 0.17 kg) racked in a touching triangle on the foot spot of a
9-foot table (2.54 m × 1.27 m of cloth) are broken by the cue ball, struck from the head spot
at 8 m/s without spin. Ball on ball the restitution is 0.95 and the friction 0.05; ball on
cloth the friction is 0.2 (the cloth's 0.8 and the balls' 0.05 give √(0.8 · 0.05) = 0.2 by
the pair rule), so the cue ball slides, loses some speed and picks up some roll on its way;
the rails are boxes (their restitution is the balls' 0.95: a pair takes the larger). The
bed is drawn 2 mm below the cloth, which is a plane.

The break is run twice:

- ``impacts="simultaneous"``: generalized reflections (Smith et al. 2012) resolve the
  impacts of the step together, round after round as the blow travels through the rack: the
  cue ball nearly stops (it comes back at 1.2 m/s), the two back corner balls leave at 4 m/s
  and the rack opens across the table, mirror-symmetric about its long axis as the rack and
  the shot are (to round-off). Each round restitutes 0.95 of its impulse, and the blow takes
  several rounds to cross the rack: the break keeps 77 % of the kinetic energy (with
  restitution 1, 99 %);
- ``impacts="sequential"``: the impacts are targets of the sequential-impulse sweeps, which
  share the blow among the touching balls at once: the cue ball rebounds from the rack as
  from one heavy body (at −5.7 m/s), the object balls leave at 0.4 to 1.6 m/s, lopsided by
  the sweeps' order, and the rack stays huddled until the cue ball comes back into it.

The summary gives, for the step of the break, the momentum and the kinetic energy
(translation and spin) just before and just after it, the cue ball's velocity after it, the
object balls' speeds and their mirror asymmetry, and how far the rack has spread: the object
balls' mean distance to their nearest neighbour (2 r = 57 mm in the rack, about 0.23 m for
balls scattered at random over the cloth) a second after the break and at the end. Between
the two moments only the cloth acts, for one step: its friction on the balls' weight is
μ M g h = 0.005 N·s, 0.4 % of the momentum, which bounds the change with simultaneous
impacts (0.05 %); with sequential ones the balls' friction on each other during the impact
(the cue ball has picked up topspin) presses the struck balls into the cloth and lifts the
cue ball off it, and the cloth's larger push allows it more friction (a 0.9 % change).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..model import SceneBuilder
from ..simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

RADIUS = 0.028575  # [m]
MASS = 0.17  # [kg]
LENGTH, WIDTH = 2.54, 1.27  # the cloth between the rails' noses [m]
SPEED = 8.0  # the cue ball's [m/s]
G = 9.81  # [m/s²]
BALL_RESTITUTION = 0.95
BALL_FRICTION = 0.05
CLOTH_FRICTION = 0.8  # with a ball's 0.05: √(0.8 · 0.05) = 0.2
DT = 1e-3  # [s]: 8 mm a step at 8 m/s, the cue ball's time of impact is found
RECORD_EVERY = 5  # 200 frames a second
IMPACTS = ("simultaneous", "sequential")
#: Pool colours by ball number; 9 to 15 are striped, drawn as 1 to 7 lightened.
SOLIDS = [(0.95, 0.8, 0.1), (0.1, 0.25, 0.75), (0.85, 0.1, 0.1), (0.4, 0.15, 0.55),
          (0.95, 0.45, 0.1), (0.05, 0.5, 0.25), (0.5, 0.1, 0.1), (0.05, 0.05, 0.05)]  # fmt: skip
#: The numbers in the rack, row by row from the apex (the 1 in front, the 8 in the middle).
RACK_ORDER = [1, 9, 2, 10, 8, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15]


def color(number: int) -> tuple[float, float, float]:
    if number <= 8:
        return SOLIDS[number - 1]
    r, g, b = SOLIDS[number - 9]
    return (0.5 + 0.5 * r, 0.5 + 0.5 * g, 0.5 + 0.5 * b)


def rack() -> np.ndarray:
    """The fifteen balls' centres on the cloth (x along the table, z across) [m], ``(15, 2)``:
    a touching triangle, its apex on the foot spot (x = L/4), rows 2 r cos 30° apart."""
    rows = [(row, k) for row in range(5) for k in range(row + 1)]
    return np.array([[LENGTH / 4 + row * np.sqrt(3.0) * RADIUS, (k - row / 2) * 2 * RADIUS]
                     for row, k in rows])  # fmt: skip


def mirror_partner() -> np.ndarray:
    """For each racked ball, the index of the ball at its mirror image across the table's
    long axis (z → −z); itself on the axis."""
    spots = rack()
    return np.array([int(np.argmin(np.linalg.norm(spots - [x, -z], axis=1))) for x, z in spots])


def scene(impacts: str, duration: float) -> SceneBuilder:
    """The break with its impacts resolved ``impacts``."""
    builder = SceneBuilder(name=f"billiards break ({impacts} impacts)")
    builder.set_world(gravity=(0.0, -G, 0.0))
    builder.set_integration(method="velocity_verlet", dt=DT, duration=duration,
                            record_every=RECORD_EVERY)  # fmt: skip
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=0.0,
                         friction=CLOTH_FRICTION, name="cloth")  # fmt: skip
    rail, height = 0.1, 0.05
    builder.add_collider("box", center=(0.0, -0.022, 0.0), size=(LENGTH + 2 * rail, 0.04,
                         WIDTH + 2 * rail), color=(0.1, 0.45, 0.25), name="bed")  # fmt: skip
    for name, center, size in (
        ("foot rail", (LENGTH / 2 + rail / 2, height / 2, 0.0), (rail, height, WIDTH + 2 * rail)),
        ("head rail", (-LENGTH / 2 - rail / 2, height / 2, 0.0), (rail, height, WIDTH + 2 * rail)),
        ("long rail", (0.0, height / 2, WIDTH / 2 + rail / 2), (LENGTH, height, rail)),
        ("other long rail", (0.0, height / 2, -WIDTH / 2 - rail / 2), (LENGTH, height, rail)),
    ):
        builder.add_collider("box", center=center, size=size, restitution=BALL_RESTITUTION,
                             friction=CLOTH_FRICTION, color=(0.35, 0.2, 0.1),
                             name=name)  # fmt: skip
    builder.add_body("sphere", radius=RADIUS, mass=MASS, position=(-LENGTH / 4, RADIUS, 0.0),
                     velocity=(SPEED, 0.0, 0.0), restitution=BALL_RESTITUTION,
                     friction=BALL_FRICTION, color=(0.95, 0.95, 0.9), name="cue ball")  # fmt: skip
    for (x, z), number in zip(rack(), RACK_ORDER, strict=True):
        builder.add_body("sphere", radius=RADIUS, mass=MASS, position=(x, RADIUS, z),
                         restitution=BALL_RESTITUTION, friction=BALL_FRICTION,
                         color=color(number), name=f"ball {number}")  # fmt: skip
    builder.add_body_contacts(impacts=impacts)
    return builder


def _kinetic(simulation: Simulation) -> float:
    """Kinetic energy of translation and spin [J]."""
    views = simulation.bodies()
    spin = simulation.state["body_angular_momentum"]
    return float(0.5 * MASS * (views.velocity**2).sum()
                 + 0.5 * np.einsum("bi,bi->", views.angular_velocity, spin))  # fmt: skip


def the_break(model: Any) -> dict[str, Any]:
    """Step ``model`` to the break and measure the step it happens in."""
    simulation = Simulation(model)
    racked = slice(1, None)
    while not np.any(simulation.state["body_momentum"][racked]):
        momentum = simulation.state["body_momentum"].sum(axis=0)
        energy = _kinetic(simulation)
        cue = simulation.state["body_momentum"][0] / MASS
        simulation.step(1)
        if simulation.time > 1.0:
            raise RuntimeError("the cue ball never reached the rack")
    after = simulation.state["body_momentum"]
    velocity = after / MASS
    speeds = np.linalg.norm(velocity[racked][:, [0, 2]], axis=1)
    mirrored = velocity[racked][mirror_partner()] * [1.0, 1.0, -1.0]
    return {
        "time_s": simulation.time,
        "cue_ball_velocity_before_m_per_s": cue.tolist(),
        "cue_ball_velocity_after_m_per_s": velocity[0].tolist(),
        "momentum_before_N_s": momentum.tolist(),
        "momentum_after_N_s": after.sum(axis=0).tolist(),
        "momentum_change_along_the_table": float(after[:, 0].sum() / momentum[0] - 1.0),
        "cloth_friction_of_the_weight_N_s": float(
            np.sqrt(CLOTH_FRICTION * BALL_FRICTION) * 16 * MASS * G * DT
        ),
        "kinetic_energy_before_J": energy,
        "kinetic_energy_after_J": _kinetic(simulation),
        "kinetic_energy_kept": _kinetic(simulation) / energy,
        "object_ball_speeds_m_per_s": sorted(speeds.tolist(), reverse=True),
        "mirror_asymmetry_m_per_s": float(np.abs(velocity[racked] - mirrored).max()),
    }


def nearest(points: np.ndarray) -> float:
    """Mean distance [m] from each of points ``(n, 2)`` to its nearest other one."""
    gaps = np.linalg.norm(points[:, None] - points[None], axis=-1)
    np.fill_diagonal(gaps, np.inf)
    return float(gaps.min(axis=1).mean())


#: Mean nearest-neighbour distance of 15 points scattered at random over the cloth, 1/(2√ρ)
#: (Clark and Evans 1954, edges neglected) [m].
SCATTERED = 0.5 / np.sqrt(15 / (LENGTH * WIDTH))


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    found: dict[str, dict[str, Any]] = {}
    for impacts in IMPACTS:
        model = scene(impacts, duration).build()
        recording = Simulation(model).record(until=duration)
        output.recordings[impacts] = recording
        found[impacts] = {"break": the_break(model)}
        t = recording.time
        table = recording["body_origin"][:, 1:][:, :, [0, 2]]
        spreads = np.array([nearest(frame) for frame in table])
        later = found[impacts]["break"]["time_s"] + 1.0
        found[impacts] |= {
            "nearest_ball_at_start_m": spreads[0],
            "nearest_ball_a_second_after_the_break_m": (
                float(np.interp(later, t, spreads)) if later <= t[-1] else None
            ),
            "nearest_ball_at_end_m": spreads[-1],
        }
        found[impacts]["_spreads"] = (t, spreads)

    figure = Figure(figsize=(13, 4.8), layout="constrained")
    grow, simultaneous, sequential = figure.subplots(1, 3, width_ratios=(1.0, 1.2, 1.2))
    for impacts in IMPACTS:
        t, spreads = found[impacts].pop("_spreads")
        grow.plot(t, spreads, label=f"{impacts} impacts")
    grow.axhline(SCATTERED, color="grey", lw=0.8, ls="--", label="scattered at random")
    grow.set_xlabel("t [s]")
    grow.set_ylabel("object balls' mean distance to the nearest other [m]")
    grow.set_title("How far the rack spreads")
    legend_below(grow)
    for ax, impacts in ((simultaneous, "simultaneous"), (sequential, "sequential")):
        recording = output.recordings[impacts]
        path = recording["body_origin"]
        colors = recording.static["body_color"]
        ax.add_patch(_cloth())
        for b in range(path.shape[1]):
            ax.plot(path[:, b, 0], path[:, b, 2], color=colors[b], lw=0.8)
            ax.plot(path[-1, b, 0], path[-1, b, 2], "o", color=colors[b], ms=5, mec="k",
                    mew=0.4)  # fmt: skip
        cue = found[impacts]["break"]["cue_ball_velocity_after_m_per_s"][0]
        kept = found[impacts]["break"]["kinetic_energy_kept"]
        ax.set_title(f"{impacts}: cue ball leaves at {cue:+.2f} m/s, {100 * kept:.0f} % of "
                     "the energy kept", fontsize=9)  # fmt: skip
        ax.set_xlim(-LENGTH / 2 - 0.05, LENGTH / 2 + 0.05)
        ax.set_ylim(-WIDTH / 2 - 0.05, WIDTH / 2 + 0.05)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("z [m]")
    output.figures["billiards"] = figure
    return {
        "cue_ball_speed_m_per_s": SPEED,
        "restitution_ball_ball": BALL_RESTITUTION,
        "friction_ball_cloth": float(np.sqrt(CLOTH_FRICTION * BALL_FRICTION)),
        "nearest_ball_scattered_at_random_m": SCATTERED,
        **found,
    }


def _cloth() -> Any:
    from matplotlib.patches import Rectangle

    return Rectangle((-LENGTH / 2, -WIDTH / 2), LENGTH, WIDTH, color=(0.85, 0.93, 0.87))


register_demo(
    Demo(
        "billiards",
        BUILTIN_DEMOS["billiards"].summary,
        3.0,
        run,
        picture=True,
        speed=0.5,
    )
)
