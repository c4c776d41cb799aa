"""The neighbour grid against brute force: same sets on every kind of cloud, or a clean refusal.

The grid's neighbour relation is ``(xi − xj)² + (yi − yj)² + (zi − zj)² ≤ r²`` in float64,
evaluated in that order; the brute force here evaluates exactly that, so the comparisons are
of sets, with no tolerance, including points exactly on cell borders and exactly ``r`` apart.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numba import njit

import visviva as vv
from thread_counts import assert_same_bits, on_one_and_two_threads
from visviva.errors import ModelError
from visviva.geometry import neighbour_grid
from visviva.geometry.neighbour_cells import cell_of, cell_range, neighbour_runs
from visviva.geometry.neighbour_grid import PARALLEL_MIN_POINTS, NeighbourGrid, neighbours

# --------------------------------------------------------------------------------------------
# Brute force
# --------------------------------------------------------------------------------------------


def brute_matrix(points: np.ndarray, radius: float, alive: np.ndarray | None = None):
    """``near[i, j]``: j is a neighbour of i (i ≠ j, both alive), by the grid's formula."""
    n = points.shape[0]
    near = np.zeros((n, n), dtype=bool)
    r2 = radius * radius
    for lo in range(0, n, 512):
        d = points[lo : lo + 512, None, :] - points[None, :, :]
        dx, dy, dz = d[..., 0], d[..., 1], d[..., 2]
        near[lo : lo + 512] = dx * dx + dy * dy + dz * dz <= r2
    np.fill_diagonal(near, False)
    if alive is not None:
        near &= alive[:, None] & alive[None, :]
    return near


def assert_lists_match(start, index, points, radius, alive=None):
    near = brute_matrix(points, radius, alive)
    n = points.shape[0]
    assert start.shape == (n + 1,) and start[0] == 0
    assert index.shape == (start[-1],)
    for i in range(n):
        got = index[start[i] : start[i + 1]]
        expected = np.flatnonzero(near[i])
        assert got.tolist() == expected.tolist(), f"point {i}: {got} != {expected}"


def assert_pairs_match(first, second, points, radius, alive=None):
    near = brute_matrix(points, radius, alive)
    i, j = np.nonzero(np.triu(near))  # row-major: lexicographic order, i < j
    assert first.tolist() == i.tolist()
    assert second.tolist() == j.tolist()


def check_cloud(points, radius, alive=None, query_radius=None):
    grid = NeighbourGrid(radius)
    grid.update(points, alive)
    r = radius if query_radius is None else query_radius
    start, index = grid.neighbours(query_radius)
    assert_lists_match(start, index, points, r, alive)
    first, second = grid.pairs(query_radius)
    assert_pairs_match(first, second, points, r, alive)
    return start, index


# --------------------------------------------------------------------------------------------
# Clouds
# --------------------------------------------------------------------------------------------

RNG = np.random.default_rng(20261125)


def uniform_cloud(n: int, neighbours_wanted: float, radius: float = 1.0) -> np.ndarray:
    side = (n * (4.0 / 3.0) * np.pi * radius**3 / neighbours_wanted) ** (1.0 / 3.0)
    return RNG.uniform(0.0, side, size=(n, 3))


def test_uniform_cloud():
    points = uniform_cloud(2000, 15.0)
    _, index = check_cloud(points, 1.0)
    assert 10 < index.size / points.shape[0] < 20  # the density the test meant


def test_clustered_cloud():
    centres = RNG.uniform(-5.0, 5.0, size=(6, 3))
    blobs = [c + RNG.normal(scale=0.2, size=(250, 3)) for c in centres]
    background = RNG.uniform(-8.0, 8.0, size=(300, 3))
    points = np.concatenate([*blobs, background])
    start, _ = check_cloud(points, 0.3)
    assert np.diff(start).max() > 100  # the blobs are dense


def test_points_on_cell_borders():
    """Coordinates exact multiples of the cell size, and of the radius: exact ties at r and h."""
    grid = NeighbourGrid(1.0)
    on_cells = RNG.integers(-6, 6, size=(1500, 3)) * grid.cell_size
    check_cloud(on_cells, 1.0)
    on_radius = RNG.integers(-6, 6, size=(1500, 3)).astype(float)
    _, index = check_cloud(on_radius, 1.0)
    assert index.size > 0  # axis neighbours exactly r apart count
    tenths = RNG.integers(-20, 20, size=(1500, 3)) * 0.1  # 0.1 is not exact in binary
    check_cloud(tenths, 0.1)


