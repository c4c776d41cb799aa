"""Demo ``sun-earth-moon``: a year of the Sun, the Earth and the Moon in SI units.

Initial conditions at J2000.0 (see :func:`visviva.mechanics.sun_earth_moon`), velocity Verlet
with a one-hour step for a year. The measured sidereal year and month are compared with the
observed 365.256 d and 27.322 d (the starting Moon comes from a truncated lunar theory, good
to about 0.1%); the total energy and angular momentum are conserved.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..analysis.invariants import angular_momentum
from ..io.job import JobOutput
from ..mechanics import sun_earth_moon
from ..simulation.solution import solve
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._bodies import body_states, drawn_bodies, drawn_if_interrupted
from .catalogue import BUILTIN_DEMOS

DAY = 86_400.0  # [s]
YEAR = 365.25 * DAY  # Julian year [s]
DT = 3600.0  # one hour [s]
AU = 149_597_870_700.0  # [m]
#: How the bodies are drawn: the Sun yellow, the Earth blue, the Moon grey, and far larger than
#: they are (the Earth's true radius is 4e-5 AU, a hundredth of a pixel here). The Moon's orbit
#: (0.0026 AU) is smaller than the Earth's drawn sphere: the Moon shows as a grey cap on it.
COLORS = np.array([[1.0, 0.78, 0.18], [0.16, 0.42, 0.86], [0.78, 0.78, 0.76]])
DISPLAY_RADIUS = np.array([0.08, 0.025, 0.0125]) * AU


def _period(t: np.ndarray, relative: np.ndarray) -> float:
    """Sidereal period [s] of a relative position turning in the x–z plane.

    Over whole turns: the time until its angle (unwrapped, counter-clockwise seen from +y) has
    grown by ``2π k`` for the largest whole ``k``, divided by ``k`` — averaging over partial
    turns would weight the fast and slow parts of an eccentric orbit unevenly. Less than one
    turn: the mean angular rate so far.
    """
    angle = np.abs(
        np.unwrap(np.arctan2(-relative[:, 2], relative[:, 0]))
        - np.arctan2(-relative[0, 2], relative[0, 0])
    )
    turns = int(angle[-1] // (2 * np.pi))
    if turns == 0:
        return float(2 * np.pi * (t[-1] - t[0]) / angle[-1])
    return float((np.interp(2 * np.pi * turns, angle, t) - t[0]) / turns)


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    bodies = sun_earth_moon()
    draw = functools.partial(drawn_bodies, color=COLORS, display_radius=DISPLAY_RADIUS)
    with drawn_if_interrupted(draw):
        solution = solve(
            bodies.problem(name="Sun-Earth-Moon"), "velocity_verlet", dt=DT, until=duration
        )
    output.recordings["velocity_verlet"] = draw(solution.recording)
    x, v = body_states(solution.recording)
    earth = x[:, 1] - x[:, 0]
    moon = x[:, 2] - x[:, 1]
    spin = angular_momentum(bodies.masses, x, v)[:, 1]
    figure = Figure(figsize=(13, 4.5), layout="constrained")
    year, month, invariants = figure.subplots(1, 3)
    year.plot(earth[:, 0] / AU, earth[:, 2] / AU)
    year.plot(0, 0, "o", color="orange", markersize=12)
    year.set_aspect("equal")
    year.set_xlabel("x [AU]")
    year.set_ylabel("z [AU]")
    year.set_title("The Earth about the Sun")
    month.plot(moon[:, 0] / 1e6, moon[:, 2] / 1e6, linewidth=0.5)
    month.set_aspect("equal")
    month.set_xlabel("x [1000 km]")
    month.set_ylabel("z [1000 km]")
    month.set_title("The Moon about the Earth")
    days = solution.t / DAY
    invariants.semilogy(
        days, np.maximum(np.abs(solution.energy / solution.energy[0] - 1), 1e-17), label="energy"
    )
    invariants.semilogy(
        days, np.maximum(np.abs(spin / spin[0] - 1), 1e-17), label="angular momentum"
    )
    invariants.set_xlabel("t [days]")
    invariants.set_ylabel("relative change")
    invariants.set_title(f"Velocity Verlet, h = {DT / 3600:g} h")
    legend_below(invariants)
    output.figures["sun_earth_moon"] = figure
    return {
        "sidereal_year_days": _period(solution.t, earth) / DAY,
        "sidereal_month_days": _period(solution.t, moon) / DAY,
        "observed_days": {"year": 365.256, "month": 27.322},
        "max_energy_error": float(np.abs(solution.energy / solution.energy[0] - 1).max()),
    }


register_demo(
    Demo(
        "sun-earth-moon",
        BUILTIN_DEMOS["sun-earth-moon"].summary,
        YEAR,
        run,
        picture=True,
        speed=7 * DAY,  # a week per second: the year in 52 s
        trail=60 * DAY,  # two months of orbit behind each body
    )
)
