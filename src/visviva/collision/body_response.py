"""The response to one step's contacts between rigid bodies, as one compiled pass.

Given the contacts found at the step's end poses (sorted bottom-up), :func:`respond` does what
:mod:`~visviva.collision.body_contacts` describes, in order:

1. each contact's arms, depth at the step's start (from how the two material points moved
   over the step, or ``d + h v_n`` when the start is unknown), tangent frame, effective masses
   and target (:func:`~visviva.collision.body_impulses.prepare_contacts`); a colliding
   contact's target taken at the moment of impact within the step;
2. with simultaneous impacts, the impact by generalized reflections
   (:mod:`~visviva.collision.simultaneous`); then the warm start from the last step's
   impulses, and sequential impulses
   (:func:`~visviva.collision.body_impulses.solve_impulses`);
3. the step redone for the bodies the impulses changed, from each one's first impact;
4. the position correction of what overlap is left;
5. the momenta ``P = M v`` and ``L = I ω`` written back.

Body index ``-1`` is the world. Lengths in metres, times in seconds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry.quaternion_kernels import write_matrix
from .body_impulses import correct_positions, prepare_contacts, solve_impulses
from .simultaneous import reflect_impacts

__all__ = ["body_frames", "normal_velocities", "respond", "turned"]


@njit(cache=True)
def body_frames(q, inverse_inertia_body, inverse_mass, momentum, spin):
    """Each body's rotation ``R(q)`` ``(B, 3, 3)``, world inverse inertia ``R I⁻¹ Rᵀ``,
    velocity ``P/M`` and angular velocity ``I⁻¹ L`` ``(B, 3)`` (``q`` normalized first)."""
    count = q.shape[0]
    rotation = np.empty((count, 3, 3))
    inverse = np.empty((count, 3, 3))
    v = np.empty((count, 3))
    w = np.empty((count, 3))
    for b in range(count):
        write_matrix(q[b, 0], q[b, 1], q[b, 2], q[b, 3], rotation[b])
        r = rotation[b]
        # R I⁻¹ Rᵀ, written out (small matrix products would allocate)
        body_inverse = inverse_inertia_body[b]
        for i in range(3):
            for j in range(3):
                total = 0.0
                for k in range(3):
                    for m in range(3):
                        total += r[i, k] * body_inverse[k, m] * r[j, m]
                inverse[b, i, j] = total
        for i in range(3):
            v[b, i] = momentum[b, i] * inverse_mass[b]
            w[b, i] = (
                inverse[b, i, 0] * spin[b, 0]
                + inverse[b, i, 1] * spin[b, 1]
                + inverse[b, i, 2] * spin[b, 2]
            )
    return rotation, inverse, v, w


@njit(cache=True)
def normal_velocities(body_a, body_b, normal, arm_a, arm_b, v, w):
    """Each contact's ``n·(v_b + ω_b × r_b − v_a − ω_a × r_a)`` ``(C,)`` (any pair of
    per-body rates: velocities, or a step's moves and turns)."""
    out = np.empty(body_a.shape[0])
    for c in range(body_a.shape[0]):
        total = 0.0
        for side in range(2):
            b = body_b[c] if side == 1 else body_a[c]
            if b < 0:
                continue
            arm = arm_b[c] if side == 1 else arm_a[c]
            sign = 1.0 if side == 1 else -1.0
            ux = v[b, 0] + w[b, 1] * arm[2] - w[b, 2] * arm[1]
            uy = v[b, 1] + w[b, 2] * arm[0] - w[b, 0] * arm[2]
            uz = v[b, 2] + w[b, 0] * arm[1] - w[b, 1] * arm[0]
            total += sign * (ux * normal[c, 0] + uy * normal[c, 1] + uz * normal[c, 2])
        out[c] = total
    return out


@njit(cache=True)
def turned(q, twist):
    """Unit quaternions ``q`` turned by small world rotation vectors ``θ``:
    ``q + ½ (0, θ) ⊗ q``, normalized; in place."""
    for b in range(q.shape[0]):
        tx, ty, tz = twist[b, 0], twist[b, 1], twist[b, 2]
        if tx == 0.0 and ty == 0.0 and tz == 0.0:
            continue
        w, x, y, z = q[b, 0], q[b, 1], q[b, 2], q[b, 3]
        nw = w + 0.5 * (-tx * x - ty * y - tz * z)
        nx = x + 0.5 * (tx * w + ty * z - tz * y)
        ny = y + 0.5 * (ty * w + tz * x - tx * z)
        nz = z + 0.5 * (tz * w + tx * y - ty * x)
        norm = math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
        q[b, 0], q[b, 1], q[b, 2], q[b, 3] = nw / norm, nx / norm, ny / norm, nz / norm