def test_duplicates():
    base = RNG.uniform(0.0, 3.0, size=(200, 3))
    points = np.concatenate([base, base, base[:50], np.zeros((40, 3))])
    start, index = check_cloud(points, 0.5)
    # A point 200 rows on is the same point: a neighbour, at distance 0.
    assert 200 in index[start[0] : start[1]].tolist()


def test_far_from_origin():
    points = uniform_cloud(1500, 12.0, radius=0.01) + np.array([1e6, -2e6, 3e6])
    check_cloud(points, 0.01)


def test_negative_coordinates():
    points = -uniform_cloud(1500, 12.0) - 0.5
    check_cloud(points, 1.0)
    straddling = uniform_cloud(1500, 12.0) - 5.0  # across every zero plane
    check_cloud(straddling, 1.0)


def test_flat_cloud():
    points = uniform_cloud(1500, 12.0)
    points[:, 2] = 0.0
    check_cloud(points, 1.0)


def test_query_radius_smaller_than_the_grid():
    points = uniform_cloud(1500, 30.0)
    for query in (0.9, 0.5, 0.123, 1e-3):
        check_cloud(points, 1.0, query_radius=query)
    # One grid, queries alternating radii: the pairs found for one radius are not reused.
    grid = NeighbourGrid(1.0)
    grid.update(points)
    for query in (0.5, 1.0, None, 0.5, 0.7):
        start, index = grid.neighbours(query)
        assert_lists_match(start, index, points, 1.0 if query is None else query)


def test_lists_ascending_without_the_point_itself():
    points = uniform_cloud(1500, 20.0)
    start, index = neighbours(points, 1.0)
    for i in range(points.shape[0]):
        own = index[start[i] : start[i + 1]]
        assert i not in own
        assert np.all(np.diff(own) > 0)


def test_dead_points_neither_have_nor_are_neighbours():
    points = uniform_cloud(2000, 15.0)
    alive = RNG.random(2000) < 0.7
    start, index = check_cloud(points, 1.0, alive=alive)
    dead = np.flatnonzero(~alive)
    assert np.all(start[dead + 1] == start[dead])
    assert not np.isin(index, dead).any()
    grid = NeighbourGrid(1.0)
    grid.update(points, alive)
    assert grid.count == alive.sum()
    # Dead rows are not looked at: they may hold anything.
    points[~alive] = np.nan
    grid.update(points, alive)
    assert np.array_equal(grid.neighbours()[1], index)


def test_empty_and_all_dead():
    start, index = neighbours(np.zeros((0, 3)), 1.0)
    assert start.tolist() == [0] and index.size == 0
    grid = NeighbourGrid(1.0)
    grid.update(np.zeros((0, 3)))
    first, second = grid.pairs()
    assert first.size == second.size == 0
    grid.update(np.ones((5, 3)), alive=np.zeros(5, dtype=bool))
    start, index = grid.neighbours()
    assert start.tolist() == [0] * 6 and index.size == 0
    assert grid.count == 0


def test_public_entry_point():
    points = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [2.0, 0.0, 0.0]])
    start, index = vv.particles.neighbours(points, 1.0)
    assert start.tolist() == [0, 1, 2, 2] and index.tolist() == [1, 0]
    assert start.flags.writeable  # the function's results are the caller's own
    grid = vv.particles.NeighbourGrid(1.0)
    grid.update(points.tolist())  # any array-like
    view_start, view_index = grid.neighbours()
    assert not view_start.flags.writeable and not view_index.flags.writeable


def test_a_grid_follows_a_moving_cloud():
    """One grid over many steps, the cloud changing size: every step right, buffers reused."""
    grid = NeighbourGrid(1.0)
    points = uniform_cloud(1200, 15.0)
    for step in range(6):
        n = (1200, 1200, 700, 1500, 1500, 0)[step]
        points = uniform_cloud(n, 15.0) if n != points.shape[0] else points + 0.05
        grid.update(points)
        start, index = grid.neighbours()
        assert_lists_match(start, index, points, 1.0)
        first, second = grid.pairs()
        assert_pairs_match(first, second, points, 1.0)
    grid.update(uniform_cloud(1500, 15.0))
    before = grid.arrays.x.base
    grid.update(uniform_cloud(1500, 15.0))
    assert grid.arrays.x.base is before  # same N: no new buffer


