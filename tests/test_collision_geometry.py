"""Collider geometry against closed forms and brute force.

Primitives: signed distances, normals and segment entries against their closed forms, with
``x − d·n`` checked to lie on the surface. Meshes: a subdivided cube against the analytic box,
an icosphere against the ball within its polygonization error, BVH queries against brute force
over every triangle (closest points, segment hits), the inside/outside sign of a non-convex
prism at its concave edge; and every refusal names its field.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from visviva.collision import Box, ColliderKind, Plane, Sphere, TriangleMesh, collider_table
from visviva.collision.bvh import mesh_distance, mesh_first_hit
from visviva.collision.queries import box_distance, plane_distance, sphere_first_hit
from visviva.collision.tables import PARALLEL_MIN_POINTS, collider_distances, planes_first_hit
from visviva.errors import ModelError

SETTINGS = settings(max_examples=25, deadline=None)

coordinate = st.floats(-5.0, 5.0)
vector = st.tuples(coordinate, coordinate, coordinate)
length = st.floats(0.05, 3.0)


def unit_quaternion(seed: int) -> tuple[float, float, float, float]:
    q = np.random.default_rng(seed).normal(size=4)
    q /= np.linalg.norm(q)
    return tuple(float(x) for x in q)


def rotation(q: tuple[float, float, float, float]) -> Rotation:
    """SciPy's rotation of a (w, x, y, z) quaternion (SciPy orders it scalar-last)."""
    w, x, y, z = q
    return Rotation.from_quat([x, y, z, w])


