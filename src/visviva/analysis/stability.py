"""Linear stability: regions, intervals and the largest stable time step.

Apply a one-step method to the test equation ``y' = λy`` and every step multiplies ``y`` by
``R(z)``, ``z = hλ`` (seeds 000 and 004). The method is stable where ``|R(z)| ≤ 1``. A larger
system ``y' = Ay`` (or the linearization ``A = ∂f/∂y`` of a nonlinear one) is stable when
``hλ`` is in the region for every eigenvalue ``λ`` of ``A``, which gives the largest stable step
for the most restrictive mode (seed 000, "Matrix eigenvalues").

Numerically "stable" means ``|R(z)| ≤ 1 + STABILITY_TOLERANCE``. Methods whose ``|R(iy)|``
exceeds 1 only by ``O(y⁴)`` (midpoint, Heun) therefore show an imaginary-axis interval of a few
``1e-4`` rather than the exact ``{0}``: steps that small amplify by less than ``1e-14`` per step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import describe
from ..errors import ModelError
from ..integrators import Integrator, get

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.system import System

__all__ = [
    "max_stable_dt",
    "spectrum",
    "stability_function",
    "stability_interval",
    "stability_region",
    "state_jacobian",
]

#: |R| may exceed 1 by this much and still count as stable (round-off in R itself).
STABILITY_TOLERANCE = 1e-14
#: Largest |z| searched along a ray; beyond it a method counts as unconditionally stable.
RAY_LIMIT = 1e6
#: Systems up to this size get all their eigenvalues (dense); larger ones the extreme few.
DENSE_EIGEN_LIMIT = 1500
#: Eigenvalues requested from the sparse (Arnoldi) solver for large systems, and their
#: relative accuracy: an advisor needs a few digits, and clustered spectra (a long chain of
#: springs) converge slowly to full precision.
SPARSE_EIGEN_COUNT = 8
SPARSE_EIGEN_TOLERANCE = 1e-4


def stability_function(method: str | Integrator, z: Any) -> np.ndarray:
    """``R(z)`` of a method at complex points ``z`` (any shape)."""
    return get(method).stability_function(z)


def _ray_exit(method: Integrator, directions: np.ndarray) -> np.ndarray:
    """For each unit complex ``direction``, the largest ``r`` with ``|R(s·d)| ≤ 1`` on ``(0, r]``.

    Samples ``s`` geometrically from 1e-6 to :data:`RAY_LIMIT`, then bisects the first crossing.
    Returns ``inf`` where no sample is unstable and ``0`` where the first one already is.
    """
    directions = np.asarray(directions, dtype=np.complex128).ravel()
    samples = np.geomspace(1e-6, RAY_LIMIT, 3001)
    modulus = np.abs(method.stability_function(samples[None, :] * directions[:, None]))
    unstable = modulus > 1.0 + STABILITY_TOLERANCE
    exits = np.full(directions.size, np.inf)
    crossing = unstable.any(axis=1)
    first = np.argmax(unstable, axis=1)
    exits[crossing & (first == 0)] = 0.0
    refine = np.flatnonzero(crossing & (first > 0))
    if refine.size:
        low = samples[first[refine] - 1]
        high = samples[first[refine]]
        d = directions[refine]
        for _ in range(60):
            middle = 0.5 * (low + high)
            bad = np.abs(method.stability_function(middle * d)) > 1.0 + STABILITY_TOLERANCE
            high = np.where(bad, middle, high)
            low = np.where(bad, low, middle)
        # The tolerance lets the bisection end up to ~1e-14 beyond the true boundary; report
        # 12 significant digits so that, e.g., explicit Euler's limit reads 2, not 2.00000000000001.
        exits[refine] = [float(f"{r:.12g}") for r in low]
    return exits


def stability_interval(method: str | Integrator, axis: str = "real") -> tuple[float, float]:
    """The interval of the real or imaginary axis around 0 where ``|R(z)| ≤ 1``.

    Args:
        method: Method name or instance.
        axis: ``"real"`` (``z = x``, decaying modes) or ``"imaginary"`` (``z = iy``, undamped
            oscillations).

    Returns:
        ``(lower, upper)`` in units of ``z`` (``−inf``/``inf`` if unbounded). On the imaginary
        axis the values are ``y`` of ``z = iy``. Examples: explicit Euler ``(-2, 0)`` and
        ``(0, 0)``; RK4 ``(-2.785, 0)`` and ``(-2.828, 2.828)``; backward Euler ``(-inf, 0)``
        (it is also stable for ``x > 2``, which is not connected to 0).
    """
    integrator = get(method)
    if axis == "real":
        negative, positive = _ray_exit(integrator, np.array([-1.0, 1.0]))
    elif axis == "imaginary":
        negative, positive = _ray_exit(integrator, np.array([-1j, 1j]))
    else:
        raise ModelError(f"`axis` must be 'real' or 'imaginary' (got {axis!r})")
    return -float(negative), float(positive)


def stability_region(
    method: str | Integrator,
    bounds: tuple[float, float, float, float] = (-5.0, 3.0, -4.0, 4.0),
    resolution: int = 401,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``|R(z)|`` on a grid, for plotting the region ``|R| ≤ 1``.

    Args:
        method: Method name or instance.
        bounds: ``(re_min, re_max, im_min, im_max)`` of the window in the ``z`` plane.
        resolution: Grid points per axis.

    Returns:
        ``(re, im, modulus)``: the real and imaginary coordinates ``(resolution,)`` and
        ``|R(re + i·im)|`` of shape ``(resolution, resolution)`` (rows follow ``im``).
    """
    re = np.linspace(bounds[0], bounds[1], resolution)
    im = np.linspace(bounds[2], bounds[3], resolution)
    z = re[None, :] + 1j * im[:, None]
    return re, im, np.abs(get(method).stability_function(z))