@njit(cache=True)
def _rotation_vector(q0, q1, b):
    """The rotation vector [rad] of ``q₁ ⊗ q₀⁻¹`` for body ``b``, the shorter way round."""
    w0, x0, y0, z0 = q0[b, 0], -q0[b, 1], -q0[b, 2], -q0[b, 3]
    w1, x1, y1, z1 = q1[b, 0], q1[b, 1], q1[b, 2], q1[b, 3]
    w = w1 * w0 - x1 * x0 - y1 * y0 - z1 * z0
    x = w1 * x0 + x1 * w0 + y1 * z0 - z1 * y0
    y = w1 * y0 - x1 * z0 + y1 * w0 + z1 * x0
    z = w1 * z0 + x1 * y0 - y1 * x0 + z1 * w0
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sine = math.sqrt(x * x + y * y + z * z)
    scale = 2.0 * math.atan2(sine, w) / sine if sine > 0.0 else 2.0
    return x * scale, y * scale, z * scale


@njit(cache=True)
def _start_depths(body_a, body_b, point, normal, depth, x, rotation, x0, q0):
    """Each contact's depth at the step's start: the end depth plus how far the two material
    points at the contact moved toward each other along ``n`` (a point at arm ``r`` from the
    centre at the end was at ``x₀ + R₀ R₁ᵀ r``)."""
    out = np.empty(depth.shape[0])
    start_rotation = np.empty((3, 3))
    local_arm = np.empty(3)
    for c in range(depth.shape[0]):
        moved = 0.0
        for side in range(2):
            b = body_b[c] if side == 1 else body_a[c]
            if b < 0:
                continue
            sign = 1.0 if side == 1 else -1.0
            write_matrix(q0[b, 0], q0[b, 1], q0[b, 2], q0[b, 3], start_rotation)
            # arm in the body's axes at the end, then turned as the body was at the start
            ax = point[c, 0] - x[b, 0]
            ay = point[c, 1] - x[b, 1]
            az = point[c, 2] - x[b, 2]
            for i in range(3):
                local = rotation[b, 0, i] * ax + rotation[b, 1, i] * ay + rotation[b, 2, i] * az
                local_arm[i] = local
            for i in range(3):
                earlier = x0[b, i] + (
                    start_rotation[i, 0] * local_arm[0]
                    + start_rotation[i, 1] * local_arm[1]
                    + start_rotation[i, 2] * local_arm[2]
                )
                moved += sign * (point[c, i] - earlier) * normal[c, i]
        out[c] = depth[c] + moved
    return out


@njit(cache=True)
def _impact_time(depth, start):
    """The fraction of the step at which a contact touched, moving linearly from its start
    depth to its end depth (0 if it overlapped already at the start, 1 if it ends just short
    of touching)."""
    if start >= 0.0 or not start - depth < 0.0:
        return 0.0
    return min(max(start / (start - depth), 0.0), 1.0)


