"""The constant mass matrix ``M`` of a second-order problem ``M q'' = F(t, q, v)``.

Three storage forms, chosen from what the user passes:

* **diagonal** — a scalar or an array with at most as many axes as ``q0``, broadcast against
  ``q0``: one mass per coordinate (particles), per system (``(batch, 1)``) or for all.
* **dense** — an array with one more axis than ``q0``: ``(n, n)`` for one system, or
  ``(batch, n, n)`` / ``(1, n, n)`` for a batch. Must be symmetric positive definite.
* **sparse** — a ``scipy.sparse`` matrix ``(n, n)`` for one (large) system.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import describe
from ..errors import ModelError

__all__ = ["Mass"]

#: Relative asymmetry ‖M − Mᵀ‖ / ‖M‖ above which a mass matrix is refused.
SYMMETRY_TOLERANCE = 1e-10


class Mass:
    """A validated, constant mass matrix [kg] (or the generalized mass of the coordinates).

    Attributes:
        kind: ``"diagonal"``, ``"dense"`` or ``"sparse"``.
        values: The diagonal (broadcastable to ``q``), the dense matrices ``(..., n, n)``, or the
            sparse ``(n, n)`` matrix.
    """

    def __init__(self, mass: Any, q0: np.ndarray) -> None:
        import scipy.sparse as sp

        n = q0.shape[-1]
        if sp.issparse(mass):
            if q0.ndim != 1:
                raise ModelError(
                    "a sparse `mass` matrix is for one system; for a batch pass a diagonal "
                    f"or dense (batch, n, n) mass (q0 has shape {q0.shape})"
                )
            if mass.shape != (n, n):
                raise ModelError(f"`mass` must have shape ({n}, {n}) (got {mass.shape})")
            matrix = sp.csc_matrix(mass, dtype=np.float64)
            if not np.isfinite(matrix.data).all():
                raise ModelError("`mass` must be finite (the sparse matrix holds nan or inf)")
            asymmetry = abs(matrix - matrix.T).max() if matrix.nnz else 0.0
            if asymmetry > SYMMETRY_TOLERANCE * max(abs(matrix).max(), 1e-300):
                raise ModelError(f"`mass` must be symmetric (max |M - M^T| = {asymmetry:.3g})")
            if (matrix.diagonal() <= 0).any():
                raise ModelError("`mass` must be positive definite (a diagonal entry is <= 0)")
            self.kind = "sparse"
            self.values: Any = matrix
            self._factor = sp.linalg.splu(matrix)
            return

        try:
            array = np.asarray(mass, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            raise ModelError(
                f"`mass` must be a number, an array or a scipy.sparse matrix (got {describe(mass)})"
            ) from None
        if not np.isfinite(array).all():
            raise ModelError(f"`mass` must be finite ({_first(array, ~np.isfinite(array))})")
        if array.ndim <= q0.ndim:
            try:
                np.broadcast_shapes(array.shape, q0.shape)
            except ValueError:
                raise ModelError(
                    f"a diagonal `mass` must broadcast against q0 of shape {q0.shape} "
                    f"(got shape {array.shape})"
                ) from None
            if (array <= 0).any():
                raise ModelError(f"`mass` must be positive ({_first(array, array <= 0)})")
            self.kind = "diagonal"
            self.values = array
            return

        if array.ndim != q0.ndim + 1 or array.shape[-2:] != (n, n):
            raise ModelError(
                f"`mass` must be a diagonal broadcastable to q0 {q0.shape} or matrices of shape "
                f"(..., {n}, {n}) with one more axis than q0 (got shape {array.shape})"
            )
        if q0.ndim == 2 and array.shape[0] not in (1, q0.shape[0]):
            raise ModelError(
                f"`mass` holds {array.shape[0]} matrices for a batch of {q0.shape[0]} systems"
            )
        scale = np.abs(array).max()
        asymmetry = np.abs(array - np.swapaxes(array, -1, -2)).max()
        if asymmetry > SYMMETRY_TOLERANCE * scale:
            raise ModelError(f"`mass` must be symmetric (max |M - M^T| = {asymmetry:.3g})")
        smallest = float(np.linalg.eigvalsh(array).min())
        if smallest <= 0.0:
            raise ModelError(
                f"`mass` must be positive definite (its smallest eigenvalue is {smallest:.6g})"
            )
        self.kind = "dense"
        self.values = array

    def solve(self, force: np.ndarray) -> np.ndarray:
        """Return ``M⁻¹ force`` (accelerations from forces), same shape as ``force``."""
        if self.kind == "diagonal":
            return force / self.values
        if self.kind == "sparse":
            return self._factor.solve(force)
        return np.linalg.solve(self.values, force[..., None])[..., 0]

    def apply(self, vector: np.ndarray) -> np.ndarray:
        """Return ``M vector`` (e.g. momenta from velocities), same shape as ``vector``."""
        if self.kind == "diagonal":
            return self.values * vector
        if self.kind == "sparse":
            return self.values @ vector
        return (self.values @ vector[..., None])[..., 0]

    def diagonal(self) -> np.ndarray:
        """The diagonal of ``M`` [kg], shape ``(n,)`` (or broadcastable to ``q``'s shape)."""
        if self.kind == "diagonal":
            return np.asarray(self.values)
        if self.kind == "sparse":
            return np.asarray(self.values.diagonal())
        return np.diagonal(self.values, axis1=-2, axis2=-1)

    def dense(self, q_shape: tuple[int, ...]) -> np.ndarray:
        """Return ``M`` as dense matrices of shape ``q_shape + (n,)``."""
        if self.kind == "sparse":
            return self.values.toarray()
        if self.kind == "dense":
            return np.broadcast_to(self.values, q_shape + q_shape[-1:])
        diagonal = np.broadcast_to(self.values, q_shape)
        matrices = np.zeros(q_shape + q_shape[-1:])
        index = np.arange(q_shape[-1])
        matrices[..., index, index] = diagonal
        return matrices


def _first(array: np.ndarray, bad: np.ndarray) -> str:
    """``got X`` for a scalar, ``entry I is X`` for the first offending entry of an array."""
    if array.ndim == 0:
        return f"got {describe(array)}"
    index = tuple(int(i) for i in np.argwhere(bad)[0])
    where = index[0] if len(index) == 1 else index
    return f"entry {where} is {describe(array[index])}"
