"""Unit quaternions ``(w, x, y, z)`` as Numba scalars, inlined into the rigid-body kernels.

The conventions and the NumPy forms are in :mod:`~visviva.geometry.quaternions`, which needs no
Numba (reading a recording turns body surfaces with it); the product is that module's
:func:`~visviva.geometry.quaternions.hamilton_product`, compiled.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .quaternions import hamilton_product

__all__ = ["multiply", "normalized", "rotate", "rotate_back", "write_matrix"]

#: The Hamilton product ``a ⊗ b`` of components: the rotation ``b``, then ``a``.
multiply = njit(cache=True, inline="always")(hamilton_product)


@njit(cache=True, inline="always")
def rotate(w, x, y, z, vx, vy, vz):  # pragma: no cover - compiled
    """``R(q) v`` for a unit quaternion ``q`` (``v + 2w (u × v) + 2 u × (u × v)``, ``u`` the
    vector part)."""
    cx = y * vz - z * vy
    cy = z * vx - x * vz
    cz = x * vy - y * vx
    return (
        vx + 2.0 * (w * cx + y * cz - z * cy),
        vy + 2.0 * (w * cy + z * cx - x * cz),
        vz + 2.0 * (w * cz + x * cy - y * cx),
    )


@njit(cache=True, inline="always")
def rotate_back(w, x, y, z, vx, vy, vz):  # pragma: no cover - compiled
    """``R(q)ᵀ v``: world to body coordinates."""
    return rotate(w, -x, -y, -z, vx, vy, vz)


@njit(cache=True, inline="always")
def normalized(w, x, y, z):  # pragma: no cover - compiled
    """``q / |q|``."""
    inverse = 1.0 / np.sqrt(w * w + x * x + y * y + z * z)
    return w * inverse, x * inverse, y * inverse, z * inverse


@njit(cache=True, inline="always")
def write_matrix(w, x, y, z, out):  # pragma: no cover - compiled
    """Write the rotation matrix ``R(q)`` of ``q`` (normalized first) into ``out`` ``(3, 3)``."""
    w, x, y, z = normalized(w, x, y, z)
    out[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[0, 1] = 2.0 * (x * y - w * z)
    out[0, 2] = 2.0 * (x * z + w * y)
    out[1, 0] = 2.0 * (x * y + w * z)
    out[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[1, 2] = 2.0 * (y * z - w * x)
    out[2, 0] = 2.0 * (x * z - w * y)
    out[2, 1] = 2.0 * (y * z + w * x)
    out[2, 2] = 1.0 - 2.0 * (x * x + y * y)
