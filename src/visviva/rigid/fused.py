"""The fused rigid-body step: a scene of free bodies stepped in one compiled pass.

A scene made only of rigid bodies under gravity and damping, stepped by symplectic Euler (the
scenes' default), spends most of a generic step outside the bodies' arithmetic: the force
function's NumPy passes, the integrator's array sums, the projection stage's norms and the
divergence watch each read and write the state once more. Here one parallel pass does per
body what they do, in place on the state's arrays:

    P ← P + h (M g − γ P),    L ← L + h (−γ' L)          the kick (forces and torques)
    x ← x + h P/M,  q ← the free rotation by L            the drift (:mod:`.motion`)

then the watch's check (a body whose numbers leave the watch's bounds is counted, and the
watch looks closer). The drift leaves each quaternion unit, so the projection stage has
nothing to do. The results are the generic pipeline's to round-off (``tests/test_rigid_
bodies.py`` compares them); pushes, anchors, particles and the other integrators take the
generic pipeline.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange

from ..forces.body_forces import BodyDamping, BodyGravity
from .motion import drift_body
from .projection import BodyProjection

if TYPE_CHECKING:
    from ..ode.state import State

__all__ = ["FusedBodies"]


class FusedBodies:
    """The fused step of a scene of rigid bodies (see :meth:`of`)."""

    def __init__(self, model: Any) -> None:
        bodies = model.bodies
        motion = bodies.motion(0)
        self.inverse_mass = motion.inverse_mass
        self.inverse_inertia = motion.inverse_inertia
        self.axes = motion.axes
        self.mass = np.asarray(bodies.mass, dtype=np.float64)
        self.gravity = np.zeros(3)
        self.linear = np.zeros(bodies.count)
        self.angular = np.zeros(bodies.count)
        for force in model.body_forces:
            if isinstance(force, BodyGravity):
                self.gravity += force.gravity
            else:
                self.linear += force.linear[:, 0]
                self.angular += force.angular[:, 0]

    @classmethod
    def of(cls, model: Any, method: str) -> FusedBodies | None:
        """The fused step of ``model`` for ``method``, or ``None``: the method must be
        symplectic Euler, the scene made of rigid bodies only, under gravity and damping."""
        if method != "symplectic_euler" or model.bodies is None:
            return None
        if model.particle_count or model.systems:
            return None
        if not all(isinstance(f, (BodyGravity, BodyDamping)) for f in model.body_forces):
            return None
        if not all(isinstance(s, BodyProjection) for s in model.stages):
            return None
        return cls(model)

    def step(self, state: State, h: float, t_after: float, limit: float) -> tuple[State, bool]:
        """Advance ``state`` by ``h`` [s] in place (``state`` is spent); the state at
        ``t_after`` and whether a body may be beyond ``limit`` or not finite."""
        q, v = state.parts
        suspects = _step(
            q, v, h, self.mass, self.inverse_mass, self.inverse_inertia, self.axes,
            self.gravity, self.linear, self.angular, limit,
        )  # fmt: skip
        return state.from_parts(t_after, state.parts), suspects != 0

    def settled(self, state: State) -> State:
        """``state`` itself: the step works on its arrays."""
        return state


# fmt: off
@njit(cache=True, parallel=True, error_model="numpy")
def _step(
    q, v, h, mass, inverse_mass, inverse_inertia, axes, g, linear, angular, limit,
):  # pragma: no cover - compiled
    """The step of the module docstring for every body, in place; returns how many bodies may
    be beyond ``limit`` or not finite."""
    # fmt: on
    count = mass.shape[0]
    gx, gy, gz = g[0], g[1], g[2]
    suspects = 0
    for b in prange(count):
        m = 3 * count + 3 * b
        keep, spin = 1.0 - h * linear[b], 1.0 - h * angular[b]
        v[3 * b] = keep * v[3 * b] + h * mass[b] * gx
        v[3 * b + 1] = keep * v[3 * b + 1] + h * mass[b] * gy
        v[3 * b + 2] = keep * v[3 * b + 2] + h * mass[b] * gz
        v[m], v[m + 1], v[m + 2] = spin * v[m], spin * v[m + 1], spin * v[m + 2]
        drift_body(q, v, h, inverse_mass, inverse_inertia, axes, q, b, count)
        k = 3 * count + 4 * b
        extent = (
            abs(q[3 * b]) + abs(q[3 * b + 1]) + abs(q[3 * b + 2])
            + abs(q[k]) + abs(q[k + 1]) + abs(q[k + 2]) + abs(q[k + 3])
            + abs(v[3 * b]) + abs(v[3 * b + 1]) + abs(v[3 * b + 2])
            + abs(v[m]) + abs(v[m + 1]) + abs(v[m + 2])
        )
        suspects += 0 if extent <= limit else 1
    return suspects
