"""Mass properties estimated by Monte Carlo: uniform points in the shape's bounding box.

With N points pᵢ uniform in a box B of volume |B| containing the shape, χᵢ = 1 when pᵢ is inside
the shape (its implicit inequality for a primitive, ray parity for a mesh:
:class:`visviva.geometry.point_in_mesh.InsideTest`) and 0 otherwise, and the coordinates taken
from the box's centre c₀ (so that the sums hold no large constant), each integral ∫ f dV over the
shape is estimated by |B| · mean(χ f):

    V ≈ |B| ū₀,   x_cm ≈ c₀ + ū₁/ū₀,   ∫ r rᵀ dV ≈ |B| (Ū₂ − ū₁ ū₁ᵀ/ū₀),

where uᵢ = χᵢ (1, p, p pᵀ) are the ten sampled values and ū their means. The one-sigma standard
errors come from the sample covariance Σ of u by the delta method, σ² = gᵀ Σ g / N for each
estimate's gradient g with respect to ū: for the centre of mass the influence of one sample
is χ (p − d)/ū₀ and for the central second moments χ (p − d)(p − d)ᵀ, d the estimated centre.
The error falls as 1/√N, the Monte-Carlo rate, whatever the dimension; a box sampled in its own
bounding box has χ ≡ 1 and a volume with no error at all. The covariance is accumulated batch by
batch with the pairwise update of T. F. Chan, G. H. Golub and R. J. LeVeque, "Algorithms for
computing the sample variance", *The American Statistician* 37(3), 1983.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import describe, whole_number, with_article
from ..errors import ModelError
from ..geometry.mesh_topology import check_closed_mesh
from ..geometry.point_in_mesh import InsideTest
from ..geometry.self_intersection import check_self_intersections
from .mass_properties import MassProperties
from .primitives import dimension, dimensions3
from .shapes import shape_dimensions

__all__ = ["MAX_SAMPLES", "SampledMassProperties", "sampled_mass_properties"]

#: Points drawn and tested at a time: bounds the memory (about 150 bytes a point).
_BATCH = 1 << 16
#: Fewest points inside the shape for a standard error to mean anything.
_MIN_INSIDE = 10
#: Most points drawn in one call: about ten minutes on one core, an error of 3e-5 of the mass.
MAX_SAMPLES = 10**9


@dataclass(frozen=True, eq=False)
class SampledMassProperties:
    """A Monte-Carlo estimate of mass properties, each with its one-sigma standard error.

    Attributes:
        mass: Estimated mass [kg]; ``mass_error`` its standard error [kg].
        center_of_mass: Estimated centre of mass ``(3,)`` [m]; ``center_of_mass_error`` the
            standard error of each coordinate [m].
        inertia: Estimated inertia ``(3, 3)`` [kg·m²] about the estimated centre of mass, in the
            shape's axes; ``inertia_error`` the standard error of each entry [kg·m²].
        volume: Estimated volume [m³]; ``volume_error`` its standard error [m³].
        samples: Points drawn; ``inside`` how many fell inside the shape.
    """

    mass: float
    mass_error: float
    center_of_mass: np.ndarray
    center_of_mass_error: np.ndarray
    inertia: np.ndarray
    inertia_error: np.ndarray
    volume: float
    volume_error: float
    samples: int
    inside: int

    def properties(self) -> MassProperties:
        """The estimate as checked :class:`~visviva.rigid.MassProperties` (a ModelError if the
        estimate is too rough to be a body's, e.g. from too few samples)."""
        return MassProperties(self.mass, self.center_of_mass, self.inertia, self.volume)


Region = tuple[np.ndarray, np.ndarray, Callable[[np.ndarray], np.ndarray]]


def _region(shape: str, dims: dict[str, Any], check_intersections: bool) -> Region:
    """The shape's bounding box (low, high corners [m]) and its inside test."""
    if shape in ("box", "ellipsoid"):
        meaning = "full edge lengths" if shape == "box" else "semi-axes"
        size = dimensions3(shape, "size", dims["size"], meaning)
        half = 0.5 * size if shape == "box" else size
        if shape == "box":
            return -half, half, lambda p: np.all(np.abs(p) <= half, axis=1)
        return -half, half, lambda p: np.sum((p / half) ** 2, axis=1) <= 1.0
    if shape == "sphere":
        r = dimension(shape, "radius", dims["radius"], "m")
        return np.full(3, -r), np.full(3, r), lambda p: np.sum(p * p, axis=1) <= r * r
    if shape in ("cylinder", "capsule", "cone"):
        r = dimension(shape, "radius", dims["radius"], "m")
        h = dimension(shape, "height", dims["height"], "m", zero=shape == "capsule")
        if shape == "cylinder":
            return (
                np.array([-r, -0.5 * h, -r]),
                np.array([r, 0.5 * h, r]),
                lambda p: (p[:, 0] ** 2 + p[:, 2] ** 2 <= r * r) & (np.abs(p[:, 1]) <= 0.5 * h),
            )
        if shape == "capsule":

            def capsule(p: np.ndarray) -> np.ndarray:
                axial = np.clip(p[:, 1], -0.5 * h, 0.5 * h)  # nearest point of the axis segment
                return p[:, 0] ** 2 + (p[:, 1] - axial) ** 2 + p[:, 2] ** 2 <= r * r

            return np.array([-r, -0.5 * h - r, -r]), np.array([r, 0.5 * h + r, r]), capsule

        def cone(p: np.ndarray) -> np.ndarray:
            radius = r * (1.0 - p[:, 1] / h)
            inside = (p[:, 1] >= 0.0) & (p[:, 1] <= h)
            return inside & (p[:, 0] ** 2 + p[:, 2] ** 2 <= radius * radius)

        return np.array([-r, 0.0, -r]), np.array([r, h, r]), cone
    vertices, triangles = dims["vertices"], dims["triangles"]
    vertices, triangles, edges = check_closed_mesh(vertices, triangles)
    if check_intersections:
        check_self_intersections(vertices, triangles, edges)
    test = InsideTest.of(vertices, triangles)
    return vertices.min(axis=0), vertices.max(axis=0), test.contains


def _values(inside: np.ndarray, p: np.ndarray) -> np.ndarray:
    """uᵢ = χᵢ (1, x, y, z, x², y², z², xy, yz, zx): ``(n, 10)``."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    columns = (np.ones_like(x), x, y, z, x * x, y * y, z * z, x * y, y * z, z * x)
    return np.stack(columns, axis=1) * inside[:, None]


def _generator(rng: Any) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or (isinstance(rng, (int, np.integer)) and not isinstance(rng, bool)):
        try:
            return np.random.default_rng(rng)
        except ValueError as exc:
            raise ModelError(f"`rng` seed must be a non-negative integer (got {rng!r})") from exc
    raise ModelError(
        f"`rng` must be a numpy.random.Generator, an integer seed or None (got {describe(rng)})"
    )


def sampled_mass_properties(
    shape: str,
    density: float,
    *,
    samples: int = 100_000,
    rng: np.random.Generator | int | None = None,
    size: Any = None,
    radius: Any = None,
    height: Any = None,
    vertices: Any = None,
    triangles: Any = None,
    check_intersections: bool = True,
) -> SampledMassProperties:
    """Monte-Carlo mass properties of a shape of uniform ``density`` [kg/m³], with error bars.

    The shape and its dimensions are given as to :func:`~visviva.rigid.mass_properties`; the
    conventions (axes, where each shape sits) are the same, so the estimate and the closed form
    differ by the sampling error alone.

    Args:
        shape: ``"box"``, ``"sphere"``, ``"cylinder"``, ``"capsule"``, ``"cone"``,
            ``"ellipsoid"`` or ``"mesh"``.
        density: Uniform density [kg/m³], positive.
        samples: Points drawn uniformly in the shape's bounding box (at least 100, at most
            :data:`MAX_SAMPLES`).
        rng: The random generator (a seeded ``numpy.random.default_rng(seed)`` makes the result
            reproducible), or an integer seed; ``None`` draws fresh entropy.
        size, radius, height, vertices, triangles, check_intersections: As for
            :func:`~visviva.rigid.mass_properties`.

    Returns:
        The estimates with their one-sigma standard errors (see the module docstring).

    >>> estimate = sampled_mass_properties("sphere", 1000.0, radius=1.0, samples=40_000, rng=1)
    >>> bool(abs(estimate.mass - 4188.79) < 3 * estimate.mass_error)
    True
    """
    given = {
        "size": size,
        "radius": radius,
        "height": height,
        "vertices": vertices,
        "triangles": triangles,
    }
    dims = shape_dimensions(shape, given).values
    rho = dimension(shape, "density", density, "kg/m³")
    count = whole_number("samples", samples, minimum=100)
    if count > MAX_SAMPLES:
        raise ModelError(
            f"`samples` must be at most {MAX_SAMPLES:.0e} (got {count}); the error falls only as "
            "1/√N, so the exact mesh_mass_properties or the closed forms serve better"
        )
    generator = _generator(rng)
    low, high, contains = _region(shape, dims, check_intersections)
    with np.errstate(over="ignore"):  # a box beyond float64 is refused just below
        center = 0.5 * (low + high)
        half = 0.5 * (high - low)
        extent = high - low
        box_volume = float(np.prod(extent))
    if not (math.isfinite(box_volume) and box_volume > 0.0):
        raise ModelError(
            f"the {shape}'s bounding box {describe(extent)} m has volume {box_volume:.3g} "
            "m³, beyond what float64 holds; express its dimensions in other units"
        )

    mean = np.zeros(10)
    scatter = np.zeros((10, 10))  # Σ (u − ū)(u − ū)ᵀ
    drawn = 0
    inside_count = 0
    while drawn < count:
        n = min(_BATCH, count - drawn)
        p = generator.uniform(-1.0, 1.0, size=(n, 3)) * half  # from the box's centre
        inside = contains(p + center)
        inside_count += int(inside.sum())
        u = _values(inside, p)
        batch_mean = u.mean(axis=0)
        deviation = u - batch_mean
        delta = batch_mean - mean
        total = drawn + n
        mean += delta * (n / total)
        scatter += deviation.T @ deviation + np.outer(delta, delta) * (drawn * n / total)
        drawn = total
    if inside_count < _MIN_INSIDE:
        raise ModelError(
            f"only {inside_count} of {count} `samples` fell inside the {shape} (at least "
            f"{_MIN_INSIDE} are needed); draw more samples"
        )
    result = _estimate(mean, scatter / (count - 1), count, inside_count, center, box_volume, rho)
    figures = np.concatenate([[result.mass, result.mass_error], result.inertia.ravel()])
    if not np.isfinite(figures).all():
        raise ModelError(
            f"{with_article(shape)} of `density` {rho!r} kg/m³ and volume about "
            f"{result.volume:.3g} m³ has "
            "a mass or inertia beyond what float64 holds; express its dimensions and density "
            "in other units"
        )
    return result


def _estimate(
    mean: np.ndarray,
    covariance: np.ndarray,
    count: int,
    inside: int,
    center: np.ndarray,
    box_volume: float,
    density: float,
) -> SampledMassProperties:
    """The estimates and their delta-method standard errors from the means of u and Σ."""
    fill = mean[0]
    d = mean[1:4] / fill  # centre of mass from the box's centre
    pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0))  # the order of u[4:10]
    second = np.empty((3, 3))
    for column, (j, k) in enumerate(pairs):
        second[j, k] = second[k, j] = mean[4 + column]
    central = second - fill * np.outer(d, d)  # ∫ r rᵀ dV / |B|, r from the centre of mass

    # Gradients g (rows, with respect to ū) of each estimate, for σ² = gᵀ Σ g / N.
    com_rows = np.zeros((3, 10))
    com_rows[:, 0] = -d / fill
    com_rows[:, 1:4] = np.eye(3) / fill
    central_rows = np.zeros((3, 3, 10))  # of C_jk = S_jk − b_j b_k / ū₀
    for column, (j, k) in enumerate(pairs):
        central_rows[j, k, 4 + column] = central_rows[k, j, 4 + column] = 1.0
    for j in range(3):
        for k in range(3):
            central_rows[j, k, 0] += d[j] * d[k]
            central_rows[j, k, 1 + j] -= d[k]
            central_rows[j, k, 1 + k] -= d[j]
    trace_row = central_rows[0, 0] + central_rows[1, 1] + central_rows[2, 2]
    inertia_rows = trace_row[None, None, :] * np.eye(3)[:, :, None] - central_rows

    def error(rows: np.ndarray) -> np.ndarray:
        variance = np.einsum("...i,ij,...j->...", rows, covariance, rows)
        return np.sqrt(np.maximum(variance, 0.0) / count)

    scale = density * box_volume
    volume_error = box_volume * math.sqrt(max(covariance[0, 0], 0.0) / count)
    return SampledMassProperties(
        mass=scale * fill,
        mass_error=density * volume_error,
        center_of_mass=center + d,
        center_of_mass_error=error(com_rows),
        inertia=scale * (np.trace(central) * np.eye(3) - central),
        inertia_error=scale * error(inertia_rows),
        volume=box_volume * fill,
        volume_error=volume_error,
        samples=count,
        inside=inside,
    )
