"""Contact manifolds (vv.collision.contacts): the right points, depths and normal for resting
shapes, checked against the geometry by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from visviva.collision import (
    Box,
    Capsule,
    ConvexHull,
    Cylinder,
    Plane,
    Sphere,
    contacts,
    distance,
)
from visviva.collision.manifold import CANDIDATES, contact_manifold
from visviva.collision.solids import posed_shape

FLOOR = Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))


def _quaternion(rotation: Rotation) -> tuple[float, ...]:
    x, y, z, w = rotation.as_quat()
    return (w, x, y, z)


def _sorted(points: np.ndarray) -> np.ndarray:
    return points[np.lexsort(points.T[::-1])]


def test_a_box_sunk_into_the_floor_touches_at_its_four_bottom_corners():
    box = Box(center=(1.0, 0.49, 2.0), size=(1.0, 1.0, 2.0))
    patch = contacts(FLOOR, box)
    assert patch.normal.tolist() == [0.0, 1.0, 0.0]
    assert patch.depths == pytest.approx([0.01] * 4, abs=1e-14)
    # Midway between the floor (y = 0) and the box's bottom (y = −0.01).
    expected = [[x, -0.005, z] for x in (0.5, 1.5) for z in (1.0, 3.0)]
    assert _sorted(patch.points) == pytest.approx(np.array(expected), abs=1e-14)


def test_a_tilted_box_touches_along_its_lowest_edge():
    # Tilted by θ about z, a cube of half edge h has its lowest edge h(cos θ + sin θ) below
    # its centre; put the centre 1 mm less high than that.
    theta, h = 0.3, 0.5
    reach = h * (math.cos(theta) + math.sin(theta))
    box = Box(
        center=(0.0, reach - 1e-3, 0.0),
        size=(1.0, 1.0, 1.0),
        orientation=_quaternion(Rotation.from_euler("z", theta)),
    )
    patch = contacts(FLOOR, box)
    assert len(patch.points) == 2
    assert patch.depths == pytest.approx([1e-3, 1e-3], abs=1e-12)
    assert sorted(patch.points[:, 2]) == pytest.approx([-0.5, 0.5])


def test_a_box_on_a_box_touches_where_their_faces_overlap():
    # The upper cube sticks out past the lower one's edge at x = 0.5: the patch is the overlap
    # of the two faces, x in [0.3, 0.5], z in [−0.5, 0.5].
    lower = Box(center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0))
    upper = Box(center=(0.8, 0.998, 0.0), size=(1.0, 1.0, 1.0))
    patch = contacts(lower, upper)
    assert patch.normal == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    assert patch.depths == pytest.approx([0.002] * 4, abs=1e-12)
    corners = sorted((round(p[0], 12), round(p[2], 12)) for p in patch.points)
    assert corners == [(0.3, -0.5), (0.3, 0.5), (0.5, -0.5), (0.5, 0.5)]
    # The same pair the other way round: the same points, the normal reversed.
    other = contacts(upper, lower)
    assert other.normal == pytest.approx([0.0, -1.0, 0.0], abs=1e-12)
    assert _sorted(other.points) == pytest.approx(_sorted(patch.points), abs=1e-12)


def test_a_standing_cylinder_touches_on_its_rim_and_a_lying_one_along_a_line():
    standing = Cylinder(center=(0.0, 0.999, 0.0), radius=0.4, height=2.0)
    patch = contacts(FLOOR, standing)
    assert len(patch.points) == 4
    assert np.hypot(patch.points[:, 0], patch.points[:, 2]) == pytest.approx([0.4] * 4)
    assert patch.depths == pytest.approx([1e-3] * 4, abs=1e-12)
    # Four rim points that span the disc: opposite pairs across the centre.
    assert np.abs(patch.points[:, [0, 2]].sum(axis=0)).max() < 1e-12
    lying = Cylinder(
        center=(0.0, 0.399, 0.0),
        radius=0.4,
        height=2.0,
        orientation=_quaternion(Rotation.from_euler("x", 90, degrees=True)),
    )
    line = contacts(FLOOR, lying)
    assert len(line.points) == 2
    assert sorted(line.points[:, 2]) == pytest.approx([-1.0, 1.0], abs=1e-12)


def test_a_capsule_lying_on_a_box_touches_at_both_ends_of_its_segment():
    table = Box(center=(0.0, -0.5, 0.0), size=(4.0, 1.0, 4.0))
    capsule = Capsule(
        center=(0.2, 0.25 - 0.004, 0.0),
        radius=0.25,
        height=1.0,
        orientation=_quaternion(Rotation.from_euler("z", 90, degrees=True)),
    )
    patch = contacts(table, capsule)
    assert len(patch.points) == 2
    assert sorted(patch.points[:, 0]) == pytest.approx([-0.3, 0.7], abs=1e-12)
    assert patch.depths == pytest.approx([0.004, 0.004], abs=1e-12)
    # Two parallel capsules side by side touch along the overlap of their segments.
    a = Capsule(center=(0.0, 0.0, 0.0), radius=0.2, height=2.0)
    b = Capsule(center=(0.39, 0.5, 0.0), radius=0.2, height=2.0)
    pair = contacts(a, b)
    assert len(pair.points) == 2
    assert sorted(pair.points[:, 1]) == pytest.approx([-0.5, 1.0], abs=1e-12)
    assert pair.depths == pytest.approx([0.01, 0.01], abs=1e-12)


def test_a_sphere_touches_at_one_point():
    patch = contacts(
        Box(center=(0.0, 0.0, 0.0), size=(2.0, 2.0, 2.0)), Sphere((0.2, 1.4, 0.1), 0.5)
    )
    assert len(patch.points) == 1
    assert patch.points[0] == pytest.approx([0.2, 0.95, 0.1], abs=1e-12)
    assert patch.depths == pytest.approx([0.1], abs=1e-12)


def test_a_many_sided_face_is_reduced_to_four_points_keeping_the_deepest():
    # A 24-sided prism lying on its cap, tilted a little: its cap's lowest vertex must survive.
    angles = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    ring = np.stack([np.cos(angles), np.zeros(24), np.sin(angles)], axis=1)
    prism = np.concatenate([ring, ring + [0.0, 0.5, 0.0]])
    tilt = Rotation.from_euler("x", 0.001)
    lowest = float((tilt.apply(prism)[:, 1]).min())
    hull = ConvexHull(prism, position=(0.0, -lowest - 5e-3, 0.0), orientation=_quaternion(tilt))
    patch = contacts(FLOOR, hull)
    assert len(patch.points) == 4
    assert patch.depths.max() == pytest.approx(5e-3, abs=1e-12)


def test_speculative_contacts_report_a_gap():
    box = Box(center=(0.0, 0.51, 0.0), size=(1.0, 1.0, 1.0))
    assert len(contacts(FLOOR, box).points) == 0
    near = contacts(FLOOR, box, max_separation=0.02)
    assert near.depths == pytest.approx([-0.01] * 4, abs=1e-12)


def test_a_face_far_off_the_normal_is_not_taken_as_the_reference():
    # A box's corner region 27 mm into a cylinder's side (from a pile of mixed shapes): the
    # normal of least penetration is 44° from the box's nearest face. Clipping against that
    # face used to give its normal and a 38 mm depth, which pushed the two along the wrong
    # direction and kept them overlapped; the nearest points stand instead.
    box = Box(center=(-0.3399, 0.176605, -0.353939), size=(0.16, 0.12, 0.1),
              orientation=(-0.562011, -0.183699, -0.387919, 0.707048))  # fmt: skip
    cylinder = Cylinder(center=(-0.293994, 0.251859, -0.439336), radius=0.07, height=0.12,
                        orientation=(-0.167001, 0.748689, 0.407317, 0.49565))  # fmt: skip
    least = distance(box, cylinder)
    patch = contacts(box, cylinder)
    assert least.distance == pytest.approx(-0.027257, abs=1e-6)
    assert patch.normal == pytest.approx(least.normal, abs=1e-12)
    assert patch.depths == pytest.approx([-least.distance], abs=1e-12)


def test_the_patch_is_never_shallower_than_the_shapes_depth():
    # In a pile of rocks (hulls) one's corner sat 4 mm inside another just beside the face
    # the manifold clipped against: clipping dropped it and left a point 1 µm apart, and the
    # solver held two overlapping rocks as if they barely touched. The contract: when the
    # clipped points are shallower than the separation's depth, its nearest points' pair
    # joins the patch. Here two boxes overlap by 1 mm face to face and the separation handed
    # to the manifold says 5 mm at a point: the patch keeps that point and depth.
    a = posed_shape(Box(center=(0.0, -0.5, 0.0), size=(1.0, 1.0, 1.0)))
    b = posed_shape(Box(center=(0.0, 0.499, 0.0), size=(1.0, 1.0, 1.0)))
    separation = (-0.005, 0.0, 1.0, 0.0, 0.1, 0.0, 0.1, 0.1, -0.005, 0.1)
    points = np.empty((CANDIDATES, 3))
    depths = np.empty(CANDIDATES)
    count, *normal = contact_manifold(a, b, separation, 0.0, points, depths)
    assert normal == pytest.approx([0.0, 1.0, 0.0])
    assert depths[:count].max() == pytest.approx(0.005, abs=1e-15)
    assert points[int(np.argmax(depths[:count]))] == pytest.approx([0.1, -0.0025, 0.1])
    assert np.sort(depths[:count])[:-1] == pytest.approx([0.001] * (count - 1), abs=1e-12)
