"""Two boxes by separating axes (collision.box_box) against the general path (GJK, EPA and the
clipped manifold) and against hand geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from visviva.collision.box_box import TIE, box_box_contacts, clip_work
from visviva.collision.convex import BOX
from visviva.collision.manifold import CANDIDATES, MAX_CONTACTS
from visviva.collision.separation import shape_distance

NO_HULL = (np.zeros((0, 3)), np.zeros((0, 4)), np.zeros(0, np.int64), np.zeros(0, np.int64))


def _contacts(pa, ra, ea, pb, rb, eb, reach=0.0):
    points = np.full((CANDIDATES, 3), np.nan)
    depths = np.full(CANDIDATES, np.nan)
    count, *normal = box_box_contacts(np.asarray(pa, float), np.asarray(ra, float),
                                      np.asarray(ea, float), np.asarray(pb, float),
                                      np.asarray(rb, float), np.asarray(eb, float), reach,
                                      points, depths, clip_work())  # fmt: skip
    return count, np.array(normal), points[: max(count, 0)], depths[: max(count, 0)]


def _distance(pa, ra, ea, pb, rb, eb):
    """GJK/EPA's signed distance of the two boxes."""
    shape_a = (BOX, np.array([0.0, *ea]), *NO_HULL, np.asarray(pa, float), np.asarray(ra, float))
    shape_b = (BOX, np.array([0.0, *eb]), *NO_HULL, np.asarray(pb, float), np.asarray(rb, float))
    return shape_distance(shape_a, shape_b)[0]


def _outside(point, centre, rotation, extents):
    """Signed distance-like measure of a point from a box's surface: 0 on it (the largest of
    the per-axis excesses |local| − e; exact on the surface and inside)."""
    local = np.abs(rotation.T @ (point - centre)) - extents
    return local.max()


def _random_pair(rng):
    ea, eb = rng.uniform(0.1, 1.0, 3), rng.uniform(0.1, 1.0, 3)
    ra = Rotation.random(random_state=rng).as_matrix()
    rb = ra.copy() if rng.random() < 0.3 else Rotation.random(random_state=rng).as_matrix()
    pa = rng.normal(size=3)
    pb = pa + rng.normal(size=3)
    return pa, ra, ea, pb, rb, eb


def test_random_overlapping_boxes_match_epa_and_touch_both_surfaces():
    # EPA's depth is the exact smallest push apart; the axes agree with it up to the tie
    # tolerance that keeps a face over an edge of nearly the same depth.
    rng = np.random.default_rng(27)
    overlapping = 0
    for _ in range(1500):
        pa, ra, ea, pb, rb, eb = _random_pair(rng)
        distance = _distance(pa, ra, ea, pb, rb, eb)
        if distance >= 0.0:
            continue
        count, normal, points, depths = _contacts(pa, ra, ea, pb, rb, eb)
        if count < 0:  # the general path answers these (none expected overlapping)
            pytest.fail("overlapping boxes left to the general path")
        overlapping += 1
        assert 1 <= count <= MAX_CONTACTS
        assert np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-12)
        tie = TIE * min(ea.min(), eb.min())
        assert depths.max() == pytest.approx(-distance, abs=tie + 1e-9)
        for point, depth in zip(points, depths, strict=True):
            # a = p + ½ d n on A's surface, b = p − ½ d n on B's (b − a = −d n).
            assert _outside(point + 0.5 * depth * normal, pa, ra, ea) == pytest.approx(0, abs=1e-9)
            assert _outside(point - 0.5 * depth * normal, pb, rb, eb) == pytest.approx(0, abs=1e-9)
    assert overlapping > 300


def test_separated_boxes_report_a_gap_no_larger_than_their_distance():
    # An axis's gap is a lower bound of the distance (equal on a face's axis): speculative
    # contacts never claim more room than there is.
    rng = np.random.default_rng(28)
    reach = 0.3
    seen = 0
    for _ in range(1500):
        pa, ra, ea, pb, rb, eb = _random_pair(rng)
        distance = _distance(pa, ra, ea, pb, rb, eb)
        count, _, _, depths = _contacts(pa, ra, ea, pb, rb, eb, reach)
        if distance > reach:
            assert count <= 0 or -depths.max() <= distance + 1e-9
            continue
        if distance > 0.0 and count > 0:
            seen += 1
            assert -depths.max() <= distance + 1e-9
    assert seen > 50


