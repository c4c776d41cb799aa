"""Unit quaternions ``(w, x, y, z)`` for orientations: products, rotations, matrices.

A body's orientation is the unit quaternion ``q`` that takes body coordinates to world ones:
``p_world = R(q) p_body`` (Baraff & Witkin's notes, "Rigid body dynamics", §4). Quaternions are
easier to keep a rotation than matrices (seed 003): a unit quaternion drifts off the unit
sphere by round-off only, and one division brings it back, where a matrix needs Gram–Schmidt.
The functions here are NumPy forms, for the model's setup, the recordings' body surfaces and the
tests; the scalar forms inlined into the rigid-body kernels are in
:mod:`~visviva.geometry.quaternion_kernels`, so that reading a recording needs no Numba.

References:
    D. Baraff, A. Witkin, "Physically based modeling: rigid body dynamics", SIGGRAPH course
    notes, 2001; K. Shoemake, "Animating rotation with quaternion curves", SIGGRAPH 1985.
"""

from __future__ import annotations

import numpy as np

__all__ = ["matrix_quaternion", "quaternion_matrix", "quaternion_multiply", "quaternion_rotate"]


def hamilton_product(aw, ax, ay, az, bw, bx, by, bz):
    """The Hamilton product ``a ⊗ b``: the rotation ``b``, then ``a``.

    On components that are floats or arrays alike: :func:`quaternion_multiply` calls it on
    arrays, and :mod:`~visviva.geometry.quaternion_kernels` compiles this same function for the
    rigid-body kernels.
    """
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def quaternion_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a ⊗ b`` for ``(..., 4)`` arrays."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
    return np.stack(hamilton_product(*np.moveaxis(a, -1, 0), *np.moveaxis(b, -1, 0)), axis=-1)


def quaternion_rotate(q: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``R(q) v`` for ``(..., 4)`` unit quaternions and ``(..., 3)`` vectors."""
    return np.einsum("...ij,...j->...i", quaternion_matrix(q), np.asarray(vectors, np.float64))


def quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """The rotation matrices ``(..., 3, 3)`` of unit quaternions ``(..., 4)``."""
    q = np.asarray(q, dtype=np.float64)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def matrix_quaternion(matrix: np.ndarray) -> np.ndarray:
    """The unit quaternion ``(w, x, y, z)`` with ``w ≥ 0`` of a rotation matrix ``(3, 3)``.

    From the largest of ``4w², 4x², 4y², 4z²`` (the trace and the diagonal), which keeps the
    division well away from zero (Shepperd, J. Guidance Control 1(3), 1978)."""
    m = np.asarray(matrix, dtype=np.float64)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    squares = np.array([1.0 + trace, 1.0 + 2 * m[0, 0] - trace, 1.0 + 2 * m[1, 1] - trace,
                        1.0 + 2 * m[2, 2] - trace])  # 4w², 4x², 4y², 4z²  # fmt: skip
    k = int(np.argmax(squares))
    big = 0.5 * np.sqrt(squares[k])  # the largest component
    quarter = 0.25 / big
    if k == 0:
        q = [big, (m[2, 1] - m[1, 2]) * quarter, (m[0, 2] - m[2, 0]) * quarter,
             (m[1, 0] - m[0, 1]) * quarter]  # fmt: skip
    elif k == 1:
        q = [(m[2, 1] - m[1, 2]) * quarter, big, (m[0, 1] + m[1, 0]) * quarter,
             (m[0, 2] + m[2, 0]) * quarter]  # fmt: skip
    elif k == 2:
        q = [(m[0, 2] - m[2, 0]) * quarter, (m[0, 1] + m[1, 0]) * quarter, big,
             (m[1, 2] + m[2, 1]) * quarter]  # fmt: skip
    else:
        q = [(m[1, 0] - m[0, 1]) * quarter, (m[0, 2] + m[2, 0]) * quarter,
             (m[1, 2] + m[2, 1]) * quarter, big]  # fmt: skip
    q = np.array(q)
    return q if q[0] >= 0.0 else -q
