"""The time of impact within a step: bisection as seed 003 writes it, and conservative
advancement, which also catches a fast body that would pass through a thin one.

Over a step each body moves from its start pose to its end pose; in between it is taken to
move linearly, its centre along the straight line and its orientation by normalized linear
interpolation of the quaternions. The time of impact of two pieces is the first fraction
``τ`` of the step at which they come within a tolerance of each other.

* **Bisection** (seed 003, ``findCollisionTime``): if the pieces overlap at the step's end,
  halve the interval until the distance is positive but below the tolerance. It needs the
  overlap at the end, so it misses a body that passed clean through another in one step.
* **Conservative advancement** (B. Mirtich, *Impulse-based dynamic simulation of rigid body
  systems*, PhD thesis, Berkeley 1996, §2.3; X. Zhang, S. Redon, M. Lee, Y. J. Kim, "Continuous
  collision detection for articulated models using Taylor models and temporal culling",
  SIGGRAPH 2007): from the start, advance by the distance divided by a bound on how fast any
  point of one piece can approach the other — ``|Δx_b − Δx_a| + θ_a r_a + θ_b r_b`` per step,
  for the step's translations, rotation angles and the pieces' reaches — so the pieces never
  meet between two advances. It finds the first contact along the whole motion.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry.quaternion_kernels import write_matrix
from .body_pieces import piece_shape
from .separation import shape_distance

__all__ = ["ADVANCEMENT", "BISECTION", "impact_fraction", "pull_back"]

ADVANCEMENT = 0
BISECTION = 1
#: Most advances or halvings before giving up on a pair (it is then taken not to meet).
MAX_STEPS = 64


@njit(cache=True)
def _pose(body, local_position, local_rotation, x0, q0, x1, q1, t, position, rotation):
    """Write a piece's world pose at fraction ``t`` of the step into ``position`` (3,) and
    ``rotation`` (3, 3); a static piece (body -1) keeps its own."""
    if body < 0:
        position[:] = local_position
        rotation[:] = local_rotation
        return
    qw = (1.0 - t) * q0[body, 0] + t * q1[body, 0]
    qx = (1.0 - t) * q0[body, 1] + t * q1[body, 1]
    qy = (1.0 - t) * q0[body, 2] + t * q1[body, 2]
    qz = (1.0 - t) * q0[body, 3] + t * q1[body, 3]
    if (
        q0[body, 0] * q1[body, 0]
        + q0[body, 1] * q1[body, 1]
        + q0[body, 2] * q1[body, 2]
        + (q0[body, 3] * q1[body, 3])
        < 0.0
    ):
        # The shorter way round: q and −q are the same rotation.
        qw = (1.0 - t) * q0[body, 0] - t * q1[body, 0]
        qx = (1.0 - t) * q0[body, 1] - t * q1[body, 1]
        qy = (1.0 - t) * q0[body, 2] - t * q1[body, 2]
        qz = (1.0 - t) * q0[body, 3] - t * q1[body, 3]
    r = np.empty((3, 3))
    write_matrix(qw, qx, qy, qz, r)
    for i in range(3):
        position[i] = (1.0 - t) * x0[body, i] + t * x1[body, i]
        for j in range(3):
            position[i] += r[i, j] * local_position[j]
            total = 0.0
            for k in range(3):
                total += r[i, k] * local_rotation[k, j]
            rotation[i, j] = total


@njit(cache=True)
def _distance_at(t, i, j, pieces, body, local_position, local_rotation, x0, q0, x1, q1):
    pi, ri = np.empty(3), np.empty((3, 3))
    pj, rj = np.empty(3), np.empty((3, 3))
    _pose(body[i], local_position[i], local_rotation[i], x0, q0, x1, q1, t, pi, ri)
    _pose(body[j], local_position[j], local_rotation[j], x0, q0, x1, q1, t, pj, rj)
    return shape_distance(piece_shape(i, pieces, pi, ri), piece_shape(j, pieces, pj, rj))[0]


@njit(cache=True)
def _turn_angle(q0, q1, body):
    """The angle [rad] the body turns through over the step (0 for the world)."""
    if body < 0:
        return 0.0
    dot = abs(q0[body, 0] * q1[body, 0] + q0[body, 1] * q1[body, 1] + q0[body, 2] * q1[body, 2]
              + q0[body, 3] * q1[body, 3])  # fmt: skip
    return 2.0 * math.acos(min(dot, 1.0))


@njit(cache=True)
def impact_fraction(i, j, method, tolerance, pieces, body, local_position, local_rotation,
                    reach, x0, q0, x1, q1):  # fmt: skip
    """The fraction of the step at which pieces ``i`` and ``j`` first come within
    ``tolerance`` [m] of each other, or 1 if they do not (module docstring for the two
    ``method`` s: :data:`ADVANCEMENT`, :data:`BISECTION`).

    Args:
        pieces: :meth:`~visviva.collision.body_pieces.BodyPieces.arrays`; ``body``,
            ``local_position``, ``local_rotation``: the pieces' bodies and poses in them.
        reach: ``(P,)`` each piece's farthest point from its body's centre of mass [m].
        x0, q0, x1, q1: The bodies' centres and orientations at the step's start and end.
    """
    a, b = body[i], body[j]
    args = (i, j, pieces, body, local_position, local_rotation, x0, q0, x1, q1)
    if method == BISECTION:
        if _distance_at(1.0, *args) >= 0.0:
            return 1.0
        low, high = 0.0, 1.0
        for _ in range(MAX_STEPS):
            middle = 0.5 * (low + high)
            d = _distance_at(middle, *args)
            if d < 0.0:
                high = middle
            elif d < tolerance:
                return middle
            else:
                low = middle
        return low
    # Conservative advancement: the bound on the approach per unit fraction of the step.
    speed = 0.0
    for k in range(3):
        da = x1[a, k] - x0[a, k] if a >= 0 else 0.0
        db = x1[b, k] - x0[b, k] if b >= 0 else 0.0
        speed += (db - da) ** 2
    speed = math.sqrt(speed) + _turn_angle(q0, q1, a) * reach[i] + _turn_angle(q0, q1, b) * reach[j]
    if speed == 0.0:
        return 1.0
    t = 0.0
    for _ in range(MAX_STEPS):
        d = _distance_at(t, *args)
        if d <= tolerance:
            return t
        t += d / speed
        if t >= 1.0:
            return 1.0
    return 1.0


@njit(cache=True)
def pull_back(pairs, fast, method, allowance, pieces, body, local_position, local_rotation,
              reach, radius, x0, q0, x1, q1):  # fmt: skip
    """Move each ``fast`` body back along its step to its first impact with a piece it did not
    touch at the start (``pairs``: candidate pairs of pieces from the swept bounds), in place
    on its end pose ``x1``, ``q1``: it then ends the step touching what it hit, within
    ``allowance`` of the smaller piece's size, and the contact response sees the impact.
    Returns how many bodies were moved back."""
    earliest = np.ones(x1.shape[0])
    for k in range(pairs.shape[0]):
        i, j = pairs[k, 0], pairs[k, 1]
        a, b = body[i], body[j]
        if a == b or not ((a >= 0 and fast[a]) or (b >= 0 and fast[b])):
            continue
        tolerance = 0.5 * allowance * min(radius[i], radius[j])
        args = (i, j, pieces, body, local_position, local_rotation, x0, q0, x1, q1)
        if _distance_at(0.0, *args) <= 2.0 * tolerance:
            continue  # touching already: a contact, not an impact
        tau = impact_fraction(i, j, method, tolerance, pieces, body, local_position,
                              local_rotation, reach, x0, q0, x1, q1)  # fmt: skip
        for c in (a, b):
            if c >= 0 and fast[c]:
                earliest[c] = min(earliest[c], tau)
    moved = 0
    position = np.empty(3)
    rotation = np.empty((3, 3))
    identity = np.eye(3)
    zero = np.zeros(3)
    for c in range(x1.shape[0]):
        if earliest[c] >= 1.0:
            continue
        t = earliest[c]
        _pose(c, zero, identity, x0, q0, x1, q1, t, position, rotation)
        # Back to a quaternion: the same interpolation _pose used, shorter way round.
        sign = 1.0 if np.dot(q0[c], q1[c]) >= 0.0 else -1.0
        q = (1.0 - t) * q0[c] + sign * t * q1[c]
        q1[c] = q / math.sqrt(np.dot(q, q))
        x1[c] = position
        moved += 1
    return moved
