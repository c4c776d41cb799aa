"""Gravitating bodies as named scene systems: Kepler orbit, Sun–Earth–Moon, star cluster, galaxies.

The coordinates are the bodies' positions flattened (see :func:`visviva.mechanics.nbody_problem`),
so the picture is those positions themselves (orbits lie in the horizontal x–z plane; the
video's ground sits below the lowest body). Their gravitation is the one implementation of
:mod:`visviva.mechanics.gravity` (the :class:`~visviva.forces.Gravitation` force among particles
uses it too); world gravity does not act on them. The mechanics package loads only when a
scene uses one of these.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ...ode.problems import Problem
from .system_type import Parameter, SystemType

__all__ = ["GRAVITY_SYSTEMS"]

#: Above this many bodies a galaxy uses the Barnes–Hut tree instead of direct summation.
DIRECT_MAX_BODIES = 4000
#: Largest galaxy a scene may ask for (bodies per disk), checked before anything is allocated.
MAX_BODIES_PER_DISK = 5_000_000
#: The astronomical unit [m] (IAU 2012, exact): the scale of the Sun–Earth–Moon picture.
ASTRONOMICAL_UNIT = 149_597_870_700.0


def _kepler_bodies(p: Mapping[str, float]) -> Any:
    from ...mechanics import kepler_orbit

    orbit = kepler_orbit(
        p["semi_major_axis"], p["eccentricity"], masses=(p["mass1"], p["mass2"]), G=p["G"]
    )
    return orbit.bodies()


def _cluster(p: Mapping[str, float]) -> Any:
    from ...mechanics import plummer_sphere

    return plummer_sphere(
        int(p["bodies"]),
        total_mass=p["total_mass"],
        scale_radius=p["scale_radius"],
        G=p["G"],
        seed=int(p["seed"]),
    )


def _sun_earth_moon(p: Mapping[str, float]) -> Any:
    from ...mechanics import sun_earth_moon

    return sun_earth_moon()


def _galaxy(p: Mapping[str, float]) -> Any:
    from ...mechanics import colliding_disks

    return colliding_disks(
        int(p["bodies_per_disk"]),
        central_mass=p["central_mass"],
        disk_mass=p["disk_mass"],
        radius=p["radius"],
        separation=p["separation"],
        pericenter=p["pericenter"],
        G=p["G"],
        softening=p["softening"],
        seed=int(p["seed"]),
    )


def _gravity(
    name: str,
    summary: str,
    parameters: dict[str, Parameter],
    bodies: Callable[[Mapping[str, float]], Any],
) -> SystemType:
    def build(values: Mapping[str, float], gravity: np.ndarray) -> Problem:
        made = bodies(values)
        tree = made.count > DIRECT_MAX_BODIES
        return made.problem(
            softening=values.get("softening", 0.0),
            method="barnes_hut" if tree else "direct",
            theta=values.get("theta", 0.5),
            name=name,
        )

    return SystemType(name, summary, parameters, build, draw=_bodies_as_points, bodies=True)


def _bodies_as_points(
    values: Mapping[str, float], gravity: np.ndarray, parts: tuple[np.ndarray, ...]
) -> np.ndarray:
    """The coordinates are the bodies' positions, ``(x, y, z)`` per body: the picture itself."""
    q = parts[0]
    return q.reshape(q.shape[0], -1, 3)


_G = Parameter(1.0, "m^3/(kg s^2)", "constant of gravitation (1: N-body units)", positive=True)


def _many_body_parameters(softening: float) -> dict[str, Parameter]:
    """The parameters every many-body system shares: softening, tree, units and seed."""
    return {
        "softening": Parameter(softening, "m", "Plummer softening length", minimum=0.0),
        "theta": Parameter(
            0.5,
            "",
            f"Barnes-Hut opening angle, in (0, 1] (above {DIRECT_MAX_BODIES} bodies)",
            positive=True,
            maximum=1.0,
        ),
        "G": _G,
        "seed": Parameter(0.0, "", "random seed", integer=True, minimum=0.0, maximum=2.0**63 - 1),
    }


GRAVITY_SYSTEMS: dict[str, SystemType] = {
    system.name: system
    for system in (
        _gravity(
            "kepler",
            "two bodies on a Kepler ellipse about their centre of mass, from periapsis",
            {
                "semi_major_axis": Parameter(1.0, "m", "semi-major axis a", positive=True),
                "eccentricity": Parameter(0.5, "", "eccentricity e, in [0, 1)", minimum=0.0),
                "mass1": Parameter(1.0, "kg", "first mass", positive=True),
                "mass2": Parameter(0.001, "kg", "second mass", positive=True),
                "G": _G,
            },
            _kepler_bodies,
        ),
        _gravity(
            "sun-earth-moon",
            "the Sun, the Earth and the Moon at J2000.0, SI units (one year: 3.156e7 s)",
            {},
            _sun_earth_moon,
        ),
        _gravity(
            "cluster",
            "a star cluster: Plummer's sphere in virial equilibrium (Aarseth, Hénon & Wielen 1974)",
            {
                "bodies": Parameter(
                    1000.0,
                    "",
                    "number of stars",
                    positive=True,
                    integer=True,
                    maximum=2 * MAX_BODIES_PER_DISK,
                ),
                "total_mass": Parameter(1.0, "kg", "mass of the cluster", positive=True),
                "scale_radius": Parameter(1.0, "m", "Plummer radius a", positive=True),
                **_many_body_parameters(softening=0.01),
            },
            _cluster,
        ),
        _gravity(
            "galaxy",
            "two disk galaxies colliding on a parabolic orbit (Toomre & Toomre 1972)",
            {
                "bodies_per_disk": Parameter(
                    1000.0,
                    "",
                    "disk bodies per galaxy",
                    positive=True,
                    integer=True,
                    maximum=MAX_BODIES_PER_DISK,
                ),
                "central_mass": Parameter(1.0, "kg", "mass at each centre", positive=True),
                "disk_mass": Parameter(
                    0.0, "kg", "mass of each disk (0: test particles)", minimum=0.0
                ),
                "radius": Parameter(1.0, "m", "disk radius", positive=True),
                "separation": Parameter(6.0, "m", "initial distance of the centres", positive=True),
                "pericenter": Parameter(1.5, "m", "closest approach of the centres", positive=True),
                **_many_body_parameters(softening=0.05),
            },
            _galaxy,
        ),
    )
}
