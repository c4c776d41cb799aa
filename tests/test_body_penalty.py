"""Penalty contact for rigid bodies (collision.body_penalty): springs at the overlapping
contact points, checked against statics, energy and Coulomb's law."""

from __future__ import annotations

import math

import numpy as np
import pytest

import visviva as vv

H = 1.0 / 1000.0
G = 9.81


def _scene(stiffness, damping, *, method="velocity_verlet", mu=0.5, duration=2.0):
    builder = vv.SceneBuilder(name="penalty")
    builder.set_integration(method=method, dt=H, duration=duration)
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), friction=mu)
    return builder


def test_a_box_rests_sunk_by_its_weight_over_four_springs():
    # Statics: a box on its face rests on four contact points, each a spring k, so it sinks
    # d = M g / (4 k); damped critically it settles there and does not turn.
    k = 2.0e5
    builder = _scene(k, None)
    builder.add_body("box", size=(0.4, 0.2, 0.4), density=500.0, position=(0, 0.1, 0),
                     friction=0.5)  # fmt: skip
    builder.add_body_contacts(response="penalty", stiffness=k)
    simulation = vv.Simulation(builder.build())
    simulation.step(1500)
    mass = 500.0 * 0.4 * 0.2 * 0.4
    sink = 0.1 - simulation.state["body_position"][0, 1]
    assert sink == pytest.approx(mass * G / (4 * k), rel=0.01)
    assert simulation.state["body_orientation"][0] == pytest.approx([1, 0, 0, 0], abs=1e-9)
    assert np.abs(simulation.state["body_momentum"]).max() < 1e-6 * mass


def test_an_undamped_ball_bounces_back_to_its_drop_height():
    # With c = 0 the spring gives back what it took: ½ m v² = m g h before and after, so the
    # ball rises again to h. The force switches on within a step (a kink, not a smooth
    # force), so velocity Verlet keeps the energy to O(h ω) per contact, not O(h²): with
    # ω = √(k/m) = 155 rad/s and h = 1 ms, within 1.5 % (measured 0.8 %).
    builder = _scene(1e5, 0.0)
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(0, 1.1, 0))
    builder.add_body_contacts(response="penalty", stiffness=1e5, damping=0.0)
    simulation = vv.Simulation(builder.build())
    heights = []
    for _ in range(1000):
        simulation.step(1)
        heights.append(float(simulation.state["body_position"][0, 1]) - 0.1)
    heights = np.array(heights)
    bounce = int(np.argmin(heights[:500]))
    # It sank into the floor, which is the penalty's way: about √(2 m g h / k) = 2.9 cm.
    assert heights[bounce] == pytest.approx(-math.sqrt(2 * 4.18879 * G * 1.0 / 1e5), rel=0.05)
    assert heights[bounce:].max() == pytest.approx(1.0, rel=0.015)


def test_a_sliding_box_stops_where_coulomb_says():
    # Kinetic friction μ M g decelerates it: it stops after v²/(2 μ g) (the viscous part
    # below the cone acts only at the very end: within 2 %).
    mu, v = 0.4, 2.0
    builder = _scene(2e5, None, mu=mu, duration=1.5)
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=1000.0, position=(0, 0.1, 0),
                     velocity=(v, 0, 0), friction=mu)  # fmt: skip
    builder.add_body_contacts(response="penalty", stiffness=2e5, friction=mu)
    simulation = vv.Simulation(builder.build())
    simulation.step(1500)
    travelled = simulation.state["body_position"][0, 0]
    assert travelled == pytest.approx(v * v / (2 * mu * G), rel=0.02)


def test_penalty_needs_a_stiffness_and_no_particles():
    builder = _scene(1.0, None)
    builder.add_body("sphere", radius=0.1, density=1000.0, position=(0, 1, 0))
    builder.add_body_contacts(response="penalty")
    with pytest.raises(vv.SceneError, match="stiffness"):
        builder.build()


def test_the_penalty_is_the_derivative_of_its_potential():
    # F = −∂U/∂x for c = 0: the force on a sunk box equals the finite difference of
    # U = ½ k Σ d² along y (central, step 1e-7 m).
    k = 1e5
    builder = _scene(k, 0.0)
    builder.add_body("box", size=(0.4, 0.2, 0.4), density=500.0, position=(0.0, 0.099, 0.0),
                     orientation=(math.cos(0.05), math.sin(0.05), 0.0, 0.0))  # fmt: skip
    builder.add_body_contacts(response="penalty", stiffness=k, damping=0.0)
    model = builder.build()
    penalty = next(f for f in model.body_forces if type(f).__name__ == "BodyPenalty")
    state = vv.Simulation(model).state
    x, q = np.array(state["body_position"]), np.array(state["body_orientation"])
    zero = np.zeros((1, 3))
    force, torque = np.zeros((1, 3)), np.zeros((1, 3))
    penalty.accumulate_wrench(0.0, x, q, zero, zero, force, torque)
    step = 1e-7
    up, down = x.copy(), x.copy()
    up[0, 1] += step
    down[0, 1] -= step
    slope = (penalty.potential(0.0, up, q) - penalty.potential(0.0, down, q)) / (2 * step)
    assert force[0, 1] == pytest.approx(-slope, rel=1e-6)
