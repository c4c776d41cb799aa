"""Walls (plane colliders other than floors) are drawn: cut to the picture's box, the near ones
left out of the video, every one translucent in the viewer."""

from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.viz.frame import drawn_bounds
from visviva.viz.walls import plane_in_box, wall_scenery, with_walls

BALL_PIT = Path(__file__).parents[1] / "examples" / "scenes" / "ball_pit.toml"


@pytest.mark.parametrize(
    "normal",
    [(1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (1.0, 1.0, 0.0), (0.3, -0.2, 0.9), (1.0, 1.0, 1.0)],
)
def test_a_plane_cut_by_a_box_is_a_convex_polygon_on_the_plane_inside_the_box(normal):
    normal = np.array(normal) / np.linalg.norm(normal)
    point = np.array([0.2, 0.1, -0.1])
    low, high = np.array([-1.0, -1.0, -1.0]), np.array([1.0, 2.0, 1.0])
    polygon = plane_in_box(point, normal, low, high)
    assert 3 <= polygon.shape[0] <= 6
    np.testing.assert_allclose((polygon - point) @ normal, 0.0, atol=1e-12)  # on the plane
    assert np.all(polygon >= low - 1e-12) and np.all(polygon <= high + 1e-12)  # in the box
    # Ordered counter-clockwise seen from the normal's side: every turn is to the left.
    for a, b, c in zip(polygon, np.roll(polygon, -1, 0), np.roll(polygon, -2, 0), strict=True):
        assert np.dot(np.cross(b - a, c - b), normal) > 0.0
    # A plane beside the box misses it.
    assert plane_in_box(np.array([5.0, 0, 0]), np.array([1.0, 0, 0]), low, high).shape == (0, 3)


def test_the_ball_pit_records_its_four_walls_and_the_video_draws_the_far_two():
    model = vv.load_model(BALL_PIT)
    recording = vv.Simulation(model).record(until=0.05)
    geometry = recording.geometry()
    walls = geometry.walls
    assert walls is not None and walls.point.shape == (4, 3)  # the floor is the ground
    np.testing.assert_allclose(np.linalg.norm(walls.normal, axis=1), 1.0)
    # A camera above and in front of the +x, +z corner is outside the +x and +z walls (whose
    # inward normals point to −x and −z): it sees the other two from inside, and only those.
    eye = np.array([10.0, 5.0, 10.0])
    inside = [np.dot(eye - p, n) > 0 for p, n in zip(walls.point, walls.normal, strict=True)]
    assert sum(inside) == 2
    seen = wall_scenery(walls, *drawn_bounds(geometry), eye)
    assert seen.count == 2
    drawn = with_walls(geometry, eye).scenery
    assert drawn.count == (0 if geometry.scenery is None else geometry.scenery.count) + 2


def test_the_viewer_draws_every_wall(tmp_path):
    recording = vv.Simulation(vv.load_model(BALL_PIT)).record(until=0.05)
    page = vv.viz.viewer.write_viewer(recording, tmp_path / "v.html").read_text()
    assert '"walls":{"count":4' in page
