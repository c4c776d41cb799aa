"""Impulses between rigid bodies at their contact points: seed 003's collision impulse, solved
for many contacts at once by sequential impulses, and the split position correction.

At a contact point ``p`` between bodies A and B with unit normal ``n`` from A toward B, the
arms ``r_a = p − x_a`` and ``r_b = p − x_b`` from the centres of mass, the relative velocity
of the two material points is

    v_rel = (v_b + ω_b × r_b) − (v_a + ω_a × r_a),     v_n = n · v_rel

(negative: approaching). An impulse ``j n`` on B and ``−j n`` on A changes ``v_n`` by
``j K`` with

    K = 1/M_a + 1/M_b + (r_a × n)·I_a⁻¹(r_a × n) + (r_b × n)·I_b⁻¹(r_b × n),

so that the collision impulse of seed 003 (Baraff, "Rigid body simulation", SIGGRAPH 2001
course notes, §8), which reverses the approach with restitution ``e``, is

    j = −(1 + e) v_n⁻ / K,    ΔP_b = j n,  ΔL_b = r_b × j n,   ΔP_a = −j n,  ΔL_a = −r_a × j n

(``n·(I⁻¹(r × n)) × r = (r × n)·I⁻¹(r × n)``: the seed's denominator). Both bodies' momenta
change by opposite amounts and their angular momenta about any fixed point too: linear and
angular momentum are conserved.

Many contacts at once (a stack, a pile, a box on four corners) are solved by sequential
impulses, a projected Gauss–Seidel iteration on the contacts' accumulated impulses (E. Catto,
"Iterative dynamics with temporal coherence", GDC 2005): each sweep gives each contact the
impulse that brings its ``v_n`` to its target, keeps the accumulated normal impulse ``λ ≥ 0``
(contacts push, never pull), and a friction impulse in the tangent plane that opposes the
sliding, its accumulated size at most ``μ λ`` (Coulomb's cone). The contacts are found at the
step's end poses, and the bodies are moved again by ``h Δv`` (and turned by ``h Δω``) for the
velocity change ``Δv`` the impulses make — what the step would have done had the bodies had
those velocities — so the target is posed on the depth at the step's start ``d₀``
(``d + h v_n`` to first order): ``−e v_n`` for a contact that reaches the other body within
the step faster than the resting speed (it collides), and otherwise ``min(d₀, 0)/h``: a
resting contact stops (B. Mirtich, J. Canny, "Impulse-based simulation of rigid bodies",
I3D 1995), and a speculative one a gap apart may close the gap this step but not more.
Friction and restitution act through the same impulses as in E. Guendelman, R. Bridson,
R. Fedkiw, "Nonconvex rigid bodies with stacking", SIGGRAPH 2003: both change the spin.

What overlap is left is removed by moving the bodies, not by speeding them apart (which would
add energy: Guendelman et al. separate the two). :func:`correct_positions` sweeps the
penetrating contacts with pseudo-impulses that translate and turn the bodies, each removing a
fraction of its remaining depth beyond a small allowance; velocities are untouched.

Body index ``-1`` is the static world (infinite mass, at rest).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "correct_positions",
    "lever_impulse",
    "lever_speed",
    "levers",
    "prepare_contacts",
    "solve_impulses",
    "with_world",
]


@njit(cache=True, inline="always")
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, inline="always")
def _times(m, b, x, y, z):
    """``m[b] @ (x, y, z)`` for a stack of 3×3 matrices."""
    return (
        m[b, 0, 0] * x + m[b, 0, 1] * y + m[b, 0, 2] * z,
        m[b, 1, 0] * x + m[b, 1, 1] * y + m[b, 1, 2] * z,
        m[b, 2, 0] * x + m[b, 2, 1] * y + m[b, 2, 2] * z,
    )


@njit(cache=True, inline="always")
def _point_velocity(b, v, w, rx, ry, rz):
    """Velocity ``v + ω × r`` of the point at arm ``r`` of body ``b`` (0 for the world)."""
    if b < 0:
        return 0.0, 0.0, 0.0
    cx, cy, cz = _cross(w[b, 0], w[b, 1], w[b, 2], rx, ry, rz)
    return v[b, 0] + cx, v[b, 1] + cy, v[b, 2] + cz


@njit(cache=True, inline="always")
def _resistance(b, inverse_mass, inverse_inertia, rx, ry, rz, dx, dy, dz):
    """``1/M + (r × d)·I⁻¹(r × d)`` of body ``b`` along the unit direction ``d``."""
    if b < 0:
        return 0.0
    cx, cy, cz = _cross(rx, ry, rz, dx, dy, dz)
    ix, iy, iz = _times(inverse_inertia, b, cx, cy, cz)
    return inverse_mass[b] + cx * ix + cy * iy + cz * iz


@njit(cache=True)
def _tangents(nx, ny, nz):
    """Two unit vectors that make a right-handed frame with the unit ``n``."""
    if abs(nx) < 0.57735:
        tx, ty, tz = _cross(nx, ny, nz, 1.0, 0.0, 0.0)
    else:
        tx, ty, tz = _cross(nx, ny, nz, 0.0, 1.0, 0.0)
    length = math.sqrt(tx * tx + ty * ty + tz * tz)
    if not length > 0.0:  # a normal that is not a direction (NaN from a diverged state)
        return 1.0, 0.0, 0.0, 0.0, 0.0, 1.0
    tx, ty, tz = tx / length, ty / length, tz / length
    sx, sy, sz = _cross(nx, ny, nz, tx, ty, tz)
    return tx, ty, tz, sx, sy, sz


@njit(cache=True)
def prepare_contacts(
    body_a, body_b, point, normal, depth, start_depth, touch, restitution, resting_speed, h,
    position, inverse_mass, inverse_inertia, v, w,
    arm_a, arm_b, frame, mass_n, mass_t, target,
):  # fmt: skip
    """Fill each contact's arms, tangent frame, effective masses and normal-velocity target.

    Args:
        body_a, body_b: ``(C,)`` the bodies (``-1``: the world).
        point, normal: ``(C, 3)`` contact points [m] and unit normals from A toward B.
        depth: ``(C,)`` penetration [m] at the step's end poses, negative for a speculative
            contact's gap.
        touch: ``(C,)`` [m]: a contact closer than this counts as touching (it may collide).
        start_depth: ``(C,)`` the same at the step's start (NaN: unknown, then ``d + h v_n``,
            as if the bodies had moved with ``v`` all the step).
        restitution: ``(C,)`` coefficient of restitution of each contact's pair.
        resting_speed: Approach speed [m/s] below which a contact rests rather than bounces.
        h: The step [s].
        position: ``(B, 3)`` centres of mass [m]; ``inverse_mass`` ``(B,)`` [1/kg];
            ``inverse_inertia`` ``(B, 3, 3)`` world frame [1/(kg·m²)]; ``v``, ``w``
            ``(B, 3)`` velocities [m/s] and angular velocities [rad/s] before the solve.
        arm_a, arm_b: ``(C, 3)`` outputs, ``p − x``.
        frame: ``(C, 2, 3)`` output, the two tangents.
        mass_n: ``(C,)`` output, ``1/K`` along the normal [kg].
        mass_t: ``(C, 2)`` output, the same along each tangent.
        target: ``(C,)`` output, the normal velocity each contact is driven to [m/s].
    """
    for c in range(body_a.shape[0]):
        a = body_a[c]
        b = body_b[c]
        nx, ny, nz = normal[c, 0], normal[c, 1], normal[c, 2]
        for k in range(3):
            arm_a[c, k] = point[c, k] - position[a, k] if a >= 0 else 0.0
            arm_b[c, k] = point[c, k] - position[b, k] if b >= 0 else 0.0
        rax, ray, raz = arm_a[c, 0], arm_a[c, 1], arm_a[c, 2]
        rbx, rby, rbz = arm_b[c, 0], arm_b[c, 1], arm_b[c, 2]
        k_n = _resistance(a, inverse_mass, inverse_inertia, rax, ray, raz, nx, ny, nz)
        k_n += _resistance(b, inverse_mass, inverse_inertia, rbx, rby, rbz, nx, ny, nz)
        mass_n[c] = 1.0 / k_n if k_n > 0.0 else 0.0
        tx, ty, tz, sx, sy, sz = _tangents(nx, ny, nz)
        frame[c, 0, 0], frame[c, 0, 1], frame[c, 0, 2] = tx, ty, tz
        frame[c, 1, 0], frame[c, 1, 1], frame[c, 1, 2] = sx, sy, sz
        for t in range(2):
            dx, dy, dz = frame[c, t, 0], frame[c, t, 1], frame[c, t, 2]
            k_t = _resistance(a, inverse_mass, inverse_inertia, rax, ray, raz, dx, dy, dz)
            k_t += _resistance(b, inverse_mass, inverse_inertia, rbx, rby, rbz, dx, dy, dz)
            mass_t[c, t] = 1.0 / k_t if k_t > 0.0 else 0.0
        vax, vay, vaz = _point_velocity(a, v, w, rax, ray, raz)
        vbx, vby, vbz = _point_velocity(b, v, w, rbx, rby, rbz)
        v_n = (vbx - vax) * nx + (vby - vay) * ny + (vbz - vaz) * nz
        start = start_depth[c] if start_depth[c] == start_depth[c] else depth[c] + h * v_n
        if v_n < -resting_speed and depth[c] >= -touch[c]:
            # It reaches the other body within the step, fast: it collides.
            target[c] = -restitution[c] * v_n
        else:
            # It rests, or has a gap it may close this step but not more (speculative).
            target[c] = min(start, 0.0) / h


@njit(cache=True)
def levers(body_a, body_b, normal, frame, arm_a, arm_b, inverse_inertia, bodies, directions):
    """Each contact's first ``directions`` of (n, t₁, t₂) and, per body and direction, r × d
    (what the spin adds to the velocity along d) and I⁻¹(r × d) (how an impulse along d turns
    the body), computed once so that a sweep is dot products and additions; and each
    contact's two bodies, the world as the extra body ``bodies`` (at rest, of infinite mass),
    so that no sweep branches on it."""
    count = body_a.shape[0]
    axes = np.empty((count, 3, 3))
    lever = np.zeros((count, 2, 3, 3))
    turn = np.zeros((count, 2, 3, 3))
    index = np.empty((count, 2), dtype=np.int64)
    for c in range(count):
        axes[c, 0] = normal[c]
        if directions > 1:
            axes[c, 1] = frame[c, 0]
            axes[c, 2] = frame[c, 1]
        for side in range(2):
            b = body_a[c] if side == 0 else body_b[c]
            index[c, side] = b if b >= 0 else bodies
            if b < 0:
                continue
            arm = arm_a[c] if side == 0 else arm_b[c]
            for k in range(directions):
                cx, cy, cz = _cross(arm[0], arm[1], arm[2], axes[c, k, 0], axes[c, k, 1],
                                    axes[c, k, 2])  # fmt: skip
                lever[c, side, k, 0], lever[c, side, k, 1], lever[c, side, k, 2] = cx, cy, cz
                tx, ty, tz = _times(inverse_inertia, b, cx, cy, cz)
                turn[c, side, k, 0], turn[c, side, k, 1], turn[c, side, k, 2] = tx, ty, tz
    return axes, lever, turn, index


@njit(cache=True)
def with_world(v, w, inverse_mass):
    """Copies of the per-body rates ``v``, ``w`` ``(B, 3)`` and ``inverse_mass`` ``(B,)`` with
    one more row, the world's: at rest, of infinite mass (see :func:`levers`)."""
    bodies = v.shape[0]
    vel = np.zeros((bodies + 1, 3))
    spin = np.zeros((bodies + 1, 3))
    weight = np.zeros(bodies + 1)
    vel[:bodies] = v
    spin[:bodies] = w
    weight[:bodies] = inverse_mass
    return vel, spin, weight


