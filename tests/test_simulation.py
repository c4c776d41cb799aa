"""The simulation loop: time, frames, substeps, batches, the compiled path, divergence."""

import numba
import numpy as np
import pytest

import visviva as vv
from visviva.analysis.reference_problems import reference_problem


def _spring(q0=(1.0,), v0=(0.0,), stiffness=1.0):
    return vv.ode.SecondOrderProblem(lambda t, q: -stiffness * q, q0=list(q0), v0=list(v0))


def test_time_comes_from_the_step_counter():
    """Frame k is at exactly t0 + k·dt (no accumulated `t += dt` rounding)."""
    t0, dt, steps = 0.1, 0.1, 20_000
    problem = vv.ode.FirstOrderProblem(lambda t, y: 0.0 * y, [1.0], t0=t0)
    solution = vv.solve(problem, "explicit_euler", dt=dt, until=t0 + steps * dt, record_every=100)
    expected = t0 + np.arange(0, steps + 1, 100) * dt
    expected[-1] = t0 + steps * dt
    np.testing.assert_array_equal(solution.t, expected)
    accumulated = t0
    for _ in range(steps):
        accumulated += dt
    assert accumulated != solution.t[-1]  # what the counter avoids


def test_time_seen_by_the_force_is_exact():
    """A time-dependent force is evaluated at t0 + k·h exactly."""
    seen = []

    def f(t, y):
        seen.append(t)
        return np.zeros_like(y)

    vv.solve(vv.ode.FirstOrderProblem(f, [0.0]), "explicit_euler", dt=0.1, until=1.0)
    np.testing.assert_array_equal(seen[1:], 0.1 * np.arange(10))  # [0] is the shape check


def test_last_step_is_shortened_to_land_on_until():
    """until − t0 not a multiple of dt: full steps, then one shorter step ending at until."""
    solution = vv.solve(_spring(), "rk4", dt=0.3, until=1.0)
    np.testing.assert_array_equal(solution.t, [0.0, 0.3, 2 * 0.3, 3 * 0.3, 1.0])
    np.testing.assert_allclose(solution.q[-1, 0], np.cos(1.0), atol=1e-4)


@pytest.mark.parametrize(
    ("until", "every", "frames"),
    [(1.0, 3, [0, 3, 6, 9, 10]), (1.2, 4, [0, 4, 8, 12]), (1.25, 4, [0, 4, 8, 12, 13])],
)
def test_record_every_keeps_every_kth_step_and_the_last(until, every, frames):
    solution = vv.solve(_spring(), "leapfrog", dt=0.1, until=until, record_every=every)
    expected = np.minimum(np.array(frames) * 0.1, until)
    np.testing.assert_allclose(solution.t, expected, rtol=0, atol=1e-15)


def test_substeps_equal_smaller_steps():
    """dt with 4 substeps is the same computation as dt/4 recorded every 4th step."""
    a = vv.solve(_spring(), "velocity_verlet", dt=0.2, until=2.0, substeps=4)
    b = vv.solve(_spring(), "velocity_verlet", dt=0.05, until=2.0, record_every=4)
    np.testing.assert_allclose(a.t, b.t, rtol=0, atol=1e-15)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-15)
    assert a.counters["accepted_steps"] == 40


@pytest.mark.parametrize("method", vv.integrators.names())
def test_a_batch_equals_its_systems_run_one_by_one(method):
    """Each system of a batch follows exactly the trajectory it follows alone."""
    rng = np.random.default_rng(2)
    q0, v0 = rng.uniform(-1, 1, (5, 2)), rng.uniform(-1, 1, (5, 2))

    def acceleration(t, q, v):
        return -np.sin(q) - 0.1 * v

    batch = vv.solve(
        vv.ode.SecondOrderProblem(acceleration, q0, v0), method, dt=0.05, until=1.0, adaptive=False
    )
    for i in range(5):
        alone = vv.solve(
            vv.ode.SecondOrderProblem(acceleration, q0[i], v0[i]),
            method,
            dt=0.05,
            until=1.0,
            adaptive=False,
        )
        np.testing.assert_allclose(batch.q[:, i], alone.q, rtol=0, atol=1e-12)


