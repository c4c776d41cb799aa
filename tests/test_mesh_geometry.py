"""Mesh geometry under the mass properties: the closed-mesh check's fast edge pairing, the
self-intersection test and the ray-parity inside test."""

from __future__ import annotations

import numpy as np
import pytest

from mesh_shapes import box_mesh, cube_sphere, rotation_matrix, transformed
from visviva.errors import ModelError
from visviva.geometry import mesh_topology
from visviva.geometry.mesh_topology import check_closed_mesh, mesh_arrays
from visviva.geometry.point_in_mesh import InsideTest
from visviva.geometry.self_intersection import check_self_intersections, find_self_intersection


def merged(*meshes):
    vertices, triangles, offset = [], [], 0
    for v, t in meshes:
        vertices.append(v)
        triangles.append(t + offset)
        offset += len(v)
    return mesh_arrays(np.vstack(vertices), np.vstack(triangles))


def test_fast_edge_pairing_numbers_edges_as_the_general_table():
    _, triangles = cube_sphere(12)
    _, _, fast = check_closed_mesh(*cube_sphere(12))
    _, general = mesh_topology._edge_table(triangles.astype(np.int64))
    np.testing.assert_array_equal(fast, general)


def test_crossing_shells_are_found_and_touching_ones_are_not():
    box = box_mesh()
    # Overlapping at a generic offset: edges pierce faces.
    assert find_self_intersection(*merged(box, (box[0] + [0.5, 0.3, 0.2], box[1]))) is not None
    # Offset along the diagonal: every piercing passes exactly through a face's diagonal edge.
    assert find_self_intersection(*merged(box, (box[0] + 0.4, box[1]))) is not None
    # Turned: edges cross faces at general angles.
    turned = transformed(box[0], rotation_matrix([1.0, 1.0, 0.0], 0.6), [0.7, 0.1, 0.0])
    assert find_self_intersection(*merged(box, (turned, box[1]))) is not None
    # Apart, touching face to face, edge on face, or edge across edge: no crossing.
    for offset in ([2.0, 0.0, 0.0], [1.0, 0.3, 0.2], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0]):
        assert find_self_intersection(*merged(box, (box[0] + offset, box[1]))) is None, offset
    # A box turned 45° about x resting its lower edge on the top face (y = 0.5): a touching
    # line, through which no edge passes to the other side.
    diamond = transformed(box[0], rotation_matrix([1.0, 0.0, 0.0], np.pi / 4), 0.0)
    diamond = diamond + [0.2, 0.5 - diamond[:, 1].min(), 0.0]
    assert find_self_intersection(*merged(box, (diamond, box[1]))) is None
    # The same box lowered a little: now it cuts into the top face.
    assert find_self_intersection(*merged(box, (diamond - [0.0, 0.05, 0.0], box[1]))) is not None


def test_nested_shells_do_not_cross_and_a_probe_through_a_big_sphere_is_found():
    sphere = cube_sphere(40)  # 19,200 triangles
    vertices, triangles = mesh_arrays(*sphere)
    assert find_self_intersection(vertices, triangles) is None
    cavity = cube_sphere(10, 0.5)
    assert find_self_intersection(*merged(sphere, (cavity[0], cavity[1][:, ::-1]))) is None
    probe = box_mesh([0.05, 0.05, 0.05])
    poking = merged(sphere, (probe[0] + [0.0, 0.0, 1.0], probe[1]))  # straddles the surface
    pair = find_self_intersection(*poking)
    assert pair is not None and pair[0] < len(triangles) <= pair[1]
    with pytest.raises(ModelError, match=r"cross each other: entries .* near \[.*\] m"):
        check_self_intersections(*poking)


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_the_check_does_not_depend_on_units(scale):
    box = box_mesh()
    crossing = merged(box, (box[0] + [0.5, 0.3, 0.2], box[1]))
    touching = merged(box, (box[0] + [1.0, 0.3, 0.2], box[1]))
    assert find_self_intersection(crossing[0] * scale, crossing[1]) is not None
    assert find_self_intersection(touching[0] * scale, touching[1]) is None


def test_inside_test_on_a_cube_lattice_with_rays_through_edges_and_vertices():
    # Rays along +x from lattice points meet the cube's faces exactly on their diagonal edges
    # and corners: each must be counted once.
    vertices, triangles = mesh_arrays(*box_mesh())
    test = InsideTest.of(vertices, triangles)
    grid = np.array([-0.75, -0.5 + 1e-12, -0.25, 0.0, 0.25, 0.5 - 1e-12, 0.75])
    points = np.stack(np.meshgrid(grid, grid, grid, indexing="ij"), axis=-1).reshape(-1, 3)
    expected = np.all(np.abs(points) < 0.5, axis=1)
    np.testing.assert_array_equal(test.contains(points), expected)


def test_inside_test_matches_the_sphere_and_its_cavity():
    outer, inner = cube_sphere(24, 1.0), cube_sphere(24, 0.5)
    vertices, triangles = merged(outer, (inner[0], inner[1][:, ::-1]))
    test = InsideTest.of(vertices, triangles)
    rng = np.random.default_rng(0)
    points = rng.uniform(-1.2, 1.2, size=(200_000, 3))
    radius = np.linalg.norm(points, axis=1)
    # Away from both surfaces (the mesh lies within 0.3% of each sphere).
    clear = (np.abs(radius - 1.0) > 0.01) & (np.abs(radius - 0.5) > 0.01)
    expected = (radius < 1.0) & (radius > 0.5)
    np.testing.assert_array_equal(test.contains(points)[clear], expected[clear])