# --------------------------------------------------------------------------------------------
# The kernel pattern of the module docstring
# --------------------------------------------------------------------------------------------


@njit
def _count_by_runs(g, radius, counts):
    r2 = radius * radius
    runs = np.empty((27, 2), dtype=np.int64)
    for s in range(g.order.shape[0]):
        cx, cy, cz = cell_of(g.x[s], g.y[s], g.z[s], g.inv_cell)
        found = 0
        for k in range(neighbour_runs(g, cx, cy, cz, runs)):
            for t in range(runs[k, 0], runs[k, 1]):
                ex, ey, ez = g.x[s] - g.x[t], g.y[s] - g.y[t], g.z[s] - g.z[t]
                if t != s and ex * ex + ey * ey + ez * ez <= r2:
                    found += 1
        counts[g.order[s]] = found


@njit
def _count_by_cells(g, radius, counts):
    r2 = radius * radius
    for s in range(g.order.shape[0]):
        cx, cy, cz = cell_of(g.x[s], g.y[s], g.z[s], g.inv_cell)
        found = 0
        for dz in range(-1, 2):
            for dy in range(-1, 2):
                for dx in range(-1, 2):
                    begin, end = cell_range(g, cx + dx, cy + dy, cz + dz)
                    for t in range(begin, end):
                        ex, ey, ez = g.x[s] - g.x[t], g.y[s] - g.y[t], g.z[s] - g.z[t]
                        if t != s and ex * ex + ey * ey + ez * ez <= r2:
                            found += 1
        counts[g.order[s]] = found


def test_kernel_pattern_counts_each_neighbour_once():
    points = np.concatenate([uniform_cloud(1500, 15.0), RNG.integers(0, 5, (300, 3)) * 1.0])
    alive = RNG.random(points.shape[0]) < 0.9
    grid = NeighbourGrid(1.0)
    grid.update(points, alive)
    expected = brute_matrix(points, 1.0, alive).sum(axis=1)
    for kernel in (_count_by_runs, _count_by_cells):
        counts = np.zeros(points.shape[0], dtype=np.int64)
        kernel(grid.arrays, 1.0, counts)
        assert np.array_equal(counts, expected)


# --------------------------------------------------------------------------------------------
# Determinism
# --------------------------------------------------------------------------------------------


def test_same_arrays_whatever_the_thread_count(monkeypatch):
    """The parallel rebuild and search on 1 and 2 threads, and the serial ones, agree bit
    for bit (the sort is stable, so its result is unique)."""
    points = uniform_cloud(3 * PARALLEL_MIN_POINTS // 2, 15.0)
    alive = RNG.random(points.shape[0]) < 0.95

    def run():
        grid = NeighbourGrid(1.0)
        grid.update(points, alive)
        arrays = tuple(np.array(a, copy=True) for a in grid.arrays[:5])
        lists = tuple(np.array(a, copy=True) for a in grid.neighbours())
        pairs = tuple(np.array(a, copy=True) for a in grid.pairs())
        return arrays + lists + pairs

    results = on_one_and_two_threads(run)
    monkeypatch.setattr(neighbour_grid, "PARALLEL_MIN_POINTS", 10**12)
    results.append(run())
    assert_same_bits(results)


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("radius", "words"),
    [
        (0.0, "`radius` must be positive"),
        (-1.0, "`radius` must be positive"),
        (float("nan"), "`radius` must be finite"),
        (float("inf"), "`radius` must be finite"),
        (True, "`radius` must be a real number"),
        ("1", "`radius` must be a real number"),
        (1e-200, r"`radius` must lie between 1e-150 and 1e\+150 m"),
        (1e200, "`radius` must lie between"),
    ],
)
def test_bad_radius(radius, words):
    with pytest.raises(ModelError, match=words):
        NeighbourGrid(radius)
    with pytest.raises(ModelError, match=words):
        neighbours(np.zeros((2, 3)), radius)


