"""The contacts of a state: which particles touch which colliders, where, and how they move.

Baraff's contact classification (seed 003; D. Baraff, "Physically based modeling: rigid body
simulation", SIGGRAPH 2001 course notes): at a contact with outward collider normal ``n``, the
relative normal velocity ``v_rel = n · v`` (the colliders are static) says what happens next:

* ``v_rel < −ε``: **colliding** — the particle moves into the collider; an impulse must stop it;
* ``|v_rel| ≤ ε``: **resting** — it stays in contact; a contact force (or the stage's resting
  rule) holds it;
* ``v_rel > ε``: **separating** — it leaves; nothing needs doing.

``ε`` is each collider's resting speed, the same threshold below which the collision stage
stops a particle from bouncing. A particle is in contact with a collider when the signed
distance of its centre is within its radius plus a small ``gap``.

:class:`Contacts` holds them as arrays, for users to inspect and plot (``sim.contacts()``):

>>> import numpy as np
>>> from visviva.collision import ColliderSet, Plane
>>> floor = ColliderSet([Plane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))])
>>> contacts = find_contacts(
...     np.array([[0.0, 0.1, 0.0], [1.0, 0.1, 0.0], [2.0, 0.5, 0.0]]),
...     np.array([[0.0, -2.0, 0.0], [0.0, 0.0, 0.0], [0.0, -1.0, 0.0]]),
...     np.full(3, 0.1), np.ones(3, dtype=bool), np.ones(3, dtype=np.uint64),
...     floor, np.array([0.05]), ("floor",),
... )
>>> contacts.particle.tolist(), contacts.classes()
([0, 1], ['colliding', 'resting'])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numba import njit, prange

from .colliders import ColliderSet, collider_distance

if TYPE_CHECKING:
    from ..ode.state import State

__all__ = [
    "CLASSES",
    "COLLIDING",
    "DEFAULT_GAP",
    "RESTING",
    "SEPARATING",
    "Classified",
    "ContactSource",
    "Contacts",
]

#: Contact classes (the codes of :attr:`Contacts.kind`).
COLLIDING, RESTING, SEPARATING = 0, 1, 2
CLASSES = ("colliding", "resting", "separating")
#: How far [m] beyond its radius a particle still counts as touching: the collision stage leaves
#: a resting particle on the surface up to round-off.
DEFAULT_GAP = 1e-6


class Classified:
    """What a set of contacts with Baraff's classes (a ``kind`` array) answers."""

    kind: np.ndarray

    def __len__(self) -> int:
        return int(self.kind.shape[0])

    def classes(self) -> list[str]:
        """Each contact's class by name."""
        return [CLASSES[k] for k in self.kind]

    def counts(self) -> dict[str, int]:
        """How many contacts of each class."""
        return {name: int(np.count_nonzero(self.kind == k)) for k, name in enumerate(CLASSES)}


@dataclass(frozen=True)
class Contacts(Classified):
    """Particle–collider contacts, one entry per touching pair, by particle then collider.

    Attributes:
        particle: ``(k,)`` slot index of the particle.
        collider: ``(k,)`` index of the collider in :attr:`labels`.
        point: ``(k, 3)`` the closest point of the collider's surface [m].
        normal: ``(k, 3)`` outward unit normal of the collider there.
        depth: ``(k,)`` penetration ``r − d`` [m] (negative: a gap smaller than the tolerance).
        normal_velocity: ``(k,)`` ``n · v`` [m/s] (negative: moving in).
        kind: ``(k,)`` :data:`COLLIDING`, :data:`RESTING` or :data:`SEPARATING`.
        labels: Each collider's name (or where it is in the scene).
    """

    particle: np.ndarray
    collider: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    normal_velocity: np.ndarray
    kind: np.ndarray
    labels: tuple[str, ...] = ()

    @classmethod
    def none(cls, labels: Sequence[str] = ()) -> Contacts:
        """No contacts."""
        return cls(
            np.zeros(0, np.int64),
            np.zeros(0, np.int64),
            np.zeros((0, 3)),
            np.zeros((0, 3)),
            np.zeros(0),
            np.zeros(0),
            np.zeros(0, np.int8),
            tuple(labels),
        )

    @classmethod
    def join(cls, parts: Sequence[Contacts]) -> Contacts:
        """The contacts of several collider sets as one, colliders numbered in turn and the
        contacts sorted by particle (then collider)."""
        if not parts:
            return cls.none()
        shifts = np.cumsum([0] + [len(p.labels) for p in parts])[:-1]
        collider = np.concatenate([p.collider + s for p, s in zip(parts, shifts, strict=True)])
        particle = np.concatenate([p.particle for p in parts])
        order = np.lexsort((collider, particle))
        return cls(
            particle[order],
            collider[order],
            np.concatenate([p.point for p in parts])[order],
            np.concatenate([p.normal for p in parts])[order],
            np.concatenate([p.depth for p in parts])[order],
            np.concatenate([p.normal_velocity for p in parts])[order],
            np.concatenate([p.kind for p in parts])[order],
            tuple(label for p in parts for label in p.labels),
        )