# Numba versions of the damped pendulum, in the four accepted forms.
@numba.njit
def _returning(t, q, v):
    return -np.sin(q) - 0.1 * v + 0.2 * np.cos(t)


@numba.njit
def _filling(t, q, v, out):
    for k in range(q.size):
        out[k] = -np.sin(q[k]) - 0.1 * v[k] + 0.2 * np.cos(t)


@numba.njit
def _position_only(t, q):
    return -np.sin(q) + 0.2 * np.cos(t)


def _numpy_damped(t, q, v):
    return -np.sin(q) - 0.1 * v + 0.2 * np.cos(t)


def _numpy_position_only(t, q):
    return -np.sin(q) + 0.2 * np.cos(t)


EXPLICIT_FIXED_STEP = [
    m
    for m in vv.integrators.names()
    if not vv.integrators.get(m).implicit and not vv.integrators.get(m).adaptive
]
FORMS = {
    "returning": (_returning, _numpy_damped),
    "out": (_filling, _numpy_damped),
    "position-only": (_position_only, _numpy_position_only),
}
# Every explicit method in one form, and every form for the methods whose kernels branch on it
# (each case compiles a kernel, so the matrix is kept to what can differ).
COMPILED_CASES = [(m, "out") for m in EXPLICIT_FIXED_STEP] + [
    (m, form)
    for m in ("rk4", "velocity_verlet", "leapfrog")
    for form in ("returning", "position-only")
]


@pytest.mark.parametrize(("method", "form"), COMPILED_CASES)
def test_compiled_loop_matches_numpy_loop(method, form):
    """The compiled whole-run path gives the NumPy path's frames, times and work counts, for a
    batch and for a single system, with a diagonal mass."""
    compiled_force, numpy_force = FORMS[form]
    rng = np.random.default_rng(3)
    mass = np.array([1.0, 2.5])
    for shape in ((7, 2), (2,)):
        q0, v0 = rng.uniform(-1, 1, shape), rng.uniform(-1, 1, shape)
        compiled = vv.ode.SecondOrderProblem.from_force(compiled_force, mass, q0, v0)
        reference = vv.ode.SecondOrderProblem.from_force(numpy_force, mass, q0, v0)
        a = vv.solve(compiled, method, dt=0.01, until=1.234, record_every=7, substeps=2)
        b = vv.solve(reference, method, dt=0.01, until=1.234, record_every=7, substeps=2)
        assert a.recording.attrs["compiled"] and not b.recording.attrs["compiled"]
        np.testing.assert_array_equal(a.t, b.t)
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-13)
        np.testing.assert_allclose(a.v, b.v, rtol=0, atol=1e-13)
        assert a.counters == b.counters


def test_problems_from_one_numba_function_share_their_batch_wrappers():
    """The compiled loop over a batch is built once per function, not once per problem (each
    build is a parallel Numba compilation of about half a second)."""
    from visviva.ode.batching import batched

    rng = np.random.default_rng(4)
    problems = [
        vv.ode.SecondOrderProblem(_filling, rng.uniform(-1, 1, (3, 2)), np.zeros((3, 2)))
        for _ in range(2)
    ]
    assert batched(problems[0].force, "array") is batched(problems[1].force, "array")


@numba.njit
def _first_order_numba(t, y, out):
    out[0] = y[1]
    out[1] = -np.sin(y[0]) + np.cos(t) * 0.1


def test_compiled_first_order_matches_numpy():
    y0 = np.random.default_rng(4).uniform(-1, 1, (11, 2))
    a = vv.solve(vv.ode.FirstOrderProblem(_first_order_numba, y0), "rk4", dt=0.01, until=2.0)
    b = vv.solve(
        vv.ode.FirstOrderProblem(_first_order_numba, y0), "rk4", dt=0.01, until=2.0, compiled=False
    )
    assert a.recording.attrs["compiled"] and not b.recording.attrs["compiled"]
    np.testing.assert_allclose(a.y, b.y, rtol=0, atol=1e-13)


