"""Free rigid bodies stepped through the shared integrators, tested against physics.

A torque-free body keeps its angular momentum L exactly (L' = τ = 0) and its kinetic energy
T = ½ Πᵀ I⁻¹ Π (Π = Rᵀ L); its angular velocity ω = R I⁻¹ Rᵀ L is not conserved. Spun about
its intermediate principal axis it flips over and over (Dzhanibekov), about the largest or
smallest it does not. The symplectic methods drift the orientation by the splitting of
Dullweber, Leimkuhler & McLachlan (1997): exact rotations, so the quaternion stays unit to
round-off and the energy error oscillates within O(h²) without drift; the Runge–Kutta methods
step q' = ½ ω ⊗ q linearly, which moves the quaternion off the unit sphere.
"""

import numpy as np
import pytest

import visviva as vv
from visviva.errors import ModelError
from visviva.geometry.quaternions import (
    matrix_quaternion,
    quaternion_matrix,
    quaternion_multiply,
)
from visviva.ode.state import Layout, PartView, State
from visviva.ode.system import SecondOrderSystem
from visviva.rigid.motion import BodyMotion

INERTIA = (1.0, 2.0, 3.0)  # kg·m², principal moments of an asymmetric body
MASS = 2.0  # kg


def _free_body(omega_body, orientation=(1.0, 0.0, 0.0, 0.0), inertia=INERTIA, particles=0):
    """A torque-free body (after ``particles`` free particles) spinning at ``omega_body``
    [rad/s] in its own frame: the system and its state."""
    n = 3 * particles
    motion = BodyMotion(n, np.array([MASS]), np.array([inertia]))
    q0 = np.asarray(orientation, dtype=np.float64)
    q0 = q0 / np.linalg.norm(q0)
    angular_momentum = quaternion_matrix(q0) @ (np.array(inertia) * np.array(omega_body))
    q = np.concatenate([np.arange(n, dtype=np.float64), [0.5, 1.0, -0.5], q0])
    v = np.concatenate([np.ones(n), [0.2, 0.0, 0.0], angular_momentum])
    layout = Layout(
        True,
        (
            PartView("body_position", 0, n, n + 3, (1, 3), "m"),
            PartView("body_orientation", 0, n + 3, n + 7, (1, 4)),
            PartView("body_momentum", 1, n, n + 3, (1, 3), "kg m/s"),
            PartView("body_angular_momentum", 1, n + 3, n + 6, (1, 3), "kg m^2/s"),
        ),
    )
    system = SecondOrderSystem(
        lambda t, q, v: np.zeros_like(v), velocity_dependent=False, kinematics=motion,
        layout=layout,
    )  # fmt: skip
    return system, State(0.0, (q, v), layout), motion


def _run(method, state, system, h, steps, watch=None):
    integrator = vv.integrators.get(method)
    integrator.check(system)
    for _ in range(steps):
        state = integrator.step(system, state, h)
        if watch is not None:
            watch(state)
    return state


def _body_frame_spin(state, motion):
    """ω in the body frame, (3,)."""
    q, v = state.parts
    orientation = q[-4:] / np.linalg.norm(q[-4:])
    return quaternion_matrix(orientation).T @ motion.angular_velocity(q, v)[0]


@pytest.mark.parametrize("h", [0.02, 0.01])
def test_a_free_tumbling_body_keeps_l_exactly_and_its_energy_within_order_h_squared(h):
    """Default (symplectic Euler) over 100 s: L unchanged to round-off, T never more than
    1 % above its start — in fact within c h² of it, c measured 0.031 (3.1e-6 at h = 0.01),
    with no drift — and ω, which is not conserved, changes by order one."""
    system, state, motion = _free_body((1.0, 2.0, 3.0))
    start_l = state.parts[1][-3:].copy()
    start_t = motion.kinetic_energy(*state.parts)
    start_omega = motion.angular_velocity(*state.parts)[0]
    energies, omegas = [], []

    def watch(s):
        energies.append(motion.kinetic_energy(*s.parts))
        omegas.append(motion.angular_velocity(*s.parts)[0])

    end = _run("symplectic_euler", state, system, h, round(100.0 / h), watch)
    np.testing.assert_allclose(end.parts[1][-3:], start_l, rtol=0, atol=1e-12)
    error = (np.array(energies) - start_t) / start_t
    assert error.max() <= 0.01  # the bound
    assert np.abs(error).max() <= 0.05 * h**2  # O(h²), the splitting's order
    # No drift: the last tenth's mean error is no larger than the first tenth's spread allows.
    tenth = len(error) // 10
    assert abs(error[-tenth:].mean() - error[:tenth].mean()) <= 0.05 * h**2
    assert np.abs(np.array(omegas) - start_omega).max() > 0.5  # ω itself wanders


