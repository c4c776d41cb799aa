"""Rigid bodies that touch: the contact stage of rigid bodies.

After each integrator step (and the projection onto unit quaternions), :class:`BodyContacts`
stops the bodies' pieces (:mod:`~visviva.collision.body_pieces`) from passing into each other,
into static convex scenery and into planes:

1. **Detection** at the step's end poses (:mod:`~visviva.collision.body_detection`): bounding
   boxes grown by each body's speculative reach — what it may travel in a step,
   ``h (|v| + |ω| r)``, plus :data:`SPECULATIVE` of its size — swept and pruned, then GJK/EPA
   and the contact manifold per candidate pair, and every moving piece against every plane.
2. **Impulses** (velocities): sequential impulses with restitution and Coulomb friction
   (:mod:`~visviva.collision.body_impulses`), swept bottom-up along gravity (a stack's support
   first) and warm-started from the impulses of the last step's contacts at the same place on
   the same pair of pieces (carried in the state).
3. **The step again**: each body is moved by ``(1 − τ) h Δv`` and turned by ``(1 − τ) h Δω``
   for the velocity change the impulses made, as if it had moved with its old velocity until
   its earliest collision of the step, at the fraction ``τ`` (from the contact's depths at the
   step's start and end, to first order; 0 for a body that only rests) and with the new one
   after: a resting body stays where it was, a bouncing one leaves from where it hit.
4. **Position correction**: what overlap is left beyond :data:`ALLOWANCE` of the smaller
   piece's size is removed by moving and turning the bodies (velocities untouched).

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

from ..geometry.quaternions import quaternion_matrix
from ..ode.stage import Phase
from .body_detection import contact_arrays, pair_contacts, piece_poses, plane_contacts
from .body_impulses import correct_positions, prepare_contacts, solve_impulses
from .body_pieces import BodyPieces
from .broad_phase import overlapping_pairs
from .contact_classes import CLASSES, COLLIDING, RESTING, SEPARATING
from .manifold import MAX_CONTACTS

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["BodyContactSet", "BodyContacts", "Planes"]

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
class BodyContactSet:
    """The bodies' contacts at one moment, in solve order, for inspection.

    Attributes:
        piece_a, piece_b: ``(C,)`` the pieces (``-1 − f`` for plane ``f`` as ``piece_a``).
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

    def __len__(self) -> int:
        return int(self.piece_a.shape[0])

    def classes(self) -> list[str]:
        """Each contact's class by name."""
        return [CLASSES[k] for k in self.kind]

    def counts(self) -> dict[str, int]:
        """How many contacts of each class."""
        return {name: int(np.count_nonzero(self.kind == k)) for k, name in enumerate(CLASSES)}


