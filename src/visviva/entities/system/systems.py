"""Named mechanical systems a scene can hold: ``type = "system"`` with ``system = "pendulum"``.

Each entry knows its parameters (with defaults and units), builds the ordinary
:mod:`visviva.ode` problem that the one simulation loop runs, and draws itself: it maps the
recorded coordinates to points (and edges) in the world so the video, viewer and exporters can
show it. A system without a picture (the test equation) records no geometry. The systems of
classical mechanics (the oscillator, pendulums, the rock, ...) live in :mod:`.classic`,
gravitating bodies in :mod:`.gravitating`; :data:`SYSTEMS` holds them all.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..._registry import Registry
from ...ode.problems import FirstOrderProblem, Problem, SecondOrderProblem
from .classic import CLASSIC_SYSTEMS
from .gravitating import GRAVITY_SYSTEMS
from .system_type import Parameter, SystemType

__all__ = ["SYSTEMS", "Parameter", "SystemType"]


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


def _draw_circular(
    p: Mapping[str, float], gravity: np.ndarray, parts: tuple[np.ndarray, ...]
) -> np.ndarray:
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


#: Every named system, by name (``SYSTEMS.get(name)``, ``name in SYSTEMS``, ``SYSTEMS.names()``).
SYSTEMS: Registry[SystemType] = Registry("system")

for _system in (
    *CLASSIC_SYSTEMS,
    SystemType(
        "circular",
        "seed 004's circular motion: 1 kg pulled to the centre, q'' = -omega^2 q",
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
            "y0": Parameter(1.0, "", "initial value", initial=True),
        },
        _test_equation,
    ),
    *GRAVITY_SYSTEMS.values(),
):
    SYSTEMS.register(_system)
del _system
