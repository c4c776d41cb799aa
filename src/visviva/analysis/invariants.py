"""Quantities the exact dynamics conserves, and how far a run strays from them.

Energy, linear momentum and angular momentum are conserved by an isolated conservative system.
A numerical method may keep them exactly (momentum under symmetric pair forces; quadratic
invariants under implicit midpoint), bound their error (energy under a symplectic method),
or let them drift (energy under explicit or backward Euler). These helpers measure which.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ModelError

if TYPE_CHECKING:
    from ..simulation.recording import Recording

__all__ = [
    "angular_momentum",
    "center_of_mass",
    "energy_drift",
    "linear_momentum",
    "max_energy_error",
    "relative_change",
]


def relative_change(values: Any) -> np.ndarray:
    """``(x(t) − x(0)) / |x(0)|`` along the first (frame) axis; ``nan`` where ``x(0) = 0``."""
    series = np.asarray(values, dtype=np.float64)
    start = np.abs(series[0])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(start > 0, (series - series[0]) / np.where(start > 0, start, 1.0), np.nan)


def _energy(recording: Recording) -> np.ndarray | None:
    return recording.fields.get("energy")


def energy_drift(recording: Recording) -> float | None:
    """Relative energy change from the first to the last frame (the largest over a batch).

    Returns ``None`` when the recording has no energy or its initial energy is zero.
    """
    energy = _energy(recording)
    if energy is None or energy.shape[0] == 0:
        return None
    change = relative_change(energy)[-1]
    change = np.atleast_1d(change)
    if not np.isfinite(change).any():
        return None
    return float(change[np.nanargmax(np.abs(change))])


def max_energy_error(recording: Recording) -> float | None:
    """Largest ``|E(t) − E(0)| / |E(0)|`` over all frames (and systems), or ``None``."""
    energy = _energy(recording)
    if energy is None or energy.shape[0] == 0:
        return None
    change = np.abs(relative_change(energy))
    return float(np.nanmax(change)) if np.isfinite(change).any() else None


def _masses_positions(masses: Any, array: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    m = np.asarray(masses, dtype=np.float64)
    x = np.asarray(array, dtype=np.float64)
    if x.ndim < 2 or m.shape != x.shape[-2:-1]:
        raise ModelError(
            f"`{name}` must have shape (..., N, dim) for N = {m.size} masses (got {x.shape})"
        )
    return m, x


def linear_momentum(masses: Any, velocities: Any) -> np.ndarray:
    """``P = Σ m_i v_i`` [kg·m/s] for point masses.

    Args:
        masses: ``(N,)`` [kg].
        velocities: ``(..., N, dim)`` [m/s]; leading axes (frames, batch) are kept.

    Returns:
        ``(..., dim)``.
    """
    m, v = _masses_positions(masses, velocities, "velocities")
    return np.einsum("i,...ij->...j", m, v)


def center_of_mass(masses: Any, positions: Any) -> np.ndarray:
    """``Σ m_i x_i / Σ m_i`` [m], shape ``(..., dim)``."""
    m, x = _masses_positions(masses, positions, "positions")
    return np.einsum("i,...ij->...j", m, x) / m.sum()


def angular_momentum(masses: Any, positions: Any, velocities: Any) -> np.ndarray:
    """``L = Σ m_i x_i × v_i`` about the origin [kg·m²/s].

    Returns ``(..., 3)`` for 3-D points and ``(...,)`` (the z component) for 2-D points.
    """
    m, x = _masses_positions(masses, positions, "positions")
    _, v = _masses_positions(masses, velocities, "velocities")
    if x.shape[-1] == 3:
        return np.einsum("i,...ij->...j", m, np.cross(x, v))
    if x.shape[-1] == 2:
        return np.einsum("i,...i->...", m, x[..., 0] * v[..., 1] - x[..., 1] * v[..., 0])
    raise ModelError(f"angular momentum needs 2-D or 3-D points (got dim {x.shape[-1]})")