class ContactSource(Protocol):
    """Colliders that report their contacts with a state's particles: a collision stage's or
    a penalty force's."""

    def contacts(self, state: State, gap: float = DEFAULT_GAP) -> Contacts:
        """The contacts of ``state``'s live particles, surfaces within ``gap`` [m]."""
        ...


def find_contacts(
    x: np.ndarray,
    v: np.ndarray,
    radius: np.ndarray,
    alive: np.ndarray,
    masks: np.ndarray,
    colliders: ColliderSet,
    resting_speed: np.ndarray,
    labels: Sequence[str],
    gap: float = DEFAULT_GAP,
) -> Contacts:
    """The contacts of particles at ``x`` [m] moving at ``v`` [m/s] (``(N, 3)`` each) of
    radii ``radius`` with ``colliders`` (live particles only; bit ``k`` of ``masks[i]`` set
    where particle ``i`` meets collider ``k``), classified with each collider's
    ``resting_speed`` [m/s]."""
    arrays = colliders.kernel_arrays[1:]
    x, v = np.ascontiguousarray(x, dtype=np.float64), np.ascontiguousarray(v, dtype=np.float64)
    counts = _count(x, radius, alive, masks, gap, *arrays)
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    total = int(starts[-1])
    contacts = Contacts(
        np.zeros(total, np.int64),
        np.zeros(total, np.int64),
        np.zeros((total, 3)),
        np.zeros((total, 3)),
        np.zeros(total),
        np.zeros(total),
        np.zeros(total, np.int8),
        tuple(labels),
    )
    if total:
        _fill(
            x,
            v,
            radius,
            alive,
            masks,
            gap,
            np.asarray(resting_speed, dtype=np.float64),
            starts,
            contacts.particle,
            contacts.collider,
            contacts.point,
            contacts.normal,
            contacts.depth,
            contacts.normal_velocity,
            contacts.kind,
            *arrays,
        )
    return contacts


@njit(cache=True, parallel=True)
def _count(x, radius, alive, masks, gap, kinds, rows, offsets, nb, nl, tp, tn):  # pragma: no cover
    """How many colliders each particle touches."""
    counts = np.zeros(x.shape[0], dtype=np.int64)
    for i in prange(x.shape[0]):
        if not alive[i] or masks[i] == 0:
            continue
        for k in range(kinds.shape[0]):
            if (masks[i] >> np.uint64(k)) & np.uint64(1):
                d, _, _, _ = collider_distance(
                    k, x[i, 0], x[i, 1], x[i, 2], kinds, rows, offsets, nb, nl, tp, tn
                )
                if d - radius[i] <= gap:
                    counts[i] += 1
    return counts


# fmt: off
@njit(cache=True, parallel=True)
def _fill(
    x, v, radius, alive, masks, gap, resting, starts,
    particle, collider, point, normal, depth, normal_velocity, kind,
    kinds, rows, offsets, nb, nl, tp, tn,
):  # pragma: no cover - compiled
    """Each particle's contacts, into its range ``starts[i]:starts[i + 1]`` of the outputs."""
    # fmt: on
    for i in prange(x.shape[0]):
        if starts[i + 1] == starts[i]:
            continue
        j = starts[i]
        for k in range(kinds.shape[0]):
            if not (masks[i] >> np.uint64(k)) & np.uint64(1):
                continue
            d, nx, ny, nz = collider_distance(
                k, x[i, 0], x[i, 1], x[i, 2], kinds, rows, offsets, nb, nl, tp, tn
            )
            if d - radius[i] > gap:
                continue
            particle[j], collider[j] = i, k
            point[j, 0] = x[i, 0] - d * nx
            point[j, 1] = x[i, 1] - d * ny
            point[j, 2] = x[i, 2] - d * nz
            normal[j, 0], normal[j, 1], normal[j, 2] = nx, ny, nz
            depth[j] = radius[i] - d
            vn = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
            normal_velocity[j] = vn
            if vn < -resting[k]:
                kind[j] = COLLIDING
            elif vn > resting[k]:
                kind[j] = SEPARATING
            else:
                kind[j] = RESTING
            j += 1
