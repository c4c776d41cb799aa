"""Energy behaviour of each method on the undamped oscillator q'' = −ω²q, E = ½v² + ½ω²q².

Explicit Euler multiplies E by exactly 1 + (ωh)² per step and backward Euler divides it by the
same factor (their amplification matrices are I ± hA with AᵀA ∝ I); symplectic methods keep a
modified energy, so E oscillates within O((ωh)^p) and never drifts; the trapezoidal rule and
implicit midpoint conserve E of a linear system exactly.
"""

import math

import numba
import numpy as np
import pytest

import visviva as vv

OMEGA = 3.0


def _oscillator(compiled=False):
    if compiled:

        @numba.njit
        def acceleration(t, q, out):
            out[0] = -(OMEGA**2) * q[0]
    else:

        def acceleration(t, q):
            return -(OMEGA**2) * q

    def energy(t, q, v):
        return 0.5 * v[..., 0] ** 2 + 0.5 * OMEGA**2 * q[..., 0] ** 2

    # Released from rest: E(0) equals the modified energy a symplectic method conserves, so
    # the bounds below hold from the first step (Hairer, Lubich & Wanner 2006, §I.1).
    return vv.ode.SecondOrderProblem(
        acceleration,
        q0=[1.0],
        v0=[0.0],
        energy=energy,
        jacobian=lambda t, q: np.full(q.shape + (1,), -(OMEGA**2)),
    )


@pytest.mark.parametrize(("method", "sign"), [("explicit_euler", 1), ("backward_euler", -1)])
def test_euler_energy_factor_is_exact(method, sign):
    """E_n / E_0 = (1 + (ωh)²)^(±n) to round-off."""
    dt, n = 0.01, 300
    solution = vv.solve(_oscillator(), method, dt=dt, until=n * dt)
    steps = np.arange(n + 1)
    expected = (1.0 + (OMEGA * dt) ** 2) ** (sign * steps)
    np.testing.assert_allclose(solution.energy / solution.energy[0], expected, rtol=1e-9)


def _energy_error(method, dt, steps):
    solution = vv.solve(
        _oscillator(compiled=True), method, dt=dt, until=steps * dt, record_every=100
    )
    assert solution.recording.attrs["compiled"]
    return solution.energy / solution.energy[0] - 1.0


@pytest.mark.parametrize(
    ("method", "bound"),
    [
        ("symplectic_euler", lambda wh: 0.55 * wh),
        ("symplectic_euler_position_first", lambda wh: 0.55 * wh),
        ("velocity_verlet", lambda wh: 0.3 * wh**2),
        ("leapfrog", lambda wh: 0.3 * wh**2),
    ],
)
@pytest.mark.parametrize("omega_h", [0.05, 0.1])
def test_symplectic_energy_error_is_bounded_without_drift(method, bound, omega_h):
    """Over 1e6 steps |E/E0 − 1| stays below the bound and shows no secular trend: the
    spread of the error over the last tenth of the run equals that of the first tenth."""
    error = _energy_error(method, omega_h / OMEGA, 1_000_000)
    assert np.abs(error).max() <= bound(omega_h)
    tenth = error.size // 10
    early, late = error[:tenth], error[-tenth:]
    # No drift: mean and extremes of the oscillation agree between the two ends of the run.
    assert abs(late.mean() - early.mean()) < 1e-3 * bound(omega_h)
    assert abs(np.abs(late).max() - np.abs(early).max()) < 1e-2 * bound(omega_h)


@pytest.mark.parametrize("method", ["symplectic_euler", "symplectic_euler_position_first"])
def test_symplectic_euler_energy_error_has_its_closed_form(method):
    """Symplectic Euler conserves E̅ = ½(v² + ω²q² ∓ hω²qv) exactly; from rest, E/E0 − 1 then
    ranges over [−s/(2 + s), s/(2 − s)] with s = ωh, reached where |ωq| = |v|."""
    s = 0.3
    error = _energy_error(method, s / OMEGA, 200_000)
    assert error.max() <= s / (2 - s) + 1e-12
    assert error.min() >= -s / (2 + s) - 1e-12
    assert error.max() > 0.99 * s / (2 - s) and error.min() < 0.99 * -s / (2 + s)


@pytest.mark.parametrize("method", ["trapezoidal", "implicit_midpoint"])
def test_implicit_second_order_methods_conserve_linear_energy(method):
    """|R(iy)| = 1: the energy of a linear oscillator is kept to the Newton tolerance."""
    solution = vv.solve(_oscillator(), method, dt=0.1, until=100.0)
    np.testing.assert_allclose(solution.energy, solution.energy[0], rtol=1e-9)


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
def test_runge_kutta_slowly_loses_energy(method):
    """|R(iy)| < 1 just inside the imaginary interval: RK4 damps, by (1 − (ωh)^6/72)^2 per
    step to leading order — a small, monotone loss, not an oscillation."""
    solution = vv.solve(_oscillator(), method, dt=0.05, until=100.0, adaptive=False)
    ratio = solution.energy / solution.energy[0]
    assert np.all(np.diff(ratio) <= 1e-15)
    if method == "rk4":
        wh = OMEGA * 0.05
        growth = abs(sum((1j * wh) ** k / math.factorial(k) for k in range(5)))
        np.testing.assert_allclose(ratio[-1], growth ** (2 * 2000), rtol=1e-9)


@pytest.mark.parametrize("method", ["velocity_verlet", "leapfrog"])
def test_verlet_runs_backwards_to_its_start(method):
    """Time reversibility: n steps forward, flip v, n steps, flip v → start to ≤ 1e-13."""

    def acceleration(t, q):
        return -np.sin(q) - 0.3 * q**3  # nonlinear, position-only

    q0, v0 = np.array([0.8, -0.3]), np.array([0.2, 1.1])
    forward = vv.solve(
        vv.ode.SecondOrderProblem(acceleration, q0, v0),
        method,
        dt=0.01,
        until=10.0,
        record_every=1000,
    )
    q1, v1 = forward.q[-1], forward.v[-1]
    back = vv.solve(
        vv.ode.SecondOrderProblem(acceleration, q1, -v1),
        method,
        dt=0.01,
        until=10.0,
        record_every=1000,
    )
    np.testing.assert_allclose(back.q[-1], q0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(-back.v[-1], v0, rtol=0, atol=1e-13)


def test_explicit_euler_energy_grows_on_the_circle_of_seed_004():
    """Seed 004's circular motion: |q| grows by √(1 + h²) per explicit Euler step and shrinks
    by the same factor under backward Euler, while symplectic Euler stays within h/2."""
    from visviva.demos.circular import circular_problem

    h, n = 0.1, 200
    radius = {}
    for method in ("explicit_euler", "backward_euler", "symplectic_euler"):
        s = vv.solve(circular_problem(), method, dt=h, until=n * h)
        radius[method] = np.hypot(s.q[:, 0], s.v[:, 0])
    growth = np.sqrt(1 + h**2) ** np.arange(n + 1)
    np.testing.assert_allclose(radius["explicit_euler"], growth, rtol=1e-12)
    np.testing.assert_allclose(radius["backward_euler"], 1 / growth, rtol=1e-9)
    assert np.abs(radius["symplectic_euler"] - 1).max() < 0.5 * h
