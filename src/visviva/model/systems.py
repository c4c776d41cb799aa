"""Named mechanical systems a scene can hold: ``type = "system"`` with ``system = "pendulum"``.

Each entry knows its parameters (with defaults and units), builds the ordinary
:mod:`visviva.ode` problem that the one simulation loop runs, and draws itself: it maps the
recorded coordinates to points (and edges) in the world so the video, viewer and exporters can
show it. A system without a picture (the test equation) records no geometry.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..ode.problems import FirstOrderProblem, Problem, SecondOrderProblem

__all__ = ["SYSTEMS", "Parameter", "SystemType"]


@dataclass(frozen=True)
class Parameter:
    """One parameter of a named system.

    Attributes:
        default: Value used when the scene does not give one.
        unit: SI unit, for messages and the schema.
        description: One line.
        positive: The value must be > 0.
    """

    default: float
    unit: str
    description: str
    positive: bool = False


#: Draws frames of a system: ``(q, v)`` or ``(y,)`` with a leading frame axis → points
#: ``(frames, P, 3)`` [m].
Drawing = Callable[[Mapping[str, float], tuple[np.ndarray, ...]], np.ndarray]


@dataclass(frozen=True)
class SystemType:
    """A named system: its parameters, its problem and its picture.

    Attributes:
        name: Name used in scene files.
        summary: One line.
        parameters: Parameter name → :class:`Parameter`.
        build: ``build(values, gravity)`` → the problem; ``gravity`` [m/s²] is the world's.
        draw: Maps recorded frames to points, or ``None`` if the system has no picture.
        edges: Point-index pairs drawn as lines, or ``None``.
    """

    name: str
    summary: str
    parameters: Mapping[str, Parameter]
    build: Callable[[Mapping[str, float], np.ndarray], Problem]
    draw: Drawing | None = None
    edges: tuple[tuple[int, int], ...] | None = None


def _oscillator(p: Mapping[str, float], gravity: np.ndarray) -> Problem:
    omega2 = p["omega"] ** 2

    def acceleration(t: float, q: np.ndarray) -> np.ndarray:
        return -omega2 * q  # q'' = −ω² q

    def jacobian(t: float, q: np.ndarray) -> np.ndarray:
        return np.full(q.shape + q.shape[-1:], -omega2)

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        return 0.5 * v[..., 0] ** 2 + 0.5 * omega2 * q[..., 0] ** 2  # per unit mass [J/kg]

    return SecondOrderProblem(
        acceleration, [p["q0"]], [p["v0"]], jacobian=jacobian, energy=energy, name="oscillator"
    )


def _draw_oscillator(p: Mapping[str, float], parts: tuple[np.ndarray, ...]) -> np.ndarray:
    q = parts[0][:, 0]
    amplitude = np.hypot(p["q0"], p["v0"] / p["omega"])
    points = np.zeros((q.shape[0], 2, 3))
    points[:, 0, 0] = -2.0 * amplitude  # the wall the spring hangs from
    points[:, 1, 0] = q
    points[:, :, 1] = amplitude  # lift the picture off the ground plane
    return points


def _pendulum(p: Mapping[str, float], gravity: np.ndarray) -> Problem:
    g_over_l = float(np.linalg.norm(gravity)) / p["length"]
    length = p["length"]

    def acceleration(t: float, q: np.ndarray) -> np.ndarray:
        return -g_over_l * np.sin(q)  # θ'' = −(g/L) sin θ

    def jacobian(t: float, q: np.ndarray) -> np.ndarray:
        return (-g_over_l * np.cos(q))[..., None]

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        # per unit mass [J/kg]: ½ L² θ'² + g L (1 − cos θ)
        return length**2 * (0.5 * v[..., 0] ** 2 + g_over_l * (1.0 - np.cos(q[..., 0])))

    return SecondOrderProblem(
        acceleration,
        [p["theta0"]],
        [p["omega0"]],
        jacobian=jacobian,
        energy=energy,
        name="pendulum",
    )


def _draw_pendulum(p: Mapping[str, float], parts: tuple[np.ndarray, ...]) -> np.ndarray:
    theta, length = parts[0][:, 0], p["length"]
    points = np.zeros((theta.shape[0], 2, 3))
    points[:, :, 1] = 1.2 * length  # pivot above the ground
    points[:, 1, 0] = length * np.sin(theta)
    points[:, 1, 1] -= length * np.cos(theta)
    return points


def _circular(p: Mapping[str, float], gravity: np.ndarray) -> Problem:
    omega2 = p["omega"] ** 2

    def acceleration(t: float, q: np.ndarray) -> np.ndarray:
        return -omega2 * q  # central force: uniform circular motion from these initial values

    def jacobian(t: float, q: np.ndarray) -> np.ndarray:
        return -omega2 * np.broadcast_to(np.eye(2), q.shape + (2,)).copy()

    def energy(t: float, q: np.ndarray, v: np.ndarray) -> Any:
        return 0.5 * np.sum(v**2, axis=-1) + 0.5 * omega2 * np.sum(q**2, axis=-1)

    radius = p["radius"]
    return SecondOrderProblem(
        acceleration,
        [radius, 0.0],
        [0.0, p["omega"] * radius],
        jacobian=jacobian,
        energy=energy,
        name="circular motion",
    )


def _draw_circular(p: Mapping[str, float], parts: tuple[np.ndarray, ...]) -> np.ndarray:
    q = parts[0]
    points = np.zeros((q.shape[0], 2, 3))
    points[:, :, 1] = 0.25 * p["radius"]  # orbit in a horizontal plane above the ground
    points[:, 1, 0] = q[:, 0]
    points[:, 1, 2] = q[:, 1]
    return points


def _test_equation(p: Mapping[str, float], gravity: np.ndarray) -> Problem:
    rate = p["lambda"]

    def f(t: float, y: np.ndarray) -> np.ndarray:
        return rate * y  # y' = λ y

    def jacobian(t: float, y: np.ndarray) -> np.ndarray:
        return np.full(y.shape + y.shape[-1:], rate)

    return FirstOrderProblem(f, [p["y0"]], jacobian=jacobian, name="test equation")


#: Every named system, by name.
SYSTEMS: dict[str, SystemType] = {
    system.name: system
    for system in (
        SystemType(
            "oscillator",
            "unit mass on a spring: q'' = -omega^2 q",
            {
                "omega": Parameter(2.0 * np.pi, "rad/s", "angular frequency", positive=True),
                "q0": Parameter(1.0, "m", "initial displacement"),
                "v0": Parameter(0.0, "m/s", "initial velocity"),
            },
            _oscillator,
            _draw_oscillator,
            ((0, 1),),
        ),
        SystemType(
            "pendulum",
            "simple pendulum in the world's gravity: theta'' = -(g/L) sin theta",
            {
                "length": Parameter(1.0, "m", "rod length", positive=True),
                "theta0": Parameter(0.5, "rad", "initial angle from the downward vertical"),
                "omega0": Parameter(0.0, "rad/s", "initial angular velocity"),
            },
            _pendulum,
            _draw_pendulum,
            ((0, 1),),
        ),
        SystemType(
            "circular",
            "seed 004's circular motion: a particle pulled to the centre, q'' = -omega^2 q",
            {
                "radius": Parameter(1.0, "m", "orbit radius", positive=True),
                "omega": Parameter(1.0, "rad/s", "angular velocity", positive=True),
            },
            _circular,
            _draw_circular,
            ((0, 1),),
        ),
        SystemType(
            "test-equation",
            "Dahlquist's test equation y' = lambda y (no picture)",
            {
                "lambda": Parameter(-1.0, "1/s", "rate"),
                "y0": Parameter(1.0, "", "initial value"),
            },
            _test_equation,
        ),
    )
}