class BodyContacts:
    """The rigid bodies' contact stage (see the module docstring).

    Args:
        pieces: The bodies' and the scenery's convex pieces.
        mass: ``(B,)`` [kg]; ``inertia``: ``(B, 3, 3)`` about the centre of mass in each
            body's axes [kg·m²].
        dynamic: ``(B,)`` bool: the bodies contacts push (the others have infinite mass).
        planes: Static planes.
        iterations: Sweeps of impulses, and of position corrections, per step.
        resting_speed: Approach speed [m/s] below which a contact rests.
        restitution, friction: One coefficient for every pair, or ``None`` for the pair rule.
        gravity: Gravitational acceleration [m/s²]: the contacts are swept against it.
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
        iterations: int = 20,
        resting_speed: float = 0.0,
        restitution: float | None = None,
        friction: float | None = None,
        gravity: Sequence[float] = (0.0, -9.81, 0.0),
    ) -> None:
        self.pieces = pieces
        self.count = int(np.shape(mass)[0])
        dynamic = np.asarray(dynamic, dtype=np.bool_)
        self.inverse_mass = np.where(dynamic, 1.0 / np.asarray(mass, dtype=np.float64), 0.0)
        self.inertia = np.asarray(inertia, dtype=np.float64)
        self.inverse_inertia_body = np.where(
            dynamic[:, None, None], np.linalg.inv(self.inertia), 0.0
        )
        self.dynamic = dynamic
        self.planes = planes
        self.iterations = iterations
        self.resting_speed = resting_speed
        self.restitution = restitution
        self.friction = friction
        g = np.asarray(gravity, dtype=np.float64)
        size = float(np.linalg.norm(g))
        self.up = -g / size if size > 0.0 else np.zeros(3)
        # Each body's size: its largest piece's reach from the centre of mass.
        size = np.zeros(self.count)
        for p in range(pieces.count):
            b = pieces.body[p]
            if b >= 0:
                reach = np.linalg.norm(pieces.local_position[p]) + pieces.radius[p]
                size[b] = max(size[b], reach)
        self.size = size

    def carried_start(self) -> dict[str, np.ndarray]:
        """The last step's contacts for the warm start: ``body_contact_key`` ``(C,)`` (the
        pair of pieces), ``body_contact_anchor`` ``(C, 3)`` (the point in piece B's axes),
        ``body_contact_normal_impulse`` ``(C,)`` and ``body_contact_friction_impulse``
        ``(C, 3)`` [N·s]; empty at the start."""
        return dict(zip(MEMORY, (np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0),
                                 np.zeros((0, 3))), strict=True))  # fmt: skip

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """The state with the bodies' contacts resolved."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        x = result["body_position"]
        q = result["body_orientation"]
        momentum = result["body_momentum"]
        spin = result["body_angular_momentum"]
        memory = tuple(after[name] for name in MEMORY)
        q0 = before["body_orientation"]
        v0, w0 = self.velocities(q0, before["body_momentum"], before["body_angular_momentum"])
        start = (before["body_position"], q0, v0, w0)
        memory = self.resolve(x, q, momentum, spin, h, memory, start)
        return result.with_carried(**dict(zip(MEMORY, memory, strict=True)))

    def contacts(self, state: Mapping[str, np.ndarray], gap: float) -> BodyContactSet:
        """The contacts of ``state``'s bodies (a state, or a mapping of ``body_position``,
        ``body_orientation``, ``body_momentum`` and ``body_angular_momentum``): the pairs of
        pieces within ``gap`` [m] of each other, classified with the stage's resting speed."""
        x = np.ascontiguousarray(state["body_position"], dtype=np.float64)
        q = np.asarray(state["body_orientation"], dtype=np.float64)
        q = q / np.linalg.norm(q, axis=1, keepdims=True)
        v, w = self.velocities(q, state["body_momentum"], state["body_angular_momentum"])
        found, _, _ = self.detect(x, quaternion_matrix(q), np.full(self.count, 0.5 * gap))
        piece_a, piece_b, point, normal, depth = found
        body_a, body_b = self._bodies_of(piece_a, piece_b)
        arm_a = np.where((body_a >= 0)[:, None], point - x[body_a], 0.0)
        arm_b = point - x[body_b]
        velocity = _normal_velocities(body_a, body_b, normal, arm_a, arm_b, v, w)
        kind = np.full(velocity.shape, RESTING, dtype=np.int64)
        kind[velocity < -self.resting_speed] = COLLIDING
        kind[velocity > self.resting_speed] = SEPARATING
        return BodyContactSet(piece_a, piece_b, body_a, body_b, point, normal, depth,
                              velocity, kind)  # fmt: skip

    def _bodies_of(self, piece_a: np.ndarray, piece_b: np.ndarray) -> tuple[np.ndarray, ...]:
        """The bodies of the contacts' pieces (-1: a plane or the scenery)."""
        body = self.pieces.body
        return np.where(piece_a >= 0, body[np.maximum(piece_a, 0)], -1), body[piece_b]

    def detect(self, x: np.ndarray, rotation: np.ndarray, margin: np.ndarray) -> tuple:
        """The contacts at centres of mass ``x`` ``(B, 3)`` and rotations ``(B, 3, 3)``, with
        speculative reach ``margin`` ``(B,)`` [m]: ``(piece_a, piece_b, point, normal,
        depth)`` and the pieces' world poses."""
        pieces = self.pieces
        arrays = pieces.arrays()
        position = pieces.local_position.copy()
        turn = pieces.local_rotation.copy()
        lo = np.empty((pieces.count, 3))
        hi = np.empty((pieces.count, 3))
        piece_poses(arrays, pieces.body, x, rotation, margin, position, turn, lo, hi)
        active = np.ones(pieces.count, dtype=np.bool_)
        pairs = overlapping_pairs(lo, hi, active)
        # Two pieces of bodies that nothing moves never need contacts.
        moving = np.append(self.dynamic, False)[pieces.body]
        pairs = pairs[moving[pairs[:, 0]] | moving[pairs[:, 1]]]
        planes = self.planes
        capacity = MAX_CONTACTS * (pairs.shape[0] + planes.point.shape[0] * pieces.count)
        out = contact_arrays(capacity)
        count = pair_contacts(arrays, pieces.body, pairs, position, turn, margin, out)
        count = plane_contacts(arrays, pieces.body, position, turn, lo, hi, margin, planes.point,
                               planes.normal, planes.thickness, out, count)  # fmt: skip
        return tuple(a[:count] for a in out), position, turn

    def velocities(self, q: np.ndarray, momentum: np.ndarray, spin: np.ndarray) -> tuple:
        """``v = P/M`` and ``ω = I⁻¹ L`` ``(B, 3)`` of the dynamic bodies (0 for the others)."""
        rotation = quaternion_matrix(q)
        inverse_inertia = rotation @ self.inverse_inertia_body @ rotation.transpose(0, 2, 1)
        return momentum * self.inverse_mass[:, None], np.einsum("bij,bj->bi", inverse_inertia, spin)

    def resolve(self, x, q, momentum, spin, h, memory, start=None):
        """Resolve one step's contacts in place on the bodies' ``x``, ``q``, ``P``, ``L``
        (``(B, 3)``, ``(B, 4)``, ``(B, 3)``, ``(B, 3)``); ``memory`` the last step's carried
        impulses; ``start`` the bodies at the step's start, ``(x, q, v, ω)``, if known: the
        contacts' depths at the start are then measured from how the bodies moved, and a
        collision within the step reverses the approach at the moment of impact, not the
        step's end. Returns this step's contacts and impulses, the carried parts (:data:`MEMORY`)
        the next step warm-starts from."""
        rotation = quaternion_matrix(q)
        inverse_inertia = rotation @ self.inverse_inertia_body @ rotation.transpose(0, 2, 1)
        v = momentum * self.inverse_mass[:, None]
        w = np.einsum("bij,bj->bi", inverse_inertia, spin)
        speed = np.linalg.norm(v, axis=1) + np.linalg.norm(w, axis=1) * self.size
        margin = h * speed + SPECULATIVE * self.size
        found, position, turn = self.detect(x, rotation, margin)
        # Bottom up along gravity: a stack's support is met before what rests on it, which
        # is what a sweep needs to carry the weight down in few iterations.
        order = np.argsort(found[2] @ self.up, kind="stable")
        piece_a, piece_b, point, normal, depth = (a[order] for a in found)
        pieces = self.pieces
        body_a, body_b = self._bodies_of(piece_a, piece_b)
        restitution, friction = self._coefficients(piece_a, piece_b)
        count = piece_a.shape[0]
        arm_a, arm_b = np.zeros((count, 3)), np.zeros((count, 3))
        frame = np.zeros((count, 2, 3))
        mass_n, mass_t, target = np.zeros(count), np.zeros((count, 2)), np.zeros(count)
        start_depth = self._start_depths(body_a, body_b, point, normal, depth, x, rotation, start)
        prepare_contacts(body_a, body_b, point, normal, depth, start_depth, restitution,
                         self.resting_speed,
                         h, x, self.inverse_mass, inverse_inertia, v, w, arm_a, arm_b, frame,
                         mass_n, mass_t, target)  # fmt: skip
        velocity_before = _normal_velocities(body_a, body_b, normal, arm_a, arm_b, v, w)
        if start is not None:
            self._reverse_at_impact(body_a, body_b, normal, arm_a, arm_b, depth, start_depth,
                                    restitution, velocity_before, start[2:], target)  # fmt: skip
        key = (piece_a + self.planes.point.shape[0]) * (pieces.count + 1) + piece_b
        anchor = np.einsum("cji,cj->ci", turn[piece_b], point - position[piece_b])
        normal_impulse = np.zeros(count)
        tangent_impulse = np.zeros((count, 2))
        _warm_start(key, anchor, MATCH * pieces.radius[piece_b], frame, *memory,
                    normal_impulse, tangent_impulse)  # fmt: skip
        v_start, w_start = v.copy(), w.copy()
        solve_impulses(body_a, body_b, normal, friction, arm_a, arm_b, frame, mass_n, mass_t,
                       target, self.inverse_mass, inverse_inertia, v, w, normal_impulse,
                       tangent_impulse, self.iterations)  # fmt: skip
        # The step again with the new velocities: a body that collided within the step moves
        # as the integrator moved it until the impact (the fraction τ of the step at which its
        # earliest colliding contact touched, to first order), with its new velocity after;
        # the others touched as if they had had the new velocity all along. So each body the
        # impulses changed ends at x(τ) + (1 − τ) h v: moved by (1 − τ)(h v − Δx) for the
        # step's move Δx (h v before the impulses if the start is unknown), turned likewise.
        impact = self._impact_fractions(body_a, body_b, depth, start_depth, velocity_before, h)
        remainder = (1.0 - impact)[:, None]
        travel, rotation_vector = (
            (h * v_start, h * w_start) if start is None else _moves(start[0], start[1], x, q)
        )
        touched = (np.any(v != v_start, axis=1) | np.any(w != w_start, axis=1))[:, None]
        shift = np.where(touched, remainder * (h * v - travel), 0.0)
        twist = np.where(touched, remainder * (h * w - rotation_vector), 0.0)
        moved = _normal_velocities(body_a, body_b, normal, arm_a, arm_b, shift, twist)
        remaining = depth - moved
        smaller = np.minimum(
            np.where(piece_a >= 0, pieces.radius[np.maximum(piece_a, 0)], np.inf),
            pieces.radius[piece_b],
        )
        allowance = ALLOWANCE * float(smaller.min()) if count else 0.0
        correction, turn_correction = np.zeros_like(x), np.zeros_like(x)
        correct_positions(body_a, body_b, normal, remaining, arm_a, arm_b, mass_n,
                          self.inverse_mass, inverse_inertia, allowance, CORRECTION,
                          self.iterations, correction, turn_correction)  # fmt: skip
        x += shift + correction
        q[...] = _turned(q, twist + turn_correction)
        # Back to momenta, with the inertia of the step's end (world frame).
        mass = np.where(self.dynamic, 1.0 / np.where(self.dynamic, self.inverse_mass, 1.0), 0.0)
        momentum[...] = np.where(self.dynamic[:, None], mass[:, None] * v, momentum)
        inertia = rotation @ self.inertia @ rotation.transpose(0, 2, 1)
        spin[...] = np.where(self.dynamic[:, None], np.einsum("bij,bj->bi", inertia, w), spin)
        friction_world = np.einsum("ct,ctk->ck", tangent_impulse, frame)
        return key, anchor, normal_impulse, friction_world

    def _start_depths(self, body_a, body_b, point, normal, depth, x, rotation, start):
        """Each contact's depth at the step's start ``(C,)`` [m]: the end depth plus how far
        the two material points at the contact moved toward each other along ``n`` over the
        step (a point at arm ``r`` from the centre at the end was at ``x₀ + R₀ R₁ᵀ r``); NaN
        when the start is unknown."""
        if start is None:
            return np.full(depth.shape, np.nan)
        x0, q0 = start[0], start[1]
        turn = quaternion_matrix(q0) @ rotation.transpose(0, 2, 1)  # R₀ R₁ᵀ
        moved = np.zeros(point.shape)
        for body, sign in ((body_b, 1.0), (body_a, -1.0)):
            real = body >= 0
            b = body[real]
            arm = point[real] - x[b]
            earlier = x0[b] + np.einsum("cij,cj->ci", turn[b], arm)
            moved[real] += sign * (point[real] - earlier)
        return depth + np.einsum("ck,ck->c", moved, normal)

    @staticmethod
    def _impact_times(depth, start_depth):
        """The fraction of the step at which each contact touched, moving linearly from its
        start depth to its end depth (0 if it overlapped already at the start)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            tau = np.where(start_depth < 0.0, start_depth / (start_depth - depth), 0.0)
        return np.clip(np.where(np.isfinite(tau), tau, 0.0), 0.0, 1.0)

    def _reverse_at_impact(self, body_a, body_b, normal, arm_a, arm_b, depth, start_depth,
                           restitution, approach, start, target):  # fmt: skip
        """Targets of the colliding contacts from the approach at the impact: the forces of
        the step (gravity) change a contact's normal velocity from ``v₀`` at the start to
        ``v₁`` at the end; at the impact, the fraction ``τ`` of the step, it is
        ``v₀ + τ (v₁ − v₀)``; reversed with restitution and changed by the forces for the rest
        of the step, the target is ``−e (v₀ + τ (v₁ − v₀)) + (1 − τ)(v₁ − v₀)``."""
        colliding = (depth >= 0.0) & (approach < -self.resting_speed)
        if not colliding.any():
            return
        initial = _normal_velocities(body_a, body_b, normal, arm_a, arm_b, *start)
        tau = self._impact_times(depth, start_depth)
        change = approach - initial
        at_impact = np.minimum(initial + tau * change, 0.0)
        reversed_ = -restitution * at_impact + (1.0 - tau) * change
        target[colliding] = reversed_[colliding]

    def _impact_fractions(self, body_a, body_b, depth, start_depth, approach, h) -> np.ndarray:
        """``(B,)``: for each body, the fraction ``τ`` of the step at which its earliest
        colliding contact touched, 0 for a body with none (start depths unknown: as if it had
        moved at its end velocity, ``d₀ = d + h v_n``)."""
        colliding = (depth >= 0.0) & (approach < -self.resting_speed)
        if not colliding.any():
            return np.zeros(self.count)
        known = np.where(np.isnan(start_depth), depth + h * approach, start_depth)
        tau = self._impact_times(depth[colliding], known[colliding])
        earliest = np.ones(self.count + 1)  # the last entry stands for the world (-1)
        np.minimum.at(earliest, body_a[colliding], tau)
        np.minimum.at(earliest, body_b[colliding], tau)
        return np.where(earliest < 1.0, earliest, 0.0)[: self.count]

    def _coefficients(self, piece_a: np.ndarray, piece_b: np.ndarray) -> tuple[np.ndarray, ...]:
        """Each contact's restitution and friction (the pair rule, or the stage's value)."""
        pieces, planes = self.pieces, self.planes
        plane = -1 - np.minimum(piece_a, -1)
        on_plane = piece_a < 0
        index = np.maximum(piece_a, 0)
        e_a = np.where(on_plane, planes.restitution[plane] if planes.point.shape[0] else 0.0,
                       pieces.restitution[index])  # fmt: skip
        mu_a = np.where(on_plane, planes.friction[plane] if planes.point.shape[0] else 0.0,
                        pieces.friction[index])  # fmt: skip
        e = np.maximum(e_a, pieces.restitution[piece_b])
        mu = np.sqrt(mu_a * pieces.friction[piece_b])
        if self.restitution is not None:
            e = np.full_like(e, self.restitution)
        if self.friction is not None:
            mu = np.full_like(mu, self.friction)
        return e, mu


def _normal_velocities(body_a, body_b, normal, arm_a, arm_b, v, w) -> np.ndarray:
    """Each contact's relative normal velocity ``n·(v_b + ω_b × r_b − v_a − ω_a × r_a)``."""
    zero = np.zeros((1, 3))
    va = np.concatenate([v, zero])[body_a] + np.cross(np.concatenate([w, zero])[body_a], arm_a)
    vb = np.concatenate([v, zero])[body_b] + np.cross(np.concatenate([w, zero])[body_b], arm_b)
    return np.einsum("ck,ck->c", vb - va, normal)


