"""Impulses between rigid bodies (collision.body_impulses): seed 003's formula by hand,
conservation of linear and angular momentum, restitution, Coulomb friction and the split
position correction."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from visviva.collision.body_impulses import correct_positions, prepare_contacts, solve_impulses


def _solve(body_a, body_b, point, normal, depth, restitution, friction, position, inverse_mass,
           inverse_inertia, v, w, *, iterations=1, resting_speed=0.0, h=0.01):  # fmt: skip
    count = len(body_a)
    arrays = dict(
        arm_a=np.zeros((count, 3)),
        arm_b=np.zeros((count, 3)),
        frame=np.zeros((count, 2, 3)),
        mass_n=np.zeros(count),
        mass_t=np.zeros((count, 2)),
        target=np.zeros(count),
    )
    body_a = np.array(body_a, dtype=np.int64)
    body_b = np.array(body_b, dtype=np.int64)
    point, normal = np.array(point, float), np.array(normal, float)
    prepare_contacts(body_a, body_b, point, normal, np.array(depth, float),
                     np.full(count, np.nan), np.zeros(count), np.array(restitution, float),
                     resting_speed, h,
                     position, inverse_mass, inverse_inertia, v, w,
                     *arrays.values())  # fmt: skip
    normal_impulse = np.zeros(count)
    tangent_impulse = np.zeros((count, 2))
    solve_impulses(body_a, body_b, normal, np.array(friction, float), arrays["arm_a"],
                   arrays["arm_b"], arrays["frame"], arrays["mass_n"], arrays["mass_t"],
                   arrays["target"], inverse_mass, inverse_inertia, v, w, normal_impulse,
                   tangent_impulse, iterations)  # fmt: skip
    return normal_impulse, tangent_impulse, arrays


def _box_inertia(mass, size):
    a, b, c = size
    return mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def test_an_off_centre_hit_against_the_world_is_seed_003s_impulse():
    # A 2 kg box of 1 × 0.5 × 0.8 m, turned, falls at 3 m/s and spins; its corner at arm r hits
    # the floor (normal +y from the world toward the box).
    mass, e = 2.0, 0.6
    rotation = Rotation.from_euler("xyz", [0.2, -0.4, 0.3]).as_matrix()
    inertia = rotation @ _box_inertia(mass, (1.0, 0.5, 0.8)) @ rotation.T
    inverse = np.linalg.inv(inertia)
    x = np.array([[0.3, 0.4, -0.1]])
    r = np.array([0.45, -0.4, 0.2])
    v = np.array([[0.5, -3.0, 0.2]])
    w = np.array([[0.3, -1.0, 2.0]])
    n = np.array([0.0, 1.0, 0.0])
    # Seed 003: j = −(1 + e) v_rel⁻ / (1/M + n·(I⁻¹(r × n)) × r), v_rel⁻ = n·(v + ω × r).
    v_rel = n @ (v[0] + np.cross(w[0], r))
    j = -(1 + e) * v_rel / (1 / mass + n @ np.cross(inverse @ np.cross(r, n), r))
    expected_v = v[0] + j * n / mass
    expected_w = w[0] + inverse @ np.cross(r, j * n)
    impulse, _, _ = _solve([-1], [0], [x[0] + r], [n], [0.0], [e], [0.0], x,
                           np.array([1 / mass]), inverse[None], v, w)  # fmt: skip
    assert impulse[0] == pytest.approx(j, rel=1e-13)
    assert v[0] == pytest.approx(expected_v, rel=1e-13)
    assert w[0] == pytest.approx(expected_w, rel=1e-13)
    # The contact point now leaves at e times its approach speed.
    assert n @ (v[0] + np.cross(w[0], r)) == pytest.approx(-e * v_rel, rel=1e-12)


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_sphere_on_sphere_conserves_momentum_and_scales_the_approach_by_e(e):
    # Two spheres hit off the line of their centres' velocities; the normal is along the line
    # of centres, so no torque: the 1-D closed form holds along n.
    rng = np.random.default_rng(1)
    mass = np.array([1.5, 4.0])
    radius = np.array([0.3, 0.5])
    x = np.array([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0]])
    n = (x[1] - x[0]) / np.linalg.norm(x[1] - x[0])
    point = x[0] + radius[0] * n
    v = rng.normal(size=(2, 3))
    v[0] += 3 * n
    w = rng.normal(size=(2, 3))
    inertia = np.array([0.4 * m * r * r * np.eye(3) for m, r in zip(mass, radius, strict=True)])
    inverse = np.linalg.inv(inertia)
    before_p = mass @ v
    before_l = sum(np.cross(x[i], mass[i] * v[i]) + inertia[i] @ w[i] for i in range(2))
    v_n = n @ (v[1] - v[0])
    assert v_n < 0
    _solve([0], [1], [point], [n], [0.0], [e], [0.0], x, 1 / mass, inverse, v, w)
    assert mass @ v == pytest.approx(before_p, abs=1e-12)
    after_l = sum(np.cross(x[i], mass[i] * v[i]) + inertia[i] @ w[i] for i in range(2))
    assert after_l == pytest.approx(before_l, abs=1e-12)
    assert n @ (v[1] - v[0]) == pytest.approx(-e * v_n, abs=1e-12)


def test_many_contacts_between_turning_bodies_conserve_angular_momentum():
    # Three boxes touching at several points, with friction: whatever the impulses, they come
    # in equal and opposite pairs at shared points, so P and L about the origin are kept.
    rng = np.random.default_rng(4)
    mass = np.array([1.0, 2.5, 0.7])
    x = rng.normal(size=(3, 3))
    rotations = Rotation.random(3, random_state=rng).as_matrix()
    inertia = np.array([
        rotations[i] @ _box_inertia(mass[i], rng.uniform(0.3, 1.0, size=3)) @ rotations[i].T
        for i in range(3)
    ])  # fmt: skip
    inverse = np.linalg.inv(inertia)
    v = rng.normal(size=(3, 3))
    w = rng.normal(size=(3, 3))
    pairs = [(0, 1), (0, 1), (1, 2), (0, 2), (1, 2)]
    points = [0.5 * (x[a] + x[b]) + 0.1 * rng.normal(size=3) for a, b in pairs]
    normals = []
    for a, b in pairs:
        d = x[b] - x[a]
        normals.append(d / np.linalg.norm(d))
    momentum = lambda: (mass @ v, sum(np.cross(x[i], mass[i] * v[i]) + inertia[i] @ w[i]  # noqa: E731
                                      for i in range(3)))  # fmt: skip
    p0, l0 = momentum()
    _solve([a for a, _ in pairs], [b for _, b in pairs], points, normals, [0.01] * 5, [0.3] * 5,
           [0.8] * 5, x, 1 / mass, inverse, v, w, iterations=20)  # fmt: skip
    p1, l1 = momentum()
    assert p1 == pytest.approx(p0, abs=1e-12)
    assert l1 == pytest.approx(l0, abs=1e-12)


def test_friction_stops_a_slow_slide_and_is_bounded_by_mu_lambda():
    # A 1 kg point-like body (huge inertia: no spin) slides on the floor at 0.05 m/s while
    # pressed into it at 1 m/s: the normal impulse is 1 N·s, so friction (μ = 0.2) can take
    # up to 0.2 N·s — more than the 0.05 N·s the sliding needs: it stops.
    v = np.array([[0.05, -1.0, 0.0]])
    w = np.zeros((1, 3))
    inverse = np.zeros((1, 3, 3))
    normal_impulse, tangent_impulse, _ = _solve(
        [-1], [0], [[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]], [0.0], [0.0], [0.2],
        np.array([[0.0, 0.5, 0.0]]), np.array([1.0]), inverse, v, w, iterations=10,
    )  # fmt: skip
    assert normal_impulse[0] == pytest.approx(1.0)
    assert v[0] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)
    # Faster sliding: friction takes exactly μ λ off the tangential speed.
    v = np.array([[3.0, -1.0, 0.0]])
    _, tangent_impulse, _ = _solve(
        [-1], [0], [[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]], [0.0], [0.0], [0.2],
        np.array([[0.0, 0.5, 0.0]]), np.array([1.0]), inverse, v, w, iterations=10,
    )  # fmt: skip
    assert np.hypot(*tangent_impulse[0]) == pytest.approx(0.2, rel=1e-12)
    assert v[0] == pytest.approx([2.8, 0.0, 0.0], abs=1e-12)


def test_targets_are_posed_on_the_depth_at_the_steps_start():
    # Depths are measured at the step's end (h = 0.01 s). Ending 5 mm apart at 0.5 m/s: it
    # started 1 cm apart and is free to go on. Ending 1 cm deep at 2 m/s: it touched within the
    # step, fast: it collides (e = 0.5). Ending 0.2 mm deep at 0.05 m/s, below the resting
    # speed 0.1 m/s: it started 0.3 mm apart and may close that gap only: -0.03 m/s. Ending
    # 1 mm deep at that speed it started 0.5 mm deep: it stops.
    cases = ((0.5, -0.005, -0.5), (2.0, 0.01, 1.0), (0.05, 2e-4, -0.03), (0.05, 1e-3, 0.0))
    for speed, depth, expected in cases:
        v = np.array([[0.0, -speed, 0.0]])
        _solve([-1], [0], [[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]], [depth], [0.5], [0.0],
               np.array([[0.0, 0.5, 0.0]]), np.array([1.0]), np.zeros((1, 3, 3)), v,
               np.zeros((1, 3)), iterations=4, resting_speed=0.1)  # fmt: skip
        assert v[0, 1] == pytest.approx(expected)


def test_position_correction_removes_the_excess_depth_and_keeps_the_centre_of_mass():
    # Two equal spheres 0.9 m apart overlapping by 10 cm along x, allowance 1 mm: after the
    # sweeps they overlap by 1 mm, each moved half the way, their centre of mass unmoved.
    inverse_inertia = np.zeros((2, 3, 3))
    body_a, body_b = np.array([0]), np.array([1])
    normal = np.array([[1.0, 0.0, 0.0]])
    shift, turn = np.zeros((2, 3)), np.zeros((2, 3))
    correct_positions(body_a, body_b, normal, np.array([0.1]), np.array([[0.5, 0.0, 0.0]]),
                      np.array([[-0.4, 0.0, 0.0]]), np.array([0.5]), np.array([1.0, 1.0]),
                      inverse_inertia, np.array([1e-3]), 0.8, 30, shift, turn)  # fmt: skip
    assert shift[1, 0] - shift[0, 0] == pytest.approx(0.099, rel=1e-9)
    assert shift[0] + shift[1] == pytest.approx(np.zeros(3), abs=1e-15)
