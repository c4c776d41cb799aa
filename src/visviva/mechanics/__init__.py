"""Mechanics in generalized coordinates and gravitation."""

from __future__ import annotations

from . import classic
from .barnes_hut import TreeError, tree_force_error
from .classic import (
    constrained_pendulum,
    damped_oscillator,
    double_pendulum,
    pendulum,
    pendulum_period,
    rock,
    spring_pendulum,
)
from .clusters import colliding_disks, disk_galaxy, plummer_sphere
from .gravity import (
    GRAVITATIONAL_CONSTANT,
    gravitational_potential_energy,
    gravity_accelerations,
)
from .kepler import KeplerOrbit, eccentric_anomaly, kepler_orbit, sun_earth_moon
from .lagrangian import LagrangianSystem
from .nbody import Bodies, nbody_problem

__all__: list[str] = [
    "GRAVITATIONAL_CONSTANT",
    "Bodies",
    "KeplerOrbit",
    "LagrangianSystem",
    "TreeError",
    "classic",
    "colliding_disks",
    "constrained_pendulum",
    "damped_oscillator",
    "disk_galaxy",
    "double_pendulum",
    "eccentric_anomaly",
    "gravitational_potential_energy",
    "gravity_accelerations",
    "kepler_orbit",
    "nbody_problem",
    "pendulum",
    "pendulum_period",
    "plummer_sphere",
    "rock",
    "spring_pendulum",
    "sun_earth_moon",
    "tree_force_error",
]