@njit(cache=True)
def solve_impulses(
    body_a, body_b, normal, friction, arm_a, arm_b, frame, mass_n, mass_t, target,
    inverse_mass, inverse_inertia, v, w, normal_impulse, tangent_impulse, iterations,
):  # fmt: skip
    """Sequential impulses: ``iterations`` sweeps over the contacts in order, changing ``v``
    and ``w`` in place (module docstring).

    ``normal_impulse`` ``(C,)`` [N·s] and ``tangent_impulse`` ``(C, 2)`` [N·s] hold each
    contact's accumulated impulse; whatever they hold on entry (a warm start) is applied
    first.
    """
    count = body_a.shape[0]
    bodies = v.shape[0]
    axes, lever, turn, index = levers(body_a, body_b, normal, frame, arm_a, arm_b,
                                       inverse_inertia, bodies, 3)  # fmt: skip
    vel, spin, weight = with_world(v, w, inverse_mass)
    for c in range(count):
        lever_impulse(c, 0, normal_impulse[c], axes, lever, turn, index, weight, vel, spin)
        lever_impulse(c, 1, tangent_impulse[c, 0], axes, lever, turn, index, weight, vel, spin)
        lever_impulse(c, 2, tangent_impulse[c, 1], axes, lever, turn, index, weight, vel, spin)
    for _ in range(iterations):
        for c in range(count):
            _contact_step(c, friction, mass_n, mass_t, target, normal_impulse, tangent_impulse,
                          axes, lever, turn, index, weight, vel, spin)  # fmt: skip
    v[:] = vel[:bodies]
    w[:] = spin[:bodies]