def test_bad_positions():
    grid = NeighbourGrid(1.0)
    with pytest.raises(
        ModelError, match=r"`positions` must have shape \(N, 3\) \(got shape \(4,\)"
    ):
        grid.update(np.zeros(4))
    with pytest.raises(ModelError, match=r"got shape \(5, 2\)"):
        grid.update(np.zeros((5, 2)))
    with pytest.raises(ModelError, match="`positions` must be an \\(N, 3\\) array of real"):
        grid.update(np.zeros((2, 3), dtype=complex))
    with pytest.raises(ModelError, match="`positions` must be an \\(N, 3\\) array"):
        grid.update([[0.0, 0.0, 0.0], [1.0, 2.0]])
    bad = np.zeros((10, 3))
    bad[7, 1] = np.nan
    with pytest.raises(ModelError, match=r"`positions` must be finite; point 7 is \[0.0, nan"):
        grid.update(bad)
    bad[7, 1] = np.inf
    with pytest.raises(ModelError, match="point 7 is"):
        neighbours(bad, 1.0)
    far = np.zeros((10, 3))
    far[3, 2] = 2e12
    with pytest.raises(ModelError, match=r"`positions`: point 3 at .* beyond the grid's reach"):
        grid.update(far)
    with pytest.raises(ModelError, match="larger radius"):
        neighbours(np.full((2, 3), 1e151), 1e140)
    # A refused update leaves an empty grid, not half of one.
    assert grid.count == 0 and grid.neighbours()[1].size == 0


def test_bad_alive_and_query_radius():
    grid = NeighbourGrid(1.0)
    with pytest.raises(ModelError, match=r"`alive` must have shape \(3,\).*\(got shape \(4,\)\)"):
        grid.update(np.zeros((3, 3)), alive=np.ones(4, dtype=bool))
    with pytest.raises(ModelError, match=r"`alive` must be a boolean mask.*int64"):
        grid.update(np.zeros((3, 3)), alive=np.ones(3, dtype=np.int64))
    grid.update(np.zeros((3, 3)))
    with pytest.raises(ModelError, match=r"`radius` of a query must not exceed .* 1.0 m"):
        grid.neighbours(1.5)
    with pytest.raises(ModelError, match="`radius` must be positive"):
        grid.pairs(-0.5)


# --------------------------------------------------------------------------------------------
# Generated clouds: brute force's sets, or a clean ModelError
# --------------------------------------------------------------------------------------------

magnitudes = st.sampled_from(
    [1e-300, 1e-160, 1e-140, 1e-9, 1e-3, 1.0, 1e3, 1e9, 1e140, 1e160, 1e300]
)


@st.composite
def clouds(draw):
    n = draw(st.integers(0, 60))
    scale = draw(magnitudes)
    offset = draw(st.sampled_from([0.0, 1.0, -1e6, 1e12, 1e200])) * draw(st.sampled_from([0, 1]))
    # Small integers times the scale (ties, duplicates, cell borders) or uniform reals.
    if draw(st.booleans()):
        coords = draw(st.lists(st.integers(-8, 8), min_size=3 * n, max_size=3 * n))
    else:
        coords = draw(
            st.lists(
                st.floats(-8.0, 8.0, allow_nan=False, allow_infinity=False),
                min_size=3 * n,
                max_size=3 * n,
            )
        )
    points = np.array(coords, dtype=float).reshape(n, 3) * scale + offset
    kind = draw(st.sampled_from(["spacing", "scaled", "any"]))
    if kind == "spacing":  # exactly the lattice spacing, or a simple multiple of it
        radius = scale * draw(st.sampled_from([0.5, 1.0, 2.0]))
    else:
        radius = draw(st.floats(0.1, 4.0)) * (scale if kind == "scaled" else draw(magnitudes))
    alive = np.array(draw(st.lists(st.booleans(), min_size=n, max_size=n)), dtype=bool)
    return points, radius, (alive if draw(st.booleans()) else None)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(clouds())
def test_generated_clouds_match_brute_force_or_are_refused(cloud):
    points, radius, alive = cloud
    try:
        grid = NeighbourGrid(radius)
        grid.update(points, alive)
    except ModelError as error:
        message = str(error)
        assert "`radius`" in message or "`positions`" in message
        return
    with np.errstate(over="raise", under="ignore", invalid="raise"):
        start, index = grid.neighbours()
        assert_lists_match(start, index, points, radius, alive)
        first, second = grid.pairs()
        assert_pairs_match(first, second, points, radius, alive)