def spectrum(jacobian: Any, *, count: int = SPARSE_EIGEN_COUNT) -> np.ndarray:
    """Eigenvalues of a Jacobian: all of them for a small matrix, the extreme few for a large one.

    Args:
        jacobian: ``(m, m)`` dense array, ``scipy.sparse`` matrix or
            ``scipy.sparse.linalg.LinearOperator``.
        count: How many largest-magnitude eigenvalues to compute when the matrix is large
            (ARPACK's implicitly restarted Arnoldi iteration, to a relative accuracy of
            :data:`SPARSE_EIGEN_TOLERANCE`).

    Returns:
        Complex eigenvalues, shape ``(k,)``.
    """
    import scipy.sparse as sp

    m = jacobian.shape[0]
    dense = isinstance(jacobian, np.ndarray)
    if m <= DENSE_EIGEN_LIMIT:
        matrix = jacobian if dense else _to_dense(jacobian)
        return np.linalg.eigvals(matrix).astype(np.complex128)
    from scipy.sparse.linalg import eigs

    operator = sp.csr_matrix(jacobian) if dense else jacobian
    # A fixed start vector: ARPACK's default is random, and the same Jacobian should give the
    # same advice (to the last digit) on every call.
    start = np.random.default_rng(0).standard_normal(m)
    return eigs(
        operator,
        k=min(count, m - 2),
        which="LM",
        v0=start,
        tol=SPARSE_EIGEN_TOLERANCE,
        return_eigenvectors=False,
    )


def _to_dense(matrix: Any) -> np.ndarray:
    if hasattr(matrix, "toarray"):
        return np.asarray(matrix.toarray())
    return np.asarray(matrix @ np.eye(matrix.shape[1]))


def max_stable_dt(
    method: str | Integrator,
    *,
    eigenvalues: Any = None,
    jacobian: Any = None,
) -> float:
    """The largest ``dt`` for which ``dt·λ`` is in the method's stability region for every mode.

    Modes with ``Re λ > 0`` grow in the exact solution too, so they impose no limit here (and
    zero modes, such as free translation, none at all); eigenvalues with a negligible real part
    (``|Re λ| ≤ 1e-9 |λ|``) count as purely oscillatory. Give the eigenvalues, or a Jacobian
    whose eigenvalues are computed (see :func:`spectrum`).

    Args:
        method: Method name or instance.
        eigenvalues: Eigenvalues ``λ`` [1/s] of the linearized system.
        jacobian: Alternatively the Jacobian ``∂f/∂y`` (``(m, m)`` dense or sparse); for a
            second-order problem use :func:`state_jacobian` to get the first-order one.

    Returns:
        The step [s]; ``inf`` if every mode is stable for any step, ``0`` if none is stable
        (explicit Euler on an undamped oscillation).

    Example:
        >>> import visviva as vv
        >>> round(vv.analysis.max_stable_dt("explicit_euler", eigenvalues=[-100.0]), 6)
        0.02
    """
    integrator = get(method)
    if (eigenvalues is None) == (jacobian is None):
        raise ModelError("pass exactly one of `eigenvalues` and `jacobian`")
    if eigenvalues is not None:
        try:
            lam = np.asarray(eigenvalues, dtype=np.complex128).ravel()
        except (TypeError, ValueError):
            raise ModelError(
                f"`eigenvalues` must be numbers (got {describe(eigenvalues)})"
            ) from None
        if not np.isfinite(lam).all():
            i = int(np.argmax(~np.isfinite(lam)))
            raise ModelError(f"`eigenvalues` must be finite; entry {i} is {describe(lam[i])}")
    else:
        lam = spectrum(_checked_jacobian(jacobian))
    size = np.abs(lam)
    if size.size == 0 or size.max() == 0.0:
        return float("inf")
    keep = size > 1e-12 * size.max()
    lam, size = lam[keep], size[keep]
    real = np.where(np.abs(lam.real) <= 1e-9 * size, 0.0, lam.real)
    decaying_or_oscillating = real <= 0.0
    if not decaying_or_oscillating.any():
        return float("inf")
    lam = (real + 1j * lam.imag)[decaying_or_oscillating]
    size = size[decaying_or_oscillating]
    directions = np.round(lam / size, 12)
    unique, inverse = np.unique(directions, return_inverse=True)
    exits = _ray_exit(integrator, unique)[inverse]
    return float(np.min(exits / size))