def test_the_quaternion_stays_unit_under_the_symplectic_drift_and_not_under_a_linear_update():
    """10⁴ steps of 0.01 s at |ω| = 5 rad/s: the splitting's rotations keep |q| = 1 within
    1e-12; explicit Euler's linear update q + h q' without the projection does not (each step
    multiplies |q| by √(1 + (h|ω|/2)²))."""
    spin = np.array([3.0, 0.0, 4.0])  # |ω| = 5 rad/s
    system, state, _ = _free_body(spin, orientation=(0.9, 0.1, -0.3, 0.2))
    worst = []
    _run(
        "symplectic_euler", state, system, 0.01, 10_000,
        lambda s: worst.append(abs(np.linalg.norm(s.parts[0][-4:]) - 1.0)),
    )  # fmt: skip
    assert max(worst) <= 1e-12
    end = _run("explicit_euler", state, system, 0.01, 10_000)
    assert abs(np.linalg.norm(end.parts[0][-4:]) - 1.0) > 1e-3


@pytest.mark.parametrize(("axis", "flips"), [(0, False), (1, True), (2, False)])
def test_only_a_spin_about_the_intermediate_axis_flips(axis, flips):
    """Spin 5 rad/s about one principal axis with a 0.2 % nudge about the others, 60 s: the
    body-frame spin about that axis changes sign (the tennis-racket flip) only for the
    intermediate moment I₂; about I₁ and I₃ it stays within a few % of its start."""
    spin = np.full(3, 0.01)
    spin[axis] = 5.0
    system, state, motion = _free_body(spin)
    along = []
    _run(
        "symplectic_euler", state, system, 0.005, 12_000,
        lambda s: along.append(_body_frame_spin(s, motion)[axis]),
    )  # fmt: skip
    along = np.array(along)
    if flips:
        assert along.min() < -4.5 and along.max() > 4.5
        assert np.count_nonzero(np.diff(np.sign(along))) >= 2
    else:
        assert np.abs(along - 5.0).max() < 0.05


@pytest.mark.parametrize(("method", "order"), [("velocity_verlet", 2), ("leapfrog", 2), ("rk4", 4)])
def test_orientation_error_falls_at_the_methods_order(method, order):
    """The orientation after 1 s against a reference with h = 1e-4 (RK4): the error ratio
    between h and h/2 is 2^p within ±0.3 in the exponent."""
    spin = (1.0, 2.0, 3.0)
    system, state, _ = _free_body(spin, orientation=(0.8, 0.2, 0.4, -0.4))
    reference = _run("rk4", state, system, 1e-4, 10_000).parts[0][-4:]
    reference = reference / np.linalg.norm(reference)
    errors = []
    for h in (0.02, 0.01):
        end = _run(method, state, system, h, round(1.0 / h)).parts[0][-4:]
        errors.append(np.linalg.norm(end / np.linalg.norm(end) - reference))
    assert np.log2(errors[0] / errors[1]) == pytest.approx(order, abs=0.3)


