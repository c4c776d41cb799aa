"""Particles bouncing off static colliders: the collision stage (impulses, seeds 002 and 003).

After each integrator step the stage looks at every live particle's motion from ``x0`` to
``x1`` and, where it met a collider (a particle of radius ``r`` touches when the signed
distance of its centre falls below ``r``):

1. **Time of impact** (colliders with ``time_of_impact``, seed 003's bisection): if the particle
   was clearly outside at the start of the step and is inside at its end — or its path crossed
   a thin collider it has jumped over — the fraction ``s`` of the step at which it touched is
   found by bisection along the step's chord until ``0 ≤ d − r < ε``. The state there
   (position on the chord, velocity interpolated) gets the impulse below, and the rest of the
   step, ``(1 − s) h``, is flown again with the reflected velocity and the step's mean
   acceleration ``(v1 − v0)/h``: "restart the ODE solver at t_c with the new state". Up to
   :data:`MAX_IMPACTS` impacts per particle per step (a corner).
2. **Contact** (every collider): a particle still inside is moved out along the normal to
   the surface, and if it moves inwards its velocity gets the impulse.

The impulse (seed 002) reverses the normal velocity with the coefficient of restitution ``e``:
``v' = v − (1 + e)(v·N)N``; below the resting speed the contact rests (``e = 0``), which stops
the chatter of a particle lying on a floor. Coulomb friction takes from the tangential velocity
at most ``μ`` times the normal velocity change, never reversing it (a sliding particle
decelerates at ``μ g`` and stops after ``v²/(2μg)``).

References:
    Seed 002 (particle–plane response, restitution); seed 003 (time of collision by
    bisection, impulses); B. Mirtich, J. Canny, "Impulse-based simulation of rigid bodies",
    I3D 1995 (the resting-contact threshold).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numba import njit, prange

from ..ode.stage import Phase
from .colliders import UNROLLED_PLANES, ColliderSet, collider_distance, collider_first_hit
from .contact_classes import DEFAULT_GAP, Contacts, find_contacts
from .queries import plane_distance, plane_first_hit
from .tables import ColliderKind

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["MAX_IMPACTS", "ColliderResponse", "ParticleCollisions", "resolve"]

#: Impacts with time of impact handled per particle per step (a particle in a corner may meet
#: two walls in one step); what is left is resolved by contact.
MAX_IMPACTS = 4
_PLANE = int(ColliderKind.PLANE)
#: Bisection steps: enough to halve a step to round-off.
BISECTION_STEPS = 60
#: Relative tolerance of the bisection on ``d − r``, times the step's travel or the radius.
BISECTION_TOLERANCE = 1e-6


class ColliderResponse:
    """How particles respond to each collider (arrays of one entry per collider).

    Args:
        restitution: Coefficients of restitution ``e`` in [0, 1].
        friction: Coulomb friction coefficients ``μ`` ≥ 0.
        resting_speed: Normal speeds [m/s] below which a contact rests (``e`` = 0).
        time_of_impact: Whether impacts are found within the step.
    """

    def __init__(
        self,
        restitution: Sequence[float],
        friction: Sequence[float],
        resting_speed: Sequence[float],
        time_of_impact: Sequence[bool],
    ) -> None:
        self.restitution = np.asarray(restitution, dtype=np.float64)
        self.friction = np.asarray(friction, dtype=np.float64)
        self.resting_speed = np.asarray(resting_speed, dtype=np.float64)
        self.time_of_impact = np.asarray(time_of_impact, dtype=np.bool_)


class ParticleCollisions:
    """The collision stage for particles and static colliders (see the module docstring).

    Args:
        colliders: The colliders.
        response: Restitution, friction, resting speed and time of impact per collider.
        masks: ``(N,)`` uint64: bit ``k`` set where particle ``i`` meets collider ``k``.
        labels: Each collider's name, for :class:`~visviva.collision.contact_classes.Contacts`
            (default ``collider 0``, ``collider 1``, ...).

    The state must carry ``particle_radius`` and ``particle_alive`` and name its particle
    positions and velocities ``particle_position`` / ``particle_velocity``.
    """

    phase: ClassVar[Phase] = Phase.CONTACTS
    order: ClassVar[int] = 1
    compiled: ClassVar[bool] = True
    changes_energy: ClassVar[bool] = True
    kills_particles: ClassVar[bool] = False

    def __init__(
        self,
        colliders: ColliderSet,
        response: ColliderResponse,
        masks: np.ndarray,
        labels: Sequence[str] | None = None,
    ) -> None:
        self.colliders = colliders
        self.response = response
        self.masks = np.asarray(masks, dtype=np.uint64)
        self.labels = tuple(labels or (f"collider {k}" for k in range(len(colliders))))

    def carried_start(self) -> dict[str, np.ndarray]:
        """None: it carries nothing in the state."""
        return {}

    def contacts(self, state: State, gap: float = DEFAULT_GAP) -> Contacts:
        """The contacts of ``state``'s live particles with these colliders (classified with
        each collider's resting speed; see :mod:`~visviva.collision.contact_classes`)."""
        return find_contacts(
            state["particle_position"],
            state["particle_velocity"],
            state["particle_radius"],
            state["particle_alive"],
            self.masks,
            self.colliders,
            self.response.resting_speed,
            self.labels,
            gap,
        )

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """The state with every particle moved out of the colliders and bounced."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        r = self.response
        _collide(
            before["particle_position"],
            before["particle_velocity"],
            result["particle_position"],
            result["particle_velocity"],
            after["particle_radius"],
            after["particle_alive"],
            self.masks,
            h,
            r.restitution,
            r.friction,
            r.resting_speed,
            *self.kernel_arguments(),
        )
        return result

    def kernel_arguments(self) -> tuple[Any, ...]:
        """``(toi, planes, rows, others, everything)``, how :func:`resolve` takes the
        colliders: the time-of-impact flags (``None`` if no collider has them), the number of
        leading planes, the colliders' rows, every collider's arrays for the general path
        (``None`` if all colliders are leading planes), and those arrays again (for impacts)."""
        colliders = self.colliders
        everything = colliders.kernel_arrays[1:]
        toi = self.response.time_of_impact
        unrolled = min(colliders.planes, UNROLLED_PLANES)
        return (
            toi if toi.any() else None,
            colliders.planes,
            colliders.rows,
            everything if len(colliders) > unrolled else None,
            everything,
        )


@njit(cache=True, error_model="numpy", inline="always")
def _bounce(vx, vy, vz, nx, ny, nz, e, mu, resting):  # pragma: no cover - compiled
    """The velocity after an impulse along ``n`` (restitution ``e``, friction ``mu``), and
    whether static friction holds the particle (a resting contact whose sliding stopped)."""
    vn = vx * nx + vy * ny + vz * nz
    if vn >= 0.0:
        return vx, vy, vz, False
    rests = -vn < resting
    if rests:
        e = 0.0
    tx, ty, tz = vx - vn * nx, vy - vn * ny, vz - vn * nz
    tangential = np.sqrt(tx * tx + ty * ty + tz * tz)
    # Coulomb: the tangential impulse is at most μ times the normal one, (1 + e)|vn| per mass.
    keep = 0.0
    if tangential > 0.0:
        keep = max(0.0, 1.0 - mu * (1.0 + e) * (-vn) / tangential)
    held = rests and keep == 0.0
    return keep * tx - e * vn * nx, keep * ty - e * vn * ny, keep * tz - e * vn * nz, held


@njit(cache=True, error_model="numpy", inline="always")
def _contact(
    sx, sy, sz, px, py, pz, vx, vy, vz, d, nx, ny, nz, r, e, mu, resting
):  # pragma: no cover - compiled
    """A particle at distance ``d`` < ``r`` from a collider with outward normal ``n``: moved
    out to the surface, given the impulse if it moves in; if static friction holds it, the
    step's slide along the surface (from ``s``) is taken back too, so that a particle held on
    a slope stays where it is instead of creeping by ``h² g sin θ`` a step."""
    depth = r - d
    px, py, pz = px + depth * nx, py + depth * ny, pz + depth * nz
    vx, vy, vz, held = _bounce(vx, vy, vz, nx, ny, nz, e, mu, resting)
    if held:
        dx, dy, dz = px - sx, py - sy, pz - sz
        along = dx * nx + dy * ny + dz * nz
        px, py, pz = sx + along * nx, sy + along * ny, sz + along * nz
    return px, py, pz, vx, vy, vz


@njit(cache=True, error_model="numpy")
def _touch_fraction(
    k, x0, y0, z0, dx, dy, dz, high, radius, tolerance, colliders
):  # pragma: no cover
    """Seed 003's bisection: the fraction in [0, high] of the chord at which the particle
    touches collider ``k`` (``d − r`` in [0, tolerance)), given that it is outside at 0 and
    inside at ``high``."""
    kinds, rows, offsets, nb, nl, tp, tn = colliders
    low = 0.0
    for _ in range(BISECTION_STEPS):
        middle = 0.5 * (low + high)
        d, _, _, _ = collider_distance(
            k,
            x0 + middle * dx,
            y0 + middle * dy,
            z0 + middle * dz,
            kinds,
            rows,
            offsets,
            nb,
            nl,
            tp,
            tn,
        )
        gap = d - radius
        if gap < 0.0:
            high = middle
        elif gap < tolerance:
            return middle
        else:
            low = middle
    return low


# fmt: off
@njit(cache=True, parallel=True, error_model="numpy")
def _collide(
    x0, v0, x, v, radius, alive, masks, h, restitution, friction, resting,
    toi, planes, rows, others, everything,
):  # pragma: no cover - compiled
    for i in prange(x.shape[0]):
        if masks[i] == 0 or not alive[i]:
            continue
        px, py, pz, vx, vy, vz = resolve(
            x0[i, 0], x0[i, 1], x0[i, 2], v0[i, 0], v0[i, 1], v0[i, 2],
            x[i, 0], x[i, 1], x[i, 2], v[i, 0], v[i, 1], v[i, 2],
            radius[i], masks[i], h, restitution, friction, resting,
            toi, planes, rows, others, everything,
        )
        x[i, 0], x[i, 1], x[i, 2] = px, py, pz
        v[i, 0], v[i, 1], v[i, 2] = vx, vy, vz


@njit(cache=True, error_model="numpy", inline="always")
def resolve(
    sx, sy, sz, svx, svy, svz, px, py, pz, vx, vy, vz, r, mask, h,
    restitution, friction, resting, toi, planes, rows, others, everything,
):  # pragma: no cover - compiled
    """One particle's step from ``(s, sv)`` to ``(p, v)`` made collision-free (see the module
    docstring): returns the corrected position and velocity. The fused particle step calls
    this too (:mod:`visviva.particles.fused`). The colliders come as
    :meth:`ParticleCollisions.kernel_arguments` gives them.

    Inlined into the callers' loops, and written for them to vectorize: the leading planes
    (up to four) are handled one by one without a loop; the general path (other shapes, and
    impacts within the step) is compiled only where it is needed, since ``toi`` and
    ``others`` are ``None`` when no collider asks for it (Numba compiles one loop per case).
    """
    unrolled = min(planes, UNROLLED_PLANES)
    if toi is not None:
        impact = False
        for k in range(unrolled):
            impact = impact or _plane_impact(k, sx, sy, sz, px, py, pz, r, mask, toi, rows)
        if others is not None:
            impact = impact or _impact_possible(
                unrolled, sx, sy, sz, px, py, pz, r, mask, toi, everything
            )
        if impact:
            px, py, pz, vx, vy, vz = _impacts(
                sx, sy, sz, svx, svy, svz, px, py, pz, vx, vy, vz, r, mask, h,
                restitution, friction, resting, toi, everything,
            )
            # After an impact, what friction may hold is where the particle now is.
            sx, sy, sz = px, py, pz
    if unrolled > 0:
        px, py, pz, vx, vy, vz = _plane_contact(
            0, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask, rows, restitution, friction, resting
        )
    if unrolled > 1:
        px, py, pz, vx, vy, vz = _plane_contact(
            1, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask, rows, restitution, friction, resting
        )
    if unrolled > 2:
        px, py, pz, vx, vy, vz = _plane_contact(
            2, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask, rows, restitution, friction, resting
        )
    if unrolled > 3:
        px, py, pz, vx, vy, vz = _plane_contact(
            3, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask, rows, restitution, friction, resting
        )
    if others is not None:
        px, py, pz, vx, vy, vz = _other_contacts(
            unrolled, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask,
            restitution, friction, resting, others,
        )
    return px, py, pz, vx, vy, vz


@njit(cache=True, error_model="numpy")
def _other_contacts(
    first, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask, restitution, friction, resting, colliders,
):  # pragma: no cover - compiled
    """The contacts of the colliders from ``first`` on (the general path)."""
    kinds, rows, offsets, nb, nl, tp, tn = colliders
    for k in range(first, kinds.shape[0]):
        if not (mask >> np.uint64(k)) & np.uint64(1):
            continue
        d, nx, ny, nz = collider_distance(k, px, py, pz, kinds, rows, offsets, nb, nl, tp, tn)
        if d < r:
            px, py, pz, vx, vy, vz = _contact(
                sx, sy, sz, px, py, pz, vx, vy, vz, d, nx, ny, nz, r,
                restitution[k], friction[k], resting[k],
            )
    return px, py, pz, vx, vy, vz


@njit(cache=True, error_model="numpy")
def _impact_possible(first, sx, sy, sz, px, py, pz, r, mask, toi, colliders):  # pragma: no cover
    """True if, for a collider from ``first`` on with time of impact, the particle was clearly
    outside at the start and either ends inside or its path crossed the collider."""
    kinds, rows, offsets, nb, nl, tp, tn = colliders
    for k in range(first, kinds.shape[0]):
        if not toi[k] or not (mask >> np.uint64(k)) & np.uint64(1):
            continue
        d1, _, _, _ = collider_distance(k, px, py, pz, kinds, rows, offsets, nb, nl, tp, tn)
        if d1 >= r and kinds[k] == _PLANE and rows[k, 6] == np.inf:
            continue  # ends clear of a half-space, which cannot be jumped over
        d0, _, _, _ = collider_distance(k, sx, sy, sz, kinds, rows, offsets, nb, nl, tp, tn)
        if d0 - r <= _tolerance(sx, sy, sz, px, py, pz, r):
            continue  # touching at the start: a resting contact
        if d1 < r:
            return True
        hit = collider_first_hit(k, sx, sy, sz, px, py, pz, kinds, rows, offsets, nb, nl, tp, tn)
        if hit <= 1.0:
            return True
    return False
# fmt: on


@njit(cache=True, error_model="numpy", inline="always")
def _plane_contact(
    k, sx, sy, sz, px, py, pz, vx, vy, vz, r, mask, rows, restitution, friction, resting
):  # pragma: no cover - compiled
    """The contact of plane ``k`` (:func:`_contact`)."""
    if (mask >> np.uint64(k)) & np.uint64(1):
        d, nx, ny, nz = plane_distance(
            px, py, pz, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4], rows[k, 5],
            rows[k, 6],
        )  # fmt: skip
        if d < r:
            px, py, pz, vx, vy, vz = _contact(
                sx, sy, sz, px, py, pz, vx, vy, vz, d, nx, ny, nz, r,
                restitution[k], friction[k], resting[k],
            )  # fmt: skip
    return px, py, pz, vx, vy, vz


@njit(cache=True, error_model="numpy", inline="always")
def _plane_impact(k, sx, sy, sz, px, py, pz, r, mask, toi, rows):  # pragma: no cover - compiled
    """True if plane ``k`` (with time of impact) was met within the step from clearly outside:
    the end inside, or a thin plane crossed."""
    if not toi[k] or not (mask >> np.uint64(k)) & np.uint64(1):
        return False
    d1 = _plane_gap(k, px, py, pz, rows)
    if d1 >= r and rows[k, 6] == np.inf:
        return False  # ends clear of a half-space, which cannot be jumped over
    if _plane_gap(k, sx, sy, sz, rows) - r <= _tolerance(sx, sy, sz, px, py, pz, r):
        return False  # touching at the start: a resting contact
    if d1 < r:
        return True
    hit = plane_first_hit(
        sx, sy, sz, px, py, pz, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4],
        rows[k, 5], rows[k, 6],
    )  # fmt: skip
    return hit <= 1.0


@njit(cache=True, error_model="numpy", inline="always")
def _plane_gap(k, x, y, z, rows):  # pragma: no cover - compiled
    """The signed distance [m] of a point from plane ``k`` (its row read entry by entry)."""
    d, _, _, _ = plane_distance(
        x, y, z, rows[k, 0], rows[k, 1], rows[k, 2], rows[k, 3], rows[k, 4], rows[k, 5],
        rows[k, 6],
    )  # fmt: skip
    return d


@njit(cache=True, error_model="numpy", inline="always")
def _tolerance(sx, sy, sz, px, py, pz, r):  # pragma: no cover - compiled
    """The bisection's tolerance on ``d − r`` [m] for a step from ``s`` to ``p``."""
    dx, dy, dz = px - sx, py - sy, pz - sz
    return BISECTION_TOLERANCE * max(np.sqrt(dx * dx + dy * dy + dz * dz), r) + 1e-300