def _checked_jacobian(jacobian: Any) -> Any:
    """The Jacobian if it is a finite square matrix (dense, sparse or operator)."""
    import scipy.sparse as sp

    shape: Any = getattr(jacobian, "shape", None)
    if shape is None and not sp.issparse(jacobian):
        try:
            jacobian = np.asarray(jacobian, dtype=np.complex128)
        except (TypeError, ValueError):
            raise ModelError(f"`jacobian` must be a matrix (got {describe(jacobian)})") from None
        shape = jacobian.shape
    if len(shape) != 2 or shape[0] != shape[1] or shape[0] == 0:
        raise ModelError(f"`jacobian` must be a square (m, m) matrix (got shape {tuple(shape)})")
    values = (
        jacobian.data
        if sp.issparse(jacobian)
        else (jacobian if isinstance(jacobian, np.ndarray) else None)
    )
    if values is not None and not np.isfinite(values).all():
        raise ModelError("`jacobian` must be finite (it holds nan or inf)")
    return jacobian


def state_jacobian(system: System, state: State) -> Any:
    """The first-order Jacobian ``∂(dy/dt)/∂y`` of a system at a state.

    For a second-order system with ``y = [q, v]`` it is ``[[0, I], [M⁻¹∂F/∂q, M⁻¹∂F/∂v]]``.
    Batched states give ``(batch, m, m)``; sparse Jacobians stay sparse.
    """
    import scipy.sparse as sp

    if not system.second_order:
        return system.jacobian(state.t, state.parts[0])  # type: ignore[union-attr]
    q, v = state.parts
    if q.shape != v.shape:
        # Rigid bodies: orientations as quaternions (4 numbers) against 3 angular velocities.
        raise ModelError(
            "the stability advisor linearizes q'' = F(q, v) with as many coordinates as "
            f"velocities; this system has {q.shape[-1]} and {v.shape[-1]} (rigid bodies)"
        )
    stiffness, damping = system.force_jacobian(state.t, q, v)  # type: ignore[union-attr]
    mass = system.mass  # type: ignore[union-attr]
    n = q.shape[-1]
    if damping is None:
        damping = sp.csc_matrix((n, n)) if sp.issparse(stiffness) else np.zeros_like(stiffness)
    stiffness = _inverse_mass_times(mass, stiffness, q.shape)
    damping = _inverse_mass_times(mass, damping, q.shape)
    if sp.issparse(stiffness):
        return sp.bmat([[None, sp.identity(n)], [stiffness, damping]], format="csr")
    batch = q.shape[:-1]
    top = np.concatenate(
        [np.zeros(batch + (n, n)), np.broadcast_to(np.eye(n), batch + (n, n))], axis=-1
    )
    return np.concatenate([top, np.concatenate([stiffness, damping], axis=-1)], axis=-2)


def _inverse_mass_times(mass: Any, matrix: Any, q_shape: tuple[int, ...]) -> Any:
    """``M⁻¹ matrix`` for a dense ``(…, n, n)`` or sparse ``(n, n)`` matrix."""
    import scipy.sparse as sp

    if mass is None:
        return matrix
    if sp.issparse(matrix):
        if mass.kind == "diagonal":
            inverse = 1.0 / np.broadcast_to(mass.values, q_shape)
            return sp.diags(inverse) @ matrix
        return sp.csc_matrix(mass.solve(matrix.toarray()))
    if mass.kind == "diagonal":
        return matrix / np.broadcast_to(mass.values, q_shape)[..., :, None]
    return np.linalg.solve(mass.dense(q_shape), matrix)
