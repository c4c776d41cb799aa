"""The emission stage: particles are born, age and die (seed 002, "Particle animation").

After each integrator step, for each emitter, in order:

1. every live particle ages by the step; those whose age reached their lifetime die, and dead
   slots are parked at rest at the origin (dead particles feel forces like live ones, so
   parking them keeps their numbers small; every output hides them);
2. the particles born during the step ``[t0, t1)`` (continuous births at ``start + k/rate``,
   and bursts) take the lowest free slots of the emitter; each draws its position on the
   emitter's shape, a direction in the cone, a speed, a lifetime and a radius from the
   counter-based generator of :mod:`visviva.particles.random`, and has already flown for
   ``t1 − τ`` seconds since its birth time ``τ`` (so a stream of particles leaves evenly spaced,
   not in clumps at each step), in a straight line: the forces act from the next step on, which
   misplaces a newborn by less than ``½|a|h²``;
3. the radius of every live particle follows its size ramp.

The carried parts: ``particle_alive``, ``particle_age`` [s], ``particle_lifetime`` [s],
``particle_size`` (the radius drawn at birth) [m], ``particle_radius`` (after the ramp) [m];
per emitter, ``emitter_serial`` (births so far: the random state) and ``emitter_dropped``
(births that found no free slot).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numba import njit, prange

from ..ode.stage import Phase
from .emitters import EmitterSpec, ramp_values
from .random import uniform

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["Emission"]


class Emission:
    """The emission stage of a scene's emitters (see the module docstring).

    Args:
        emitters: The emitters, in scene order (their slot ranges do not overlap).
        alive: ``(N,)`` which of the scene's particle slots hold a particle at the start.
        radius: ``(N,)`` the slots' radii at the start [m].
    """

    phase: ClassVar[Phase] = Phase.EMISSION
    order: ClassVar[int] = 0
    compiled: ClassVar[bool] = True
    changes_energy: ClassVar[bool] = True
    #: Particles die at the end of their lifetimes.
    kills_particles: ClassVar[bool] = True

    def __init__(
        self, emitters: Sequence[EmitterSpec], alive: np.ndarray, radius: np.ndarray
    ) -> None:
        count = alive.shape[0]
        self.emitters = tuple(emitters)
        self._alive = np.array(alive, dtype=np.bool_)
        self._radius = np.array(radius, dtype=np.float64)
        #: The emitter owning each slot (−1: a particle that lives for the whole run).
        self.slot_emitter = np.full(count, -1, dtype=np.int64)
        longest = max(e.size_ramp.shape[0] for e in self.emitters)
        #: Each emitter's size ramp, padded with its last stop: ``(E, S, 2)``.
        self.size_ramps = np.zeros((len(self.emitters), longest, 2))
        for spec in self.emitters:
            self.slot_emitter[spec.first_slot : spec.first_slot + spec.capacity] = spec.index
            stops = spec.size_ramp
            self.size_ramps[spec.index, : stops.shape[0]] = stops
            self.size_ramps[spec.index, stops.shape[0] :] = stops[-1]
        #: Each emitter's fixed geometry for the sampling kernel: the bases of its normal and
        #: direction, and its triangles' cumulative areas (empty without a mesh).
        self._geometry = {spec.index: _geometry(spec) for spec in self.emitters}
        #: Whether slot ``i``'s size changes with age (its emitter's size ramp is not 1).
        self.slot_ramped = np.zeros(count, dtype=np.bool_)
        for spec in self.emitters:
            ramped = bool((spec.size_ramp[:, 1] != 1.0).any())
            self.slot_ramped[spec.first_slot : spec.first_slot + spec.capacity] = ramped

    def carried_start(self) -> dict[str, np.ndarray]:
        """Per slot ``particle_age`` [s] (0), ``particle_lifetime`` [s] (∞ for the particles
        alive at the start, which live for the whole run; 0 for the empty slots) and
        ``particle_size`` [m], the radius before its ramp; per emitter ``emitter_serial`` (the
        births so far, which number the random draws) and ``emitter_dropped`` (births that
        found no free slot)."""
        count, emitters = self._alive.shape[0], len(self.emitters)
        return {
            "particle_age": np.zeros(count),
            "particle_lifetime": np.where(self._alive, np.inf, 0.0),
            "particle_size": self._radius.copy(),
            "emitter_serial": np.zeros(emitters, dtype=np.int64),
            "emitter_dropped": np.zeros(emitters, dtype=np.int64),
        }

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """Age, kill, give birth and ramp sizes (see the module docstring)."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        carried = {name: np.array(after[name]) for name in CARRIED}
        x, v = result["particle_position"], result["particle_velocity"]
        _age_all(
            x,
            v,
            carried["particle_alive"],
            carried["particle_age"],
            carried["particle_lifetime"],
            carried["particle_size"],
            carried["particle_radius"],
            self.slot_emitter,
            self.size_ramps,
            h,
        )
        self.give_birth(before.t, after.t, x, v, carried)
        return result.with_carried(**carried)

    def give_birth(
        self, t0: float, t1: float, x: np.ndarray, v: np.ndarray, carried: dict[str, np.ndarray]
    ) -> int:
        """The births of the step ``[t0, t1)``, written in place into the particle arrays
        ``x``, ``v`` and the ``carried`` parts (the fused particle step calls this too); returns
        one past the highest slot filled (0 if none)."""
        alive, age = carried["particle_alive"], carried["particle_age"]
        lifetime, size = carried["particle_lifetime"], carried["particle_size"]
        serial, dropped = carried["emitter_serial"], carried["emitter_dropped"]
        filled = 0
        for spec in self.emitters:
            total = _birth_count(spec, t0, t1)
            if not total:
                continue
            end = spec.first_slot + spec.capacity
            words = alive[: alive.shape[0] // 8 * 8].view(np.uint64)
            free = _free_slots(alive, words, spec.first_slot, end, min(total, spec.capacity))
            times = _birth_times(spec, t0, t1, free.shape[0])
            dropped[spec.index] += total - times.shape[0]
            born = times
            serials = serial[spec.index] + np.arange(born.shape[0], dtype=np.int64)
            serial[spec.index] += total
            _sample(
                spec, self._geometry[spec.index], serials, t1 - born, free, x, v, lifetime, size
            )
            age[free] = t1 - born
            alive[free] = age[free] < lifetime[free]
            fraction = age[free] / lifetime[free]
            carried["particle_radius"][free] = (
                size[free] * ramp_values(spec.size_ramp, fraction)[:, 0]
            )
            if free.shape[0]:
                filled = max(filled, int(free.max()) + 1)
        return filled


#: The carried parts the emission stage updates.
CARRIED = (
    "particle_alive",
    "particle_age",
    "particle_lifetime",
    "particle_size",
    "particle_radius",
    "emitter_serial",
    "emitter_dropped",
)


@njit(cache=True, error_model="numpy", inline="always")
def age_one(alive, age, lifetime, size, emitter, size_ramps, h):  # pragma: no cover - compiled
    """One slot after a step of ``h``: ``(alive, age, radius)``. A particle whose age reaches
    its lifetime dies; a live emitted particle's radius follows its emitter's size ramp."""
    if not alive:
        return False, age, size
    age = age + h
    if not age < lifetime:
        return False, age, size
    if emitter < 0:
        return True, age, size
    return True, age, size * ramp(size_ramps, emitter, age / lifetime)


@njit(cache=True, error_model="numpy", inline="always")
def ramp(ramps, e, fraction):  # pragma: no cover - compiled
    """Ramp ``e``'s value at ``fraction`` (``ramps[e]``: ``(fraction, value)`` stops): linear
    between stops, constant beyond the first and last (as ``numpy.interp``). Entries are read
    one by one: a view per particle would cost an atomic reference count in a parallel loop."""
    if fraction <= ramps[e, 0, 0]:
        return ramps[e, 0, 1]
    for k in range(1, ramps.shape[1]):
        if fraction < ramps[e, k, 0]:
            a0, a1, b0, b1 = ramps[e, k - 1, 0], ramps[e, k - 1, 1], ramps[e, k, 0], ramps[e, k, 1]
            return a1 + (fraction - a0) / (b0 - a0) * (b1 - a1)
    return ramps[e, ramps.shape[1] - 1, 1]


@njit(cache=True, parallel=True, error_model="numpy")
def _age_all(
    x, v, alive, age, lifetime, size, radius, slot_emitter, size_ramps, h
):  # pragma: no cover
    for i in prange(alive.shape[0]):
        was = alive[i]
        alive[i], age[i], radius[i] = age_one(
            was, age[i], lifetime[i], size[i], slot_emitter[i], size_ramps, h
        )
        if not alive[i]:  # parked at rest at the origin (see the module docstring)
            for k in range(3):
                x[i, k] = 0.0
                v[i, k] = 0.0


def _birth_count(spec: EmitterSpec, t0: float, t1: float) -> int:
    """How many births the step ``[t0, t1)`` has (continuous and bursts)."""
    in_step = (spec.burst_times >= t0) & (spec.burst_times < t1)
    continuous = spec.births_before(t1) - spec.births_before(t0)
    return continuous + int(spec.burst_counts[in_step].sum())


def _birth_times(spec: EmitterSpec, t0: float, t1: float, room: int) -> np.ndarray:
    """The earliest ``room`` birth times of the step ``[t0, t1)``, sorted (bursts before
    continuous births at a tie). Births beyond the room are only counted (:func:`_birth_count`):
    a huge rate or step never makes more arrays than the emitter has slots."""
    first = spec.births_before(t0)
    kept = min(room, spec.births_before(t1) - first)
    continuous = spec.start + np.arange(first, first + kept, dtype=np.float64) / spec.rate
    in_step = (spec.burst_times >= t0) & (spec.burst_times < t1)
    counts = np.minimum(spec.burst_counts[in_step], room)
    bursts = np.repeat(spec.burst_times[in_step], counts)
    return np.sort(np.concatenate([bursts, continuous]), kind="stable")[:room]


@njit(cache=True)
def _free_slots(alive, words, start, stop, count):  # pragma: no cover - compiled
    """The lowest ``count`` (at most) free slots in ``[start, stop)``: a scan that stops when it
    has them, so a full emitter of a million slots costs nothing like a million-entry array.
    ``words`` is ``alive`` read eight slots at a time (as far as it divides by 8), so that a
    run of live particles is skipped a word at a time."""
    found = np.empty(count, dtype=np.int64)
    n = 0
    i = start
    whole = 8 * words.shape[0]
    while i < stop and n < count:
        if i % 8 == 0 and i + 8 <= min(stop, whole) and words[i // 8] == _ALL_ALIVE:
            i += 8
            continue
        if not alive[i]:
            found[n] = i
            n += 1
        i += 1
    return found[:n]


#: Eight live slots read as one word (a NumPy bool is the byte 1).
_ALL_ALIVE = np.uint64(0x0101010101010101)


def _sample(
    spec: EmitterSpec,
    geometry: tuple[np.ndarray, np.ndarray, np.ndarray],
    serials: np.ndarray,
    flown: np.ndarray,
    slots: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    lifetime: np.ndarray,
    size: np.ndarray,
) -> None:
    """Draw each newborn's state and attributes into its slot (see :func:`_sample_kernel`);
    ``geometry`` is the emitter's :func:`_geometry`."""
    if slots.shape[0] == 0:
        return
    plane, heading, areas = geometry
    _sample_kernel(
        spec.seed,
        spec.index,
        serials,
        flown,
        slots,
        spec.shape,
        spec.position,
        spec.radius,
        spec.extent,
        plane,
        spec.surface,
        spec.triangles,
        areas,
        heading,
        math.cos(spec.spread),
        np.array(spec.speed),
        np.array(spec.lifetime),
        np.array(spec.particle_radius),
        x,
        v,
        lifetime,
        size,
    )


def _geometry(spec: EmitterSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bases of the emitter's normal and direction (:func:`_basis`), and the cumulative
    areas of its triangles (empty without a mesh), computed once."""
    areas = np.zeros(0)
    if spec.triangles.shape[0]:
        t = spec.triangles
        areas = np.cumsum(
            0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
        )
    return _basis(spec.normal), _basis(spec.direction), areas


def _basis(axis: np.ndarray) -> np.ndarray:
    """``(3, 3)``: two unit vectors perpendicular to ``axis``, then ``axis`` itself."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    first = np.cross(axis, helper)
    first /= np.linalg.norm(first)
    return np.stack([first, np.cross(axis, first), axis])


#: Draw indices of each particle's random numbers.
_POSITION, _DIRECTION, _SPEED, _LIFETIME, _RADIUS = 0, 4, 6, 7, 8


@njit(cache=True, error_model="numpy")
def _between(low_high, u):  # pragma: no cover - compiled
    return low_high[0] + u * (low_high[1] - low_high[0])


@njit(cache=True, error_model="numpy")
def _position(
    seed, stream, serial, shape, centre, radius, extent, plane, surface, triangles, areas
):  # pragma: no cover
    """A point drawn uniformly on (or in) the emitter's shape."""
    u0 = uniform(seed, stream, serial, _POSITION)
    u1 = uniform(seed, stream, serial, _POSITION + 1)
    u2 = uniform(seed, stream, serial, _POSITION + 2)
    u3 = uniform(seed, stream, serial, _POSITION + 3)
    p = centre.copy()
    if shape == 1:  # disc: uniform by area, r = R √u
        r = radius * math.sqrt(u0)
        angle = 2.0 * math.pi * u1
        p += r * (math.cos(angle) * plane[0] + math.sin(angle) * plane[1])
    elif shape == 2:  # sphere: uniform direction; r = R ∛u inside, R on the surface
        z = 1.0 - 2.0 * u0
        ring = math.sqrt(max(0.0, 1.0 - z * z))
        angle = 2.0 * math.pi * u1
        r = radius if surface else radius * u2 ** (1.0 / 3.0)
        p[0] += r * ring * math.cos(angle)
        p[1] += r * ring * math.sin(angle)
        p[2] += r * z
    elif shape == 3:  # box: uniform inside, or on a face chosen by its area
        offset = np.array([u0 - 0.5, u1 - 0.5, u2 - 0.5]) * extent
        if surface:
            faces = np.array([extent[1] * extent[2], extent[0] * extent[2], extent[0] * extent[1]])
            pick = u3 * faces.sum()
            axis = 0 if pick < faces[0] else (1 if pick < faces[0] + faces[1] else 2)
            side = 1.0 if (pick * 2.0) % 2.0 < 1.0 else -1.0
            offset[axis] = 0.5 * side * extent[axis]
        p += offset
    elif shape == 4:  # mesh surface: a triangle by its area, then uniform on it
        k = np.searchsorted(areas, u3 * areas[-1], side="right")
        k = min(k, areas.shape[0] - 1)
        s = math.sqrt(u0)
        a, b = 1.0 - s, s * (1.0 - u1)
        p = a * triangles[k, 0] + b * triangles[k, 1] + (1.0 - a - b) * triangles[k, 2]
    return p


@njit(cache=True, error_model="numpy")
def _sample_kernel(
    seed,
    stream,
    serials,
    flown,
    slots,
    shape,
    centre,
    radius,
    extent,
    plane,
    surface,
    triangles,
    areas,
    cone,
    cos_spread,
    speed,
    life,
    size_range,
    x,
    v,
    lifetime,
    size,
):  # pragma: no cover - compiled
    for j in range(slots.shape[0]):
        n = serials[j]
        i = slots[j]
        p = _position(
            seed, stream, n, shape, centre, radius, extent, plane, surface, triangles, areas
        )
        # A direction uniform on the cone's cap: cos θ uniform in [cos α, 1].
        cos_theta = 1.0 - uniform(seed, stream, n, _DIRECTION) * (1.0 - cos_spread)
        sin_theta = math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta))
        angle = 2.0 * math.pi * uniform(seed, stream, n, _DIRECTION + 1)
        direction = (
            sin_theta * math.cos(angle) * cone[0]
            + sin_theta * math.sin(angle) * cone[1]
            + cos_theta * cone[2]
        )
        velocity = _between(speed, uniform(seed, stream, n, _SPEED)) * direction
        for k in range(3):
            v[i, k] = velocity[k]
            x[i, k] = p[k] + flown[j] * velocity[k]
        lifetime[i] = _between(life, uniform(seed, stream, n, _LIFETIME))
        size[i] = _between(size_range, uniform(seed, stream, n, _RADIUS))
