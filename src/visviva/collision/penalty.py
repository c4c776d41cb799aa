"""Penalty contact: colliders push penetrating particles out with a spring and a damper.

The alternative to impulses taught in seeds 000 and 002 ("temporary springs that oppose
inter-penetration"): no time of impact is sought, the particle may sink in, and a force along
the collider's outward normal ``n`` pushes it back,

    d   = signed distance of the centre − radius   (< 0 in contact)          [m]
    F   = max(0, −k d − c (v·n)) n                                          [N]
    U   = ½ k d²                                                            [J]

with stiffness ``k`` [N/m] and damping ``c`` [N·s/m]; the force never pulls a particle in. It
is a force like any other, so implicit methods see its Jacobian: with ``f = −k d − c v·n`` and
``H = ∂n/∂x``,

    ∂F/∂x = n (−k nᵀ − c vᵀ H) + f H,        ∂F/∂v = −c n nᵀ,

where ``H = 0`` on a plane and on the faces of boxes and meshes, and ``(I − n nᵀ)/ρ`` on a
sphere of centre distance ``ρ``. At a box's edges and corners and a mesh's edges and vertices
the curvature term is left out (the normal is taken as locally constant). The stiffness sets
the step an explicit method can take: ``h < 2 √(m/k)`` for the contact's oscillation.

References:
    Seeds 000 and 002 (penalty forces); M. Moore, J. Wilhelms, "Collision detection and
    response for computer animation", SIGGRAPH 1988.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from .colliders import ColliderSet, collider_distance
from .contact_classes import DEFAULT_GAP, Contacts, find_contacts

if TYPE_CHECKING:
    from ..forces.base import JacobianForm
    from ..ode.state import State
    from ..ode.workspace import Workspace
from .tables import ColliderKind

__all__ = ["PenaltyContact"]

_SPHERE = int(ColliderKind.SPHERE)


class PenaltyContact:
    """The penalty force of a set of colliders on particles (see the module docstring).

    Args:
        colliders: The colliders.
        stiffness: ``k`` [N/m] of each collider, > 0.
        damping: ``c`` [N·s/m] of each collider, ≥ 0.
        masks: ``(N,)`` uint64: bit ``k`` set where particle ``i`` meets collider ``k``.
        radius: Particle radii [m], ``(N,)`` (the radii at the start: a size ramp does not
            change the contact distance).
        labels: Each collider's name, for :class:`~visviva.collision.contact_classes.Contacts`.
        resting_speed: Normal speeds [m/s] below which :meth:`contacts` calls a contact
            resting, per collider (default 0).
    """

    velocity_dependent = True
    #: Its damper ``c (v·n) n`` changes direction with the positions: not a linear damper.
    linear_damping = False
    #: No compiled form: a scene with penalty contact takes the generic road.
    compiled = None

    def __init__(
        self,
        colliders: ColliderSet,
        stiffness: Sequence[float],
        damping: Sequence[float],
        masks: np.ndarray,
        radius: np.ndarray,
        labels: Sequence[str] | None = None,
        resting_speed: Sequence[float] | None = None,
    ) -> None:
        self.colliders = colliders
        self.stiffness = np.asarray(stiffness, dtype=np.float64)
        self.damping = np.asarray(damping, dtype=np.float64)
        self.masks = np.asarray(masks, dtype=np.uint64)
        self.radius = np.asarray(radius, dtype=np.float64)
        self.labels = tuple(labels or (f"collider {k}" for k in range(len(colliders))))
        self.resting_speed = (
            np.zeros(len(colliders))
            if resting_speed is None
            else np.asarray(resting_speed, dtype=np.float64)
        )
        self.conservative = not np.any(self.damping)
        self._touched = np.flatnonzero(self.masks).astype(np.int64)

    def contacts(self, state: State, gap: float = DEFAULT_GAP) -> Contacts:
        """The contacts of ``state``'s live particles with these colliders (see
        :mod:`~visviva.collision.contact_classes`)."""
        x = state["particle_position"]
        alive = state.carried.get("particle_alive")
        return find_contacts(
            x,
            state["particle_velocity"],
            self.radius,
            np.ones(x.shape[0], dtype=np.bool_) if alive is None else alive,
            self.masks,
            self.colliders,
            self.resting_speed,
            self.labels,
            gap,
        )

    def accumulate(
        self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray, work: Workspace | None = None
    ) -> None:
        """Add the contact forces [N] to ``out``."""
        _penalty(
            self._touched,
            x,
            v,
            self.radius,
            self.masks,
            self.stiffness,
            self.damping,
            out,
            np.zeros((0, 3, 3)),
            np.zeros((0, 3, 3)),
            False,
            False,
            *self.colliders.kernel_arrays[1:],
        )

    def potential(self, t: float, x: np.ndarray, alive: np.ndarray | None = None) -> float:
        """``Σ ½ k d²`` [J] over the particles in contact (alive ones, if given)."""
        index = self._touched if alive is None else self._touched[alive[self._touched]]
        return float(
            _penalty_energy(
                index, x, self.radius, self.masks, self.stiffness, *self.colliders.kernel_arrays[1:]
            )
        )

    def jacobian_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """One 3×3 block per particle that meets a penalty collider."""
        return self._touched, self._touched

    def add_jacobian(
        self,
        t: float,
        x: np.ndarray,
        v: np.ndarray,
        dfdx: np.ndarray,
        dfdv: np.ndarray,
        form: JacobianForm = "exact",
    ) -> None:
        """The blocks of the module docstring, summed over the colliders in contact.
        ``"symmetric"``: without the damper's change of direction with position
        (``−c n vᵀH``); ``"definite"``: without the curvature term ``f H`` too, which pushes a
        particle sideways off a sphere (positive in ``∂F/∂x``: it makes the potential's
        Hessian indefinite)."""
        symmetric, definite = form != "exact", form == "definite"
        _penalty(
            self._touched,
            x,
            v,
            self.radius,
            self.masks,
            self.stiffness,
            self.damping,
            np.zeros((0, 3)),
            dfdx,
            dfdv,
            symmetric,
            definite,
            *self.colliders.kernel_arrays[1:],
        )


@njit(cache=True, error_model="numpy")
def _penalty(
    index,
    x,
    v,
    radius,
    masks,
    stiffness,
    damping,
    out,
    dfdx,
    dfdv,
    symmetric,
    definite,
    kinds,
    rows,
    offsets,
    nb,
    nl,
    tp,
    tn,
):  # pragma: no cover - compiled
    """Forces into ``out`` (if it has rows) and Jacobian blocks into ``dfdx``/``dfdv`` (if they
    have rows), for the particles ``index``; ``symmetric``/``definite`` leave out the terms
    :meth:`PenaltyContact.add_jacobian` names."""
    forces = out.shape[0] > 0
    for b in range(index.shape[0]):
        i = index[b]
        for k in range(kinds.shape[0]):
            if not (masks[i] >> np.uint64(k)) & np.uint64(1):
                continue
            d, nx, ny, nz = collider_distance(
                k, x[i, 0], x[i, 1], x[i, 2], kinds, rows, offsets, nb, nl, tp, tn
            )
            gap = d - radius[i]
            if gap >= 0.0:
                continue
            n = np.array([nx, ny, nz])
            vn = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
            f = -stiffness[k] * gap - damping[k] * vn
            if f <= 0.0:
                continue
            if forces:
                for a in range(3):
                    out[i, a] += f * n[a]
                continue
            curvature = np.zeros((3, 3))
            if kinds[k] == _SPHERE and not definite:
                rho = abs(d + rows[k, 3])  # distance of the centre from the sphere's centre
                for r in range(3):
                    for c in range(3):
                        curvature[r, c] = ((1.0 if r == c else 0.0) - n[r] * n[c]) / rho
            # vᵀH, the velocity's change of v·n along each axis.
            vh = np.zeros(3) if symmetric else curvature.T @ v[i]
            for r in range(3):
                for c in range(3):
                    dfdx[b, r, c] += (
                        n[r] * (-stiffness[k] * n[c] - damping[k] * vh[c]) + f * curvature[r, c]
                    )
                    dfdv[b, r, c] -= damping[k] * n[r] * n[c]


@njit(cache=True, error_model="numpy")
def _penalty_energy(
    index, x, radius, masks, stiffness, kinds, rows, offsets, nb, nl, tp, tn
):  # pragma: no cover
    total = 0.0
    for i in index:
        for k in range(kinds.shape[0]):
            if not (masks[i] >> np.uint64(k)) & np.uint64(1):
                continue
            d, _, _, _ = collider_distance(
                k, x[i, 0], x[i, 1], x[i, 2], kinds, rows, offsets, nb, nl, tp, tn
            )
            gap = d - radius[i]
            if gap < 0.0:
                total += 0.5 * stiffness[k] * gap * gap
    return total