@njit(cache=True, inline="always")
def _contact_step(c, friction, mass_n, mass_t, target, normal_impulse, tangent_impulse,
                  axes, lever, turn, index, weight, vel, spin):  # fmt: skip
    """One contact's friction and normal impulses in a sweep."""
    # Friction first, bounded by the normal impulse of the last sweep (Catto 2005).
    limit = friction[c] * normal_impulse[c]
    old0 = tangent_impulse[c, 0]
    old1 = tangent_impulse[c, 1]
    new0 = old0 - mass_t[c, 0] * lever_speed(c, 1, axes, lever, index, vel, spin)
    new1 = old1 - mass_t[c, 1] * lever_speed(c, 2, axes, lever, index, vel, spin)
    size = math.sqrt(new0 * new0 + new1 * new1)
    if size > limit:
        scale = limit / size if size > 0.0 else 0.0
        new0 *= scale
        new1 *= scale
    tangent_impulse[c, 0] = new0
    tangent_impulse[c, 1] = new1
    lever_impulse(c, 1, new0 - old0, axes, lever, turn, index, weight, vel, spin)
    lever_impulse(c, 2, new1 - old1, axes, lever, turn, index, weight, vel, spin)
    # The normal impulse toward the target, accumulated and kept ≥ 0.
    v_n = lever_speed(c, 0, axes, lever, index, vel, spin)
    old = normal_impulse[c]
    new = max(old + mass_n[c] * (target[c] - v_n), 0.0)
    normal_impulse[c] = new
    lever_impulse(c, 0, new - old, axes, lever, turn, index, weight, vel, spin)