def test_rate_is_the_derivative_of_the_drift_and_particles_move_as_q_dot_v():
    """(drift(q, v, ε) − q)/ε → rate(q, v) as ε → 0 (first order in ε), with particles before
    the body moving as q' = v."""
    _, state, motion = _free_body((0.3, -1.0, 2.0), (0.7, 0.1, 0.5, -0.2), particles=2)
    q, v = state.parts
    rate = motion.rate(q, v)
    np.testing.assert_array_equal(rate[:6], v[:6])
    np.testing.assert_allclose(rate[6:9], v[6:9] / MASS)
    errors = [np.abs((motion.drift(q, v, e) - q) / e - rate).max() for e in (1e-4, 5e-5)]
    assert errors[0] < 1e-3 and errors[0] / errors[1] == pytest.approx(2.0, rel=0.05)


@pytest.mark.parametrize(("h", "steps"), [(0.1, 10), (1.0, 1)])
def test_a_quarter_turn_about_a_principal_axis_is_exact(h, steps):
    """A symmetric spin about body axis 3 at ω = π/2 rad/s for 1 s turns the body by exactly
    π/2 about that axis (the splitting's sub-flows are exact rotations): in ten steps, whose
    turns take the Taylor series, or in one, whose turn of π/2 takes the library's sin and
    cos."""
    system, state, _ = _free_body((0.0, 0.0, np.pi / 2), inertia=(1.0, 1.0, 2.0))
    end = _run("symplectic_euler", state, system, h, steps).parts[0][-4:]
    quarter = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])
    np.testing.assert_allclose(end, quarter, atol=1e-14)
    # The same turn composed from its two halves (q ⊗ q for the eighth turn twice).
    eighth = np.array([np.cos(np.pi / 8), 0.0, 0.0, np.sin(np.pi / 8)])
    np.testing.assert_allclose(quaternion_multiply(eighth, eighth), quarter, atol=1e-15)


@pytest.mark.parametrize("method", ["backward_euler", "taylor", "projected_newton"])
def test_methods_that_cannot_step_orientations_refuse_with_the_alternatives(method):
    system, _, _ = _free_body((1.0, 2.0, 3.0))
    with pytest.raises(ModelError, match=r"cannot step rigid bodies.*symplectic_euler"):
        vv.integrators.get(method).check(system)


def test_matrix_and_quaternion_convert_both_ways():
    rng = np.random.default_rng(3)
    for q in rng.normal(size=(50, 4)):
        q = q / np.linalg.norm(q) * np.sign(q[0])
        np.testing.assert_allclose(matrix_quaternion(quaternion_matrix(q)), q, atol=1e-14)
    for half_turn in np.eye(3):  # w = 0: the branches that divide by x, y or z
        q = np.concatenate([[0.0], half_turn])
        np.testing.assert_allclose(
            np.abs(matrix_quaternion(quaternion_matrix(q))), np.abs(q), atol=1e-15
        )


def test_a_body_whose_axes_are_not_principal_moves_as_its_principal_frame_does():
    """The same body given in turned axes (inertia R diag(I) Rᵀ, principal frame ``r`` in its
    axes): its orientation q is (q ⊗ r) ⊗ r⁻¹ of the principal frame's, step after step."""
    r = np.array([0.9, -0.2, 0.3, 0.25])
    r /= np.linalg.norm(r)
    principal, state, _ = _free_body((0.5, 1.5, -2.0), orientation=(0.7, 0.1, 0.5, -0.2))
    turned_q = state.parts[0].copy()
    turned_q[-4:] = quaternion_multiply(turned_q[-4:], r * [1, -1, -1, -1])
    turned = SecondOrderSystem(
        lambda t, q, v: np.zeros_like(v), velocity_dependent=False, layout=principal.layout,
        kinematics=BodyMotion(0, np.array([MASS]), np.array([INERTIA]), r[None]),
    )  # fmt: skip
    for method in ("symplectic_euler", "rk4"):
        a = _run(method, state, principal, 0.01, 200).parts[0][-4:]
        b = _run(
            method, State(0.0, (turned_q, state.parts[1]), principal.layout), turned, 0.01, 200
        )
        np.testing.assert_allclose(quaternion_multiply(b.parts[0][-4:], r), a, atol=1e-12)