@njit(cache=True, error_model="numpy")
def _impacts(
    sx,
    sy,
    sz,
    svx,
    svy,
    svz,
    px,
    py,
    pz,
    vx,
    vy,
    vz,
    r,
    mask,
    h,
    restitution,
    friction,
    resting,
    toi,
    colliders,
):  # pragma: no cover - compiled
    """Impacts within the step (seed 003): the earliest touch by bisection, the impulse there,
    and the rest of the step flown again, up to :data:`MAX_IMPACTS` times."""  # fmt: skip
    kinds, rows, offsets, nb, nl, tp, tn = colliders
    # The flight of this step: from (s, sv) over `left` seconds with acceleration a.
    ax, ay, az = (vx - svx) / h, (vy - svy) / h, (vz - svz) / h
    left = h
    for _ in range(MAX_IMPACTS):
        dx, dy, dz = px - sx, py - sy, pz - sz
        tolerance = _tolerance(sx, sy, sz, px, py, pz, r)
        best, chosen = np.inf, -1
        for k in range(kinds.shape[0]):
            if not toi[k] or not (mask >> np.uint64(k)) & np.uint64(1):
                continue
            d0, _, _, _ = collider_distance(k, sx, sy, sz, kinds, rows, offsets, nb, nl, tp, tn)
            if d0 - r <= tolerance:
                continue  # already touching: a resting contact, left to the caller
            d1, _, _, _ = collider_distance(k, px, py, pz, kinds, rows, offsets, nb, nl, tp, tn)
            high = 1.0
            if d1 - r >= 0.0:
                # Outside at both ends: did the centre jump over a thin collider?
                high = collider_first_hit(
                    k, sx, sy, sz, px, py, pz, kinds, rows, offsets, nb, nl, tp, tn
                )
                if not high <= 1.0:
                    continue
            s = _touch_fraction(k, sx, sy, sz, dx, dy, dz, high, r, tolerance, colliders)
            if s < best:
                best, chosen = s, k
        if chosen < 0:
            break
        # The state at the impact, the impulse, and the rest of the step flown again.
        cx, cy, cz = sx + best * dx, sy + best * dy, sz + best * dz
        cvx, cvy, cvz = svx + best * (vx - svx), svy + best * (vy - svy), svz + best * (vz - svz)
        _, nx, ny, nz = collider_distance(chosen, cx, cy, cz, kinds, rows, offsets, nb, nl, tp, tn)
        cvx, cvy, cvz, _ = _bounce(
            cvx, cvy, cvz, nx, ny, nz, restitution[chosen], friction[chosen], resting[chosen]
        )
        rest = (1.0 - best) * left
        sx, sy, sz, svx, svy, svz = cx, cy, cz, cvx, cvy, cvz
        px = cx + rest * cvx + 0.5 * rest * rest * ax
        py = cy + rest * cvy + 0.5 * rest * rest * ay
        pz = cz + rest * cvz + 0.5 * rest * rest * az
        vx, vy, vz = cvx + rest * ax, cvy + rest * ay, cvz + rest * az
        left = rest
    return px, py, pz, vx, vy, vz
