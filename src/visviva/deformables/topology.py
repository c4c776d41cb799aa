"""Spring topologies: where the particles of a deformable are, what they weigh, and which pairs
springs join.

* A **rope** (seed 002) joins consecutive points with stretch springs and, if asked, points two
  apart with bending springs (which, seed 000 warns, also resist stretch).
* A **hair** strand (Selle, Lentine & Fedkiw 2008) joins consecutive points with edge
  (stretch) springs, points two apart with bending springs and points three apart with torsion
  springs, each family with its own stiffness. Selle et al. also tie each run of four
  consecutive points (a tetrahedron) with *altitude* springs (and add ghost particles where a
  strand is straight), so that the tetrahedron cannot collapse flat or invert; those are left
  out here: a strand's bending and torsion springs resist bending and twisting only while the
  strand is curved, and a straight stretch of strand may fold with little resistance.
* A **spring graph** is any topology: particles at given points and a spring on each given
  pair of them, with stiffness (and, if given, rest length) one value or one per spring.
* A **cloth grid** (Choi & Ko 2002; seed 001) of ``nu × nv`` points joins grid neighbours with
  *structural* springs (stretch), the diagonals of each cell with *shear* springs, and points
  two apart along the grid with *bend* springs; each family has its own stiffness. A point's
  mass is the areal density times its share of the cells around it (a quarter of each), so
  the sheet weighs density × area.
* A **soft lattice** (seed 004's volumetric soft body) of ``nx × ny × nz`` points joins lattice
  neighbours with structural springs, the diagonals of each cell's faces with shear springs and
  the diagonals through each cell with *diagonal* springs, which keep a cube from collapsing
  flat; a point weighs the density times an eighth of each cell around it.

Every spring rests at the distance of its points as built — a network starts unstressed —
unless a spring graph is given rest lengths. Triangle and tetrahedral meshes are in
:mod:`.meshes`; the triangles that draw a sheet's or a soft body's surface, in :mod:`.surfaces`.

References:
    K.-J. Choi, H.-S. Ko, "Stable but responsive cloth", SIGGRAPH 2002.
    A. Selle, M. Lentine, R. Fedkiw, "A mass spring model for hair simulation", SIGGRAPH 2008.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ModelError
from .surfaces import box_triangles, grid_triangles, no_triangles

__all__ = [
    "BEND",
    "DIAGONAL",
    "SHEAR",
    "STRETCH",
    "TORSION",
    "DeformableError",
    "SpringNetwork",
    "cloth_grid",
    "hair",
    "rope",
    "soft_lattice",
    "spring_graph",
]

#: Spring families (the codes of :attr:`SpringNetwork.family`).
STRETCH, SHEAR, BEND, DIAGONAL, TORSION = 0, 1, 2, 3, 4


class DeformableError(ModelError):
    """A body refused for its points, springs or cells, naming the argument at fault and the
    item in it, so that a scene can point at the entry to fix (``entities[2].triangles[7]``).

    Attributes:
        field: The argument (and scene key) at fault: ``"pairs"``, ``"triangles"``, ...
        index: The item of ``field`` at fault, or ``None`` for the argument as a whole.
    """

    def __init__(self, message: str, field: str, index: int | None = None) -> None:
        super().__init__(message)
        self.field = field
        self.index = index


@dataclass(frozen=True)
class SpringNetwork:
    """Particles, the springs between them, and the surface that draws them.

    Attributes:
        points: ``(n, 3)`` positions [m].
        mass: ``(n,)`` masses [kg].
        pairs: ``(S, 2)`` indices of each spring's particles.
        stiffness: ``(S,)`` k [N/m].
        family: ``(S,)`` :data:`STRETCH`, :data:`SHEAR`, :data:`BEND`, :data:`DIAGONAL` or
            :data:`TORSION`.
        given_rest_length: ``(S,)`` rest lengths [m] chosen for the springs, or ``None``: each
            spring rests at its length as built.
        faces: ``(F, 3)`` int64 indices of the particles of each triangle of the body's
            surface, counter-clockwise seen from outside (a soft body) or from the front (a
            cloth); ``(0, 3)`` for ropes, hair and spring graphs. Drawn only: no force acts on
            them (see :mod:`.surfaces`).
        lattice: The lattice's sizes, fastest first, if the points are one and point
            ``(i, j[, k])`` is ``(k n1 + j) n0 + i`` (a cloth grid's ``(nu, nv)``, a soft
            lattice's ``(nx, ny, nz)``); ``None`` otherwise. Springs on a lattice are summed
            by a stencil (:mod:`visviva.forces.lattice_springs`).
    """

    points: np.ndarray
    mass: np.ndarray
    pairs: np.ndarray
    stiffness: np.ndarray
    family: np.ndarray
    given_rest_length: np.ndarray | None = None
    faces: np.ndarray = field(default_factory=no_triangles)
    lattice: tuple[int, ...] | None = None

    def rest_length(self) -> np.ndarray:
        """``(S,)`` each spring's rest length [m]: the given one, or its length as built.

        Raises:
            ModelError: Naming the first two points a spring joins that coincide (its
                direction would be undefined) or are too far apart for a float.
        """
        with np.errstate(over="ignore", invalid="ignore"):
            length = np.linalg.norm(
                self.points[self.pairs[:, 1]] - self.points[self.pairs[:, 0]], axis=1
            )
        good = np.isfinite(length) & (length > 0.0)
        if not good.all():
            s = int(np.argmin(good))
            a, b = self.pairs[s]
            if length[s] == 0.0:
                raise ModelError(
                    f"points {a} and {b} coincide: the spring between them (spring {s}) needs "
                    "a length > 0 to have a direction; move one of them"
                )
            raise ModelError(
                f"the spring between points {a} and {b} would be {length[s]!r} m long, "
                "beyond what a float holds: make the body smaller"
            )
        return length if self.given_rest_length is None else self.given_rest_length


def _overflow_judged_later(build: Callable[..., SpringNetwork]) -> Callable[..., SpringNetwork]:
    """Build without NumPy's overflow warnings: a body too large for a float is refused, with
    its entity named, by :func:`_network` and :meth:`SpringNetwork.rest_length`."""

    @functools.wraps(build)
    def quietly(*args: Any) -> SpringNetwork:
        with np.errstate(over="ignore", invalid="ignore"):
            return build(*args)

    return quietly


def rope(points: np.ndarray, mass: np.ndarray, stiffness: float, bending: float) -> SpringNetwork:
    """A rope through ``points`` ``(n, 3)`` [m] with masses ``mass`` ``(n,)`` [kg]: stretch
    springs of ``stiffness`` [N/m] between consecutive points, bending springs of ``bending``
    [N/m] between points two apart (none if 0)."""
    return _strand(points, mass, [(stiffness, STRETCH), (bending, BEND)])


def hair(
    points: np.ndarray, mass: np.ndarray, stiffness: float, bending: float, torsion: float
) -> SpringNetwork:
    """A hair strand through ``points`` ``(n, 3)`` [m], root first, with masses ``mass``
    ``(n,)`` [kg] (Selle et al. 2008, without their altitude springs: see the module
    docstring): edge springs of ``stiffness`` [N/m] between consecutive points, bending springs
    of ``bending`` [N/m] between points two apart and torsion springs of ``torsion`` [N/m]
    between points three apart (a family of stiffness 0 is left out)."""
    return _strand(points, mass, [(stiffness, STRETCH), (bending, BEND), (torsion, TORSION)])


def _strand(
    points: np.ndarray, mass: np.ndarray, families: list[tuple[float, int]]
) -> SpringNetwork:
    """Springs between points ``g`` apart along a strand for the ``g``-th ``(stiffness,
    family)`` of ``families`` (``g`` = 1, 2, ...), each family left out at stiffness 0."""
    n = points.shape[0]
    springs = [
        _springs(np.arange(n - gap), np.arange(gap, n), stiffness, family)
        for gap, (stiffness, family) in enumerate(families, start=1)
        if stiffness > 0.0 and n > gap
    ]
    return _network(points, mass, springs)


def spring_graph(
    points: np.ndarray,
    mass: np.ndarray,
    pairs: np.ndarray,
    stiffness: float | np.ndarray,
    rest_length: float | np.ndarray | None = None,
) -> SpringNetwork:
    """Particles at ``points`` ``(n, 3)`` [m] with masses ``mass`` ``(n,)`` [kg] and a
    :data:`STRETCH` spring on each of ``pairs`` ``(S, 2)`` (indices into ``points``), of
    ``stiffness`` k [N/m] and ``rest_length`` L [m] — each one value or ``(S,)`` — resting by
    default at its length as built.

    Raises:
        DeformableError: At ``pairs`` for an index past the points, a spring from a point to
            itself or the same unordered pair twice; at ``stiffness`` or ``rest_length`` for a
            list that is not one value per spring.
    """
    n = points.shape[0]
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    count = pairs.shape[0]
    outside = np.flatnonzero(((pairs < 0) | (pairs >= n)).any(axis=1))
    if outside.size:
        s = int(outside[0])
        raise DeformableError(
            f"spring {s} joins points {pairs[s, 0]} and {pairs[s, 1]}, but there are {n} points "
            f"(0 to {n - 1}): each index of `pairs` must name one of the `points`",
            "pairs",
            s,
        )
    loops = np.flatnonzero(pairs[:, 0] == pairs[:, 1])
    if loops.size:
        s = int(loops[0])
        raise DeformableError(
            f"spring {s} joins point {pairs[s, 0]} to itself: a spring needs two different "
            "points; remove it from `pairs`",
            "pairs",
            s,
        )
    repeated = _first_repeat(np.sort(pairs, axis=1))
    if repeated is not None:
        first, s = repeated
        raise DeformableError(
            f"springs {first} and {s} both join points {pairs[s, 0]} and {pairs[s, 1]} (a pair "
            "is unordered): remove one, or give the other the summed stiffness",
            "pairs",
            s,
        )
    rest = None if rest_length is None else _per_spring("rest_length", rest_length, count)
    springs = [(pairs, _per_spring("stiffness", stiffness, count), _family(count, STRETCH))]
    return _network(points, mass, springs, rest)


def _per_spring(name: str, value: float | np.ndarray, count: int) -> np.ndarray:
    """``value`` for each of ``count`` springs: one value repeated, or ``(count,)`` as given."""
    values = np.asarray(value, dtype=np.float64)
    if values.ndim == 0:
        return np.full(count, float(values))
    if values.shape != (count,):
        raise DeformableError(
            f"`{name}` has {values.size} values for {count} springs: give one value, or one "
            "per spring in the order of `pairs`",
            name,
        )
    return values


def _first_repeat(rows: np.ndarray) -> tuple[int, int] | None:
    """The first row of ``rows`` ``(R, k)`` equal to an earlier one, as ``(earlier, row)``, or
    ``None`` if all rows differ."""
    if rows.shape[0] < 2:
        return None
    _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    earlier = first[inverse.reshape(-1)]
    again = np.flatnonzero(earlier != np.arange(rows.shape[0]))
    return (int(earlier[again[0]]), int(again[0])) if again.size else None


@_overflow_judged_later
def cloth_grid(
    origin: np.ndarray,
    along: np.ndarray,
    across: np.ndarray,
    resolution: tuple[int, int],
    areal_density: float,
    stiffness: float,
    shear: float,
    bending: float,
) -> SpringNetwork:
    """A sheet of ``nu × nv`` points (``resolution``) spanning the parallelogram ``origin +
    s·along + t·across``, ``s, t ∈ [0, 1]`` [m]; point ``(i, j)`` (``i`` along, ``j`` across)
    has index ``j·nu + i``. ``areal_density`` [kg/m²]; ``stiffness`` (structural), ``shear``
    and ``bending`` stiffness [N/m] of each family (a family of stiffness 0 is left out). Its
    surface is two triangles per cell; their front is the side ``across × along`` points to (up
    for a sheet along +x and across +z, the scene's default)."""
    nu, nv = resolution
    s = np.arange(nu) / (nu - 1)
    t = np.arange(nv) / (nv - 1)
    points = origin + s[None, :, None] * along + t[:, None, None] * across
    points = points.reshape(-1, 3)
    index = np.arange(nu * nv).reshape(nv, nu)
    # Each cell gives a quarter of its area to each of its four corners.
    cell = float(np.linalg.norm(np.cross(along, across))) / ((nu - 1) * (nv - 1))
    share = np.zeros((nv, nu))
    for dj in (0, 1):
        for di in (0, 1):
            share[dj : nv - 1 + dj, di : nu - 1 + di] += 0.25
    mass = areal_density * cell * share.reshape(-1)
    families = []
    if stiffness > 0.0:
        families.append(_springs(index[:, :-1], index[:, 1:], stiffness, STRETCH))
        families.append(_springs(index[:-1, :], index[1:, :], stiffness, STRETCH))
    if shear > 0.0:
        families.append(_springs(index[:-1, :-1], index[1:, 1:], shear, SHEAR))
        families.append(_springs(index[:-1, 1:], index[1:, :-1], shear, SHEAR))
    if bending > 0.0:
        families.append(_springs(index[:, :-2], index[:, 2:], bending, BEND))
        families.append(_springs(index[:-2, :], index[2:, :], bending, BEND))
    # Columns across, rows along: the triangles face across × along.
    return _network(points, mass, families, faces=grid_triangles(index.T), lattice=(nu, nv))


@_overflow_judged_later
def soft_lattice(
    origin: np.ndarray,
    size: np.ndarray,
    resolution: tuple[int, int, int],
    density: float,
    stiffness: float,
    shear: float,
    diagonal: float,
) -> SpringNetwork:
    """A box of ``nx × ny × nz`` points (``resolution``) from the corner ``origin`` with edge
    lengths ``size`` [m]; point ``(i, j, k)`` has index ``(k·ny + j)·nx + i``. ``density``
    [kg/m³]; ``stiffness``, ``shear`` and ``diagonal`` stiffness [N/m] of the structural,
    face-diagonal and body-diagonal springs (a family of stiffness 0 is left out). Its surface
    is the box's six faces, two triangles per cell face, wound outward."""
    nx, ny, nz = resolution
    axes = [np.arange(n) / (n - 1) for n in (nx, ny, nz)]
    k, j, i = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = origin + np.stack([i, j, k], axis=-1).reshape(-1, 3) * size
    index = np.arange(nx * ny * nz).reshape(nz, ny, nx)
    cell = float(np.prod(size)) / ((nx - 1) * (ny - 1) * (nz - 1))
    share = np.zeros((nz, ny, nx))
    for dk in (0, 1):
        for dj in (0, 1):
            for di in (0, 1):
                share[dk : nz - 1 + dk, dj : ny - 1 + dj, di : nx - 1 + di] += 0.125
    families = []
    for k, family, offsets in (
        (stiffness, STRETCH, [(1, 0, 0), (0, 1, 0), (0, 0, 1)]),
        (shear, SHEAR, [(1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1), (0, 1, 1), (0, 1, -1)]),
        (diagonal, DIAGONAL, [(1, 1, 1), (1, 1, -1), (1, -1, 1), (-1, 1, 1)]),
    ):
        if k > 0.0:
            families += [_offset_springs(index, o, k, family) for o in offsets]
    mass = density * cell * share.reshape(-1)
    return _network(points, mass, families, faces=box_triangles(index), lattice=(nx, ny, nz))


def _offset_springs(
    index: np.ndarray, offset: tuple[int, int, int], stiffness: float, family: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Springs from every lattice point ``(i, j, k)`` to ``(i, j, k) + offset`` inside it."""
    di, dj, dk = offset
    nz, ny, nx = index.shape

    def span(step: int, n: int) -> tuple[slice, slice]:
        return (
            (slice(0, n - step), slice(step, n))
            if step >= 0
            else (slice(-step, n), slice(0, n + step))
        )

    (ai, bi), (aj, bj), (ak, bk) = span(di, nx), span(dj, ny), span(dk, nz)
    return _springs(index[ak, aj, ai], index[bk, bj, bi], stiffness, family)


def _springs(
    first: np.ndarray, second: np.ndarray, stiffness: float, family: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A family of springs of one ``stiffness`` from each of ``first`` to ``second``."""
    pairs = np.stack([first.reshape(-1), second.reshape(-1)], axis=1).astype(np.int64)
    count = pairs.shape[0]
    return pairs, np.full(count, float(stiffness)), _family(count, family)


def _family(count: int, family: int) -> np.ndarray:
    return np.full(count, family, dtype=np.int8)


#: Why a body is refused when its numbers leave the range of a float.
_BEYOND_A_FLOAT = (
    "the body's points or masses are beyond what a float holds (or its masses are zero): give "
    "it a size, density and resolution of physical magnitude"
)


def _network(
    points: np.ndarray,
    mass: np.ndarray,
    families: Sequence[tuple[np.ndarray, ...]],
    rest: np.ndarray | None = None,
    *,
    faces: np.ndarray | None = None,
    lattice: tuple[int, ...] | None = None,
) -> SpringNetwork:
    """The network of ``families`` (``(pairs, stiffness, family)`` each, in this order), drawn
    with the triangles ``faces`` (none if ``None``), its points a ``lattice`` of these sizes
    (if not ``None``)."""
    if not (np.isfinite(points).all() and np.isfinite(mass).all() and (mass > 0.0).all()):
        raise ModelError(_BEYOND_A_FLOAT)
    return SpringNetwork(
        np.asarray(points, dtype=np.float64),
        np.asarray(mass, dtype=np.float64),
        np.concatenate([f[0] for f in families]) if families else np.zeros((0, 2), np.int64),
        np.concatenate([f[1] for f in families]) if families else np.zeros(0),
        np.concatenate([f[2] for f in families]) if families else np.zeros(0, np.int8),
        rest,
        no_triangles() if faces is None else faces,
        lattice,
    )
