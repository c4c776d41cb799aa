"""The classic mechanical systems of :mod:`visviva.mechanics.classic` as named scene systems.

Each entry builds its :class:`~visviva.mechanics.LagrangianSystem` once per parameter set (the
derivation and the compiled code are reused between the problem and the pictures) and lifts its
picture so that a pendulum hanging from the origin swings above the video's ground plane
(``y = 0``) instead of through it. The ``oscillator`` is the damped oscillator of
:mod:`visviva.mechanics.classic` with a 1 kg mass and no damping, drawn from a wall that keeps
clear of its swing. SymPy and the mechanics package load only when a scene uses one of these
systems.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ..._memo import Memo
from ...ode.problems import Problem
from .system_type import Parameter, SystemType

__all__ = ["CLASSIC_SYSTEMS"]

#: Systems built, by name and the values of their equations: deriving and compiling one costs
#: seconds, and a sweep over masses must not keep every one of them alive.
_BUILT: Memo[Any] = Memo(32)


def _cached(name: str, values: Mapping[str, float], g: float, make: Callable[[], Any]) -> Any:
    """The system of ``name`` for ``values`` (its equations' parameters only: initial
    conditions do not change the equations, so every start shares one compiled system)."""
    return _BUILT.get((name, tuple(sorted(values.items())), g), make)


def _lagrangian(
    name: str,
    summary: str,
    parameters: dict[str, Parameter],
    make: Callable[[Mapping[str, float], float], Any],
    start: Callable[[Mapping[str, float]], tuple[list[float], list[float]]],
    lift: Callable[[Mapping[str, float]], float],
    edges: tuple[tuple[int, int], ...] | None,
    dissipation: str | None = None,
) -> SystemType:
    """A named system from a Lagrangian system factory ``make(values, g)``."""

    def system(values: Mapping[str, float], gravity: np.ndarray) -> Any:
        g = math.hypot(*gravity)
        equations = {k: v for k, v in values.items() if not parameters[k].initial}
        return _cached(name, equations, g, lambda: make(equations, g))

    def build(values: Mapping[str, float], gravity: np.ndarray) -> Problem:
        q0, v0 = start(values)
        return system(values, gravity).problem(q0, v0)

    def draw(
        values: Mapping[str, float], gravity: np.ndarray, parts: tuple[np.ndarray, ...]
    ) -> np.ndarray:
        points = system(values, gravity).points(parts[0])
        points[..., 1] += lift(values)
        return points

    return SystemType(name, summary, parameters, build, draw, edges, dissipation=dissipation)


def _pendulum(values: Mapping[str, float], g: float) -> Any:
    from ...mechanics import classic

    return classic.pendulum(length=values["length"], mass=values["mass"], g=g)


def _double_pendulum(values: Mapping[str, float], g: float) -> Any:
    from ...mechanics import classic

    return classic.double_pendulum(
        masses=(values["m1"], values["m2"]), lengths=(values["L1"], values["L2"]), g=g
    )


def _spring_pendulum(values: Mapping[str, float], g: float) -> Any:
    from ...mechanics import classic

    return classic.spring_pendulum(
        mass=values["mass"], stiffness=values["stiffness"], rest_length=values["rest_length"], g=g
    )


def _oscillator(values: Mapping[str, float], gravity: np.ndarray) -> Problem:
    from ...mechanics import classic

    def make() -> Any:  # the undamped spring is the damped oscillator without its damping
        return classic.damped_oscillator(mass=1.0, stiffness=values["omega"] ** 2, damping=0.0)

    spring = _cached("oscillator", {"omega": values["omega"]}, 0.0, make)
    return spring.problem([values["q0"]], [values["v0"]], name="oscillator")


def _draw_oscillator(
    values: Mapping[str, float], gravity: np.ndarray, parts: tuple[np.ndarray, ...]
) -> np.ndarray:
    q = parts[0][:, 0]
    amplitude = np.hypot(values["q0"], values["v0"] / values["omega"])
    points = np.zeros((q.shape[0], 2, 3))
    points[:, 0, 0] = -2.0 * amplitude  # the wall the spring hangs from
    points[:, 1, 0] = q
    points[:, :, 1] = amplitude  # lift the picture off the ground plane
    return points


def _damped_oscillator(values: Mapping[str, float], g: float) -> Any:
    from ...mechanics import classic

    return classic.damped_oscillator(
        mass=values["mass"], stiffness=values["stiffness"], damping=values["damping"]
    )


def _rock(values: Mapping[str, float], g: float) -> Any:
    from ...mechanics import classic

    return classic.rock(mass=values["mass"], g=g)


def _constrained_pendulum(values: Mapping[str, float], gravity: np.ndarray) -> Problem:
    from ...mechanics import classic

    problem, _ = classic.constrained_pendulum(
        values["theta0"],
        values["omega0"],
        length=values["length"],
        mass=values["mass"],
        g=math.hypot(*gravity),
        stabilization_rate=values["stabilization_rate"],
    )
    return problem


def _draw_constrained(
    values: Mapping[str, float], gravity: np.ndarray, parts: tuple[np.ndarray, ...]
) -> np.ndarray:
    q = parts[0]
    points = np.zeros((q.shape[0], 2, 3))
    points[:, 1, :2] = q  # the particle; the pivot stays at the origin
    points[..., 1] += 1.2 * values["length"]
    return points


def _angle(description: str, default: float = 0.0) -> Parameter:
    return Parameter(default, "rad", description, initial=True)


def _rate(description: str) -> Parameter:
    return Parameter(0.0, "rad/s", description, initial=True)


_MASS = Parameter(1.0, "kg", "mass", positive=True)
_LENGTH = Parameter(1.0, "m", "rod length", positive=True)

#: The classic systems, in the order they are listed.
CLASSIC_SYSTEMS: tuple[SystemType, ...] = (
    SystemType(
        "oscillator",
        "a 1 kg mass on a spring: q'' = -omega^2 q",
        {
            "omega": Parameter(2.0 * np.pi, "rad/s", "angular frequency", positive=True),
            "q0": Parameter(1.0, "m", "initial displacement", initial=True),
            "v0": Parameter(0.0, "m/s", "initial velocity", initial=True),
        },
        _oscillator,
        _draw_oscillator,
        ((0, 1),),
    ),
    _lagrangian(
        "pendulum",
        "seed 001's pendulum from K and U: theta'' = -(g/L) sin theta",
        {
            "length": _LENGTH,
            "mass": _MASS,
            "theta0": _angle("initial angle from the downward vertical", 0.5),
            "omega0": _rate("initial angular velocity"),
        },
        _pendulum,
        lambda p: ([p["theta0"]], [p["omega0"]]),
        lambda p: 1.2 * p["length"],
        ((0, 1),),
    ),
    _lagrangian(
        "double-pendulum",
        "two pendulums end to end: chaos from two coordinates",
        {
            "m1": Parameter(1.0, "kg", "upper bob mass", positive=True),
            "m2": Parameter(1.0, "kg", "lower bob mass", positive=True),
            "L1": Parameter(1.0, "m", "upper rod length", positive=True),
            "L2": Parameter(1.0, "m", "lower rod length", positive=True),
            "theta1": _angle("upper angle from the vertical", 2.0),
            "theta2": _angle("lower angle from the vertical", 1.0),
            "omega1": _rate("upper angular velocity"),
            "omega2": _rate("lower angular velocity"),
        },
        _double_pendulum,
        lambda p: ([p["theta1"], p["theta2"]], [p["omega1"], p["omega2"]]),
        lambda p: 1.1 * (p["L1"] + p["L2"]),
        ((0, 1), (1, 2)),
    ),
    _lagrangian(
        "spring-pendulum",
        "a bob on a spring swinging in polar coordinates (r, theta)",
        {
            "mass": _MASS,
            "stiffness": Parameter(40.0, "N/m", "spring constant", positive=True),
            "rest_length": Parameter(1.0, "m", "spring rest length", positive=True),
            "r0": Parameter(1.2, "m", "initial length", positive=True, initial=True),
            "theta0": _angle("initial angle from the downward vertical", 0.8),
            "rdot0": Parameter(0.0, "m/s", "initial stretching rate", initial=True),
            "omega0": _rate("initial angular velocity"),
        },
        _spring_pendulum,
        lambda p: ([p["r0"], p["theta0"]], [p["rdot0"], p["omega0"]]),
        lambda p: 2.0 * max(p["r0"], p["rest_length"]),
        ((0, 1),),
    ),
    _lagrangian(
        "damped-oscillator",
        "m x'' + c x' + k x = 0 with damping as a generalized force",
        {
            "mass": _MASS,
            "stiffness": Parameter(4.0, "N/m", "spring constant", positive=True),
            "damping": Parameter(0.4, "N s/m", "damping coefficient", minimum=0.0),
            "x0": Parameter(1.0, "m", "initial displacement", initial=True),
            "v0": Parameter(0.0, "m/s", "initial velocity", initial=True),
        },
        _damped_oscillator,
        lambda p: ([p["x0"]], [p["v0"]]),
        lambda p: 0.5,
        ((0, 1),),
        dissipation="damping",
    ),
    _lagrangian(
        "rock",
        "seed 001's thrown rock: a point mass under gravity, U = m g y",
        {
            "mass": _MASS,
            "x0": Parameter(0.0, "m", "initial x", initial=True),
            "y0": Parameter(0.0, "m", "initial height", initial=True),
            "z0": Parameter(0.0, "m", "initial z", initial=True),
            "vx": Parameter(4.0, "m/s", "initial velocity, x", initial=True),
            "vy": Parameter(8.0, "m/s", "initial velocity, y (up)", initial=True),
            "vz": Parameter(0.0, "m/s", "initial velocity, z", initial=True),
        },
        _rock,
        lambda p: ([p["x0"], p["y0"], p["z0"]], [p["vx"], p["vy"], p["vz"]]),
        lambda p: 0.0,
        None,
    ),
    SystemType(
        "constrained-pendulum",
        "the pendulum as a particle held by the constraint force lambda (r - c)",
        {
            "length": _LENGTH,
            "mass": _MASS,
            "theta0": _angle("initial angle from the downward vertical", 0.5),
            "omega0": _rate("initial angular velocity"),
            "stabilization_rate": Parameter(0.0, "1/s", "Baumgarte rate (0: none)", minimum=0.0),
        },
        _constrained_pendulum,
        _draw_constrained,
        ((0, 1),),
        dissipation="stabilization_rate",  # Baumgarte's correction removes energy too
    ),
)
