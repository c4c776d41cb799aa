"""How orientations drift: rotation matrices against quaternions, renormalized or not.

Seed 003's lesson, measured. A free body tumbling with angular momentum ``L`` (constant: no
torque) turns with ``ω = R I⁻¹ Rᵀ L``; the orientation is stepped five ways for the same
steps ``h``:

* ``matrix``: the lecture's explicit Euler on the rotation matrix, ``R ← R + h ω* R``. Each
  step multiplies ``RᵀR`` by about ``1 + h²|ω|²``: the columns grow and stop being orthogonal,
  and the "rotation" shears the body;
* ``matrix + Gram–Schmidt``: the same, its columns orthonormalized after each step;
* ``quaternion``: explicit Euler on ``q' = ½ (0, ω) ⊗ q``: ``|q|`` grows by
  ``√(1 + (h|ω|/2)²)`` a step, and ``R(q)`` with it;
* ``quaternion + normalization``: the same divided by ``|q|`` after each step (the scenes'
  projection stage, :mod:`visviva.rigid.projection`);
* any other quaternion step the caller gives, such as the scenes' default, the splitting of
  the free rotation into exact turns (:meth:`visviva.rigid.motion.BodyMotion.drift`): unit to
  round-off by construction.

:func:`drift_study` reports, per step, how far each orientation is from being a rotation
(``‖RᵀR − E‖`` of the matrix it stands for), its kinetic energy ``½ Lᵀ R I⁻¹ Rᵀ L`` against the
start, and its distance from a reference orientation (RK4 at a step 10 times smaller,
normalized).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..geometry.quaternions import quaternion_matrix

__all__ = ["METHODS", "DriftStudy", "drift_study"]

METHODS = ("matrix", "matrix + Gram–Schmidt", "quaternion", "quaternion + normalization")


@dataclass(frozen=True)
class DriftStudy:
    """Per method (:data:`METHODS` and the caller's), arrays over the steps ``(steps + 1,)``.

    Attributes:
        t: Times [s].
        not_a_rotation: ``‖RᵀR − E‖`` (Frobenius) of the orientation's matrix.
        energy_error: Kinetic energy over its start, minus 1.
        error: ``‖R − R_ref‖`` (Frobenius) against the reference.
    """

    t: np.ndarray
    not_a_rotation: dict[str, np.ndarray]
    energy_error: dict[str, np.ndarray]
    error: dict[str, np.ndarray]


def drift_study(
    moments: np.ndarray,
    omega: np.ndarray,
    h: float,
    steps: int,
    others: Mapping[str, Callable[[np.ndarray, np.ndarray, float], np.ndarray]] | None = None,
) -> DriftStudy:
    """Step a free body of principal ``moments`` ``(3,)`` [kg·m²], starting unturned with body
    angular velocity ``omega`` ``(3,)`` [rad/s], ``steps`` steps of ``h`` [s], the four ways
    of :data:`METHODS` and each of ``others``: ``step(q, L, h) -> q``, a quaternion stepped
    with the world angular momentum ``L`` held."""
    inverse = np.diag(1.0 / np.asarray(moments, dtype=np.float64))
    angular_momentum = np.asarray(moments, dtype=np.float64) * np.asarray(omega, dtype=np.float64)

    def spin(rotation: np.ndarray) -> np.ndarray:
        return rotation @ inverse @ rotation.T @ angular_momentum

    def energy(rotation: np.ndarray) -> float:
        return 0.5 * float(angular_momentum @ rotation @ inverse @ rotation.T @ angular_momentum)

    def quaternion_rate(q: np.ndarray) -> np.ndarray:
        w = spin(quaternion_matrix(q / np.linalg.norm(q)))
        return 0.5 * np.array([
            -w @ q[1:],
            q[0] * w[0] + w[1] * q[3] - w[2] * q[2],
            q[0] * w[1] + w[2] * q[1] - w[0] * q[3],
            q[0] * w[2] + w[0] * q[2] - w[1] * q[1],
        ])  # fmt: skip

    reference = _reference(quaternion_rate, h, steps)
    others = dict(others or {})
    matrices: dict[str, list[np.ndarray]] = {name: [np.eye(3)] for name in (*METHODS, *others)}
    rotations = {"matrix": np.eye(3), "matrix + Gram–Schmidt": np.eye(3)}
    quaternions = {name: np.array([1.0, 0.0, 0.0, 0.0]) for name in (*METHODS[2:], *others)}
    for _ in range(steps):
        for name, rotation in rotations.items():
            rotation = rotation + h * _cross_matrix(spin(rotation)) @ rotation
            if name.endswith("Gram–Schmidt"):
                rotation = _gram_schmidt(rotation)
            rotations[name] = rotation
            matrices[name].append(rotation)
        for name in ("quaternion", "quaternion + normalization"):
            q = quaternions[name] + h * quaternion_rate(quaternions[name])
            if name.endswith("normalization"):
                q = q / np.linalg.norm(q)
            quaternions[name] = q
            matrices[name].append(quaternion_matrix(q))
        for name, step in others.items():
            quaternions[name] = step(quaternions[name], angular_momentum, h)
            matrices[name].append(quaternion_matrix(quaternions[name]))
    start = energy(np.eye(3))

    def over_steps(measure: Callable[[np.ndarray], float]) -> dict[str, np.ndarray]:
        return {name: np.array([measure(r) for r in m]) for name, m in matrices.items()}

    return DriftStudy(
        t=h * np.arange(steps + 1),
        not_a_rotation=over_steps(lambda r: float(np.linalg.norm(r.T @ r - np.eye(3)))),
        energy_error=over_steps(lambda r: energy(r) / start - 1.0),
        error={
            name: np.linalg.norm(np.array(m) - np.array(reference), axis=(1, 2))
            for name, m in matrices.items()
        },
    )


def _cross_matrix(w: np.ndarray) -> np.ndarray:
    """``ω*``, the matrix of ``v ↦ ω × v``."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _gram_schmidt(matrix: np.ndarray) -> np.ndarray:
    """The columns of ``matrix`` made orthonormal, first to last (seed 003)."""
    a, b, _ = matrix.T
    x = a / np.linalg.norm(a)
    y = b - (x @ b) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def _reference(rate, h: float, steps: int) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    """RK4 at ``h/10``, normalized, sampled every ``h``: the orientation's matrix each step."""
    q, small = np.array([1.0, 0.0, 0.0, 0.0]), h / 10.0
    out = [np.eye(3)]
    for _ in range(steps):
        for _ in range(10):
            k1 = rate(q)
            k2 = rate(q + 0.5 * small * k1)
            k3 = rate(q + 0.5 * small * k2)
            k4 = rate(q + small * k3)
            q = q + small / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
            q = q / np.linalg.norm(q)
        out.append(quaternion_matrix(q))
    return out