def test_boxes_beyond_reach_along_an_axis_have_no_contacts():
    count, *_ = _contacts([0, 0, 0], np.eye(3), [0.5] * 3, [0, 1.2, 0], np.eye(3), [0.5] * 3, 0.1)
    assert count == 0


def test_a_box_resting_on_a_box_touches_at_the_four_corners_of_the_overlap():
    # A 1 m cube sunk 1 cm into a 2 m × 1 m × 2 m slab, shifted half a metre in x: the
    # overlap of the faces is the cube's bottom, x ∈ [0, 1], z ∈ [−0.5, 0.5].
    count, normal, points, depths = _contacts([0, 0, 0], np.eye(3), [1.0, 0.5, 1.0],
                                              [0.5, 0.99, 0], np.eye(3), [0.5] * 3)  # fmt: skip
    assert count == 4
    assert normal.tolist() == [0.0, 1.0, 0.0]
    assert depths == pytest.approx([0.01] * 4, abs=1e-12)
    corners = sorted((round(p[0], 12), round(p[2], 12)) for p in points)
    assert corners == [(0.0, -0.5), (0.0, 0.5), (1.0, -0.5), (1.0, 0.5)]
    assert points[:, 1] == pytest.approx([0.495] * 4, abs=1e-12)  # midway: 0.5 and 0.49


def test_a_turned_box_on_a_box_is_clipped_to_the_face_and_kept_to_four_points():
    # The top cube turned 45° about y: its bottom square cut by the lower cube's top square
    # is an octagon; four points are kept, all at the same depth.
    turn = Rotation.from_euler("y", 45, degrees=True).as_matrix()
    count, normal, points, depths = _contacts([0, 0, 0], np.eye(3), [0.5] * 3,
                                              [0, 0.98, 0], turn, [0.5] * 3)  # fmt: skip
    assert count == 4
    assert normal == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    assert depths == pytest.approx([0.02] * 4, abs=1e-12)
    assert np.abs(points[:, [0, 2]]).max() <= 0.5 + 1e-12


def test_crossed_edges_touch_at_one_point_between_them():
    # Two unit cubes each turned 45° (A about z, B about x) meet edge to edge: A's top edge
    # runs along z at height √½, B's bottom edge along x at its centre's height less √½; the
    # centre is put so that they overlap by 1 cm.
    half = math.sqrt(0.5)
    ra = Rotation.from_euler("z", 45, degrees=True).as_matrix()
    rb = Rotation.from_euler("x", 45, degrees=True).as_matrix()
    pb_y = 2 * half - 0.01
    count, normal, points, depths = _contacts([0, 0, 0], ra, [0.5] * 3, [0, pb_y, 0], rb,
                                              [0.5] * 3)  # fmt: skip
    assert count == 1
    assert normal == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)
    assert depths[0] == pytest.approx(0.01, abs=1e-12)
    assert points[0] == pytest.approx([0.0, half - 0.005, 0.0], abs=1e-12)


def test_the_normal_points_from_a_toward_b_whichever_face_is_the_reference():
    # The same two boxes both ways round: one normal is the other's opposite.
    rng = np.random.default_rng(5)
    for _ in range(200):
        pa, ra, ea, pb, rb, eb = _random_pair(rng)
        forward = _contacts(pa, ra, ea, pb, rb, eb, 0.05)
        backward = _contacts(pb, rb, eb, pa, ra, ea, 0.05)
        if forward[0] > 0:
            assert np.dot(forward[1], pb - pa) > 0.0 or np.allclose(pa, pb)
        if forward[0] > 0 and backward[0] > 0:
            assert forward[3].max() == pytest.approx(backward[3].max(), abs=TIE * 2)
