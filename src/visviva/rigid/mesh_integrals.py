"""Mass properties of a closed triangle mesh: Mirtich's polyhedral integrals.

B. Mirtich, "Fast and accurate computation of polyhedral mass properties", *Journal of Graphics
Tools* 1(2), 31–50, 1996, reduces the volume integrals of 1, x, x², xy, ... over a polyhedron to
integrals over its faces by the divergence theorem, ∫_V ∇·F dV = ∮_∂V F·n dA. We use the form of
D. Eberly, "Polyhedral Mass Properties (Revisited)", Geometric Tools, 2002, which derives from
Mirtich's for triangles: with F = (x, 0, 0) for ∫1, (x²/2, 0, 0) for ∫x, (x³/3, 0, 0) for ∫x²
and (x²y/2, 0, 0) for ∫xy (and likewise per axis), each face integral is a polynomial of
degree ≤ 3 over a triangle. Triangle t = (p₀, p₁, p₂) is p₀ + s(p₁ − p₀) + u(p₂ − p₀) for
s, u ≥ 0, s + u ≤ 1, so n dA = d ds du with d = (p₁ − p₀) × (p₂ − p₀), and the integrals of the
barycentric monomials over the unit triangle, ∫ λ₀ⁱ λ₁ʲ λ₂ᵏ = i! j! k!/(i + j + k + 2)!, give,
for a coordinate w with vertex values w₀, w₁, w₂:

    ∫ w = f₁/6,  ∫ w² = f₂/12,  ∫ w³ = f₃/20,  ∫ w² v = (v₀ g₀ + v₁ g₁ + v₂ g₂)/60,

where f₁, f₂, f₃ are the complete homogeneous symmetric polynomials of degree 1, 2, 3 in
(w₀, w₁, w₂) and gᵢ = f₂ + wᵢ (f₁ + wᵢ). Summing dₓ f₁ₓ/6 over the triangles gives the volume,
dₓ f₂ₓ/24 the first moment ∫x dV, dₓ f₃ₓ/60 the second moment ∫x² dV and dₓ Σ yᵢ gᵢₓ/120 the
product ∫xy dV. The result is exact for the polyhedron (to rounding): a mesh of a curved shape
gives the mass properties of the mesh, not of the shape it approximates.

Rounding: the integrals are taken about a reference point near the mesh (the centre of its
bounding box), not about the origin, so that a mesh 10⁶ m from the origin keeps the relative
precision of one at the origin; the second moments are then shifted to the centre of mass. The
triangles are summed in fixed chunks on every core and the chunks' sums added in order, so the
result does not depend on the number of threads.

Before integrating, the mesh is checked to bound a solid
(:func:`visviva.geometry.mesh_topology.check_closed_mesh`: closed, manifold, consistently
oriented, outward, no degenerate triangle) and, unless ``check_intersections=False``, not to
intersect itself (:func:`visviva.geometry.self_intersection.check_self_intersections`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, prange

from ..errors import ModelError
from ..geometry.mesh_topology import check_closed_mesh, mesh_arrays
from ..geometry.self_intersection import check_self_intersections
from .mass_properties import MassProperties
from .primitives import dimension

__all__ = ["mesh_mass_properties", "polyhedral_integrals"]

#: Triangles per chunk of the parallel sum: large enough to amortize a thread's start, small
#: enough that a 100k-triangle mesh splits over every core.
_CHUNK = 2048


@njit(cache=True, inline="always")
def _symmetric(w0: float, w1: float, w2: float) -> tuple[float, ...]:
    """f₁, f₂, f₃ (complete homogeneous symmetric polynomials) and g₀, g₁, g₂ of w₀, w₁, w₂."""
    s01 = w0 + w1
    f1 = s01 + w2
    w00 = w0 * w0
    h01 = w00 + w1 * s01  # w₀² + w₀w₁ + w₁²
    f2 = h01 + w2 * f1
    f3 = w0 * w00 + w1 * h01 + w2 * f2
    return f1, f2, f3, f2 + w0 * (f1 + w0), f2 + w1 * (f1 + w1), f2 + w2 * (f1 + w2)


@njit(cache=True, parallel=True)
def _integrals(vertices: np.ndarray, triangles: np.ndarray, origin: np.ndarray) -> np.ndarray:
    count = triangles.shape[0]
    chunks = (count + _CHUNK - 1) // _CHUNK
    partial = np.zeros((chunks, 10))
    ox, oy, oz = origin[0], origin[1], origin[2]
    for chunk in prange(chunks):
        one = sx = sy = sz = sxx = syy = szz = sxy = syz = szx = 0.0
        for t in range(chunk * _CHUNK, min(count, (chunk + 1) * _CHUNK)):
            i, j, k = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            x0, y0, z0 = vertices[i, 0] - ox, vertices[i, 1] - oy, vertices[i, 2] - oz
            x1, y1, z1 = vertices[j, 0] - ox, vertices[j, 1] - oy, vertices[j, 2] - oz
            x2, y2, z2 = vertices[k, 0] - ox, vertices[k, 1] - oy, vertices[k, 2] - oz
            ax, ay, az = x1 - x0, y1 - y0, z1 - z0
            bx, by, bz = x2 - x0, y2 - y0, z2 - z0
            dx = ay * bz - az * by
            dy = az * bx - ax * bz
            dz = ax * by - ay * bx
            f1x, f2x, f3x, g0x, g1x, g2x = _symmetric(x0, x1, x2)
            _, f2y, f3y, g0y, g1y, g2y = _symmetric(y0, y1, y2)
            _, f2z, f3z, g0z, g1z, g2z = _symmetric(z0, z1, z2)
            one += dx * f1x
            sx += dx * f2x
            sy += dy * f2y
            sz += dz * f2z
            sxx += dx * f3x
            syy += dy * f3y
            szz += dz * f3z
            sxy += dx * (y0 * g0x + y1 * g1x + y2 * g2x)
            syz += dy * (z0 * g0y + z1 * g1y + z2 * g2y)
            szx += dz * (x0 * g0z + x1 * g1z + x2 * g2z)
        partial[chunk, 0] = one
        partial[chunk, 1] = sx
        partial[chunk, 2] = sy
        partial[chunk, 3] = sz
        partial[chunk, 4] = sxx
        partial[chunk, 5] = syy
        partial[chunk, 6] = szz
        partial[chunk, 7] = sxy
        partial[chunk, 8] = syz
        partial[chunk, 9] = szx
    total = np.zeros(10)
    for chunk in range(chunks):  # in order: the same sum on any number of threads
        total += partial[chunk]
    return total


#: The face sums' factors: 1/6 for the volume, 1/24 for ∫x, 1/60 for ∫x², 1/120 for ∫xy.
_FACTORS = np.array([6.0, 24.0, 24.0, 24.0, 60.0, 60.0, 60.0, 120.0, 120.0, 120.0])


def polyhedral_integrals(
    vertices: np.ndarray, triangles: np.ndarray, origin: np.ndarray
) -> np.ndarray:
    """The volume integrals of a closed, outward mesh about ``origin`` (no checks).

    Args:
        vertices: ``(V, 3)`` float64 vertex positions [m], C-contiguous.
        triangles: ``(T, 3)`` int64 vertex indices, valid, counter-clockwise seen from outside.
        origin: ``(3,)`` the point the coordinates x, y, z are measured from [m].

    Returns:
        ``(10,)``: ∫1, ∫x, ∫y, ∫z, ∫x², ∫y², ∫z², ∫xy, ∫yz, ∫zx over the enclosed volume
        [m³, m⁴, m⁵].
    """
    return _integrals(vertices, triangles, np.asarray(origin, dtype=np.float64)) / _FACTORS


def _from_integrals(integrals: np.ndarray, origin: np.ndarray, density: float) -> MassProperties:
    volume = float(integrals[0])
    if not volume > 0.0:
        raise ModelError(
            f"`triangles` enclose no positive volume ({volume:.3g} m³): they must be "
            "counter-clockwise seen from outside and close the mesh"
        )
    d = integrals[1:4] / volume  # centre of mass from the origin
    second = np.array(
        [
            [integrals[4], integrals[7], integrals[9]],
            [integrals[7], integrals[5], integrals[8]],
            [integrals[9], integrals[8], integrals[6]],
        ]
    )
    central = second - volume * np.outer(d, d)  # ∫ r rᵀ dV, r from the centre of mass
    inertia = density * (np.trace(central) * np.eye(3) - central)
    return MassProperties(density * volume, origin + d, inertia, volume)


def mesh_mass_properties(
    vertices: Any,
    triangles: Any,
    density: Any,
    *,
    check_topology: bool = True,
    check_intersections: bool = True,
) -> MassProperties:
    """Mass properties of the solid a closed triangle mesh bounds, of uniform ``density``.

    Args:
        vertices: ``(V, 3)`` vertex positions [m].
        triangles: ``(T, 3)`` integer vertex indices, counter-clockwise seen from outside.
        density: Uniform density [kg/m³], positive.
        check_topology: Check that the mesh bounds a solid (closed, manifold, consistently
            oriented, outward, no degenerate triangle); about twice the integration's time on a
            large mesh. Turn it off only for a mesh already checked: an open mesh's integrals
            are meaningless.
        check_intersections: Also refuse a mesh whose triangles cross each other (the overlap
            would count twice); costs a few times the integration itself (see
            :mod:`visviva.geometry.self_intersection`).

    Returns:
        The mass, centre of mass (in the mesh's coordinates), inertia about the centre of mass
        (in the mesh's axes) and volume of the polyhedron.

    Raises:
        ModelError: A bad array, density or mesh, naming the field and the first offending
            triangle or edge.

    >>> import numpy as np
    >>> corners = np.array([[x, y, z] for x in (0, 2) for y in (0, 1) for z in (0, 1)], float)
    >>> faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
    ...          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    >>> box = mesh_mass_properties(corners, faces, density=1000.0)
    >>> box.mass, box.center_of_mass.tolist()
    (2000.0, [1.0, 0.5, 0.5])
    """
    rho = dimension("mesh", "density", density, "kg/m³")
    edges = None
    if check_topology:
        vertices, triangles, edges = check_closed_mesh(vertices, triangles)
    else:
        vertices, triangles = mesh_arrays(vertices, triangles)
    if check_intersections:
        check_self_intersections(vertices, triangles, edges)
    origin = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    return _from_integrals(polyhedral_integrals(vertices, triangles, origin), origin, rho)
