"""GJK and EPA against brute force and closed forms (vv.collision.distance).

Brute force for two convex polytopes A and B: the Minkowski difference D = A − B is the convex
hull of every a_i − b_j (Qhull). The distance between A and B is the distance from the origin
to D when the origin is outside; when it is inside, the penetration depth is the smallest
distance from the origin to a facet plane of D. Both are exact to rounding.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull as Qhull
from scipy.spatial.transform import Rotation

import visviva as vv
from visviva.collision import (
    Box,
    Capsule,
    Cone,
    ConvexHull,
    Cylinder,
    Ellipsoid,
    Plane,
    Sphere,
    distance,
)
from visviva.collision.convex import BOX, CONE
from visviva.collision.separation import shape_distance
from visviva.errors import ModelError


def _quaternion(rotation: Rotation) -> tuple[float, ...]:
    x, y, z, w = rotation.as_quat()
    return (w, x, y, z)


def _point_triangle_distance(p, a, b, c):
    """Distance from p to triangle abc, by projection and the three edges."""
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    q = p - np.dot(p - a, n) * n
    # Inside test by barycentric signs.
    inside = all(np.dot(np.cross(v1 - v0, q - v0), n) >= 0.0 for v0, v1 in ((a, b), (b, c), (c, a)))
    if inside:
        return abs(np.dot(p - a, n))
    best = math.inf
    for v0, v1 in ((a, b), (b, c), (c, a)):
        t = np.clip(np.dot(p - v0, v1 - v0) / np.dot(v1 - v0, v1 - v0), 0.0, 1.0)
        best = min(best, np.linalg.norm(p - (v0 + t * (v1 - v0))))
    return best


def _brute_force(world_a: np.ndarray, world_b: np.ndarray) -> float:
    """Signed distance of the hulls of two world point sets, through their Minkowski
    difference (module docstring)."""
    difference = (world_a[:, None, :] - world_b[None, :, :]).reshape(-1, 3)
    hull = Qhull(difference)
    offsets = hull.equations[:, 3]  # n·x + offset = 0, outward n: the origin's height is offset
    if (offsets < 0.0).all():
        return -float(np.min(-offsets))
    origin = np.zeros(3)
    return min(_point_triangle_distance(origin, *difference[simplex]) for simplex in hull.simplices)


def _random_hull(rng: np.random.Generator, centre: np.ndarray) -> tuple[ConvexHull, np.ndarray]:
    points = rng.normal(size=(rng.integers(5, 20), 3)) * rng.uniform(0.2, 1.5, size=3)
    rotation = Rotation.random(random_state=rng)
    hull = ConvexHull(points, position=tuple(centre), orientation=_quaternion(rotation))
    world = rotation.apply(np.array(hull.vertices)) + centre
    return hull, world


def test_gjk_matches_brute_force_on_separated_random_hulls():
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(200):
        a, world_a = _random_hull(rng, rng.normal(size=3))
        b, world_b = _random_hull(rng, rng.normal(size=3) * 4.0)
        expected = _brute_force(world_a, world_b)
        if expected <= 1e-6:
            continue
        result = distance(a, b)
        assert result.distance == pytest.approx(expected, abs=1e-9)
        # The witness points lie on their hulls and realize the distance along the normal.
        assert np.allclose(result.point_b - result.point_a, result.distance * result.normal)
        assert np.linalg.norm(result.normal) == pytest.approx(1.0, abs=1e-12)
        checked += 1
    assert checked > 100


def test_epa_matches_brute_force_on_overlapping_random_hulls():
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(200):
        a, world_a = _random_hull(rng, rng.normal(size=3) * 0.3)
        b, world_b = _random_hull(rng, rng.normal(size=3) * 0.3)
        expected = _brute_force(world_a, world_b)
        if expected >= -1e-6:
            continue
        result = distance(a, b)
        assert result.distance == pytest.approx(expected, abs=1e-9)
        # Moving b by depth along the normal leaves the two just touching.
        moved = ConvexHull(
            b.points,
            position=tuple(np.array(b.position) - result.distance * result.normal),
            orientation=b.orientation,
        )
        assert distance(a, moved).distance == pytest.approx(0.0, abs=1e-8)
        checked += 1
    assert checked > 100


def _sat_overlap(centre_a, axes_a, half_a, centre_b, axes_b, half_b) -> float:
    """The penetration depth of two overlapping oriented boxes by the separating axis theorem:
    the smallest overlap of their projections over the 15 axes (3 + 3 face normals, 9 edge
    cross products), the exact minimum translation for two boxes."""
    candidates = [*axes_a, *axes_b]
    for u in axes_a:
        for w in axes_b:
            c = np.cross(u, w)
            if np.linalg.norm(c) > 1e-9:
                candidates.append(c / np.linalg.norm(c))
    best = math.inf
    for axis in candidates:
        ra = sum(h * abs(np.dot(u, axis)) for h, u in zip(half_a, axes_a, strict=True))
        rb = sum(h * abs(np.dot(u, axis)) for h, u in zip(half_b, axes_b, strict=True))
        best = min(best, ra + rb - abs(np.dot(centre_b - centre_a, axis)))
    return best


def test_epa_depth_of_overlapping_boxes_is_the_analytic_overlap():
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(100):
        half_a = rng.uniform(0.2, 1.0, size=3)
        half_b = rng.uniform(0.2, 1.0, size=3)
        ra, rb = Rotation.random(2, random_state=rng)
        ca, cb = rng.normal(size=3) * 0.2, rng.normal(size=3) * 0.5
        overlap = _sat_overlap(ca, ra.as_matrix().T, half_a, cb, rb.as_matrix().T, half_b)
        if overlap <= 1e-6:
            continue
        a = Box(center=tuple(ca), size=tuple(2 * half_a), orientation=_quaternion(ra))
        b = Box(center=tuple(cb), size=tuple(2 * half_b), orientation=_quaternion(rb))
        assert distance(a, b).distance == pytest.approx(-overlap, abs=1e-9)
        checked += 1
    assert checked > 50


def test_sphere_pairs_in_closed_form():
    # |c_b − c_a| − r_a − r_b, apart and overlapping, along the line of centres.
    a = Sphere(center=(0.0, 0.0, 0.0), radius=1.0)
    for gap in (2.0, 0.25, -0.3):
        b = Sphere(center=(0.0, 0.0, 1.5 + gap), radius=0.5)
        result = distance(a, b)
        assert result.distance == pytest.approx(gap, abs=1e-14)
        assert result.normal == pytest.approx([0.0, 0.0, 1.0])
        assert result.point_a == pytest.approx([0.0, 0.0, 1.0])
    # A sphere whose centre is inside a box: depth = radius + centre's depth below the nearest
    # face (0.2 below the top face y = 0.5).
    box = Box(center=(0.0, 0.0, 0.0), size=(4.0, 1.0, 4.0))
    result = distance(box, Sphere(center=(0.3, 0.3, -0.2), radius=0.25))
    assert result.distance == pytest.approx(-0.45, abs=1e-12)
    assert result.normal == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)


def test_round_shapes_in_closed_form():
    # Capsule axes crossing at right angles: the gap between the segments less both radii.
    a = Capsule(center=(0.0, 0.0, 0.0), radius=0.2, height=2.0)
    turned = _quaternion(Rotation.from_euler("z", 90, degrees=True))
    b = Capsule(center=(0.0, 0.0, 0.7), radius=0.3, height=2.0, orientation=turned)
    assert distance(a, b).distance == pytest.approx(0.2, abs=1e-12)
    # A sphere beside a cylinder's side: |x| − R − r.
    cylinder = Cylinder(center=(0.0, 0.0, 0.0), radius=0.5, height=1.0)
    assert distance(cylinder, Sphere(center=(1.2, 0.1, 0.0), radius=0.3)).distance == (
        pytest.approx(0.4, abs=1e-9)
    )
    # A sphere above a cone's apex (apex at y = h above the base).
    cone = Cone(base=(0.0, 0.0, 0.0), radius=0.5, height=2.0)
    assert distance(cone, Sphere(center=(0.0, 3.0, 0.0), radius=0.25)).distance == (
        pytest.approx(0.75, abs=1e-12)
    )
    # An ellipsoid's lowest point above a floor: centre height less the vertical semi-axis of
    # the tilted ellipsoid, sqrt(a² sin²θ + b² cos²θ) for a tilt θ about z.
    theta = 0.4
    tilted = Ellipsoid(
        center=(0.0, 2.0, 0.0),
        semi_axes=(1.0, 0.5, 0.3),
        orientation=_quaternion(Rotation.from_euler("z", theta)),
    )
    floor = Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
    reach = math.sqrt(math.sin(theta) ** 2 + 0.25 * math.cos(theta) ** 2)
    assert distance(floor, tilted).distance == pytest.approx(2.0 - reach, abs=1e-12)


def test_round_core_against_a_round_core_converges():
    # Two ellipsoids along x: the gap between their tips, 4 − 1 − 1.5.
    a = Ellipsoid(center=(0.0, 0.0, 0.0), semi_axes=(1.0, 0.5, 0.5))
    b = Ellipsoid(center=(4.0, 0.0, 0.0), semi_axes=(1.5, 0.3, 0.7))
    assert distance(a, b).distance == pytest.approx(1.5, abs=1e-9)
    # Overlapping tips: EPA on round cores to its relative tolerance.
    c = Ellipsoid(center=(2.3, 0.0, 0.0), semi_axes=(1.5, 0.3, 0.7))
    assert distance(a, c).distance == pytest.approx(-0.2, abs=1e-6)


def test_the_query_is_symmetric():
    rng = np.random.default_rng(5)
    for _ in range(30):
        a, _ = _random_hull(rng, rng.normal(size=3))
        b = Cylinder(
            center=tuple(rng.normal(size=3)),
            radius=0.4,
            height=1.0,
            orientation=_quaternion(Rotation.random(random_state=rng)),
        )
        ab, ba = distance(a, b), distance(b, a)
        assert ab.distance == pytest.approx(ba.distance, abs=1e-6)
        if ab.distance > 1e-6:
            assert ab.normal == pytest.approx(-ba.normal, abs=1e-5)


def test_plane_slab_pushes_out_through_the_nearer_face():
    # A 1 m slab (−1 ≤ y ≤ 0): a sphere just below its middle leaves through the bottom face.
    slab = Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0), thickness=1.0)
    result = distance(slab, Sphere(center=(0.0, -0.6, 0.0), radius=0.1))
    assert result.distance == pytest.approx(-0.5, abs=1e-12)
    assert result.normal == pytest.approx([0.0, -1.0, 0.0])
    below = distance(slab, Sphere(center=(0.0, -2.0, 0.0), radius=0.5))
    assert below.distance == pytest.approx(0.5, abs=1e-12)


def test_bad_queries_are_refused():
    ball = Sphere(center=(0.0, 0.0, 0.0), radius=1.0)
    with pytest.raises(ModelError, match="Plane must come first"):
        distance(ball, Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0)))
    with pytest.raises(ModelError, match="convex shape"):
        distance(ball, "sphere")
    with pytest.raises(ModelError, match="one plane"):
        ConvexHull(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float))
    with pytest.raises(ModelError, match="N ≥ 4"):
        ConvexHull(np.zeros((3, 3)))
    with pytest.raises(ModelError, match="finite"):
        ConvexHull(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]]))
    with pytest.raises(ModelError, match="semi_axes"):
        Ellipsoid(center=(0, 0, 0), semi_axes=(1.0, 0.0, 1.0))
    with pytest.raises(ModelError, match="radius"):
        Capsule(center=(0, 0, 0), radius=-1.0, height=1.0)
    with pytest.raises(ModelError, match="max_separation"):
        vv.collision.contacts(ball, ball, max_separation=-1.0)


finite = st.floats(-1e3, 1e3, allow_nan=False)
sizes = st.floats(1e-3, 1e3, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(finite, finite, finite),
    st.tuples(finite, finite, finite, finite).filter(lambda q: sum(x * x for x in q) > 1e-6),
    sizes,
    sizes,
    st.sampled_from(["box", "capsule", "cylinder", "cone", "ellipsoid"]),
)
def test_any_pose_and_scale_gives_a_finite_answer(centre, q, size_a, size_b, kind):
    norm = math.sqrt(sum(x * x for x in q))
    orientation = tuple(x / norm for x in q)
    b = {
        "box": lambda: Box(centre, (size_b, size_b, 0.5 * size_b), orientation),
        "capsule": lambda: Capsule(centre, size_b, size_b, orientation),
        "cylinder": lambda: Cylinder(centre, size_b, size_b, orientation),
        "cone": lambda: Cone(centre, size_b, 2 * size_b, orientation),
        "ellipsoid": lambda: Ellipsoid(centre, (size_b, 0.5 * size_b, 0.2 * size_b), orientation),
    }[kind]()
    a = Box((0.0, 0.0, 0.0), (size_a, 2 * size_a, size_a))
    result = distance(a, b)
    assert math.isfinite(result.distance)
    assert np.isfinite(result.normal).all() and np.isfinite(result.point_a).all()
    assert np.linalg.norm(result.normal) == pytest.approx(1.0, abs=1e-9)
    patch = vv.collision.contacts(a, b)
    assert np.isfinite(patch.points).all() and len(patch.points) <= 4


def test_epa_keeps_its_last_good_face_when_rounding_breaks_the_polytope():
    # A box pressed 1.3 mm into a cone's side, posed as a pile of mixed shapes had them (to
    # the bit: the breakage is rounding's): the polytope's new points fell almost in its
    # faces' planes, the nearest face came nearer than the one before — impossible for a
    # convex polytope growing outward — and EPA used to end with an infinite depth and no
    # normal, which turned a body of the pile into NaNs.
    no_hull = (np.zeros((0, 3)), np.zeros((0, 4)), np.zeros(0, np.int64), np.zeros(0, np.int64))
    box = (BOX, np.array([0.0, 0.08, 0.06, 0.05]), *no_hull,
           np.array([-1.7442973943380524, 0.27096553281986624, 0.9989881457086917]),
           np.array([[0.9343503268410063, 0.05461043222271722, -0.352146514145111],
                     [-0.2940744520580116, 0.6762908972859467, -0.6753893979734578],
                     [0.20127017508534417, 0.734607597932813, 0.6479521538512684]]))  # fmt: skip
    cone = (CONE, np.array([0.0, 0.08, 0.14, 0.0]), *no_hull,
            np.array([-1.7487637440747368, 0.3139585631014506, 0.8516152314195027]),
            np.array([[0.8345091250678202, -0.5172639823480564, -0.1898222661964897],
                      [0.31832975338027725, 0.7338084815233135, -0.6001593792962839],
                      [0.4497340194952938, 0.440412403333374, 0.7770303898167228]]))  # fmt: skip
    depth, nx, ny, nz, ax, ay, az, bx, by, bz = shape_distance(box, cone)
    # The same pair posed through the public shapes (other roundings) converges to 1.2789 mm;
    # the last good face here is within 2 µm of it.
    assert depth == pytest.approx(-1.2789e-3, abs=2e-6)
    normal = np.array([nx, ny, nz])
    assert np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-12)
    assert np.array([bx - ax, by - ay, bz - az]) == pytest.approx(depth * normal, abs=1e-9)