@njit(cache=True)
def respond(
    body_a, body_b, point, normal, depth, restitution, friction, warm_normal, warm_friction,
    x, q, momentum, spin, rotation, inverse_inertia, v, w,
    inverse_mass, inertia_body, dynamic,
    has_start, x0, q0, v0, w0,
    h, resting_speed, iterations, position_iterations, allowance, fraction, simultaneous,
):  # fmt: skip
    """Resolve one step's contacts (module docstring) in place on ``x``, ``q``, ``momentum``
    and ``spin``; ``warm_normal`` ``(C,)`` and ``warm_friction`` ``(C, 3)`` (world frame) are
    each contact's warm start. Returns the normal impulses ``(C,)`` and the friction impulses
    ``(C, 3)`` (world frame) [N·s] the contacts ended with."""
    count = body_a.shape[0]
    bodies = x.shape[0]
    arm_a = np.zeros((count, 3))
    arm_b = np.zeros((count, 3))
    frame = np.zeros((count, 2, 3))
    mass_n = np.zeros(count)
    mass_t = np.zeros((count, 2))
    target = np.zeros(count)
    if has_start:
        start_depth = _start_depths(body_a, body_b, point, normal, depth, x, rotation, x0, q0)
    else:
        start_depth = np.full(count, np.nan)
    prepare_contacts(body_a, body_b, point, normal, depth, start_depth, allowance, restitution,
                     resting_speed, h, x, inverse_mass, inverse_inertia, v, w, arm_a, arm_b,
                     frame, mass_n, mass_t, target)  # fmt: skip
    approach = normal_velocities(body_a, body_b, normal, arm_a, arm_b, v, w)
    initial = normal_velocities(body_a, body_b, normal, arm_a, arm_b, v0, w0)
    # Each body's first impact of the step, as a fraction of it (1: none).
    first = np.ones(bodies + 1)
    for c in range(count):
        if not (depth[c] >= -allowance[c] and approach[c] < -resting_speed):
            continue
        start = start_depth[c] if has_start else depth[c] + h * approach[c]
        tau = _impact_time(depth[c], start)
        first[body_a[c]] = min(first[body_a[c]], tau)
        first[body_b[c]] = min(first[body_b[c]], tau)
        if has_start:
            # The forces of the step change v_n from v₀ to v₁: at the impact it is
            # v₀ + τ(v₁ − v₀); reversed with restitution, then changed by the forces for the
            # rest of the step.
            change = approach[c] - initial[c]
            at_impact = min(initial[c] + tau * change, 0.0)
            target[c] = -restitution[c] * at_impact + (1.0 - tau) * change
    if simultaneous:
        # The impact first, all its contacts together by generalized reflections; what is
        # left for the sweeps is to keep every contact from approaching.
        gap = np.empty(count)
        for c in range(count):
            gap[c] = max(-depth[c] - allowance[c], 0.0)
        reflect_impacts(body_a, body_b, normal, arm_a, arm_b, mass_n, restitution, gap, h,
                        resting_speed, inverse_mass, inverse_inertia, v, w)  # fmt: skip
        for c in range(count):
            if target[c] > 0.0:
                target[c] = 0.0
    normal_impulse = warm_normal.copy()
    tangent_impulse = np.empty((count, 2))
    for c in range(count):
        for k in range(2):
            tangent_impulse[c, k] = np.dot(warm_friction[c], frame[c, k])
    v_start = v.copy()
    w_start = w.copy()
    solve_impulses(body_a, body_b, normal, friction, arm_a, arm_b, frame, mass_n, mass_t,
                   target, inverse_mass, inverse_inertia, v, w, normal_impulse,
                   tangent_impulse, iterations)  # fmt: skip
    # The step again for the bodies the impulses changed: as the integrator moved them until
    # their first impact τ, with the new velocity after: x(τ) + (1 − τ) h v, that is, moved by
    # (1 − τ)(h v − Δx) for the step's move Δx (h v before the impulses if the start is
    # unknown), and turned likewise.
    shift = np.zeros((bodies, 3))
    twist = np.zeros((bodies, 3))
    for b in range(bodies):
        changed = False
        for i in range(3):
            if v[b, i] != v_start[b, i] or w[b, i] != w_start[b, i]:
                changed = True
        if not changed:
            continue
        remainder = 1.0 - (first[b] if first[b] < 1.0 else 0.0)
        if has_start:
            tx, ty, tz = _rotation_vector(q0, q, b)
            travel = (x[b, 0] - x0[b, 0], x[b, 1] - x0[b, 1], x[b, 2] - x0[b, 2])
        else:
            tx, ty, tz = h * w_start[b, 0], h * w_start[b, 1], h * w_start[b, 2]
            travel = (h * v_start[b, 0], h * v_start[b, 1], h * v_start[b, 2])
        turn = (tx, ty, tz)
        for i in range(3):
            shift[b, i] = remainder * (h * v[b, i] - travel[i])
            twist[b, i] = remainder * (h * w[b, i] - turn[i])
    # The correction measures each depth less what the moves so far took off it.
    correct_positions(body_a, body_b, normal, depth, arm_a, arm_b, mass_n, inverse_mass,
                      inverse_inertia, allowance, fraction, position_iterations, shift,
                      twist)  # fmt: skip
    x += shift
    turned(q, twist)
    # Back to momenta, with the inertia of the step's end (world frame).
    local_w = np.empty(3)
    local_l = np.empty(3)
    for b in range(bodies):
        if not dynamic[b]:
            continue
        # L = R I_body Rᵀ ω
        for i in range(3):
            local_w[i] = (
                rotation[b, 0, i] * w[b, 0]
                + rotation[b, 1, i] * w[b, 1]
                + rotation[b, 2, i] * w[b, 2]
            )
        for i in range(3):
            local_l[i] = (
                inertia_body[b, i, 0] * local_w[0]
                + inertia_body[b, i, 1] * local_w[1]
                + inertia_body[b, i, 2] * local_w[2]
            )
        for i in range(3):
            momentum[b, i] = v[b, i] / inverse_mass[b]
            spin[b, i] = (
                rotation[b, i, 0] * local_l[0]
                + rotation[b, i, 1] * local_l[1]
                + rotation[b, i, 2] * local_l[2]
            )
    friction_world = np.empty((count, 3))
    for c in range(count):
        for i in range(3):
            friction_world[c, i] = (
                tangent_impulse[c, 0] * frame[c, 0, i] + tangent_impulse[c, 1] * frame[c, 1, i]
            )
    return normal_impulse, friction_world
