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
sliding, its accumulated size at most ``μ λ`` (Coulomb's cone). The sweeps go forward and
backward in turn (symmetric Gauss–Seidel): a contact always met first takes more than its
share of an unconverged sweep, and on a box's four corners that leaves a twist — a ten-box
stack swayed 1.4 mm in its first 50 steps with forward sweeps, 0.6 mm with alternating ones
(measured). The contacts are found at the
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
    "ROW",
    "contact_rows",
    "correct_positions",
    "lever_impulse",
    "lever_speed",
    "prepare_contacts",
    "rates_with_world",
    "solve_impulses",
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


#: A contact's row in :func:`contact_rows`: the directions n, t₁, t₂ (3 each), then per side
#: (A, B) and direction the lever ``r × d`` and the turn ``I⁻¹(r × d)``, then the two inverse
#: masses; padded to a multiple of a cache line.
ROW = 48
AXES, LEVER_A, LEVER_B, TURN_A, TURN_B, WEIGHT_A, WEIGHT_B = 0, 9, 18, 27, 36, 45, 46


@njit(cache=True)
def contact_rows(body_a, body_b, normal, frame, arm_a, arm_b, inverse_mass, inverse_inertia,
                 bodies, directions):  # fmt: skip
    """What a sweep needs of each contact, computed once, so that a sweep is dot products and
    additions: its first ``directions`` of (n, t₁, t₂) and, per body and direction, r × d (what
    the spin adds to the velocity along d) and I⁻¹(r × d) (how an impulse along d turns the
    body), and the bodies' inverse masses, in a row of :data:`ROW` ``(C, ROW)``; and each
    contact's two bodies ``(C, 2)``, the world as the extra body ``bodies`` (at rest, of
    infinite mass: its weight and turns are zero, so that no sweep branches on it). The
    tangents ``frame`` ``(C, 2, 3)`` are read only for ``directions`` > 1."""
    count = body_a.shape[0]
    rows = np.zeros((count, ROW))
    index = np.empty((count, 2), dtype=np.int64)
    for c in range(count):
        for i in range(3):
            rows[c, AXES + i] = normal[c, i]
            if directions > 1:
                rows[c, AXES + 3 + i] = frame[c, 0, i]
                rows[c, AXES + 6 + i] = frame[c, 1, i]
        for side in range(2):
            b = body_a[c] if side == 0 else body_b[c]
            index[c, side] = b if b >= 0 else bodies
            if b < 0:
                continue
            arm = arm_a[c] if side == 0 else arm_b[c]
            rows[c, WEIGHT_A + side] = inverse_mass[b]
            for k in range(directions):
                d = AXES + 3 * k
                cx, cy, cz = _cross(arm[0], arm[1], arm[2], rows[c, d], rows[c, d + 1],
                                    rows[c, d + 2])  # fmt: skip
                o = (LEVER_A if side == 0 else LEVER_B) + 3 * k
                rows[c, o], rows[c, o + 1], rows[c, o + 2] = cx, cy, cz
                tx, ty, tz = _times(inverse_inertia, b, cx, cy, cz)
                o = (TURN_A if side == 0 else TURN_B) + 3 * k
                rows[c, o], rows[c, o + 1], rows[c, o + 2] = tx, ty, tz
    return rows, index


@njit(cache=True)
def rates_with_world(v, w):
    """The per-body rates ``v``, ``w`` ``(B, 3)`` side by side ``(B + 1, 6)``, with one more
    row, the world's: at rest (see :func:`contact_rows`)."""
    bodies = v.shape[0]
    rates = np.zeros((bodies + 1, 8))
    rates[:bodies, :3] = v
    rates[:bodies, 3:6] = w
    return rates


@njit(cache=True, inline="always")
def lever_speed(rows, c, k, index, rates):
    """Contact ``c``'s relative velocity along its direction ``k``, B's point from A's."""
    a = index[c, 0]
    b = index[c, 1]
    d = AXES + 3 * k
    la = LEVER_A + 3 * k
    lb = LEVER_B + 3 * k
    # Summed as a tree, not a chain: a sweep waits on each sum (measured: a third faster).
    linear = (rows[c, d] * (rates[b, 0] - rates[a, 0])
              + rows[c, d + 1] * (rates[b, 1] - rates[a, 1])) + rows[c, d + 2] * (
                  rates[b, 2] - rates[a, 2])  # fmt: skip
    spin_b = (rows[c, lb] * rates[b, 3] + rows[c, lb + 1] * rates[b, 4]) + (
        rows[c, lb + 2] * rates[b, 5])  # fmt: skip
    spin_a = (rows[c, la] * rates[a, 3] + rows[c, la + 1] * rates[a, 4]) + (
        rows[c, la + 2] * rates[a, 5])  # fmt: skip
    return linear + (spin_b - spin_a)


@njit(cache=True, inline="always")
def lever_impulse(rows, c, k, size, index, rates):
    """An impulse of ``size`` along contact ``c``'s direction ``k`` on B, its opposite on A."""
    a = index[c, 0]
    b = index[c, 1]
    d = AXES + 3 * k
    ta = TURN_A + 3 * k
    tb = TURN_B + 3 * k
    weight_a = size * rows[c, WEIGHT_A]
    weight_b = size * rows[c, WEIGHT_B]
    for i in range(3):
        rates[b, i] += weight_b * rows[c, d + i]
        rates[b, 3 + i] += size * rows[c, tb + i]
        rates[a, i] -= weight_a * rows[c, d + i]
        rates[a, 3 + i] -= size * rows[c, ta + i]


@njit(cache=True, inline="always")
def _friction_impulse(rows, c, first, second, index, rates):
    """Impulses of ``first`` and ``second`` along contact ``c``'s tangents t₁, t₂ at once."""
    a = index[c, 0]
    b = index[c, 1]
    for i in range(3):
        along = first * rows[c, AXES + 3 + i] + second * rows[c, AXES + 6 + i]
        rates[b, i] += rows[c, WEIGHT_B] * along
        rates[b, 3 + i] += first * rows[c, TURN_B + 3 + i] + second * rows[c, TURN_B + 6 + i]
        rates[a, i] -= rows[c, WEIGHT_A] * along
        rates[a, 3 + i] -= first * rows[c, TURN_A + 3 + i] + second * rows[c, TURN_A + 6 + i]


@njit(cache=True)
def solve_impulses(
    body_a, body_b, normal, friction, arm_a, arm_b, frame, mass_n, mass_t, target,
    inverse_mass, inverse_inertia, v, w, normal_impulse, tangent_impulse, iterations,
):  # fmt: skip
    """Sequential impulses: ``iterations`` sweeps over the contacts, forward and backward in
    turn, changing ``v`` and ``w`` in place (module docstring).

    ``normal_impulse`` ``(C,)`` [N·s] and ``tangent_impulse`` ``(C, 2)`` [N·s] hold each
    contact's accumulated impulse; whatever they hold on entry (a warm start) is applied
    first.
    """
    count = body_a.shape[0]
    bodies = v.shape[0]
    rows, index = contact_rows(body_a, body_b, normal, frame, arm_a, arm_b, inverse_mass,
                               inverse_inertia, bodies, 3)  # fmt: skip
    rates = rates_with_world(v, w)
    for c in range(count):
        lever_impulse(rows, c, 0, normal_impulse[c], index, rates)
        _friction_impulse(rows, c, tangent_impulse[c, 0], tangent_impulse[c, 1], index, rates)
    for sweep in range(iterations):
        for step in range(count):
            c = step if sweep % 2 == 0 else count - 1 - step
            # Friction first, bounded by the normal impulse of the last sweep (Catto 2005);
            # none while the contact does not push and had none (a gap: idle).
            limit = friction[c] * normal_impulse[c]
            old0 = tangent_impulse[c, 0]
            old1 = tangent_impulse[c, 1]
            if limit > 0.0 or old0 != 0.0 or old1 != 0.0:
                new0 = old0 - mass_t[c, 0] * lever_speed(rows, c, 1, index, rates)
                new1 = old1 - mass_t[c, 1] * lever_speed(rows, c, 2, index, rates)
                size = math.sqrt(new0 * new0 + new1 * new1)
                if size > limit:
                    scale = limit / size if size > 0.0 else 0.0
                    new0 *= scale
                    new1 *= scale
                tangent_impulse[c, 0] = new0
                tangent_impulse[c, 1] = new1
                _friction_impulse(rows, c, new0 - old0, new1 - old1, index, rates)
            # The normal impulse toward the target, accumulated and kept ≥ 0.
            v_n = lever_speed(rows, c, 0, index, rates)
            old = normal_impulse[c]
            new = max(old + mass_n[c] * (target[c] - v_n), 0.0)
            normal_impulse[c] = new
            lever_impulse(rows, c, 0, new - old, index, rates)
    v[:] = rates[:bodies, :3]
    w[:] = rates[:bodies, 3:6]


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
    rows, index = contact_rows(body_a, body_b, normal, np.empty((0, 2, 3)), arm_a, arm_b,
                               inverse_mass, inverse_inertia, bodies, 1)  # fmt: skip
    moves = rates_with_world(shift, turn)
    for _ in range(iterations):
        for c in range(body_a.shape[0]):
            # The depth now: less how far the bodies' points moved apart along n so far.
            excess = depth[c] - lever_speed(rows, c, 0, index, moves) - allowance[c]
            if excess > 0.0:
                lever_impulse(rows, c, 0, fraction * excess * mass_n[c], index, moves)
    shift[:] = moves[:bodies, :3]
    turn[:] = moves[:bodies, 3:6]