def _moves(x0: np.ndarray, q0: np.ndarray, x1: np.ndarray, q1: np.ndarray) -> tuple:
    """How each body moved over the step: ``x₁ − x₀`` ``(B, 3)`` [m] and the rotation vector
    ``θ`` ``(B, 3)`` [rad] of ``q₁ ⊗ q₀⁻¹`` (world frame, the shorter way round)."""
    w0, v0 = q0[:, :1], -q0[:, 1:]  # q₀⁻¹ = conj(q₀) for a unit quaternion
    w1, v1 = q1[:, :1], q1[:, 1:]
    w = w1 * w0 - np.einsum("bk,bk->b", v1, v0)[:, None]
    vec = w1 * v0 + w0 * v1 + np.cross(v1, v0)
    vec = np.where(w < 0.0, -vec, vec)
    w = np.abs(w)
    sine = np.linalg.norm(vec, axis=1, keepdims=True)
    angle = 2.0 * np.arctan2(sine, w)
    with np.errstate(divide="ignore", invalid="ignore"):
        axis_scale = np.where(sine > 0.0, angle / sine, 2.0)
    return x1 - x0, vec * axis_scale


def _turned(q: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """Quaternions turned by small world rotation vectors: ``q + ½ (0, θ) ⊗ q``, normalized."""
    w, x, y, z = q.T
    tx, ty, tz = twist.T
    dq = 0.5 * np.stack([
        -tx * x - ty * y - tz * z,
        tx * w + ty * z - tz * y,
        ty * w + tz * x - tx * z,
        tz * w + tx * y - ty * x,
    ], axis=1)  # fmt: skip
    turned = q + dq
    return turned / np.linalg.norm(turned, axis=1, keepdims=True)


@njit(cache=True)
def _warm_start(key, anchor, tolerance, frame, old_key, old_anchor, old_normal, old_friction,
                normal_impulse, tangent_impulse):  # fmt: skip
    """Start each contact from the impulses of the last step's contact of the same pair of
    pieces whose anchor lay nearest, within ``tolerance`` [m]; friction projected on the new
    tangents."""
    if old_key.shape[0] == 0:
        return
    order = np.argsort(old_key, kind="mergesort")
    sorted_keys = old_key[order]
    for c in range(key.shape[0]):
        first = np.searchsorted(sorted_keys, key[c])
        best = -1
        best_distance = tolerance[c] * tolerance[c]
        k = first
        while k < sorted_keys.shape[0] and sorted_keys[k] == key[c]:
            o = order[k]
            d = np.sum((old_anchor[o] - anchor[c]) ** 2)
            if d <= best_distance:
                best_distance = d
                best = o
            k += 1
        if best >= 0:
            normal_impulse[c] = old_normal[best]
            for t in range(2):
                tangent_impulse[c, t] = (
                    old_friction[best, 0] * frame[c, t, 0]
                    + old_friction[best, 1] * frame[c, t, 1]
                    + old_friction[best, 2] * frame[c, t, 2]
                )
