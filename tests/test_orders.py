"""Every registered method converges at its declared order on problems with exact solutions.

The global error of an order-p method at a fixed time behaves as C·dt^p (seed 000), so the
slope of log(error) against log(dt) over the asymptotic range must equal p. Methods are taken
from the registry at collection time, so a newly registered method is checked automatically.
"""

import itertools

import numpy as np
import pytest

import visviva as vv
from visviva.analysis.reference_problems import reference_problem

ORDER_TOLERANCE = 0.1

#: Largest step per problem; eight halvings from there keep low-order methods' errors between
#: the pre-asymptotic regime and round-off. High-order methods start at twice the step.
LARGEST_STEP = {"pendulum": 0.2, "forced": 0.2, "damped": 0.1, "first-order": 0.2}


def _steps(problem, order):
    largest = LARGEST_STEP[problem] * (2 if order >= 4 else 1)
    return [largest / 2**k for k in range(8)]


def _cases():
    for name in vv.integrators.names():
        method = vv.integrators.get(name)
        for problem in LARGEST_STEP:
            if problem == "first-order" and method.second_order_only:
                continue
            yield pytest.param(name, problem, id=f"{name}-{problem}")


@pytest.mark.parametrize(("method", "problem"), list(_cases()))
def test_declared_order_is_measured(method, problem):
    """Fitted slope within ±0.1 of the declared order, over at least three step sizes."""
    reference = reference_problem(problem)
    study = vv.studies.convergence_order(
        reference.problem,
        method,
        until=2.0,
        reference=reference.exact,
        dt=_steps(problem, vv.integrators.get(method).order),
    )
    assert study.used.sum() >= 3, study
    assert abs(study.order - study.declared_order) <= ORDER_TOLERANCE, (
        f"{method} on {problem}: measured {study.order:.3f}, errors {study.error}"
    )


def test_errors_halve_for_first_order_methods():
    """Seed 000: halving dt halves explicit Euler's error (ratio → 2 as dt → 0)."""
    reference = reference_problem("forced")
    study = vv.studies.convergence_order(
        reference.problem,
        "explicit_euler",
        until=1.0,
        reference=reference.exact,
        dt=[1e-2 / 2**k for k in range(5)],
    )
    ratios = study.error[:-1] / study.error[1:]
    np.testing.assert_allclose(ratios, 2.0, rtol=0.02)


def test_taylor_update_is_exact_for_constant_force():
    """Seed 002's x + vΔt + ½aΔt² reproduces the thrown rock's parabola to round-off."""
    g = np.array([0.0, -9.81])
    rock = vv.ode.SecondOrderProblem(
        lambda t, q: np.broadcast_to(g, q.shape).copy(), q0=[0.0, 1.0], v0=[3.0, 4.0]
    )
    solution = vv.solve(rock, "taylor", dt=0.1, until=0.8)
    t = solution.t[:, None]
    expected = np.array([0.0, 1.0]) + np.array([3.0, 4.0]) * t + 0.5 * g * t**2
    np.testing.assert_allclose(solution.q, expected, rtol=0, atol=1e-13)


def test_adaptive_dopri5_meets_its_tolerance():
    """Error-controlled DOPRI5: the global error tracks rtol (pendulum, elliptic exact)."""
    reference = reference_problem("pendulum")
    exact_q, exact_v = reference.exact(10.0)
    errors = []
    for rtol in (1e-4, 1e-6, 1e-8, 1e-10):
        solution = vv.solve(reference.problem, "dopri5", until=10.0, rtol=rtol, atol=rtol * 1e-3)
        assert solution.success
        errors.append(max(abs(solution.q[-1, 0] - exact_q[0]), abs(solution.v[-1, 0] - exact_v[0])))
        # Global error of a few times the local tolerance over ~1.6 periods.
        assert errors[-1] < 50 * rtol
    assert all(a > b for a, b in itertools.pairwise(errors))


def test_dopri5_dense_output_is_fourth_order_between_steps():
    """The continuous extension has local error O(h^5) at interior points (order 4 + 1)."""
    from visviva.integrators import DormandPrince5

    reference = reference_problem("first-order")
    system = reference.problem.system()
    start = reference.problem.initial_state()
    steps = np.array([0.4, 0.2, 0.1, 0.05])
    errors = []
    for h in steps:
        step = DormandPrince5().attempt(system, start, float(h))
        (y,) = step.interpolate(0.37)
        (exact,) = reference.exact(0.37 * h)
        errors.append(np.abs(y - exact).max())
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(slope - 5.0) < 0.3, (slope, errors)
    # The interpolant passes through both ends of the step.
    np.testing.assert_array_equal(step.interpolate(0.0)[0], start.y)
    np.testing.assert_allclose(step.interpolate(1.0)[0], step.end.y, rtol=0, atol=1e-15)


def test_dopri5_t_eval_interpolates_to_the_requested_times():
    """Recording at t_eval uses the dense output: times exact, values within tolerance."""
    reference = reference_problem("first-order")
    times = np.linspace(0.0, 2.0, 17)
    solution = vv.solve(
        reference.problem, "dopri5", until=2.0, rtol=1e-10, atol=1e-12, t_eval=times
    )
    np.testing.assert_array_equal(solution.t, times)
    exact = np.array([reference.exact(t)[0] for t in times])
    np.testing.assert_allclose(solution.y, exact, rtol=0, atol=1e-8)


def test_dopri5_counts_six_evaluations_per_step():
    """First same as last: 6 evaluations per attempted step, plus 1 for the first and 1 for
    the automatic choice of the initial step."""
    reference = reference_problem("first-order")
    solution = vv.solve(reference.problem, "dopri5", until=2.0, rtol=1e-8)
    counters = solution.counters
    attempted = counters["accepted_steps"] + counters["rejected_steps"]
    assert counters["f_evaluations"] == 6 * attempted + 2