def test_explicit_euler_on_a_stiff_spring_diverges_with_advice():
    """ω = 100, dt = 0.05: the watch stops the run, names t, step and component, and the
    advisor explains that explicit Euler is unstable on undamped oscillations (dt = 0)."""
    problem = _spring(q0=[1.0, 0.0], v0=[0.0, 0.0], stiffness=100.0**2)
    solution = vv.solve(problem, "explicit_euler", dt=0.05, until=100.0)
    assert not solution.success
    error = solution.error
    assert isinstance(error, vv.SimulationDiverged)
    assert error.component.startswith(("q[0]", "v[0]"))
    assert error.suggested_dt == 0.0
    assert f"step {error.step + 1}" in solution.message  # counted from 1 for people
    # t = (index + 1) dt: the failing step's end.
    assert error.t == pytest.approx((error.step + 1) * 0.05)
    assert "undamped oscillating modes" in solution.message
    # The frames before the blow-up are kept and finite.
    assert solution.t[-1] < error.t and np.isfinite(solution.q).all()
    with pytest.raises(vv.SimulationDiverged):
        solution.raise_for_status()


@pytest.mark.parametrize("compiled", [False, True])
def test_rk4_divergence_reports_the_stable_step(compiled):
    """RK4 on ω = 100 with dt = 0.05 (ωh = 5 > 2√2): the advisor's step is 2√2/ω."""
    if compiled:

        @numba.njit
        def acceleration(t, q):
            return -1e4 * q
    else:

        def acceleration(t, q):
            return -1e4 * q

    problem = vv.ode.SecondOrderProblem(acceleration, q0=[[1.0], [0.5]], v0=[[0.0], [0.0]])
    with pytest.raises(vv.SimulationDiverged) as caught:
        vv.solve(problem, "rk4", dt=0.05, until=1000.0).raise_for_status()
    error = caught.value
    assert error.suggested_dt == pytest.approx(2 * np.sqrt(2) / 100, rel=1e-6)
    assert "(system 0)" in str(error)
    assert error.recording.attrs["compiled"] is compiled
    assert error.recording.attrs["success"] is False


def test_divergence_limit_scales_with_the_initial_state():
    """Orbits in metres (|q| ~ 1.5e11) do not trip the default limit."""
    problem = vv.ode.SecondOrderProblem(lambda t, q: -q * 1e-14, q0=[1.5e11], v0=[3e4])
    assert vv.solve(problem, "leapfrog", dt=1.0, until=100.0).success


def test_newton_failure_is_reported_not_silent():
    """An implicit step that cannot converge in its iteration cap fails with a message."""
    problem = reference_problem("pendulum").problem
    method = vv.integrators.BackwardEuler(max_iterations=1)
    solution = vv.solve(problem, method, dt=0.5, until=5.0)
    assert not solution.success
    assert isinstance(solution.error, vv.NewtonConvergenceError)
    assert "did not converge" in solution.message and "t=0.5" in solution.message
    assert solution.error.step == 0


def test_work_counters_match_the_declared_costs():
    """Explicit methods evaluate f exactly `evaluations_per_step` times per step (Verlet's
    first step evaluates the starting acceleration too)."""
    for name in ("explicit_euler", "midpoint", "rk4", "symplectic_euler", "leapfrog"):
        solution = vv.solve(_spring(), name, dt=0.1, until=10.0)
        per_step = vv.integrators.get(name).evaluations_per_step
        assert solution.counters["f_evaluations"] == 100 * per_step
    assert (
        vv.solve(_spring(), "velocity_verlet", dt=0.1, until=10.0).counters["f_evaluations"] == 101
    )
