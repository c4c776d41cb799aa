"""Contacts held inside an implicit solve: which points the colliders hold, found by solving.

An implicit step that knows the colliders (a system's ``contact_constraints``) holds each point
whose end-of-step position ``q_b + hV`` would be inside one on its surface (Baraff & Witkin
1998, §5): its velocity along the surface normal is set so that it ends there — just outside,
by what the system asks — and that component is filtered out of the solve. The residual along
the normal is then the impulse [N·s] the collider supplies; a collider can only push, so a point
it would have to pull is let go. Which points are held is found by solving: from the points
inside at the guess, each solve adds those that end inside and releases those pulled, up to
:data:`CONTACT_ROUNDS` times, each solved roughly (to :data:`ROUGH` times the tolerance); then
one last solve to the tolerance. Every solve after the first adds Coulomb friction on the held
points with the normal impulses of the one before (:mod:`.friction`).

Held contacts are inelastic. A point sliding over a curved collider leaves it by up to
``(hV)²/2R`` along its tangent plane, so held points are looked for that far out. What is left
— bounces, the odd point still inside after the last round — is the collision stage's, after
the step.

References:
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998, §5.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .friction import LaggedFriction

__all__ = ["CONTACT_ROUNDS", "FRICTION_SLIP", "ROUGH", "hold_contacts"]

#: Solves that update the set of held points, per step.
CONTACT_ROUNDS = 4
#: The tolerance of those solves, times the step's.
ROUGH = 10.0
#: Sliding speed [m/s] below which friction on held points acts as a stiff drag (static).
FRICTION_SLIP = 1e-3

#: ``minimize(v, normals, friction, rough) -> (V, residual)``: the implicit stage solved from
#: the guess ``v`` across the held points' ``normals`` ``(N, 3)`` (zero rows: free), with
#: ``friction``, to ``rough`` times the tolerance.
Minimize = Callable[[np.ndarray, np.ndarray, Any, float], tuple[np.ndarray, np.ndarray]]


def hold_contacts(
    minimize: Minimize,
    constraints: Callable[[np.ndarray, float], tuple[np.ndarray, ...]],
    q_base: np.ndarray,
    v: np.ndarray,
    h: float,
) -> np.ndarray:
    """The stage's velocity ``V`` ``(3N,)`` with the colliders' contacts held (see the module
    docstring).

    Args:
        minimize: The solve (see :data:`Minimize`).
        constraints: ``(q, reach) ↦ (points, normals, push, friction)``: the points inside the
            colliders at ``q`` or within ``reach`` [m], their outward normals, how far [m]
            each must move along its normal to sit where it should, and the colliders'
            friction coefficients.
        q_base: ``(3N,)`` the stage's base positions [m]: the end of the step is
            ``q_b + h V``.
        v: ``(3N,)`` the guess [m/s].
        h: The stage's weight ``θh`` [s].
    """
    count = v.size // 3
    normals = np.zeros((count, 3))
    active = np.zeros(count, dtype=bool)
    pulling = np.zeros(count, dtype=bool)
    weight = np.zeros(count)  # μ J [N·s] of each held point, from the last solve
    v = v.copy()
    for round_ in range(CONTACT_ROUNDS + 1):
        reach = h * float(np.abs(v).max())
        point, normal, push, mu = constraints(q_base + h * v, reach)
        near = np.zeros(count, dtype=bool)
        near[point] = True
        inside = np.zeros(count, dtype=bool)
        inside[point[push > 0.0]] = True
        entering = inside & ~active
        settled = round_ > 0 and not entering.any() and not pulling.any()
        if settled or round_ == CONTACT_ROUNDS:
            break
        active = (active & near) | entering
        held = active[point]
        normals.fill(0.0)
        normals[point[held]] = normal[held]
        coefficient = np.zeros(count)
        coefficient[point[held]] = mu[held]
        # Feasible first: each held point's velocity along its normal makes it end where it
        # should (push [m] ÷ h); one already outside is not pulled in.
        shift = np.zeros((count, 3))
        shift[point[held]] = (np.maximum(push[held], 0.0) / h)[:, None] * normal[held]
        v += shift.reshape(v.shape)
        v, residual = minimize(v, normals, _friction(normals, active, weight), ROUGH)
        # The residual along the normal is the collider's impulse: it can only push.
        impulse = np.einsum("ij,ij->i", residual.reshape(count, 3), normals)
        pulling = active & (impulse < 0.0)
        active &= ~pulling
        weight = coefficient * np.where(active, impulse, 0.0)
    normals *= active[:, None]
    v, _ = minimize(v, normals, _friction(normals, active, weight), 1.0)
    return v


def _friction(normals: np.ndarray, active: np.ndarray, weight: np.ndarray) -> LaggedFriction | None:
    """Friction on the ``active`` points, ``weight`` ``(N,)`` = μ J [N·s] each (``None`` where
    there is none)."""
    weight = np.where(active, weight, 0.0)
    if not weight.any():
        return None
    return LaggedFriction(normals * active[:, None], weight, FRICTION_SLIP)
