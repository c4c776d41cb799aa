"""Particles colliding with each other as spheres: the particle–particle contact stage.

After each integrator step (and the handles), :class:`ParticleContacts` makes the targeted
live particles — spheres of their radii ``particle_radius`` — stop passing into each other:

1. **Detection** on the shared :class:`~visviva.geometry.NeighbourGrid`, built over the
   step's end positions with the interaction radius ``2 r_max + m``, the margin ``m`` twice
   the largest move of the step (capped at :data:`MOTION_CAP` diameters) plus
   :data:`SPECULATIVE` diameters: two spheres are in contact when their centres end closer
   than ``r_i + r_j`` (the normal along the line of centres), or when the straight chord of
   their relative motion over the step entered that distance — they passed through each
   other — and then the normal is the direction at the first touch, or when they end apart by
   less than ``m``: a speculative contact, which may close its gap ``g`` in the next step
   (its target is a normal velocity of at least ``−g/h``) but not more, unless it would close
   it anyway: then it collides now. Each sphere's contacts
   with the static impulse colliders (:class:`~visviva.collision.ColliderSet`) are found too:
   a pile resting on a floor is solved as one system, the colliders as bodies of infinite mass.
2. **Impulses** (velocities): sequential impulses, the projected Gauss–Seidel iteration of
   E. Catto, "Iterative dynamics with temporal coherence" (GDC 2005): sweeps over the contacts,
   each accumulating its normal impulse ``λ ≥ 0`` along the line of centres towards the target
   relative normal velocity ``−e v_n`` (``v_n`` the approach speed after the integrator step;
   ``e`` is the coefficient of restitution) and a Coulomb friction impulse bounded by ``μ λ``
   that at most stops the sliding. Below the resting speed the target is 0: the contact rests
   (B. Mirtich and J. Canny, "Impulse-based simulation of rigid bodies", I3D 1995). Every
   impulse ``J`` changes the two velocities by ``J / m_i`` and ``−J / m_j``: linear momentum
   is conserved to round-off. For one contact this is the closed form of a 1-D collision,
   ``v₁' = ((m₁ − e m₂) v₁ + (1 + e) m₂ v₂) / (m₁ + m₂)``. A contact that persists from the
   last step starts from the impulses it ended it with (Catto's warm start, "temporal
   coherence"), so a resting pile's impulses converge over the steps; they are carried in the
   state (:meth:`ParticleContacts.carried_start`).
3. **Projections** (positions): sweeps that remove what overlap is left, moving each pair
   apart along its normal in the ratio of the inverse masses (their centre of mass stays put),
   as position-based dynamics projects a constraint (M. Müller, B. Heidelberger, M. Hennix,
   J. Ratcliff, "Position based dynamics", VRIPHYS 2006); velocities are left alone, so no
   kinetic energy is added. Keeping the impulses (the collisions) apart from the position
   correction (the contacts) follows E. Guendelman, R. Bridson and R. Fedkiw, "Nonconvex
   rigid bodies with stacking" (SIGGRAPH 2003).

The contacts are swept bottom-up (along gravity) so that a pile's support is met before what
rests on it, and in slabs along a horizontal axis: contacts of slabs two apart share no sphere,
so the even slabs may be swept at once on every core, then the odd ones
(:data:`PARALLEL_MIN_CONTACTS` says from how many contacts). The order is the same either way
and on any number of threads, so the result is too.

The spheres do not spin: friction slows the relative sliding of their centres. Pinned
particles (held by handles) are of infinite mass. A pair whose relative move in one step is
more than :data:`MOTION_CAP` diameters may pass through each other unseen.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .._validation import describe, real_number, whole_number
from ..errors import ModelError, SimulationError
from ..geometry.neighbour_grid import PARALLEL_MIN_POINTS, NeighbourGrid
from ..ode.stage import Phase
from . import contact_detection as detection
from . import contact_kernels as kernels
from .contact_classes import COLLIDING, DEFAULT_GAP, RESTING, SEPARATING, Classified

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace
    from .response import ParticleCollisions

__all__ = [
    "MAX_ITERATIONS",
    "MEMORY",
    "MOTION_CAP",
    "SPECULATIVE",
    "PairContacts",
    "ParticleContacts",
]

#: The carried parts of the warm start (see :meth:`ParticleContacts.carried_start`).
MEMORY = ("contact_start", "contact_partner", "contact_normal_impulse", "contact_tangent_impulse")

#: The largest move of a step [in diameters of the largest sphere] the detection widens its
#: search for; faster pairs may pass through each other.
MOTION_CAP = 2.0
#: Gap [in diameters of the largest sphere] within which two spheres (or a sphere and a
#: collider) are speculative contacts besides twice the step's largest move: the projections
#: of a pile move spheres by about their overlaps, and must not push them into neighbours the
#: solve does not see.
SPECULATIVE = 0.05
#: Most sweeps of each kind per step.
MAX_ITERATIONS = 10_000
#: Most slabs (the parallel solve's unit) and layers (bottom-up order within a slab).
MAX_SLABS = 64
MAX_LAYERS = 1024
#: Fewest contacts for which the solve sweeps the slabs on every core (either path gives the
#: same numbers). Measured on 2 idle cores of a Zen 5 EPYC (November 2026;
#: benchmarks/bench_particle_contacts.py, part (c)), 20 + 20 sweeps: 1,311 contacts 0.72 ms on
#: one core against 0.56 on two, 5,535 3.2 against 2.0, 46,697 32 against 19, 306,530 220
#: against 116. Each sweep is two parallel regions and a region waits for its slowest thread:
#: with other jobs on the cores, two threads measured 6–10 times slower than one (59,000
#: contacts: 240–400 ms against 41).
PARALLEL_MIN_CONTACTS = 1024
# The slabs' width exceeds the interaction radius by this factor, so that the two spheres of a
# contact always lie in neighbouring slabs despite rounding.
_SLAB_MARGIN = 1.0 + 2.0**-10


@dataclass(frozen=True)
class PairContacts(Classified):
    """Sphere–sphere contacts, one entry per touching pair ``first < second``, in order.

    Attributes:
        first, second: ``(k,)`` particle slots.
        point: ``(k, 3)`` [m] the point between the two surfaces on the line of centres.
        normal: ``(k, 3)`` unit normal from ``second``'s centre towards ``first``'s.
        depth: ``(k,)`` [m] overlap ``r_first + r_second − distance`` (negative: a gap
            within the tolerance).
        normal_velocity: ``(k,)`` [m/s] ``n · (v_first − v_second)`` (negative: approaching).
        kind: ``(k,)`` :data:`~visviva.collision.contact_classes.COLLIDING`, ``RESTING`` or
            ``SEPARATING`` (Baraff's classes, with the stage's resting speed).
    """

    first: np.ndarray
    second: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    depth: np.ndarray
    normal_velocity: np.ndarray
    kind: np.ndarray


class ParticleContacts:
    """The particle–particle contact stage (see the module docstring).

    Args:
        inverse_mass: ``(N,)`` inverse masses [1/kg] of every particle slot (0: immovable,
            like a pinned particle).
        targets: ``(N,)`` bool, the particles that collide with each other (default: all).
        restitution: Coefficient of restitution ``e`` in [0, 1] between two spheres.
        friction: Coulomb friction coefficient ``μ`` ≥ 0 between two spheres.
        iterations: Sweeps of impulses, and then of projections, per step (≥ 1).
        resting_speed: Approach speed [m/s] below which a contact rests (``e`` = 0).
        gravity: Gravitational acceleration [m/s²]: the contacts are swept against it.
        colliders: The collider stage whose colliders (with their own restitution, friction,
            resting speed and targets) join the solve, or ``None``.

    The state must carry ``particle_radius`` and ``particle_alive`` and name its particles'
    positions and velocities ``particle_position`` / ``particle_velocity``.
    """

    phase: ClassVar[Phase] = Phase.CONTACTS
    #: Before the collision stage: the sphere–sphere solve holds the impulse colliders too,
    #: and their own stage then finds the times of impact of what is left.
    order: ClassVar[int] = 0
    compiled: ClassVar[bool] = False
    changes_energy: ClassVar[bool] = True
    kills_particles: ClassVar[bool] = False

    def __init__(
        self,
        inverse_mass: Any,
        targets: Any = None,
        *,
        restitution: float = 0.5,
        friction: float = 0.0,
        iterations: int = 10,
        resting_speed: float = 0.0,
        gravity: Sequence[float] = (0.0, -9.81, 0.0),
        colliders: ParticleCollisions | None = None,
    ) -> None:
        self.inverse_mass = _inverse_masses(inverse_mass)
        count = self.inverse_mass.shape[0]
        self.targets = _targets(targets, count)
        self.restitution = real_number("restitution", restitution, nonnegative=True)
        if self.restitution > 1.0:
            raise ModelError(f"`restitution` must lie in [0, 1] (got {restitution!r})")
        self.friction = real_number("friction", friction, nonnegative=True)
        self.iterations = whole_number("iterations", iterations, minimum=1)
        if self.iterations > MAX_ITERATIONS:
            raise ModelError(
                f"`iterations` must be at most {MAX_ITERATIONS} (got {iterations!r}): more "
                "sweeps than that mean a smaller time step is needed"
            )
        self.resting_speed = real_number("resting_speed", resting_speed, nonnegative=True)
        g = np.array([real_number("gravity", c) for c in gravity], dtype=np.float64)
        size = math.hypot(*g)
        self.up = -g / size if size > 0.0 else np.zeros(3)
        self.colliders = colliders

    def carried_start(self) -> dict[str, np.ndarray]:
        """The carried parts this stage keeps, at the start: the impulses of the last step's
        contacts by lower particle, for the warm start (``contact_start`` ``(N + 1,)``, then
        per contact ``contact_partner``, ``contact_normal_impulse`` [N·s] and
        ``contact_tangent_impulse`` [N·s], ``(C, 3)``). Kept in the state, so that a
        checkpoint restores them and two simulations of one model do not share them."""
        count = self.inverse_mass.shape[0]
        return dict(zip(MEMORY, (np.zeros(count + 1, np.int64), np.zeros(0, np.int64),
                                 np.zeros(0), np.zeros((0, 3))), strict=True))  # fmt: skip

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """The state with the targeted spheres' collisions resolved (velocities) and their
        overlaps removed (positions)."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        memory = tuple(after[name] for name in MEMORY) if MEMORY[0] in after.carried else None
        try:
            memory = self.resolve(
                before["particle_position"],
                result["particle_position"],
                result["particle_velocity"],
                after["particle_radius"],
                after["particle_alive"],
                h,
                memory,
                work,
            )
        except ModelError as error:  # a sphere flew beyond the grid's reach of the origin
            raise SimulationError(f"particle collisions: {error}", t=after.t, step=None) from None
        return result.with_carried(**dict(zip(MEMORY, memory, strict=True)))

    def resolve(
        self,
        x0: np.ndarray,
        x: np.ndarray,
        v: np.ndarray,
        radius: np.ndarray,
        alive: np.ndarray,
        h: float,
        memory: tuple[np.ndarray, ...] | None = None,
        work: Workspace | None = None,
    ) -> tuple[np.ndarray, ...]:
        """Resolve the contacts of a step of ``h`` [s] from ``x0`` to ``x`` [m] in place on
        ``x`` and ``v`` [m/s] (``(N, 3)`` each); ``radius`` ``(N,)`` [m], ``alive`` ``(N,)``
        bool; ``memory``: the last step's impulses (:meth:`carried_start`'s parts) for the
        warm start, or ``None``; ``work``: the run's storage, which keeps the neighbour grid
        and the contacts solved (``None``: fresh storage). Returns this step's impulses.
        Non-finite positions are left to the divergence watch (and nothing is remembered)."""
        scratch = _Scratch() if work is None else work.get(self, _Scratch)
        active = np.asarray(alive, dtype=np.bool_) & self.targets
        x0 = np.ascontiguousarray(x0, dtype=np.float64)
        radius = np.ascontiguousarray(radius, dtype=np.float64)
        largest, move, finite = detection.scan(x0, x, radius, active)
        if not finite or largest == 0.0:
            scratch.solved = None
            return tuple(self.carried_start().values())
        slack = SPECULATIVE * 2.0 * largest + min(2.0 * move, MOTION_CAP * 2.0 * largest)
        reach = 2.0 * largest + slack
        g = scratch.grid_over(x, active, reach)
        parallel = g.order.shape[0] >= PARALLEL_MIN_POINTS
        pairs = detection.pair_contacts(g, x0, radius, reach, slack, parallel)
        found, law = self._collider_contacts(x, radius, g.order, slack)
        contacts = kernels.assemble(
            x, v, radius, found, pairs,
            (self.restitution, self.friction, self.resting_speed), law,
            self._frame(g, reach), h,
        )  # fmt: skip
        total = contacts.first.shape[0]
        if total:
            if memory is not None and memory[0].shape[0] == x.shape[0] + 1:
                start, partner, normal, tangent = memory
                kernels.warm_start(contacts, start, partner, normal, tangent, v, self.inverse_mass)
            parallel = total >= PARALLEL_MIN_CONTACTS and contacts.slabs > 1
            kernels.solve(
                contacts, x, v, self.inverse_mass, self.iterations, self.iterations, parallel
            )
        scratch.solved = contacts
        return tuple(kernels.remember(contacts, x.shape[0]))

    def solved(self, work: Workspace) -> kernels.ContactArrays | None:
        """The contacts the latest step of the run whose storage is ``work`` solved, in solve
        order, with their impulses (``None`` before the first step, or if that step had
        none): for inspection."""
        scratch = work.peek(self)
        return None if scratch is None else scratch.solved  # type: ignore[attr-defined]

    def pair_contacts(
        self, state: State | Mapping[str, np.ndarray], gap: float = DEFAULT_GAP
    ) -> PairContacts:
        """The sphere–sphere contacts of ``state``'s targeted live particles (a state, a
        simulation's ``sim.state``, or a mapping of ``particle_position``,
        ``particle_velocity``, ``particle_radius`` and ``particle_alive``): pairs whose
        surfaces are within ``gap`` [m] (classified with the stage's resting speed)."""
        gap = real_number("gap", gap, nonnegative=True, unit=" m")
        x = np.ascontiguousarray(state["particle_position"], dtype=np.float64)
        v = np.asarray(state["particle_velocity"], dtype=np.float64)
        radius = np.ascontiguousarray(state["particle_radius"], dtype=np.float64)
        active = np.asarray(state["particle_alive"], dtype=np.bool_) & self.targets
        largest, _, finite = detection.scan(x, x, radius, active)
        if not finite:
            raise ModelError("the state's particle positions are not all finite")
        if largest == 0.0:
            i = np.zeros(0, np.int64)
            none = np.zeros((0, 3))
            return PairContacts(i, i, none, none, np.zeros(0), np.zeros(0), np.zeros(0, np.int8))
        grid = NeighbourGrid(2.0 * largest + gap)
        grid.update(x, active)
        a, b, nx, ny, nz = detection.pair_contacts(
            grid.arrays, x, radius, grid.radius, gap, grid.count >= PARALLEL_MIN_POINTS
        )
        normal = np.stack([nx, ny, nz], axis=1)
        swap = a > b
        first, second = np.where(swap, b, a), np.where(swap, a, b)
        normal[swap] *= -1.0
        order = np.lexsort((second, first))
        first, second, normal = first[order], second[order], normal[order]
        apart = np.einsum("ij,ij->i", x[first] - x[second], normal)
        depth = radius[first] + radius[second] - apart
        point = x[second] + normal * (radius[second] - 0.5 * depth)[:, None]
        vn = np.einsum("ij,ij->i", v[first] - v[second], normal)
        kind = np.full(first.shape[0], RESTING, dtype=np.int8)
        kind[vn < -self.resting_speed] = COLLIDING
        kind[vn > self.resting_speed] = SEPARATING
        return PairContacts(first, second, point, normal, depth, vn, kind)

    def _collider_contacts(
        self, x: np.ndarray, radius: np.ndarray, order: np.ndarray, slack: float
    ) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
        """The spheres' contacts with the colliders and the colliders' laws (empty if none)."""
        stage = self.colliders
        if stage is None:
            none, empty = np.zeros(0, np.int64), np.zeros(0)
            return (none, none, empty, empty, empty, empty), (empty, empty, empty)
        found = detection.collider_contacts(
            x, radius, order, stage.masks, slack, stage.colliders.kernel_arrays[1:]
        )
        r = stage.response
        return found, (r.restitution, r.friction, r.resting_speed)

    def _frame(self, g: Any, reach: float) -> tuple[Any, ...]:
        """Slabs along the horizontal axis of widest extent, layers along ``up``."""
        ux, uy, uz = (float(c) for c in self.up)
        bounds = detection.extents(g.x, g.y, g.z, ux, uy, uz)
        spans = bounds[:, 1] - bounds[:, 0]
        axis = int(np.argmax(spans[:3] * (1.0 - np.abs(self.up))))
        width = max(reach * _SLAB_MARGIN, spans[axis] / MAX_SLABS)
        slabs = int(spans[axis] / width) + 1
        if not self.up.any():
            return axis, bounds[axis, 0], 1.0 / width, slabs, (ux, uy, uz), 0.0, 0.0, 1
        height = max(reach, spans[3] / MAX_LAYERS)
        layers = int(spans[3] / height) + 1
        return (
            axis,
            bounds[axis, 0],
            1.0 / width,
            slabs,
            (ux, uy, uz),
            bounds[3, 0],
            (1.0 / height),
            layers,
        )


