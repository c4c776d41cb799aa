"""Coulomb friction inside an implicit step, as a dissipation potential with a lagged normal
impulse (Li et al. 2020, §5).

A point held against a static surface with unit normal ``n`` by a normal impulse ``J`` [N·s]
over the step resists sliding with at most ``μ J``. Over the step's velocity ``V`` its tangential
part ``u = |(I − n nᵀ) V|`` [m/s] meets the friction impulse ``μ J f₁(u)`` opposite to it, the
gradient of the potential ``μ J f₀(u)`` [J] (an impulse times a speed), which the step's
incremental potential gains as one more convex term:

    f₀(u) = u                          f₁(u) = 1                      u ≥ ε
    f₀(u) = −u³/(3ε²) + u²/ε + ε/3     f₁(u) = 2u/ε − u²/ε²           u < ε

``f₁`` rises smoothly from 0 to 1 over the sliding speed ``ε``: below it friction is a stiff
viscous drag (static friction, approximately), above it Coulomb's constant ``μ J``. ``J`` is
held from the previous solve of the same step (the residual along the normal, which is the
impulse the surface supplied), so friction stays a gradient and the solve a minimization;
its Hessian is positive semi-definite by construction, ``μ J`` times

    (f₁(u)/u) (T − t tᵀ) + f₁′(u) t tᵀ,     T = I − n nᵀ,   t = (T V)/u.

References:
    M. Li, Z. Ferguson, T. Schneider, T. Langlois, D. Zorin, D. Panozzo, C. Jiang,
    D. M. Kaufman, "Incremental potential contact: intersection- and inversion-free, large-
    deformation dynamics", ACM Trans. Graph. 39(4) (2020), §5 (lagged, smoothed friction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LaggedFriction"]


@dataclass(frozen=True)
class LaggedFriction:
    """Friction on held points (see the module docstring).

    Attributes:
        normals: ``(N, 3)`` the surface's unit normal at each held point; zero rows are free.
        weight: ``(N,)`` ``μ J`` [N·s] of each point (0 where free).
        slip: ``ε`` [m/s], the sliding speed over which friction reaches Coulomb's bound.
    """

    normals: np.ndarray
    weight: np.ndarray
    slip: float

    def _tangential(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rows = v.reshape(-1, 3)
        along = np.einsum("ij,ij->i", rows, self.normals)
        tangential = rows - along[:, None] * self.normals
        tangential[~np.any(self.normals != 0.0, axis=1)] = 0.0  # free points slide freely
        return tangential, np.linalg.norm(tangential, axis=1)

    def potential(self, v: np.ndarray) -> float:
        """``Σ μ J f₀(u)`` over the points, at the flat velocities ``v`` ``(3N,)``."""
        _, u = self._tangential(v)
        e = self.slip
        f0 = np.where(u >= e, u, -(u**3) / (3 * e * e) + u * u / e + e / 3)
        f0[~np.any(self.normals != 0.0, axis=1)] = 0.0
        return float((self.weight * f0).sum())  # not np.dot: see projected_newton._inner

    def gradient(self, v: np.ndarray) -> np.ndarray:
        """The friction impulse's negative, ``μ J f₁(u) t`` [N·s], flat ``(3N,)``: what the
        backward Euler residual gains."""
        tangential, u = self._tangential(v)
        return (self.weight * _f1_over_u(u, self.slip))[:, None] * tangential

    def blocks(self, v: np.ndarray) -> np.ndarray:
        """``(N, 3, 3)`` the Hessian block of each point (see the module docstring)."""
        tangential, u = self._tangential(v)
        e = self.slip
        over_u = _f1_over_u(u, e)
        slope = np.where(u >= e, 0.0, 2.0 / e - 2.0 * u / (e * e))  # f₁′(u)
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(u[:, None] > 0.0, tangential / u[:, None], 0.0)
        across = np.eye(3) - self.normals[:, :, None] * self.normals[:, None, :]
        outer = t[:, :, None] * t[:, None, :]
        held = np.any(self.normals != 0.0, axis=1)
        hessian = over_u[:, None, None] * (across - outer) + slope[:, None, None] * outer
        return np.where(held[:, None, None], self.weight[:, None, None] * hessian, 0.0)


def _f1_over_u(u: np.ndarray, e: float) -> np.ndarray:
    """``f₁(u)/u``, finite at ``u = 0`` (``2/ε``)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(u >= e, 1.0 / u, 2.0 / e - u / (e * e))
