"""Rigid bodies that touch: the contact stage of rigid bodies.

After each integrator step (and the projection onto unit quaternions), :class:`BodyContacts`
stops the bodies' pieces (:mod:`~visviva.collision.body_pieces`) from passing into each other,
into static convex scenery and into planes:

1. **Detection** at the step's end poses (:mod:`~visviva.collision.body_detection`): bounding
   boxes grown by each body's speculative reach — what it may travel in a step,
   ``h (|v| + |ω| r)``, plus :data:`SPECULATIVE` of its size — swept and pruned, then GJK/EPA
   and the contact manifold per candidate pair, and every moving piece against every plane.
2. **Impulses** (velocities): sequential impulses with restitution and Coulomb friction
   (:mod:`~visviva.collision.body_impulses`), the contacts in order bottom-up along gravity
   (a stack's support first, then back down) and warm-started from the impulses of the last
   step's contacts at the same place on the same pair of pieces (carried in the state).
3. **The step again**: each body is moved by ``(1 − τ) h Δv`` and turned by ``(1 − τ) h Δω``
   for the velocity change the impulses made, as if it had moved with its old velocity until
   its earliest collision of the step, at the fraction ``τ`` (from the contact's depths at the
   step's start and end, to first order; 0 for a body that only rests) and with the new one
   after: a resting body stays where it was, a bouncing one leaves from where it hit.
4. **Position correction**: what overlap is left beyond :data:`ALLOWANCE` of the smaller
   piece's size is removed by moving and turning the bodies (velocities untouched), in a
   quarter as many sweeps as the impulses (the impulses leave little).

A pair's coefficients are the larger restitution of the two and the geometric mean of their
frictions, ``e = max(e_a, e_b)``, ``μ = √(μ_a μ_b)`` (a rubber ball bounces off anything; ice
makes any pair slippery), unless the stage is given one value for every pair.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numba import njit

from ..errors import ModelError
from ..geometry.quaternions import quaternion_matrix
from ..ode.stage import Phase
from .body_detection import (
    contact_arrays,
    mesh_contacts,
    pair_contacts,
    piece_poses,
    plane_contacts,
)
from .body_pieces import BodyPieces
from .body_response import body_frames, normal_velocities, respond
from .broad_phase import overlapping_pairs
from .bvh import MeshBVH
from .contact_classes import COLLIDING, RESTING, SEPARATING, Classified
from .impact_time import pull_back
from .manifold import MAX_CONTACTS
from .movers import Movers

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["BodyContactSet", "BodyContacts", "Moving", "ParticleMembers", "Planes", "bodies_of"]

#: A body's speculative reach beyond its travel in a step, as a fraction of its pieces' size.
SPECULATIVE = 0.02
#: Overlap left alone by the position correction, as a fraction of the smaller piece's size:
#: a resting contact keeps touching (and is found again next step) instead of bouncing
#: between touching and not.
ALLOWANCE = 1e-4
#: Fraction of the excess overlap each position sweep removes.
CORRECTION = 0.4
#: A contact takes the last step's impulses of its pair's contact that lay within this
#: fraction of the piece's size of it.
MATCH = 0.05
#: How the impacts of a step are resolved (see :class:`BodyContacts`).
IMPACTS = ("sequential", "simultaneous")
#: How a fast body's time of impact is found, in :mod:`~visviva.collision.impact_time`'s order.
TIME_OF_IMPACT = ("advancement", "bisection")
#: When a body's time of impact is looked for.
BODY_TIME_OF_IMPACT = ("auto", "always", "never")
#: A body is fast, and its time of impact looked for by default, when it moves more than this
#: fraction of its size in a step: then it might pass through something as thin as itself.
FAST = 0.25
#: The carried parts, in order (:meth:`BodyContacts.carried_start`).
MEMORY = (
    "body_contact_key",
    "body_contact_anchor",
    "body_contact_normal_impulse",
    "body_contact_friction_impulse",
)


@dataclass(frozen=True)
class Planes:
    """Static planes the bodies collide with: ``(F, 3)`` points and outward unit normals,
    ``(F,)`` thicknesses [m] (``inf``: a half-space), restitutions and frictions."""

    point: np.ndarray
    normal: np.ndarray
    thickness: np.ndarray
    restitution: np.ndarray
    friction: np.ndarray

    @classmethod
    def none(cls) -> Planes:
        return cls(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0))


@dataclass(frozen=True)
class BodyContactSet(Classified):
    """The bodies' contacts at one moment, in solve order, for inspection.

    Attributes:
        piece_a, piece_b: ``(C,)`` the pieces (``piece_a`` is ``-1 − s`` for scenery ``s``:
            the planes, then the meshes' triangles).
        body_a, body_b: ``(C,)`` their bodies (``-1``: the world).
        point, normal: ``(C, 3)`` contact points [m] and unit normals from A toward B.
        depth: ``(C,)`` penetration [m] (negative: a gap).
        normal_velocity: ``(C,)`` relative normal velocity of B's point from A's [m/s]
            (negative: approaching).
        kind: ``(C,)`` :data:`~visviva.collision.contact_classes.COLLIDING`, ``RESTING`` or
            ``SEPARATING``: Baraff's classes with the stage's resting speed.
    """

    piece_a: np.ndarray
    piece_b: np.ndarray
    body_a: np.ndarray
    body_b: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    normal_velocity: np.ndarray
    kind: np.ndarray


class BodyContacts:
    """The rigid bodies' contact stage (see the module docstring).

    Args:
        pieces: The bodies' and the scenery's convex pieces.
        mass: ``(B,)`` [kg]; ``inertia``: ``(B, 3, 3)`` about the centre of mass in each
            body's axes [kg·m²].
        dynamic: ``(B,)`` bool: the bodies contacts push (the others have infinite mass).
        planes: Static planes.
        meshes: Static triangle meshes, each ``(tree, restitution, friction)``
            (:class:`~visviva.collision.bvh.MeshBVH`): a body meets them from outside.
        iterations: Sweeps of impulses, and of position corrections, per step.
        resting_speed: Approach speed [m/s] below which a contact rests.
        restitution, friction: One coefficient for every pair, or ``None`` for the pair rule.
        gravity: Gravitational acceleration [m/s²]: the contacts are swept against it.
        time_of_impact: How a fast body's first impact in a step is found
            (:mod:`~visviva.collision.impact_time`): ``"advancement"`` (conservative
            advancement, which sees a body pass through a thin one) or ``"bisection"`` (seed
            003's, which needs the overlap at the step's end).
        body_time_of_impact: Per body, ``"auto"`` (when it moves more than :data:`FAST` of
            its size in a step), ``"always"`` or ``"never"``.
        impacts: ``"sequential"``: a colliding contact's bounce is a target of the impulse
            sweeps, with the resting contacts; ``"simultaneous"``: the impacts of a step are
            resolved first, together, by generalized reflections
            (:mod:`~visviva.collision.simultaneous`), so an impact travels along a row of
            touching bodies as in a Newton's cradle.
    """

    phase: ClassVar[Phase] = Phase.CONTACTS
    order: ClassVar[int] = 2
    compiled: ClassVar[bool] = False
    changes_energy: ClassVar[bool] = True
    kills_particles: ClassVar[bool] = False

    def __init__(
        self,
        pieces: BodyPieces,
        mass: np.ndarray,
        inertia: np.ndarray,
        dynamic: np.ndarray,
        planes: Planes,
        *,
        meshes: Sequence[tuple[MeshBVH, float, float]] = (),
        iterations: int = 20,
        resting_speed: float = 0.0,
        restitution: float | None = None,
        friction: float | None = None,
        gravity: Sequence[float] = (0.0, -9.81, 0.0),
        impacts: str = "sequential",
        time_of_impact: str = "advancement",
        body_time_of_impact: Sequence[str] | None = None,
        particles: ParticleMembers | None = None,
    ) -> None:
        self.movers = Movers.of_bodies(pieces, mass, inertia, dynamic)
        self.count = self.movers.count
        self.planes = planes
        self.meshes = tuple(meshes)
        # The scenery a contact's piece A may be instead of a piece, numbered -1 − id: the
        # planes, then each mesh's triangle slots; with each one's coefficients.
        sizes = [bvh.triangle_points.shape[0] for bvh, _, _ in self.meshes]
        self.mesh_first = np.concatenate([[planes.point.shape[0]], planes.point.shape[0]
                                          + np.cumsum(sizes, dtype=np.int64)])[:-1]  # fmt: skip
        self.scenery_restitution = np.concatenate(
            [planes.restitution, *[np.full(n, e) for n, (_, e, _) in zip(sizes, self.meshes,
                                                                          strict=True)]]
        )  # fmt: skip
        self.scenery_friction = np.concatenate(
            [planes.friction, *[np.full(n, mu) for n, (_, _, mu) in zip(sizes, self.meshes,
                                                                         strict=True)]]
        )  # fmt: skip
        self.iterations = iterations
        self.resting_speed = resting_speed
        self.restitution = restitution
        self.friction = friction
        if impacts not in IMPACTS:
            raise ModelError(
                f"`impacts` must be one of {', '.join(map(repr, IMPACTS))} (got {impacts!r})"
            )
        self.impacts = impacts
        if time_of_impact not in TIME_OF_IMPACT:
            raise ModelError(
                f"`time_of_impact` must be one of {', '.join(map(repr, TIME_OF_IMPACT))} "
                f"(got {time_of_impact!r})"
            )
        self.time_of_impact = TIME_OF_IMPACT.index(time_of_impact)
        modes = ["auto"] * self.count if body_time_of_impact is None else list(body_time_of_impact)
        self.fast_mode = np.array([BODY_TIME_OF_IMPACT.index(m) for m in modes], dtype=np.int64)
        g = np.asarray(gravity, dtype=np.float64)
        size = float(np.linalg.norm(g))
        self.up = -g / size if size > 0.0 else np.zeros(3)
        self.particles = particles

    def carried_start(self) -> dict[str, np.ndarray]:
        """The last step's contacts for the warm start: ``body_contact_key`` ``(C,)`` (the
        pair of pieces), ``body_contact_anchor`` ``(C, 3)`` (the point in piece B's axes),
        ``body_contact_normal_impulse`` ``(C,)`` and ``body_contact_friction_impulse``
        ``(C, 3)`` [N·s]; empty at the start."""
        return dict(zip(MEMORY, (np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0),
                                 np.zeros((0, 3))), strict=True))  # fmt: skip

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """The state with the bodies' contacts resolved (and those of the particles that meet
        them)."""
        if not all(np.isfinite(part).all() for part in after.parts):
            return after  # diverged: the stepper's watch stops the run and says why
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        bodies = Moving(
            result["body_position"], result["body_orientation"], result["body_momentum"],
            result["body_angular_momentum"],
        )  # fmt: skip
        x0, q0 = before["body_position"], before["body_orientation"]
        movers = self.movers
        _, _, v0, w0 = body_frames(q0, movers.inverse_inertia, movers.inverse_mass,
                                   before["body_momentum"],
                                   before["body_angular_momentum"])  # fmt: skip
        start = (x0, q0, v0, w0)
        self.pull_back(x0, q0, bodies.position, bodies.orientation)
        memory = tuple(after[name] for name in MEMORY)
        members = self.particles
        if members is not None:
            index = np.flatnonzero(after["particle_alive"] & members.mask)
            if index.size:
                memory = self._with_particles(bodies, start, result, before, after, index, h,
                                              memory)  # fmt: skip
                return result.with_carried(**dict(zip(MEMORY, memory, strict=True)))
        memory = self.resolve(self.movers, bodies, h, memory, start)
        return result.with_carried(**dict(zip(MEMORY, memory, strict=True)))

    def _with_particles(self, bodies, start, result, before, after, index, h, memory):
        """Resolve the bodies' contacts with the particles ``index`` that meet them as movers
        after the bodies; in place on ``result``'s bodies and particles."""
        members = self.particles
        inverse = members.inverse_mass[index]
        movers = self.movers.with_particles(after["particle_radius"][index], inverse,
                                            members.restitution, members.friction)  # fmt: skip
        position = result["particle_position"]
        velocity = result["particle_velocity"]
        k = index.size
        identity = np.tile([1.0, 0.0, 0.0, 0.0], (k, 1))
        with np.errstate(divide="ignore"):
            mass = np.where(inverse > 0.0, 1.0 / inverse, 0.0)
        everyone = Moving(
            np.concatenate([bodies.position, position[index]]),
            np.concatenate([bodies.orientation, identity]),
            np.concatenate([bodies.momentum, velocity[index] * mass[:, None]]),
            np.concatenate([bodies.spin, np.zeros((k, 3))]),
        )
        x0, q0, v0, w0 = start
        everyone_start = (
            np.concatenate([x0, before["particle_position"][index]]),
            np.concatenate([q0, identity]),
            np.concatenate([v0, before["particle_velocity"][index]]),
            np.concatenate([w0, np.zeros((k, 3))]),
        )
        memory = self.resolve(movers, everyone, h, memory, everyone_start)
        b = self.count
        bodies.position[...] = everyone.position[:b]
        bodies.orientation[...] = everyone.orientation[:b]
        bodies.momentum[...] = everyone.momentum[:b]
        bodies.spin[...] = everyone.spin[:b]
        position[index] = everyone.position[b:]
        moved = inverse > 0.0
        velocity[index[moved]] = everyone.momentum[b:][moved] * inverse[moved, None]
        return memory

    def contacts(self, state: Mapping[str, np.ndarray], gap: float) -> BodyContactSet:
        """The contacts of ``state``'s bodies (a state, or a mapping of ``body_position``,
        ``body_orientation``, ``body_momentum`` and ``body_angular_momentum``): the pairs of
        pieces within ``gap`` [m] of each other, classified with the stage's resting speed."""
        movers = self.movers
        x = np.ascontiguousarray(state["body_position"], dtype=np.float64)
        q = np.asarray(state["body_orientation"], dtype=np.float64)
        q = q / np.linalg.norm(q, axis=1, keepdims=True)
        momentum = np.ascontiguousarray(state["body_momentum"], dtype=np.float64)
        spin = np.ascontiguousarray(state["body_angular_momentum"], dtype=np.float64)
        rotation, _, v, w = body_frames(q, movers.inverse_inertia, movers.inverse_mass,
                                        momentum, spin)  # fmt: skip
        found, _, _ = self.detect(movers, x, rotation, np.full(self.count, 0.5 * gap))
        piece_a, piece_b, point, normal, depth = found
        body_a, body_b = bodies_of(movers, piece_a, piece_b)
        arm_a = np.where((body_a >= 0)[:, None], point - x[body_a], 0.0)
        arm_b = point - x[body_b]
        velocity = normal_velocities(body_a, body_b, normal, arm_a, arm_b, v, w)
        kind = np.full(velocity.shape, RESTING, dtype=np.int64)
        kind[velocity < -self.resting_speed] = COLLIDING
        kind[velocity > self.resting_speed] = SEPARATING
        return BodyContactSet(piece_a, piece_b, body_a, body_b, point, normal, depth,
                              velocity, kind)  # fmt: skip

    def detect(self, movers: Movers, x: np.ndarray, rotation: np.ndarray,
               margin: np.ndarray) -> tuple:  # fmt: skip
        """The contacts of the ``movers`` at centres of mass ``x`` ``(M, 3)`` and rotations
        ``(M, 3, 3)``, with speculative reach ``margin`` ``(M,)`` [m]: ``(piece_a, piece_b,
        point, normal, depth)`` and the pieces' world poses."""
        pieces = movers.pieces
        arrays = pieces.arrays()
        position = pieces.local_position.copy()
        turn = pieces.local_rotation.copy()
        lo = np.empty((pieces.count, 3))
        hi = np.empty((pieces.count, 3))
        piece_poses(arrays, pieces.body, x, rotation, margin, position, turn, lo, hi)
        active = np.ones(pieces.count, dtype=np.bool_)
        pairs = overlapping_pairs(lo, hi, active)
        # Pieces that nothing moves never need contacts, nor do two particles (their own
        # stage's), nor a particle and the scenery (the colliders' stage's).
        moving = np.append(movers.dynamic, False)[pieces.body]
        particle = movers.particle
        static = pieces.body < 0
        first, second = pairs[:, 0], pairs[:, 1]
        keep = (moving[first] | moving[second]) & ~(particle[first] & particle[second])
        keep &= ~((particle[first] & static[second]) | (particle[second] & static[first]))
        pairs = pairs[keep]
        meets = ~particle
        planes = self.planes
        scenery = planes.point.shape[0] + 16 * len(self.meshes)
        capacity = MAX_CONTACTS * (pairs.shape[0] + scenery * pieces.count) + 16
        while True:
            out = contact_arrays(capacity)
            count = pair_contacts(arrays, pieces.body, pairs, position, turn, margin, out)
            count = plane_contacts(arrays, pieces.body, meets, position, turn, lo, hi, margin,
                                   planes.point, planes.normal, planes.thickness, out,
                                   count)  # fmt: skip
            for (bvh, _, _), first_id in zip(self.meshes, self.mesh_first, strict=True):
                count = mesh_contacts(bvh.node_bounds, bvh.node_links, bvh.triangle_points,
                                      first_id, arrays, pieces.body, meets, position, turn, lo,
                                      hi, margin, out, count)  # fmt: skip
            if count < capacity:
                return tuple(a[:count] for a in out), position, turn
            capacity *= 2  # a mesh gave more contacts than room was made for

    def resolve(self, movers: Movers, moving: Moving, h: float, memory: tuple,
                start: tuple | None = None) -> tuple:  # fmt: skip
        """Resolve one step's contacts of the ``movers`` in place on their state ``moving``;
        ``memory`` the last step's carried impulses; ``start`` the movers at the step's start,
        ``(x, q, v, ω)``, if known: the contacts' depths at the start are then measured from
        how the movers moved, and a collision within the step reverses the approach at the
        moment of impact, not the step's end. Returns this step's contacts and impulses, the
        carried parts (:data:`MEMORY`) the next step warm-starts from."""
        x, q, momentum, spin = moving.position, moving.orientation, moving.momentum, moving.spin
        rotation, inverse_inertia, v, w = body_frames(
            q, movers.inverse_inertia, movers.inverse_mass, momentum, spin
        )
        speed = np.sqrt((v * v).sum(axis=1)) + np.sqrt((w * w).sum(axis=1)) * movers.size
        margin = h * speed + SPECULATIVE * movers.size
        found, position, turn = self.detect(movers, x, rotation, margin)
        pieces = movers.pieces
        # Bottom up along gravity: a stack's support is met before what rests on it, which
        # is what a sweep needs to carry the weight down in few iterations.
        order = np.argsort(found[2] @ self.up, kind="stable")
        piece_a, piece_b, point, normal, depth = (a[order] for a in found)
        body_a, body_b = bodies_of(movers, piece_a, piece_b)
        restitution, friction = self.coefficients(pieces, piece_a, piece_b)
        key = (piece_a + self.scenery_restitution.shape[0]) * (pieces.count + 1) + piece_b
        anchor = np.einsum("cji,cj->ci", turn[piece_b], point - position[piece_b])
        warm_normal, warm_friction = _warm_start(key, anchor, MATCH * pieces.radius[piece_b],
                                                 *memory)  # fmt: skip
        if start is None:
            has_start, x0, q0, v0, w0 = False, x, q, v, w
        else:
            has_start, (x0, q0, v0, w0) = True, start
        radius = pieces.radius
        smaller = np.minimum(np.where(piece_a >= 0, radius[np.maximum(piece_a, 0)], np.inf),
                             radius[piece_b])  # fmt: skip
        normal_impulse, friction_impulse = respond(
            body_a, body_b, point, normal, depth, restitution, friction, warm_normal,
            warm_friction, x, q, momentum, spin, rotation, inverse_inertia, v, w,
            movers.inverse_mass, movers.inertia, movers.dynamic,
            has_start, x0, q0, v0, w0,
            h, self.resting_speed, self.iterations, max(self.iterations // 4, 1),
            ALLOWANCE * smaller, CORRECTION, self.impacts == "simultaneous",
        )  # fmt: skip
        return key, anchor, normal_impulse, friction_impulse

    def pull_back(self, x0: np.ndarray, q0: np.ndarray, x: np.ndarray, q: np.ndarray) -> int:
        """Move each fast body (see ``body_time_of_impact``) back along its step from
        ``(x0, q0)`` to ``(x, q)`` to its first impact, in place on ``x`` and ``q``; returns
        how many were moved (:mod:`~visviva.collision.impact_time`)."""
        movers = self.movers
        travel = np.sqrt(((x - x0) ** 2).sum(axis=1))
        mode = self.fast_mode
        fast = movers.dynamic & ((mode == 1) | ((mode == 0) & (travel > FAST * movers.size)))
        if not fast.any():
            return 0
        pieces = movers.pieces
        arrays = pieces.arrays()
        bounds = []
        for position, orientation in ((x0, q0), (x, q)):
            unit = orientation / np.linalg.norm(orientation, axis=1, keepdims=True)
            lo = np.empty((pieces.count, 3))
            hi = np.empty((pieces.count, 3))
            piece_poses(arrays, pieces.body, position, quaternion_matrix(unit),
                        np.zeros(self.count), pieces.local_position.copy(),
                        pieces.local_rotation.copy(), lo, hi)  # fmt: skip
            bounds.append((lo, hi))
        lo = np.minimum(bounds[0][0], bounds[1][0])
        hi = np.maximum(bounds[0][1], bounds[1][1])
        pairs = overlapping_pairs(lo, hi, np.ones(pieces.count, dtype=np.bool_))
        return pull_back(pairs, fast, self.time_of_impact, ALLOWANCE, arrays, pieces.body,
                         pieces.local_position, pieces.local_rotation, movers.reach,
                         pieces.radius, x0, q0, x, q)  # fmt: skip

    def coefficients(self, pieces: BodyPieces, piece_a: np.ndarray,
                      piece_b: np.ndarray) -> tuple[np.ndarray, ...]:  # fmt: skip
        """Each contact's restitution and friction (the pair rule, or the stage's value)."""
        scenery = -1 - np.minimum(piece_a, -1)
        on_scenery = piece_a < 0
        index = np.maximum(piece_a, 0)
        has = self.scenery_restitution.shape[0] > 0
        e_a = np.where(on_scenery, self.scenery_restitution[scenery] if has else 0.0,
                       pieces.restitution[index])  # fmt: skip
        mu_a = np.where(on_scenery, self.scenery_friction[scenery] if has else 0.0,
                        pieces.friction[index])  # fmt: skip
        e = np.maximum(e_a, pieces.restitution[piece_b])
        mu = np.sqrt(mu_a * pieces.friction[piece_b])
        if self.restitution is not None:
            e = np.full_like(e, self.restitution)
        if self.friction is not None:
            mu = np.full_like(mu, self.friction)
        return e, mu


@dataclass(frozen=True)
class Moving:
    """The movers' state a step changes, in place: centres of mass ``(M, 3)`` [m],
    orientations ``(M, 4)``, momenta ``(M, 3)`` [kg·m/s] and angular momenta ``(M, 3)``
    [kg·m²/s] (world frame)."""

    position: np.ndarray
    orientation: np.ndarray
    momentum: np.ndarray
    spin: np.ndarray


@dataclass(frozen=True)
class ParticleMembers:
    """The particles that meet the bodies: ``mask`` ``(N,)`` over the particle slots, their
    ``inverse_mass`` ``(N,)`` [1/kg] (0: held), and the ``restitution`` and ``friction`` of
    their contacts (with a body's, by the pair rule)."""

    mask: np.ndarray
    inverse_mass: np.ndarray
    restitution: float
    friction: float


def bodies_of(movers: Movers, piece_a: np.ndarray, piece_b: np.ndarray) -> tuple:
    """The movers of the contacts' pieces (-1: a plane or the scenery)."""
    body = movers.pieces.body
    return np.where(piece_a >= 0, body[np.maximum(piece_a, 0)], -1), body[piece_b]


@njit(cache=True)
def _warm_start(key, anchor, tolerance, old_key, old_anchor, old_normal, old_friction):
    """Each contact's warm start: the impulses (normal ``(C,)``, friction ``(C, 3)`` world
    frame) of the last step's contact of the same pair of pieces whose anchor lay nearest,
    within ``tolerance`` [m]; zero for a new contact."""
    count = key.shape[0]
    normal = np.zeros(count)
    friction = np.zeros((count, 3))
    if old_key.shape[0] == 0:
        return normal, friction
    order = np.argsort(old_key, kind="mergesort")
    sorted_keys = old_key[order]
    for c in range(count):
        best = -1
        best_distance = tolerance[c] * tolerance[c]
        k = np.searchsorted(sorted_keys, key[c])
        while k < sorted_keys.shape[0] and sorted_keys[k] == key[c]:
            o = order[k]
            d = 0.0
            for i in range(3):
                d += (old_anchor[o, i] - anchor[c, i]) ** 2
            if d <= best_distance:
                best_distance = d
                best = o
            k += 1
        if best >= 0:
            normal[c] = old_normal[best]
            for i in range(3):
                friction[c, i] = old_friction[best, i]
    return normal, friction