class _Scratch:
    """A run's storage for the stage: its neighbour grid (kept while its radius stays within
    [reach, 1.25 reach], so that a pile at rest does not rebuild it) and the contacts the latest
    step solved (:meth:`ParticleContacts.solved`)."""

    __slots__ = ("grid", "solved")

    def __init__(self) -> None:
        self.grid: NeighbourGrid | None = None
        self.solved: kernels.ContactArrays | None = None

    def grid_over(self, x: np.ndarray, active: np.ndarray, reach: float) -> Any:
        """The grid's arrays over the active spheres."""
        if self.grid is None or not reach <= self.grid.radius <= 1.25 * reach:
            self.grid = NeighbourGrid(reach)
        self.grid.update(x, active)
        return self.grid.arrays


def _inverse_masses(value: Any) -> np.ndarray:
    try:
        w = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ModelError(
            f"`inverse_mass` must be an array of numbers [1/kg] (got {describe(value)})"
        ) from error
    if w.ndim != 1:
        raise ModelError(f"`inverse_mass` must have shape (N,) (got shape {w.shape})")
    bad = ~(np.isfinite(w) & (w >= 0.0))
    if bad.any():
        k = int(np.argmax(bad))
        raise ModelError(
            f"`inverse_mass` of particle {k} must be finite and ≥ 0 (got {describe(w[k])})"
        )
    return w


def _targets(value: Any, count: int) -> np.ndarray:
    if value is None:
        return np.ones(count, dtype=np.bool_)
    mask = np.asarray(value)
    if mask.dtype != np.bool_ or mask.shape != (count,):
        raise ModelError(
            f"`targets` must be a boolean mask of shape ({count},), one flag per particle "
            f"(got dtype {mask.dtype}, shape {mask.shape})"
        )
    return mask.copy()
