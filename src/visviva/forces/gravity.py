"""Uniform gravity near a planet's surface: ``F_i = m_i g``, ``U = −Σ_i m_i g·x_i``."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

__all__ = ["UniformGravity"]


class UniformGravity:
    """Constant gravitational acceleration acting on every particle.

    Args:
        gravity: Acceleration ``g`` [m/s²], shape ``(3,)`` (Y up: ``(0, −9.81, 0)`` on Earth).
        mass: Particle masses [kg], shape ``(N,)``.
    """

    conservative: ClassVar[bool] = True

    def __init__(self, gravity: np.ndarray, mass: np.ndarray) -> None:
        self.gravity = np.array(gravity, dtype=np.float64)
        self.mass = np.array(mass, dtype=np.float64)
        # m_i g for every particle, computed once: the force does not depend on the state.
        self._weight = self.mass[:, None] * self.gravity[None, :]

    def accumulate(self, t: float, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """Add ``m_i g`` [N] to ``out`` ``(N, 3)`` (or a batch ``(B, N, 3)``)."""
        out += self._weight

    def potential(self, t: float, x: np.ndarray) -> np.ndarray:
        """``U = −Σ_i m_i g·x_i`` [J], zero at the origin; one value per system of a batch."""
        return -np.einsum("...ij,ij->...", x, self._weight)