def box_closed_form(box: Box, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance and outward normal of a box, evaluated in the box frame."""
    r = rotation(box.orientation)
    local = r.inv().apply(points - np.array(box.center))
    excess = np.abs(local) - np.array(box.half_extents)
    outside = np.linalg.norm(np.maximum(excess, 0.0), axis=1)
    inside = np.minimum(excess.max(axis=1), 0.0)
    normal_local = np.where(
        (outside > 0.0)[:, None],
        np.sign(local) * np.maximum(excess, 0.0) / np.where(outside > 0, outside, 1.0)[:, None],
        np.sign(local) * (excess == excess.max(axis=1, keepdims=True)),
    )
    return outside + inside, r.apply(normal_local)


def inside_box(box: Box, points: np.ndarray) -> np.ndarray:
    local = rotation(box.orientation).inv().apply(points - np.array(box.center))
    return np.all(np.abs(local) <= np.array(box.half_extents), axis=1)


def first_entry_by_bisection(inside, start, end, low, high):
    """First ``s`` with ``inside(start + s (end − start))`` given outside at low, inside at high."""
    low = np.array(low, dtype=float)
    high = np.array(high, dtype=float)
    for _ in range(60):
        middle = 0.5 * (low + high)
        hit = inside(start + middle[:, None] * (end - start))
        high = np.where(hit, middle, high)
        low = np.where(hit, low, middle)
    return high


# ---------------------------------------------------------------------------------------------
# Plane slab


@SETTINGS
@given(point=vector, normal=vector, thickness=st.one_of(st.just(math.inf), length))
def test_plane_distance_and_normal_match_the_closed_form(point, normal, thickness):
    if np.linalg.norm(normal) < 1e-3:
        normal = (0.0, 1.0, 0.0)
    plane = Plane(point, normal, thickness)
    n = np.array(normal) / np.linalg.norm(normal)
    x = np.random.default_rng(1).uniform(-8, 8, size=(400, 3))
    height = (x - np.array(point)) @ n
    expected = np.where(height >= -thickness / 2, height, -thickness - height)
    d, g = plane.signed_distance(x)
    np.testing.assert_allclose(d, expected, atol=1e-12)
    np.testing.assert_allclose(g, np.where((height >= -thickness / 2)[:, None], n, -n))
    foot_height = (x - d[:, None] * g - np.array(point)) @ n
    on_face = np.minimum(np.abs(foot_height), np.abs(foot_height + thickness))
    assert np.all(on_face < 1e-9)


@SETTINGS
@given(normal=vector, thickness=st.one_of(st.just(math.inf), length), seed=st.integers(0, 99))
def test_plane_first_hit_matches_the_interval_of_the_linear_height(normal, thickness, seed):
    if np.linalg.norm(normal) < 1e-3:
        normal = (1.0, 0.0, 0.0)
    plane = Plane((0.1, -0.2, 0.3), normal, thickness)
    n = np.array(plane.unit_normal)
    rng = np.random.default_rng(seed)
    start, end = rng.uniform(-4, 4, size=(2, 300, 3))
    h0 = (start - plane.point) @ n
    h1 = (end - plane.point) @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (0.0 - h0) / (h1 - h0)
        b = (-thickness - h0) / (h1 - h0)
    low = np.maximum(np.minimum(a, b), 0.0)
    high = np.minimum(np.maximum(a, b), 1.0)
    expected = np.where(low <= high, low, np.inf)
    expected = np.where((h0 <= 0) & (h0 >= -thickness), 0.0, expected)
    np.testing.assert_allclose(plane.first_hit(start, end), expected, rtol=1e-12, atol=1e-12)


def test_a_fast_particle_jumping_over_a_thin_wall_is_caught():
    wall = Plane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), thickness=0.01)
    start = np.array([[0.0, 0.5, 0.0], [0.0, 0.5, 0.0], [0.0, -0.005, 0.0]])
    end = np.array([[0.2, -0.5, 0.0], [0.0, 0.02, 0.0], [0.0, 1.0, 0.0]])
    d_end, _ = wall.signed_distance(end[:1])
    assert d_end[0] > 0.0  # the end is below the wall: only the segment query sees the hit
    np.testing.assert_allclose(wall.first_hit(start, end), [0.5, np.inf, 0.0])


def test_plane_table_returns_the_nearest_row_and_the_earliest_entry():
    planes = [
        Plane((0, 0, 0), (0, 1, 0)),
        Plane((0, 5, 0), (0, -1, 0)),
        Plane((3, 0, 0), (-1, 0, 0), thickness=0.1),
    ]
    table = collider_table(planes)
    assert table.shape == (3, ColliderKind.PLANE.width)
    x = np.array([[0.0, 1.0, 0.0], [0.0, 4.5, 0.0], [2.9, 2.5, 0.0]])
    d, g, row = collider_distances(ColliderKind.PLANE, table, x)
    np.testing.assert_allclose(d, [1.0, 0.5, 0.1])
    np.testing.assert_array_equal(row, [0, 1, 2])
    np.testing.assert_allclose(g[2], [-1.0, 0.0, 0.0])
    s, k = planes_first_hit(2.0, 1.0, 0.0, 4.0, -1.0, 0.0, table)
    assert (s, k) == pytest.approx((0.5, 0))
    with pytest.raises(ModelError, match="one kind"):
        collider_table([planes[0], Sphere((0, 0, 0), 1.0)])


# ---------------------------------------------------------------------------------------------
# Sphere


@SETTINGS
@given(center=vector, radius=length, seed=st.integers(0, 99))
def test_sphere_distance_normal_and_first_hit_match_the_closed_forms(center, radius, seed):
    sphere = Sphere(center, radius)
    c = np.array(center)
    rng = np.random.default_rng(seed)
    x = c + rng.uniform(-2 * radius, 2 * radius, size=(300, 3))
    d, g = sphere.signed_distance(x)
    np.testing.assert_allclose(d, np.linalg.norm(x - c, axis=1) - radius, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0)
    foot = x - d[:, None] * g
    np.testing.assert_allclose(np.linalg.norm(foot - c, axis=1), radius, rtol=1e-12)

    start = c + rng.uniform(-3 * radius, 3 * radius, size=(300, 3))
    end = c + rng.uniform(-3 * radius, 3 * radius, size=(300, 3))
    m, direction = start - c, end - start
    qa = np.sum(direction**2, axis=1)
    qb = 2 * np.sum(m * direction, axis=1)
    qc = np.sum(m**2, axis=1) - radius**2
    disc = qb**2 - 4 * qa * qc
    root = (-qb - np.sqrt(np.maximum(disc, 0.0))) / (2 * qa)
    expected = np.where((disc >= 0) & (root >= 0) & (root <= 1), root, np.inf)
    expected = np.where(qc <= 0, 0.0, expected)
    np.testing.assert_allclose(sphere.first_hit(start, end), expected, rtol=1e-9, atol=1e-12)


def test_sphere_centre_gets_an_upward_normal():
    d, g = Sphere((1.0, 2.0, 3.0), 0.5).signed_distance([1.0, 2.0, 3.0])
    assert d[0] == -0.5 and g[0].tolist() == [0.0, 1.0, 0.0]


# ---------------------------------------------------------------------------------------------
# Box


@SETTINGS
@given(center=vector, size=st.tuples(length, length, length), seed=st.integers(0, 10_000))
def test_box_distance_and_normal_match_the_closed_form(center, size, seed):
    box = Box(center, size, unit_quaternion(seed))
    rng = np.random.default_rng(seed)
    r = rotation(box.orientation)
    half = np.array(box.half_extents)
    local = rng.uniform(-2, 2, size=(600, 3)) * half
    # Points exactly on corners and edges (in the box frame), then rotated into the world.
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * half
    edges = corners * np.array([1.0, 1.0, 0.3])
    x = np.array(center) + r.apply(np.vstack([local, corners, edges]))
    d, g = box.signed_distance(x)
    expected_d, expected_g = box_closed_form(box, x)
    np.testing.assert_allclose(d, expected_d, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0, rtol=1e-12)
    away = np.abs(d) > 1e-9  # on the surface the normal of any face at that point is right
    np.testing.assert_allclose(g[away], expected_g[away], atol=1e-9)
    foot_d, _ = box_closed_form(box, x - d[:, None] * g)
    assert np.all(np.abs(foot_d) < 1e-9)
    on_surface = ~away
    assert on_surface.sum() >= 16
    # On the surface the normal lies in the normal cone there: a combination of the outward
    # normals of the faces meeting at the point (one face, an edge's two, a corner's three).
    foot = r.inv().apply(x[on_surface] - np.array(center))
    normal_local = r.inv().apply(g[on_surface])
    used = np.abs(normal_local) > 1e-9
    assert np.all(used.any(axis=1))
    np.testing.assert_allclose(
        np.abs(foot)[used], np.broadcast_to(half, foot.shape)[used], rtol=1e-12
    )
    assert np.all(np.sign(normal_local[used]) == np.sign(foot[used]))


@SETTINGS
@given(center=vector, size=st.tuples(length, length, length), seed=st.integers(0, 10_000))
def test_box_first_hit_matches_bisection_on_the_closed_form(center, size, seed):
    box = Box(center, size, unit_quaternion(seed))
    rng = np.random.default_rng(seed)
    r = rotation(box.orientation)
    half = np.array(box.half_extents)
    c = np.array(center)
    start = c + r.apply(rng.uniform(-3, 3, size=(200, 3)) * half)
    target = c + r.apply(rng.uniform(-0.5, 0.5, size=(200, 3)) * half)
    through = start + 2 * (target - start)  # passes the target at s = 0.5, inside
    s = box.first_hit(start, through)
    outside = ~inside_box(box, start)
    expected = first_entry_by_bisection(
        lambda p: inside_box(box, p),
        start[outside],
        through[outside],
        0.0,
        np.full(outside.sum(), 0.5),
    )
    np.testing.assert_allclose(s[outside], expected, atol=1e-9)
    assert np.all(s[~outside] == 0.0)
    # Both ends beyond the same face: a miss.
    beyond = rng.uniform(-2, 2, size=(200, 2, 3)) * half
    beyond[:, :, 0] = half[0] * rng.uniform(1.01, 3, size=(200, 2))
    misses = box.first_hit(c + r.apply(beyond[:, 0]), c + r.apply(beyond[:, 1]))
    assert np.all(np.isinf(misses))


def test_box_orientation_rotates_box_axes_into_the_world_y_up():
    # A quarter turn about +z takes the box's x axis (the long edge) to world +y.
    q = (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))
    box = Box((0.0, 0.0, 0.0), (4.0, 1.0, 1.0), q)
    d, g = box.signed_distance([[0.0, 3.0, 0.0], [3.0, 0.0, 0.0]])
    np.testing.assert_allclose(d, [1.0, 2.5], atol=1e-12)
    np.testing.assert_allclose(g, [[0, 1, 0], [1, 0, 0]], atol=1e-12)


def test_primitive_kernels_are_callable_from_another_kernel_and_agree_with_shapes():
    sphere = Sphere((0.0, 1.0, 0.0), 0.5)
    box = Box((2.0, 0.0, 0.0), (1.0, 2.0, 3.0), unit_quaternion(3))
    floor = Plane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))

    @numba.njit
    def kernel(x, sphere_row, box_row, plane_row):
        out = np.empty((x.shape[0], 3))
        for i in range(x.shape[0]):
            px, py, pz = x[i, 0], x[i, 1], x[i, 2]
            r, b, p = sphere_row, box_row, plane_row
            out[i, 0] = sphere_first_hit(px, py, pz, 0.0, 1.0, 0.0, r[0], r[1], r[2], r[3])
            out[i, 1] = box_distance(
                px, py, pz, b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8], b[9]
            )[0]
            out[i, 2] = plane_distance(px, py, pz, p[0], p[1], p[2], p[3], p[4], p[5], p[6])[0]
        return out

    x = np.random.default_rng(0).uniform(-3, 3, size=(50, 3))
    out = kernel(x, sphere.table_row(), box.table_row(), floor.table_row())
    np.testing.assert_array_equal(out[:, 0], sphere.first_hit(x, np.tile([0.0, 1.0, 0.0], (50, 1))))
    np.testing.assert_array_equal(out[:, 1], box.signed_distance(x)[0])
    np.testing.assert_array_equal(out[:, 2], floor.signed_distance(x)[0])


# ---------------------------------------------------------------------------------------------
# Triangle meshes: generators


def cube_mesh(half: tuple[float, float, float], n: int) -> tuple[np.ndarray, np.ndarray]:
    """A box ``[−half, half]`` with each face split into ``n × n`` quads of two triangles."""
    vertices, triangles = [], []
    for axis in range(3):
        for side in (1.0, -1.0):
            b, c = (axis + 1) % 3, (axis + 2) % 3
            if side < 0:  # e_b × e_c = e_axis: swap the tangents for the face facing −axis
                b, c = c, b
            grid = np.zeros((n + 1, n + 1, 3))
            u, v = np.meshgrid(
                np.linspace(-half[b], half[b], n + 1),
                np.linspace(-half[c], half[c], n + 1),
                indexing="ij",
            )
            grid[..., axis], grid[..., b], grid[..., c] = side * half[axis], u, v
            base = sum(len(part) for part in vertices)
            vertices.append(grid.reshape(-1, 3))
            index = base + np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
            i00, i10, i11, i01 = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
            triangles.append(np.stack([i00, i10, i11], axis=-1).reshape(-1, 3))
            triangles.append(np.stack([i00, i11, i01], axis=-1).reshape(-1, 3))
    merged, inverse = np.unique(np.vstack(vertices), axis=0, return_inverse=True)
    return merged, inverse.reshape(-1)[np.vstack(triangles)]


def icosphere(radius: float, subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    t = (1 + math.sqrt(5)) / 2
    vertices = [
        (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
        (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1),
    ]  # fmt: skip
    faces = [
        (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
        (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
        (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1),
    ]  # fmt: skip
    points = [np.array(v, dtype=float) / np.linalg.norm(v) for v in vertices]
    for _ in range(subdivisions):
        midpoint: dict[tuple[int, int], int] = {}

        def middle(i: int, j: int) -> int:
            key = (min(i, j), max(i, j))
            if key not in midpoint:
                m = points[i] + points[j]
                points.append(m / np.linalg.norm(m))
                midpoint[key] = len(points) - 1
            return midpoint[key]

        finer = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = finer
    return radius * np.array(points), np.array(faces)


L_POLYGON = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)


def l_prism(height: float) -> tuple[np.ndarray, np.ndarray]:
    """The L-shaped polygon above (counter-clockwise) extruded along z from 0 to ``height``."""
    n = len(L_POLYGON)
    bottom = np.column_stack([L_POLYGON, np.zeros(n)])
    top = np.column_stack([L_POLYGON, np.full(n, height)])
    vertices = np.vstack([bottom, top])
    # The L is star-shaped about its reflex corner (vertex 3): fan the caps from it.
    fan = [(3, (3 + k) % n, (4 + k) % n) for k in range(1, n - 1)]
    triangles = [(a + n, b + n, c + n) for a, b, c in fan] + [(a, c, b) for a, b, c in fan]
    for i in range(n):
        j = (i + 1) % n
        triangles += [(i, j, j + n), (i, j + n, i + n)]
    return vertices, np.array(triangles)


def inside_l_prism(points: np.ndarray, height: float) -> np.ndarray:
    x, y, z = points.T
    in_l = ((x >= 0) & (x <= 2) & (y >= 0) & (y <= 1)) | ((x >= 0) & (x <= 1) & (y >= 0) & (y <= 2))
    return in_l & (z >= 0) & (z <= height)


def brute_force_distance(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Unsigned distance to the nearest of ``(T, 3, 3)`` triangles, by projection onto each
    plane (inside the triangle) or else onto the three edge segments."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    best = np.full(len(points), np.inf)
    for chunk in np.array_split(np.arange(len(points)), max(1, len(points) // 100)):
        p = points[chunk][:, None, :]
        height = np.sum((p - a) * normal, axis=2)
        foot = p - height[..., None] * normal
        inside = np.ones(height.shape, dtype=bool)
        for u, v in ((a, b), (b, c), (c, a)):
            inside &= np.sum(np.cross(v - u, foot - u) * normal, axis=2) >= 0
        result = np.where(inside, np.abs(height), np.inf)
        for u, v in ((a, b), (b, c), (c, a)):
            edge = v - u
            t = np.clip(np.sum((p - u) * edge, axis=2) / np.sum(edge * edge, axis=1), 0, 1)
            result = np.minimum(result, np.linalg.norm(p - (u + t[..., None] * edge), axis=2))
        best[chunk] = result.min(axis=1)
    return best


def brute_force_crossing(start: np.ndarray, end: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """First fraction where each segment crosses any triangle (plane hit, then inside test)."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    normal = np.cross(b - a, c - a)
    result = np.full(len(start), np.inf)
    for i in range(len(start)):
        direction = end[i] - start[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.sum((a - start[i]) * normal, axis=1) / (normal @ direction)
        x = start[i] + t[:, None] * direction
        inside = (t >= 0) & (t <= 1)
        for u, v in ((a, b), (b, c), (c, a)):
            inside &= np.sum(np.cross(v - u, x - u) * normal, axis=1) >= -1e-12
        if inside.any():
            result[i] = t[inside].min()
    return result


@pytest.fixture(scope="module")
def cube() -> tuple[TriangleMesh, Box]:
    half = (0.6, 0.4, 0.9)
    return TriangleMesh(*cube_mesh(half, 8)), Box((0, 0, 0), tuple(2 * h for h in half))


# ---------------------------------------------------------------------------------------------
# Triangle meshes: queries


def test_subdivided_cube_signed_distance_equals_the_analytic_box(cube):
    mesh, box = cube
    assert mesh.volume == pytest.approx(1.2 * 0.8 * 1.8, rel=1e-12)
    x = np.random.default_rng(2).uniform(-1.1, 1.1, size=(PARALLEL_MIN_POINTS + 1000, 3))
    d, g = mesh.signed_distance(x)  # enough points for the parallel kernel
    expected_d, expected_g = box_closed_form(box, x)
    np.testing.assert_allclose(d, expected_d, atol=1e-12)
    np.testing.assert_allclose(g, expected_g, atol=1e-9)
    serial_d, serial_g = mesh.signed_distance(x[:500])
    np.testing.assert_array_equal(serial_d, d[:500])
    np.testing.assert_array_equal(serial_g, g[:500])
    assert (d < 0).sum() > 500 and (d > 0).sum() > 500


def test_icosphere_signed_distance_is_the_ball_within_its_polygonization_error():
    radius = 0.7
    mesh = TriangleMesh(*icosphere(radius, 3))
    corners = mesh.vertices[mesh.triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    inscribed = np.min(np.sum(normal * corners[:, 0], axis=1))
    # Inscribed ball ⊂ mesh ⊂ ball: the signed distance lies between theirs.
    x = np.random.default_rng(3).uniform(-1.2, 1.2, size=(2000, 3))
    d, g = mesh.signed_distance(x)
    r = np.linalg.norm(x, axis=1)
    assert np.all(d >= r - radius - 1e-12)
    assert np.all(d <= r - inscribed + 1e-12)
    assert radius - inscribed < 0.01
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0, rtol=1e-12)
    foot_d, _ = mesh.signed_distance(x - d[:, None] * g)
    assert np.all(np.abs(foot_d) < 1e-12)
    # Normals point roughly away from the centre, within the facets' angular size.
    assert np.all(np.sum(g * x, axis=1) / r > 0.97)


def test_bvh_closest_point_equals_brute_force_including_vertices_and_edges():
    vertices, triangles = icosphere(1.0, 2)
    mesh = TriangleMesh(vertices, triangles)
    rng = np.random.default_rng(4)
    corners = vertices[triangles]
    weights = rng.dirichlet([1, 1, 1], size=300)
    on_faces = np.einsum("ij,ijk->ik", weights, corners[rng.integers(0, len(triangles), 300)])
    edge_t = rng.uniform(size=(300, 1))
    edge = corners[rng.integers(0, len(triangles), 300)]
    on_edges = edge[:, 0] + edge_t * (edge[:, 1] - edge[:, 0])
    x = np.vstack(
        [
            rng.uniform(-2, 2, size=(2000 - 300 - 300 - len(vertices), 3)),
            vertices,
            on_faces,
            on_edges,
        ]
    )
    assert len(x) == 2000
    closest, triangle = mesh.closest_point(x)
    expected = brute_force_distance(x, corners)
    np.testing.assert_allclose(np.linalg.norm(x - closest, axis=1), expected, atol=1e-12)
    # The closest point lies on the triangle reported for it.
    np.testing.assert_allclose(brute_force_distance_each(closest, corners[triangle]), 0, atol=1e-12)
    vertex_rows = slice(2000 - 600 - len(vertices), 2000 - 600)
    assert np.all(np.linalg.norm(x[vertex_rows] - closest[vertex_rows], axis=1) == 0.0)


def brute_force_distance_each(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    return np.array(
        [brute_force_distance(p[None], c[None])[0] for p, c in zip(points, corners, strict=True)]
    )


def test_inside_outside_sign_of_a_non_convex_prism():
    height = 0.5
    mesh = TriangleMesh(*l_prism(height))
    assert mesh.volume == pytest.approx(3 * height, rel=1e-12)
    rng = np.random.default_rng(5)
    x = rng.uniform([-0.5, -0.5, -0.5], [2.5, 2.5, 1.0], size=(3000, 3))
    # Around the concave (reflex) edge at x = y = 1, where the closest feature is that edge.
    angle = np.linspace(0, 2 * np.pi, 72, endpoint=False) + 0.01
    ring = np.column_stack([1 + 0.05 * np.cos(angle), 1 + 0.05 * np.sin(angle), np.full(72, 0.2)])
    x = np.vstack([x, ring])
    d, g = mesh.signed_distance(x)
    inside = inside_l_prism(x, height)
    np.testing.assert_array_equal(d < 0, inside)
    np.testing.assert_array_equal(d[-72:] > 0, (np.cos(angle) > 0) & (np.sin(angle) > 0))
    expected = brute_force_distance(x, mesh.vertices[mesh.triangles])
    np.testing.assert_allclose(np.abs(d), expected, atol=1e-12)
    foot_d, _ = mesh.signed_distance(x - d[:, None] * g)
    assert np.all(np.abs(foot_d) < 1e-12)


def test_mesh_first_hit_equals_brute_force(cube):
    mesh, box = cube
    rng = np.random.default_rng(6)
    start = rng.uniform(-1.5, 1.5, size=(400, 3))
    end = rng.uniform(-1.5, 1.5, size=(400, 3))
    s = mesh.first_hit(start, end)
    expected = brute_force_crossing(start, end, mesh.vertices[mesh.triangles])
    expected[inside_box(box, start)] = 0.0
    np.testing.assert_allclose(s, expected, atol=1e-12)
    assert np.isinf(s).sum() > 20 and (s == 0).sum() > 20 and ((s > 0) & (s < 1)).sum() > 100
    np.testing.assert_allclose(s, box.first_hit(start, end), atol=1e-12)


def test_mesh_first_hit_on_a_non_convex_prism():
    mesh = TriangleMesh(*l_prism(0.5))
    # Across the notch of the L: outside the whole way, though both ends are next to the solid.
    assert mesh.first_hit([[1.5, 1.9, 0.25]], [[1.9, 1.5, 0.25]])[0] == np.inf
    # Into the notch and through the inner wall x = 1 (at y = 1.5) on the way to x = 0.5.
    s = mesh.first_hit([[1.5, 1.5, 0.25]], [[0.5, 1.5, 0.25]])[0]
    assert s == pytest.approx(0.5, abs=1e-12)


def test_mesh_kernels_are_callable_from_another_kernel(cube):
    mesh, _ = cube

    @numba.njit
    def kernel(x, nb, nl, tp, tn):
        out = np.empty((x.shape[0], 2))
        for i in range(x.shape[0]):
            out[i, 0] = mesh_distance(x[i, 0], x[i, 1], x[i, 2], nb, nl, tp, tn)[0]
            out[i, 1] = mesh_first_hit(x[i, 0], x[i, 1], x[i, 2], 0.0, 0.0, 0.0, nb, nl, tp, tn)
        return out

    x = np.random.default_rng(7).uniform(-2, 2, size=(100, 3))
    out = kernel(x, *mesh.bvh.kernel_arrays)
    np.testing.assert_array_equal(out[:, 0], mesh.signed_distance(x)[0])
    np.testing.assert_array_equal(out[:, 1], mesh.first_hit(x, np.zeros_like(x)))


# ---------------------------------------------------------------------------------------------
# Refusals


def test_mesh_refusals_name_the_field_and_the_fix(cube):
    vertices, triangles = cube_mesh((1.0, 1.0, 1.0), 1)
    with pytest.raises(ModelError, match=r"`triangles` do not close the mesh: edge \(\d+, \d+\)"):
        TriangleMesh(vertices, triangles[1:])
    flipped = triangles.copy()
    flipped[3] = flipped[3, ::-1]
    with pytest.raises(ModelError, match=r"`triangles` are not consistently oriented.*reverse"):
        TriangleMesh(vertices, flipped)
    with pytest.raises(ModelError, match=r"`triangles` are inside-out.*triangles\[:, ::-1\]"):
        TriangleMesh(vertices, triangles[:, ::-1])
    degenerate = triangles.copy()
    degenerate[2, 2] = degenerate[2, 1]
    with pytest.raises(ModelError, match=r"`triangles` entry 2 .* is degenerate"):
        TriangleMesh(vertices, degenerate)
    collinear = vertices.copy()
    collinear[triangles[5, 2]] = 0.5 * (collinear[triangles[5, 0]] + collinear[triangles[5, 1]])
    with pytest.raises(ModelError, match="degenerate"):
        TriangleMesh(collinear, triangles)
    with pytest.raises(ModelError, match="`triangles` entry 0 refers to vertex 99"):
        TriangleMesh(vertices, np.vstack([[0, 1, 99], triangles[1:]]))
    bad = vertices.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ModelError, match=r"`vertices` .* finite; vertex 4"):
        TriangleMesh(bad, triangles)
    with pytest.raises(ModelError, match=r"`triangles` .* integer"):
        TriangleMesh(vertices, triangles.astype(float))


@pytest.mark.parametrize(
    ("make", "pattern"),
    [
        (lambda: Plane((0, 0, 0), (0, 0, 0)), r"`normal` of a plane must not be zero"),
        (lambda: Plane((0, 0, 0), (0, 1, 0), thickness=0.0), "`thickness` must be positive"),
        (lambda: Plane((0, 0, math.nan), (0, 1, 0)), "`point` of a plane"),
        (lambda: Sphere((0, 0, 0), -1.0), "`radius` must be positive"),
        (lambda: Box((0, 0, 0), (1, 0, 1)), "`size` of a box must be three positive"),
        (lambda: Box((0, 0, 0), (1, 1, 1), (0, 0, 0, 0)), "`orientation` .* unit quaternion"),
        (lambda: Box((0, 0, 0), (1, 1, 1), (1, 0, 0, 0.01)), "`orientation` .* normalize it"),
        (lambda: Sphere((0, 0), 1.0), "`center` of a sphere must be 3 finite numbers"),
    ],
)
def test_primitive_refusals_name_the_field(make, pattern):
    with pytest.raises(ModelError, match=pattern):
        make()


def test_nearly_unit_quaternion_is_accepted_and_used_normalized():
    box = Box((0, 0, 0), (1, 1, 1), (1 + 5e-7, 0, 0, 0))
    assert np.linalg.norm(box.table_row()[6:]) == pytest.approx(1.0, abs=1e-15)