@njit(cache=True, inline="always")
def lever_speed(c, k, axes, lever, index, vel, spin):
    """Contact ``c``'s relative velocity along its direction ``k``, B's point from A's."""
    a = index[c, 0]
    b = index[c, 1]
    return (
        axes[c, k, 0] * (vel[b, 0] - vel[a, 0])
        + axes[c, k, 1] * (vel[b, 1] - vel[a, 1])
        + axes[c, k, 2] * (vel[b, 2] - vel[a, 2])
        + lever[c, 1, k, 0] * spin[b, 0]
        + lever[c, 1, k, 1] * spin[b, 1]
        + lever[c, 1, k, 2] * spin[b, 2]
        - lever[c, 0, k, 0] * spin[a, 0]
        - lever[c, 0, k, 1] * spin[a, 1]
        - lever[c, 0, k, 2] * spin[a, 2]
    )


@njit(cache=True, inline="always")
def lever_impulse(c, k, size, axes, lever, turn, index, weight, vel, spin):
    """An impulse of ``size`` along contact ``c``'s direction ``k`` on B, its opposite on A."""
    a = index[c, 0]
    b = index[c, 1]
    world = vel.shape[0] - 1  # at rest and of infinite mass: never written
    for i in range(3):
        d = size * axes[c, k, i]
        if b != world:
            vel[b, i] += weight[b] * d
            spin[b, i] += size * turn[c, 1, k, i]
        if a != world:
            vel[a, i] -= weight[a] * d
            spin[a, i] -= size * turn[c, 0, k, i]


@njit(cache=True)
def correct_positions(
    body_a, body_b, normal, depth, arm_a, arm_b, mass_n,
    inverse_mass, inverse_inertia, allowance, fraction, iterations, shift, turn,
):  # fmt: skip
    """Split position correction: sweeps of pseudo-impulses that move the bodies apart where
    they overlap by more than ``allowance[c]`` [m], each removing ``fraction`` of a contact's
    remaining excess depth, the depths updated to first order as the bodies move.

    ``shift`` and ``turn`` ``(B, 3)`` receive each body's translation [m] and small rotation
    vector [rad] (world frame), added to what they hold.
    """
    bodies = shift.shape[0]
    axes, lever, turn_of, index = levers(body_a, body_b, normal, normal, arm_a, arm_b,
                                          inverse_inertia, bodies, 1)  # fmt: skip
    moved, turned, weight = with_world(shift, turn, inverse_mass)
    for _ in range(iterations):
        for c in range(body_a.shape[0]):
            _correction(c, depth, allowance, fraction, mass_n, axes, lever, turn_of, index,
                        weight, moved, turned)  # fmt: skip
    shift[:] = moved[:bodies]
    turn[:] = turned[:bodies]


@njit(cache=True, inline="always")
def _correction(c, depth, allowance, fraction, mass_n, axes, lever, turn, index, weight,
                moved, turned):  # fmt: skip
    # The depth now: less how far the bodies' points moved apart along n so far.
    excess = depth[c] - lever_speed(c, 0, axes, lever, index, moved, turned) - allowance[c]
    if excess > 0.0:
        lever_impulse(c, 0, fraction * excess * mass_n[c], axes, lever, turn, index, weight,
                      moved, turned)  # fmt: skip
