"""The fused particle step: the whole step in one compiled call for scenes made only of particles.

A scene of particles under field forces and springs, with colliders, emitters and pins, stepped
by symplectic Euler (the scenes' default), is bound by memory traffic: the generic pipeline
reads and writes the particle arrays once for each force, for the integrator's kick and drift,
for each stage and for the divergence watch. This module takes the whole step in place, on
every core (``prange``). With springs, a first pass sums them: the springs of a lattice (a
cloth grid, a soft lattice) at each point by their stencil
(:mod:`~visviva.forces.lattice_springs`, vectorized over a row of points), any others by each
spring's force on its first end (:func:`~visviva.forces.springs.spring_forces`, vectorized
over springs), which each particle sums through its CSR lists in pass 1 below (that pass is
then not vectorized: a loop per particle; plain particle scenes and lattices compile without
it). Then, in two passes:

1. a pass over every particle that the compiler vectorizes (AVX-512: eight particles at a
   time), since every particle takes the same path, with no loop, no call and no conditional
   store: the acceleration from the fields folded into ``g − c_i v + b_i`` (uniform gravity,
   linear drag, wind and damping: each force's compiled form, :class:`~visviva.forces.laws.
   FieldLaw`, says whether and how it folds), symplectic Euler's kick and drift (the
   functions :class:`~visviva.integrators.SymplecticEuler` steps with), the first collider's
   contact if it is a
   plane (the floor, most often), ageing, the divergence watch's check, and a cheap test of
   whether the particle needs more: it is near another plane, may meet another collider or
   hit a plane within the step (time of impact), a field acts on it by its law (attractors,
   vortices, quadratic drag, forces on some particles only), it dies, its size follows a
   ramp. Such a particle keeps its start values (and a pinned one keeps them for good);
2. a pass over those few, each by the general path from its start values: the fields by their
   law (:func:`visviva.forces.laws.field_force`, which the fields' generic road calls too), the
   collision stage's own per-particle function
   (:func:`visviva.collision.response.resolve`), the emission stage's ageing and death
   (:func:`visviva.particles.emission.age_one`). A kernel of its own, called by pass 1's
   when some particle needs it: pass 1 is compiled once for each scene shape, this pass once
   for every scene (most of the compilation, for the collision stage it holds);

then the step's births (:meth:`~visviva.particles.emission.Emission.give_birth`) and the
handles' particles put on their paths at the step's end (:class:`~.handles.Handles`; pinned in
the passes above, they keep their start values there, where the previous step put them —
on their paths at the step's start, as the springs' forces need them). The results
are those of the generic pipeline to round-off (the order of the force sum differs), which
``tests/test_fused.py`` checks.

The step works on its own copy of the positions and velocities, one contiguous array per
component (the state's ``(N, 3)`` rows interleave them, which the compiler does not vectorize
over), and updates it **in place**, as MuJoCo's ``mj_step`` and Warp do: writing a second
copy would add a third to the step's memory traffic. The state's arrays are brought up to
date when someone reads them (:meth:`FusedParticles.settled`). Only slots up to the last one
an emitter has used are visited. The :class:`~visviva.simulation.stepper.Stepper` keeps a
journal and replays it when it must give back an earlier state (after a divergence).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit, prange

from ..collision.colliders import UNROLLED_PLANES, ColliderSet
from ..collision.queries import plane_distance
from ..collision.response import ParticleCollisions, _contact, _tolerance, resolve
from ..forces.laws import LAW_PARAMETERS, FieldLaw, field_force
from ..forces.springs import SpringSet, spring_forces, spring_incidence
from ..integrators.symplectic import drift, kick
from .emission import Emission, age_one
from .handles import Handles

if TYPE_CHECKING:
    from ..forces.base import Force
    from ..ode.state import State

__all__ = ["FusedParticles"]

#: Most fields evaluated by their law (each particle keeps which apply as bits of a mask).
MAX_LAW_FIELDS = 64


class FusedParticles:
    """The fused step of a particle scene, if it has one (see :meth:`of`)."""

    def __init__(
        self,
        count: int,
        forces: tuple[Force, ...],
        mass: np.ndarray,
        stages: tuple[Any, ...],
        pinned: np.ndarray | None = None,
    ) -> None:
        self.count = count
        self.mass = np.array(mass, dtype=np.float64)
        self.inverse_mass = 1.0 / mass
        self.gravity = np.zeros(3)
        self.drag = 0.0  # Σ k of linear drags on every particle [N·s/m]
        self.air = np.zeros(3)  # Σ k w [N]
        self.damping = 0.0  # Σ γ of damping on every particle [1/s]
        forms = [force.compiled for force in forces]
        springs = [form for form in forms if isinstance(form, SpringSet)]
        laws = []
        for form in forms:
            if not isinstance(form, FieldLaw):
                continue
            folded = form.folded() if form.targets.everything else None
            if folded is None:
                laws.append(form)
                continue
            g, k, air, gamma = folded
            self.gravity += g
            self.drag += k
            self.air += air
            self.damping += gamma
        self.kinds = np.array([form.law for form in laws], dtype=np.int64)
        self.parameters = np.array([form.row() for form in laws]).reshape(-1, LAW_PARAMETERS)
        self.law_masks = np.zeros(count, dtype=np.uint64)
        for k, form in enumerate(laws):
            self.law_masks[form.targets.indices] |= np.uint64(1) << np.uint64(k)
        self.collisions = next((s for s in stages if isinstance(s, ParticleCollisions)), None)
        self.emission = next((s for s in stages if isinstance(s, Emission)), None)
        self.handles = next((s for s in stages if isinstance(s, Handles)), None)
        self._pass_1_collisions, self._colliders, contacts = _collision_arguments(
            self.collisions, count
        )
        # Which particles take the kernel's pass 2 (none can without emitters, fields by law,
        # and colliders other than a first plane without time of impact).
        # Springs on lattices are summed per point by their stencils, into ``_point_force``
        # (zero where no lattice is); the others by a pass over springs into
        # ``_spring_force`` (each spring's force on its first particle) and the CSR gather.
        self._stencils = [f.stencil for f in springs if f.stencil is not None]
        self._point_force = np.zeros((3, count if self._stencils else 0))
        self._springs, self._lists = _spring_arguments(
            [f for f in springs if f.stencil is None], count
        )
        self._spring_force = np.empty((3, 0 if self._springs is None else len(self._springs[0])))
        # A writable copy: a read-only array is another type to Numba, another compilation.
        self.pinned = (
            np.array(pinned, dtype=np.bool_) if pinned is not None and pinned.any() else None
        )
        general = contacts or self.emission is not None or len(laws) > 0
        self._special = np.zeros(count, dtype=np.bool_) if general else None
        # The working copy: positions and velocities, (3, N) each (one contiguous array per
        # component, which the compiler vectorizes over), and the state they belong to.
        self._x = self._v = np.zeros((3, 0))
        self._current: State | None = None
        self._settled = True
        self._end = count  # one past the last slot that may be alive

    @classmethod
    def of(cls, model: Any, method: str) -> FusedParticles | None:
        """The fused step of ``model`` for ``method``, or ``None`` if it has none: the method
        must be symplectic Euler, the scene made only of particles, every force one with a
        compiled form (fields and springs; not gravitation, penalty contact or a plugin's
        force), every stage handles, collisions or emission."""
        if method != "symplectic_euler" or model.systems or model.bodies is not None:
            return None
        if not model.particle_count:
            return None
        forms = [force.compiled for force in model.forces]
        if any(form is None for form in forms):
            return None
        # A stage that declares no compiled form keeps the generic pipeline; of those that
        # do, the fused step knows how to take the handles', the collisions' and the
        # emission's place.
        if not all(
            s.compiled and isinstance(s, (Handles, ParticleCollisions, Emission))
            for s in model.stages
        ):
            return None
        laws = [
            form
            for form in forms
            if isinstance(form, FieldLaw) and not (form.targets.everything and form.folded())
        ]
        if len(laws) > MAX_LAW_FIELDS:
            return None
        return cls(
            model.particle_count,
            model.forces,
            np.asarray(model.particle_mass),
            model.stages,
            np.asarray(model.particle_pinned),
        )

    def step(self, state: State, h: float, t_after: float, limit: float) -> tuple[State, bool]:
        """Advance ``state`` by one step of ``h`` [s] ending at ``t_after``: the state at
        ``t_after``, and whether a particle may be beyond the divergence ``limit`` or not
        finite (the caller's watch decides).

        The step works on its own copy of the particles' positions and velocities, one array
        per component, and updates the carried arrays in place: ``state`` is spent, and the
        returned state's positions and velocities are brought up to date by :meth:`settled`.
        """
        if state is not self._current:
            self._load(state)
        carried = dict(state.carried)
        emission = self.emission
        if self._springs is not None:
            spring_forces(*self._springs, *self._x, *self._v, *self._spring_force)
        for stencil in self._stencils:
            start = stencil.start
            stencil.forces(self._x, self._v, self._point_force[:, start : start + stencil.points])
        alive, radius = carried["particle_alive"], carried["particle_radius"]
        ageing: tuple[np.ndarray | None, ...]
        if emission is None:
            age, ageing = _NO_AGES[0], (None, None)
        else:
            age, lifetime = carried["particle_age"], carried["particle_lifetime"]
            ageing = (lifetime, emission.slot_ramped)
        has_laws = self.kinds.shape[0] > 0
        suspects = _fused(
            *self._x,
            *self._v,
            self.inverse_mass,
            h,
            self.gravity,
            self.drag,
            self.air,
            self.damping,
            self.law_masks if has_laws else None,
            alive,
            radius,
            age,
            *ageing,
            self._end,
            *self._pass_1_collisions,
            limit,
            self._special,
            None if self._springs is None else self._spring_force,
            self._lists if self._springs is not None else None,
            self._point_force if self._stencils else None,
            self.pinned,
            self.general_arguments(carried),
        )
        if emission is not None:
            born = emission.give_birth(state.t, t_after, self._x.T, self._v.T, carried)
            self._end = max(self._end, born)
        if self.handles is not None:
            position, velocity = self.handles.place(t_after)
            self._x[:, self.handles.indices] = position.T
            self._v[:, self.handles.indices] = velocity.T
        self._current = state.from_parts(t_after, state.parts)
        self._settled = False
        return self._current, suspects != 0

    def general_arguments(self, carried: dict[str, np.ndarray]) -> tuple[Any, ...]:
        """What only pass 2 (:func:`_general_pass`) takes, from the state's ``carried`` parts:
        arrays of one type in every scene, so that it is compiled once."""
        if self.emission is None:
            ages = _NO_AGES[1:]
        else:
            emission = self.emission
            ages = (
                carried["particle_lifetime"],
                carried["particle_size"],
                emission.slot_emitter,
                emission.size_ramps,
            )
        return (
            self.kinds,
            self.parameters,
            self.law_masks,
            self.mass,
            *ages,
            *self._colliders,
            self._spring_force,
            self._lists,
            self._point_force,
        )

    def settled(self, state: State) -> State:
        """``state`` with its particle positions and velocities up to date (it is, unless it
        is the latest state this step returned; then they are copied into it)."""
        if state is self._current and not self._settled:
            n = 3 * self.count
            _interleave(self._x, state.parts[0][:n])
            _interleave(self._v, state.parts[1][:n])
            self._settled = True
        return state

    def _load(self, state: State) -> None:
        """Take the particles of ``state`` as the working copy."""
        n = 3 * self.count
        if self._x.shape[1] != self.count:
            self._x, self._v = np.empty((3, self.count)), np.empty((3, self.count))
        _deinterleave(state.parts[0][:n], self._x)
        _deinterleave(state.parts[1][:n], self._v)
        self._end = self.count
        if self.emission is not None:
            # Emitters fill their lowest free slots first: the slots past the last live one
            # stay free until a birth reaches them, and the kernel need not visit them.
            live = np.flatnonzero(state["particle_alive"])
            self._end = int(live[-1]) + 1 if live.shape[0] else 0


@njit(cache=True, inline="always")
def _spring_sum(force, lists, i):  # pragma: no cover - compiled
    """The springs' force on particle ``i`` [N]: ``+f`` of those it is the first end of,
    ``−f`` of those it is the second end of."""
    first_start, as_first, second_start, as_second = lists
    fx = fy = fz = 0.0
    for b in range(first_start[i], first_start[i + 1]):
        s = as_first[b]
        fx, fy, fz = fx + force[0, s], fy + force[1, s], fz + force[2, s]
    for b in range(second_start[i], second_start[i + 1]):
        s = as_second[b]
        fx, fy, fz = fx - force[0, s], fy - force[1, s], fz - force[2, s]
    return fx, fy, fz


@njit(cache=True, parallel=True)
def _interleave(columns, flat):  # pragma: no cover - compiled
    """``flat`` (3N,) ← ``columns`` (3, N): x0 y0 z0 x1 y1 z1 ..."""
    for i in prange(columns.shape[1]):
        flat[3 * i] = columns[0, i]
        flat[3 * i + 1] = columns[1, i]
        flat[3 * i + 2] = columns[2, i]


@njit(cache=True, parallel=True)
def _deinterleave(flat, columns):  # pragma: no cover - compiled
    """``columns`` (3, N) ← ``flat`` (3N,)."""
    for i in prange(columns.shape[1]):
        columns[0, i] = flat[3 * i]
        columns[1, i] = flat[3 * i + 1]
        columns[2, i] = flat[3 * i + 2]


def _spring_arguments(
    springs: list[SpringSet], count: int
) -> tuple[tuple[np.ndarray, ...] | None, tuple[np.ndarray, ...]]:
    """The scene's springs as one set for the kernels: ``(first, second, rest, k, c)``
    (``None`` without springs) and each particle's CSR lists of the springs it is the first
    and the second end of (empty lists without springs)."""
    if not springs:
        return None, (*spring_incidence(np.zeros(0, np.int64), count),) * 2
    pairs = np.concatenate([f.pairs for f in springs])
    ends = tuple(np.ascontiguousarray(pairs[:, e], dtype=np.int32) for e in range(2))
    values = tuple(
        np.concatenate([getattr(f, name) for f in springs])
        for name in ("rest_length", "stiffness", "damping")
    )
    lists = (*spring_incidence(pairs[:, 0], count), *spring_incidence(pairs[:, 1], count))
    return (*ends, *values), lists


#: The ageing arrays (age, lifetime, size, slot emitter, size ramps) without emitters.
_NO_AGES = (np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, np.int64), np.zeros((0, 1, 2)))


def _collision_arguments(
    collisions: ParticleCollisions | None, count: int
) -> tuple[tuple[Any, ...], tuple[Any, ...], bool]:
    """The collision stage for the kernels: what pass 1 takes, what pass 2 takes, and whether
    some contacts need pass 2.

    Pass 1 takes the particles' collider masks (``None`` if every particle meets the same
    colliders, then given as that one mask: 8 B a particle less to read); the first collider
    if it is a plane (point, normal, thickness), its mask bit (0 if it is not a plane) and its
    restitution, friction and resting speed; the other leading planes and those with time of
    impact, each as point, normal, thickness and mask bit, one after the other in a flat tuple
    (``None`` if none): it is compiled for their number (a scene with a floor only does no
    test for other planes); and the first mask bit of the other colliders (``None`` if none).
    Pass 2 takes every particle's mask, the responses and the colliders as :func:`resolve`
    takes them, always as arrays (empty without colliders): it is compiled once for all scenes.
    """
    far = (0.0, 0.0, 0.0, 0.0, 0.0, 1.0, np.inf)
    if collisions is None:
        pass_1 = (None, np.uint64(0), far, np.uint64(0), 0.0, 0.0, 0.0, None, None, None)
        empty = ColliderSet(()).kernel_arrays
        pass_2 = (np.zeros(count, np.uint64), *(np.zeros(0),) * 3, np.zeros(0, np.bool_))
        return pass_1, (*pass_2, 0, empty[2], empty[1:]), False
    r = collisions.response
    masks = collisions.masks
    common = bool(masks.shape[0]) and bool((masks == masks[0]).all())
    colliders = collisions.colliders
    rows = colliders.rows
    leading = min(colliders.planes, UNROLLED_PLANES)
    planes = [(*(float(v) for v in rows[k, :7]), float(k)) for k in range(leading)]
    near = sum(planes[1:], ()) or None
    impact = sum((plane for plane in planes if r.time_of_impact[int(plane[7])]), ()) or None
    others = np.uint64(leading) if len(colliders) > leading else None
    pass_1 = (
        None if common else masks,
        masks[0] if common else np.uint64(0),
        planes[0][:7] if leading else far,
        np.uint64(1 if leading else 0),
        *((r.restitution[0], r.friction[0], r.resting_speed[0]) if leading else (0.0,) * 3),
        near,
        impact,
        others,
    )
    pass_2 = (masks, r.restitution, r.friction, r.resting_speed, r.time_of_impact)
    arrays = colliders.kernel_arrays
    needed = near is not None or impact is not None or others is not None
    return pass_1, (*pass_2, colliders.planes, rows, arrays[1:]), needed


@njit(cache=True, error_model="numpy", inline="always")
def _law_acceleration(k, kinds, table, x, y, z, vx, vy, vz, m, w):  # pragma: no cover
    """The acceleration [m/s²] of one particle (mass ``m``, its inverse ``w``) from field
    ``k``, by its law (:func:`~visviva.forces.laws.field_force`)."""
    p = (
        table[k, 0],
        table[k, 1],
        table[k, 2],
        table[k, 3],
        table[k, 4],
        table[k, 5],
        table[k, 6],
        table[k, 7],
        table[k, 8],
    )  # entries, not a row view (an atomic reference count per particle)
    fx, fy, fz = field_force(kinds[k], p, x, y, z, vx, vy, vz, m)
    return fx * w, fy * w, fz * w


@njit(cache=True, error_model="numpy", inline="always")
def _plane_at(planes, k):  # pragma: no cover - compiled
    """The plane of the flat tuple ``planes`` (8 entries a plane) starting at entry ``k``."""
    return (
        planes[k],
        planes[k + 1],
        planes[k + 2],
        planes[k + 3],
        planes[k + 4],
        planes[k + 5],
        planes[k + 6],
        planes[k + 7],
    )


@njit(cache=True, error_model="numpy", inline="always")
def _plane_gap(plane, px, py, pz):  # pragma: no cover - compiled
    """Signed distance [m] and outward normal of a plane slab at a point (as
    :func:`~visviva.collision.queries.plane_distance`, from the plane as one tuple: point,
    normal, thickness)."""
    return plane_distance(
        px, py, pz, plane[0], plane[1], plane[2], plane[3], plane[4], plane[5], plane[6]
    )


@njit(cache=True, error_model="numpy", inline="always")
def _near(plane, bit, px, py, pz, r):  # pragma: no cover - compiled
    """True if the particle meets the plane (mask ``bit`` set) and its centre ends closer to
    it than ``r``."""
    d, _, _, _ = _plane_gap(plane, px, py, pz)
    return (bit != 0) & (d < r)


@njit(cache=True, error_model="numpy", inline="always")
def _impact_possible(plane, bit, sx, sy, sz, px, py, pz, r):  # pragma: no cover
    """True if the particle may hit the leading plane within the step, so that the time of
    impact must be found (the test of the collision stage's ``_plane_impact``, with a thin
    slab's crossing assumed; called for planes with time of impact): the particle meets it (mask
    ``bit``), was clear of it at the start and ends inside it (or the slab is thin)."""
    d0, _, _, _ = _plane_gap(plane, sx, sy, sz)
    d1, _, _, _ = _plane_gap(plane, px, py, pz)
    clear = d0 - r > _tolerance(sx, sy, sz, px, py, pz, r)
    return (bit != 0) & clear & ((d1 < r) | (plane[6] != np.inf))


# fmt: off
@njit(cache=True, parallel=True, error_model="numpy")
def _fused(
    x, y, z, vx, vy, vz, inverse_mass, h, g, drag, air, damping, law_masks, alive, radius,
    age, lifetime, slot_ramped, end, collider_masks, common_mask, floor, floor_bit, e, mu,
    rests, near_planes, impact_planes, others, limit, special, spring_force, lists,
    point_force, pinned, general,
):  # pragma: no cover - compiled
    """The step of the module docstring for every particle, in place (positions ``x, y, z``
    and velocities ``vx, vy, vz``, one array per component); returns how many particles may be
    beyond ``limit`` or not finite.

    Compiled for the scene's shape: ``None`` stands for what the scene has not (fields by
    law, ``law_masks``; emitters, ``lifetime, slot_ramped``; other colliders, ``others``,
    their first mask bit; springs, per spring ``spring_force`` summed through ``lists`` or per
    particle ``point_force``; pins; ``special``, scratch, if no particle can need pass 2), and
    the leading planes come as flat tuples (:func:`_collision_arguments`). ``general`` is
    what only :func:`_general_pass` takes."""
    # fmt: on
    one = np.uint64(1)
    # Loop invariants in registers: the compiler cannot tell that the stores miss them.
    gx, gy, gz, wx, wy, wz = g[0], g[1], g[2], air[0], air[1], air[2]
    pending = 0
    suspects = 0
    # Pass 1, vectorized: every particle takes the same path, with no loop and no call, and
    # stores by selection (a conditional store would keep the loop scalar).
    for i in prange(end):
        sx, sy, sz, svx, svy, svz = x[i], y[i], z[i], vx[i], vy[i], vz[i]
        w = inverse_mass[i]
        c = drag * w + damping
        ax = gx - c * svx + wx * w
        ay = gy - c * svy + wy * w
        az = gz - c * svz + wz * w
        if spring_force is not None:
            fx, fy, fz = _spring_sum(spring_force, lists, i)
            ax += w * fx
            ay += w * fy
            az += w * fz
        if point_force is not None:
            ax += w * point_force[0, i]
            ay += w * point_force[1, i]
            az += w * point_force[2, i]
        ux, uy, uz = kick(svx, ax, h), kick(svy, ay, h), kick(svz, az, h)
        px, py, pz = drift(sx, ux, h), drift(sy, uy, h), drift(sz, uz, h)
        r = radius[i]
        mask = common_mask if collider_masks is None else collider_masks[i]
        # A particle that may hit a plane within the step needs its time of impact: special
        # (judged by where the step would take it, before any contact moves it out).
        odd = False
        if impact_planes is not None:
            for k in range(0, len(impact_planes), 8):
                plane = _plane_at(impact_planes, k)
                bit = (mask >> np.uint64(plane[7])) & one
                odd |= _impact_possible(plane, bit, sx, sy, sz, px, py, pz, r)
        # The first plane's contact (the floor, most often) is taken here; a particle near
        # another collider is special. (The compiler vectorizes one contact, not four.)
        d, nx, ny, nz = _plane_gap(floor, px, py, pz)
        if ((mask & floor_bit) != 0) & (d < r):
            px, py, pz, ux, uy, uz = _contact(
                sx, sy, sz, px, py, pz, ux, uy, uz, d, nx, ny, nz, r, e, mu, rests
            )
        if near_planes is not None:
            for k in range(0, len(near_planes), 8):
                plane = _plane_at(near_planes, k)
                odd |= _near(plane, (mask >> np.uint64(plane[7])) & one, px, py, pz, r)
        if others is not None:
            odd |= (mask >> others) != 0
        if law_masks is not None:
            odd |= law_masks[i] != 0
        # A pinned particle keeps its place (and needs nothing else: pinned particles are
        # not emitted, and colliders skip them).
        held = False
        if pinned is not None:
            held = pinned[i]
            odd &= not held
        # Only emitted particles die: without emitters, every slot is alive.
        live = True
        if lifetime is not None:
            live = alive[i]
            older = age[i] + h
            # One that dies, or whose size follows a ramp, is special.
            odd |= (not older < lifetime[i]) | slot_ramped[i]
        if special is not None:
            odd &= live
            special[i] = odd
            pending += odd
        # A free slot stays parked; a special particle keeps its start for pass 2.
        keep = live & (not odd) & (not held)
        if lifetime is not None:
            age[i] = older if keep else age[i]
        x[i] = px if keep else sx
        y[i] = py if keep else sy
        z[i] = pz if keep else sz
        vx[i] = ux if keep else svx
        vy[i] = uy if keep else svy
        vz[i] = uz if keep else svz
        # The watch's check (a particle flagged wrongly costs only the watch's exact check).
        extent = abs(px) + abs(py) + abs(pz) + abs(ux) + abs(uy) + abs(uz)
        suspects += 0 if extent <= limit else 1
    if special is None or pending == 0:
        return suspects
    return suspects + _general_pass(
        x, y, z, vx, vy, vz, inverse_mass, h, g, drag, air, damping, alive, radius, age, end,
        limit, special, general,
    )  # fmt: skip


@njit(cache=True, parallel=True, error_model="numpy")
def _general_pass(
    x, y, z, vx, vy, vz, inverse_mass, h, g, drag, air, damping, alive, radius, age, end,
    limit, special, general,
):  # pragma: no cover - compiled
    """Pass 2 of :func:`_fused`: each ``special`` particle by the general path from its start
    values, in place; returns how many may be beyond ``limit`` or not finite.

    Everything comes as arrays, empty for what the scene has not, and is tested at run time
    (this pass visits few particles), so that one compilation serves every scene. The arrays
    it writes are arguments of their own, ``general`` holds only arrays it reads: with the
    ages unpacked from it, Numba 0.68's parallel loop here lost their stores (tests/test_fused.py
    compares the ages with the generic pipeline's).
    """
    (
        kinds, parameters, law_masks, mass, lifetime, size, slot_emitter, size_ramps, masks,
        restitution, friction, resting, toi, planes, rows, everything, spring_force, lists,
        point_force,
    ) = general  # fmt: skip
    ageing = age.shape[0] > 0
    colliding = restitution.shape[0] > 0
    per_spring = spring_force.shape[1] > 0
    per_point = point_force.shape[1] > 0
    one = np.uint64(1)
    gx, gy, gz, wx, wy, wz = g[0], g[1], g[2], air[0], air[1], air[2]
    suspects = 0
    for i in prange(end):
        if not special[i]:
            continue
        sx, sy, sz, svx, svy, svz = x[i], y[i], z[i], vx[i], vy[i], vz[i]
        w = inverse_mass[i]
        c = drag * w + damping
        ax = gx - c * svx + wx * w
        ay = gy - c * svy + wy * w
        az = gz - c * svz + wz * w
        if per_spring:
            fx, fy, fz = _spring_sum(spring_force, lists, i)
            ax += w * fx
            ay += w * fy
            az += w * fz
        if per_point:
            ax += w * point_force[0, i]
            ay += w * point_force[1, i]
            az += w * point_force[2, i]
        bits = law_masks[i]
        for k in range(kinds.shape[0]):
            if (bits >> np.uint64(k)) & one:
                bx, by, bz = _law_acceleration(
                    k, kinds, parameters, sx, sy, sz, svx, svy, svz, mass[i], w
                )
                ax += bx
                ay += by
                az += bz
        ux, uy, uz = kick(svx, ax, h), kick(svy, ay, h), kick(svz, az, h)
        px, py, pz = drift(sx, ux, h), drift(sy, uy, h), drift(sz, uz, h)
        r = radius[i]
        if colliding:
            px, py, pz, ux, uy, uz = resolve(
                sx, sy, sz, svx, svy, svz, px, py, pz, ux, uy, uz, r, masks[i], h,
                restitution, friction, resting, toi, planes, rows, everything, everything,
            )  # fmt: skip
        if ageing:
            live, age[i], radius[i] = age_one(
                True, age[i], lifetime[i], size[i], slot_emitter[i], size_ramps, h
            )
            if not live:  # parked at rest at the origin
                alive[i] = False
                px = py = pz = ux = uy = uz = 0.0
        x[i], y[i], z[i], vx[i], vy[i], vz[i] = px, py, pz, ux, uy, uz
        extent = abs(px) + abs(py) + abs(pz) + abs(ux) + abs(uy) + abs(uz)
        suspects += 0 if extent <= limit else 1
    return suspects
