"""Demo ``fireworks``: shells fired one after another burst into spheres of sparks.

Each shell is a single particle fired straight up at speed ``U`` by an emitter's burst; it
flies without drag (a heavy shell) and its fuse burns for ``U/g``, so it dies at the top of its
flight, ``U²/(2g)`` above the launch point. There a second emitter bursts at that time: sparks
born in a small sphere, flying out in every direction (a 180° cone) at high speed, slowed by
quadratic drag ``F = −c|v|v``, shrinking and fading from white-hot through their shell's
colour to dark as they age, and dying after a short lifetime. The same scene ships as
``examples/scenes/fireworks.toml``.

Without gravity a spark thrown at ``v₀`` against quadratic drag has flown
``(m/c) ln(1 + c v₀ t/m)`` after ``t`` (its speed falls as ``v₀/(1 + c v₀ t/m)``); shortly after
a burst, gravity only moves the sphere's centre, so the sparks' mean distance from their centre
follows that law. The summary compares the two, counts the births (each shell and each of its
sparks once) and the births that found no free slot (none: each emitter's capacity is its
burst).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..simulation.simulation import Simulation
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

DURATION = 6.0  # [s]: the last shell's sparks are gone by then
DT = 1.0 / 200.0  # [s]
RECORD_EVERY = 4  # 50 frames per second
GRAVITY = 9.81  # [m/s²]
SHELL_RADIUS = 0.25  # [m]
SHELL_COLOR = (1.0, 0.86, 0.55)
SPARKS = 1500  # per shell
SPARK_SPEED = (10.0, 11.0)  # [m/s]: a thin shell of sparks
SPARK_LIFETIME = (1.3, 1.9)  # [s]
SPARK_RADIUS = (0.10, 0.14)  # [m]: a pixel or two in a video of the whole show
SPARK_MASS = 1e-3  # [kg]
BURST_RADIUS = 0.2  # [m]: sparks are born inside a sphere this size
DRAG = 3e-4  # c [kg/m]: m/c = 3.3 m, terminal speed √(mg/c) = 5.7 m/s
#: Sparks shrink to a third of their first size over their lives: [age fraction, radius factor].
SIZE_RAMP = [[0.0, 1.3], [1.0, 0.45]]
#: Time after each burst at which the sphere's radius is compared with the drag law [s].
RADIUS_CHECK_AFTER = 0.3
DESCRIPTION = (
    "four shells fired one after another burst at the top of their flights into spheres of "
    "1500 sparks each, slowed by quadratic drag, fading to dark"
)


@dataclass(frozen=True)
class Shell:
    """One shell: fired straight up at ``speed`` [m/s] from ``launch`` [m] at ``time`` [s].

    Its sparks' ``color_ramp`` (``[age fraction, r, g, b]`` stops) goes from white-hot through
    the shell's colour to a dark ember, every channel falling with age, so that every spark
    darkens as it ages.
    """

    name: str
    time: float
    launch: tuple[float, float, float]
    speed: float
    color_ramp: tuple[tuple[float, float, float, float], ...]

    @property
    def fuse(self) -> float:
        """Flight time to the top, ``U/g`` [s]."""
        return self.speed / GRAVITY

    @property
    def burst_time(self) -> float:
        """When it bursts [s]."""
        return self.time + self.fuse

    @property
    def burst_point(self) -> tuple[float, float, float]:
        """Where it bursts, ``U²/(2g)`` above the launch point [m]."""
        x, y, z = self.launch
        return (x, y + self.speed**2 / (2.0 * GRAVITY), z)


WHITE_HOT = (0.0, 1.0, 1.0, 1.0)
SHELLS = (
    Shell(
        "red",
        0.0,
        (-6.0, 0.0, 0.0),
        22.0,
        (WHITE_HOT, (0.12, 1.0, 0.22, 0.16), (0.7, 0.45, 0.1, 0.07), (1.0, 0.08, 0.01, 0.01)),
    ),
    Shell(
        "green",
        0.5,
        (-2.0, 0.0, 1.5),
        24.0,
        (WHITE_HOT, (0.12, 0.3, 1.0, 0.35), (0.7, 0.13, 0.45, 0.16), (1.0, 0.02, 0.04, 0.01)),
    ),
    Shell(
        "blue",
        1.0,
        (2.0, 0.0, -1.5),
        21.0,
        (WHITE_HOT, (0.12, 0.35, 0.5, 1.0), (0.7, 0.16, 0.22, 0.45), (1.0, 0.03, 0.02, 0.04)),
    ),
    Shell(
        "gold",
        1.5,
        (6.0, 0.0, 0.0),
        23.0,
        (WHITE_HOT, (0.12, 1.0, 0.75, 0.2), (0.7, 0.45, 0.34, 0.09), (1.0, 0.08, 0.03, 0.01)),
    ),
)


def build_scene(duration: float = DURATION) -> SceneBuilder:
    """The fireworks as a scene (``examples/scenes/fireworks.toml`` holds the same one)."""
    builder = SceneBuilder(name="fireworks", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(
        method="symplectic_euler", dt=DT, duration=duration, record_every=RECORD_EVERY
    )
    for k, shell in enumerate(SHELLS):
        builder.add_emitter(
            name=f"{shell.name} shell",
            bursts=[{"time": shell.time, "count": 1}],
            shape="point",
            position=shell.launch,
            direction=(0.0, 1.0, 0.0),
            speed=shell.speed,
            lifetime=shell.fuse,
            particle_radius=SHELL_RADIUS,
            particle_mass=0.5,
            color=SHELL_COLOR,
        )
        builder.add_emitter(
            name=f"{shell.name} sparks",
            bursts=[{"time": shell.burst_time, "count": SPARKS}],
            shape="sphere",
            position=shell.burst_point,
            radius=BURST_RADIUS,
            direction=(0.0, 1.0, 0.0),
            spread_deg=180.0,
            speed=SPARK_SPEED,
            lifetime=SPARK_LIFETIME,
            particle_radius=SPARK_RADIUS,
            particle_mass=SPARK_MASS,
            color_ramp=shell.color_ramp,
            size_ramp=SIZE_RAMP,
            seed=k,
        )
    builder.add_force(
        "quadratic_drag",
        coefficient=DRAG,
        targets=[f"{shell.name} sparks" for shell in SHELLS],
        name="air",
    )
    return builder


def drag_distance(speed: float, t: float) -> float:
    """Distance [m] flown in ``t`` [s] from ``speed`` [m/s] against quadratic drag alone:
    ``(m/c) ln(1 + c v₀ t/m)``."""
    return SPARK_MASS / DRAG * math.log1p(DRAG * speed * t / SPARK_MASS)


def expected_sparks(age: np.ndarray) -> np.ndarray:
    """Mean number of a shell's sparks alive ``age`` [s] after its burst (uniform lifetimes)."""
    low, high = SPARK_LIFETIME
    return np.where(age < 0.0, 0.0, SPARKS * np.clip((high - age) / (high - low), 0.0, 1.0))


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    model = build_scene(duration).build()
    simulation = Simulation(model)
    recording = simulation.record(until=duration)
    output.recordings["symplectic_euler"] = recording
    t, alive, points = recording.time, recording["particle_alive"], recording["particle_position"]
    sparks = {spec.name: spec for spec in model.emitters if spec.name.endswith("sparks")}

    figure = Figure(figsize=(12, 4.8), layout="constrained")
    count, sky = figure.subplots(1, 2)
    spreads = {}
    for shell in SHELLS:
        spec = sparks[f"{shell.name} sparks"]
        slots = slice(spec.first_slot, spec.first_slot + spec.capacity)
        live = alive[:, slots].sum(axis=1)
        count.plot(
            t,
            live,
            color=shell.color_ramp[1][1:],
            label=f"{shell.name}: burst at {shell.burst_time:.2f} s",
        )
        count.plot(
            t, expected_sparks(t - shell.burst_time), color="k", linestyle=":", linewidth=0.8
        )
        k = int(np.searchsorted(t, shell.burst_time + RADIUS_CHECK_AFTER))
        if k < t.shape[0]:
            cloud = points[k, slots][alive[k, slots]]
            distance = np.linalg.norm(cloud - cloud.mean(axis=0), axis=1)
            after = t[k] - shell.burst_time
            spreads[shell.name] = {
                "after_s": float(after),
                "measured_m": float(distance.mean()),
                "drag_law_m": drag_distance(float(np.mean(SPARK_SPEED)), after),
            }
    count.set_xlabel("t [s]")
    count.set_ylabel("live sparks")
    count.set_title("Sparks alive per shell (dotted: uniform lifetimes)")
    legend_below(count)
    k = int(np.searchsorted(t, SHELLS[-1].burst_time + 0.4))
    k = min(k, t.shape[0] - 1)
    shown = alive[k]
    sky.set_facecolor("black")
    sky.scatter(
        points[k, shown, 0], points[k, shown, 1], s=1.5, c=recording["particle_color"][k][shown]
    )
    sky.set_aspect("equal")
    sky.set_xlabel("x [m]")
    sky.set_ylabel("height y [m]")
    sky.set_title(f"Seen from the front at t = {t[k]:.2f} s")
    output.figures["fireworks"] = figure

    state = simulation.state
    return {
        "shells": len(SHELLS),
        "sparks_per_shell": SPARKS,
        "births": int(state["emitter_serial"].sum()),
        "births_expected": sum(1 + SPARKS * (shell.burst_time < duration) for shell in SHELLS),
        "dropped": int(state["emitter_dropped"].sum()),
        "burst_heights_m": {shell.name: shell.burst_point[1] for shell in SHELLS},
        "sphere_radius_after_burst": spreads,
    }


register_demo(
    Demo(
        "fireworks",
        BUILTIN_DEMOS["fireworks"].summary,
        DURATION,
        run,
        picture=True,
        style="night",  # sparks are light: spots that add up on a night sky
    )
)
