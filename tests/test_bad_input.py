"""Bad input is refused before anything runs, with a message a user can act on.

The promise (DESIGN.md, "Contracts worth keeping stable"): invalid input raises
:class:`visviva.ModelError` naming the argument, the value received and what is accepted, and it
does so before the first step. To prove "before any step", the user functions here count their
calls: building a problem calls each function exactly once to validate it, and ``solve``
with an invalid argument must not call ``f`` at all.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import visviva as vv
from visviva import ModelError

FirstOrderProblem = vv.ode.FirstOrderProblem
SecondOrderProblem = vv.ode.SecondOrderProblem


def counted(func: Callable[..., Any]) -> Any:
    """``func`` with the same signature, counting its calls in ``.calls``."""

    @functools.wraps(func)
    def wrapper(*args: Any) -> Any:
        wrapper.calls += 1  # type: ignore[attr-defined]
        return func(*args)

    wrapper.calls = 0  # type: ignore[attr-defined]
    return wrapper


def refused(call: Callable[[], Any], *fragments: str) -> str:
    """Run ``call``: it must raise ModelError whose message contains every fragment."""
    with pytest.raises(ModelError) as caught:
        call()
    message = str(caught.value)
    missing = [fragment for fragment in fragments if fragment not in message]
    assert not missing, f"message {message!r} does not mention {missing}"
    return message


def restoring(t: float, x: np.ndarray) -> np.ndarray:
    """``-x``: a valid f(t, y), acceleration(t, q) or force(t, q)."""
    return -x


#: Builds a problem of each kind around a two-component right-hand side ``f``, with its name.
each_right_hand_side = pytest.mark.parametrize(
    ("build", "name"),
    [
        (lambda f: FirstOrderProblem(f, [1.0, 0.5]), "f"),
        (lambda f: SecondOrderProblem(f, [1.0, 0.5], [0.0, 0.0]), "acceleration"),
        (lambda f: SecondOrderProblem.from_force(f, 2.0, [1.0, 0.5], [0.0, 0.0]), "force"),
    ],
    ids=["f", "acceleration", "force"],
)


@pytest.fixture
def decay() -> tuple[FirstOrderProblem, Any]:
    """``y' = -y`` from ``y = (1, 0.5)``, with its f counting calls (reset after construction)."""
    f = counted(restoring)
    problem = FirstOrderProblem(f, [1.0, 0.5])
    f.calls = 0
    return problem, f


@pytest.fixture
def spring() -> tuple[SecondOrderProblem, Any]:
    """``q'' = -q`` from ``q = (1, 0.5)`` at rest, acceleration counting calls (reset)."""
    acceleration = counted(restoring)
    problem = SecondOrderProblem(acceleration, [1.0, 0.5], [0.0, 0.0])
    acceleration.calls = 0
    return problem, acceleration


# --------------------------------------------------------------------------------------------
# Problems: every function called once to validate it, every bad argument named.


def test_first_order_construction_calls_each_function_exactly_once():
    """A problem checks f, jacobian and energy by calling each once at the initial state."""
    f = counted(restoring)
    jacobian = counted(lambda t, y: -np.eye(2))
    energy = counted(lambda t, y: 0.5 * np.sum(y**2))
    FirstOrderProblem(f, [1.0, 0.5], jacobian=jacobian, energy=energy)
    assert (f.calls, jacobian.calls, energy.calls) == (1, 1, 1)


def test_second_order_construction_calls_each_function_exactly_once():
    """from_force checks a damped force, its Jacobian pair and the energy with one call each."""
    force = counted(lambda t, q, v: -4.0 * q - 0.1 * v)
    jacobian = counted(lambda t, q, v: (-4.0 * np.eye(2), -0.1 * np.eye(2)))
    energy = counted(lambda t, q, v: 0.5 * np.sum(2.0 * v**2 + 4.0 * q**2))
    SecondOrderProblem.from_force(
        force, 2.0, [1.0, 0.5], [0.0, 0.0], jacobian=jacobian, energy=energy
    )
    assert (force.calls, jacobian.calls, energy.calls) == (1, 1, 1)


#: How to build a problem with a bad value for each initial-state argument.
STATE_ARGUMENTS: dict[str, Callable[[Any, Any], Any]] = {
    "y0": lambda value, f: FirstOrderProblem(f, value),
    "q0": lambda value, f: SecondOrderProblem(f, value, [0.0, 0.0]),
    "v0": lambda value, f: SecondOrderProblem(f, [1.0, 0.5], value),
    "q0 (from_force)": lambda value, f: SecondOrderProblem.from_force(f, 1.0, value, [0.0, 0.0]),
    "v0 (from_force)": lambda value, f: SecondOrderProblem.from_force(f, 1.0, [1.0, 0.5], value),
}


@pytest.mark.parametrize("argument", list(STATE_ARGUMENTS))
@pytest.mark.parametrize(
    ("bad", "shown"),
    [(math.nan, "nan"), (math.inf, "inf"), (-math.inf, "-inf"), (1e400, "inf")],
    ids=["nan", "inf", "-inf", "1e400"],
)
def test_non_finite_initial_state_is_refused(argument, bad, shown):
    """A nan or infinite initial coordinate is named by argument, entry and value; f never runs."""
    f = counted(restoring)
    name = argument.split()[0]
    refused(
        lambda: STATE_ARGUMENTS[argument]([1.0, bad], f), f"`{name}`", "finite", "entry 1", shown
    )
    assert f.calls == 0


@pytest.mark.parametrize("argument", ["y0", "q0", "v0 (from_force)"])
@pytest.mark.parametrize("bad", ["abc", ["1.0", "2.0"], None], ids=["str", "str-list", "None"])
def test_initial_state_that_is_not_numbers_is_refused(argument, bad):
    """Strings or None as a state are refused, and the message shows what was passed."""
    f = counted(restoring)
    name = argument.split()[0]
    refused(lambda: STATE_ARGUMENTS[argument](bad, f), f"`{name}`", "numbers", repr(bad))
    assert f.calls == 0


@pytest.mark.parametrize("argument", list(STATE_ARGUMENTS))
@pytest.mark.parametrize(
    ("bad", "shape"), [([], "(0,)"), (np.empty((3, 0)), "(3, 0)")], ids=["empty", "batch-of-empty"]
)
def test_empty_initial_state_is_refused(argument, bad, shape):
    """A state with no coordinates is refused, naming the argument and the shape received."""
    f = counted(restoring)
    name = argument.split()[0]
    refused(lambda: STATE_ARGUMENTS[argument](bad, f), f"`{name}`", "empty", shape)
    assert f.calls == 0


@pytest.mark.parametrize("argument", list(STATE_ARGUMENTS))
def test_three_dimensional_initial_state_is_refused(argument):
    """States are (n,) or (batch, n); a 3-D array is refused with its shape and the forms."""
    f = counted(restoring)
    name = argument.split()[0]
    refused(
        lambda: STATE_ARGUMENTS[argument](np.zeros((2, 2, 2)), f),
        f"`{name}`",
        "(2, 2, 2)",
        "(n,)",
        "(batch, n)",
    )
    assert f.calls == 0


@pytest.mark.parametrize("from_force", [False, True], ids=["acceleration", "from_force"])
def test_velocities_must_have_the_shape_of_positions(from_force):
    """v0 of another shape than q0 is refused with both shapes; the force never runs."""
    f = counted(restoring)
    q0, v0 = [1.0, 0.5], [0.0, 0.0, 0.0]
    build = (
        (lambda: SecondOrderProblem.from_force(f, 1.0, q0, v0))
        if from_force
        else (lambda: SecondOrderProblem(f, q0, v0))
    )
    refused(build, "`v0`", "(2,)", "(3,)")
    assert f.calls == 0


@pytest.mark.parametrize(
    ("build", "name", "type_name"),
    [
        (lambda: FirstOrderProblem(3.0, [1.0]), "f", "float"),
        (lambda: SecondOrderProblem("spring", [1.0], [0.0]), "acceleration", "str"),
        (lambda: SecondOrderProblem.from_force(None, 1.0, [1.0], [0.0]), "force", "NoneType"),
    ],
    ids=["f", "acceleration", "force"],
)
def test_function_that_is_not_callable_is_refused(build, name, type_name):
    """A number, string or None where a function belongs is named with its type."""
    refused(build, f"`{name}`", "callable", type_name)


@pytest.mark.parametrize(
    ("build", "accepted", "got"),
    [
        (lambda: FirstOrderProblem(lambda t: t, [1.0]), "f(t, y)", "f(t)"),
        (lambda: FirstOrderProblem(lambda t, y, z, w: y, [1.0]), "f(t, y)", "f(t, y, z, w)"),
        (
            lambda: SecondOrderProblem(lambda t: t, [1.0], [0.0]),
            "acceleration(t, q, v)",
            "acceleration(t)",
        ),
        (
            lambda: SecondOrderProblem(lambda t, q, v, w: q, [1.0], [0.0]),
            "acceleration(t, q)",
            "acceleration(t, q, v, w)",
        ),
        (
            lambda: SecondOrderProblem.from_force(lambda t: t, 1.0, [1.0], [0.0]),
            "force(t, q)",
            "force(t)",
        ),
        (
            lambda: FirstOrderProblem(restoring, [1.0], energy=lambda t: 0.0),
            "energy(t, y)",
            "energy(t)",
        ),
    ],
    ids=["f(t)", "f(t,y,z,w)", "acceleration(t)", "acceleration(t,q,v,w)", "force(t)", "energy(t)"],
)
def test_function_with_wrong_signature_is_refused(build, accepted, got):
    """The message shows the accepted form and the signature the user wrote."""
    refused(build, accepted, got)


@each_right_hand_side
def test_function_returning_wrong_shape_is_refused(build, name):
    """A right-hand side of 3 components for 2 coordinates is refused after its one check call."""
    f = counted(lambda t, x: np.zeros(3))
    refused(lambda: build(f), f"`{name}`", "(3,)", "(2,)")
    assert f.calls == 1


@pytest.mark.parametrize(
    "build",
    [
        lambda: vv.ode.FirstOrderProblem(lambda t, y: 1j * y, y0=[1.0]),
        lambda: vv.ode.SecondOrderProblem(lambda t, q: 1j * q, q0=[1.0], v0=[0.0]),
    ],
)
def test_complex_rate_for_a_real_state_is_refused(build):
    """A real state would silently drop the imaginary part of the rate; say how to keep it."""
    with pytest.raises(vv.ModelError, match=r"complex values for a real state.*y0 \+ 0j"):
        build()


def test_complex_state_with_complex_rate_is_accepted():
    rotation = vv.ode.FirstOrderProblem(lambda t, y: 1j * y, y0=[1.0 + 0j])
    sol = vv.solve(rotation, method="rk4", dt=1e-3, until=1.0)
    # y(t) = exp(i t); RK4's global error is O(h^4) = 1e-12 here.
    np.testing.assert_allclose(sol.y[-1, 0], np.exp(1j), atol=1e-11)


def test_numpy_function_not_vectorised_over_the_batch_is_refused():
    """A NumPy f sees the whole (batch, n) state; returning one system's row is refused."""
    f = counted(lambda t, y: -y[0])
    refused(lambda: FirstOrderProblem(f, np.ones((4, 2))), "`f`", "(2,)", "(4, 2)")
    assert f.calls == 1


@each_right_hand_side
def test_function_returning_none_is_refused(build, name):
    """Forgetting `return` is reported as such, with the `out` alternative."""
    f = counted(lambda t, x: None)
    refused(lambda: build(f), f"`{name}`", "None", "out")
    assert f.calls == 1


@each_right_hand_side
def test_function_returning_nan_at_initial_state_is_refused(build, name):
    """A right-hand side that is already nan at t0 is caught before any step, with the entry."""
    f = counted(lambda t, x: np.array([-x[0], np.nan]))
    refused(lambda: build(f), f"`{name}`", "nan", "entry 1")
    assert f.calls == 1


@numba.njit
def _numba_rhs_one_too_long(t, y):
    return np.zeros(y.shape[0] + 1)


@numba.njit
def _numba_acceleration_one_too_long(t, q):
    return np.zeros(q.shape[0] + 1)


@pytest.mark.parametrize(
    ("build", "name"),
    [
        (lambda: FirstOrderProblem(_numba_rhs_one_too_long, np.ones((4, 2))), "f"),
        (
            lambda: SecondOrderProblem(
                _numba_acceleration_one_too_long, np.ones((4, 2)), np.zeros((4, 2))
            ),
            "acceleration",
        ),
    ],
    ids=["f", "acceleration"],
)
def test_numba_function_of_wrong_shape_for_a_batch_is_refused(build, name):
    """A Numba function describes one system: its (3,) result for n = 2 is refused up front."""
    refused(build, f"`{name}`", "(3,)", "(2,)")


@pytest.mark.parametrize(
    ("build", "what"),
    [
        (lambda f, j: FirstOrderProblem(f, [1.0, 0.5], jacobian=j), "df/dy"),
        (lambda f, j: SecondOrderProblem(f, [1.0, 0.5], [0.0, 0.0], jacobian=j), "dF/dq"),
        (
            lambda f, j: SecondOrderProblem.from_force(f, 2.0, [1.0, 0.5], [0.0, 0.0], jacobian=j),
            "dF/dq",
        ),
    ],
    ids=["first-order", "acceleration", "from_force"],
)
def test_jacobian_of_wrong_shape_is_refused(build, what):
    """A (3, 3) Jacobian for 2 coordinates is refused with both shapes; f runs only its check."""
    f = counted(restoring)
    jacobian = counted(lambda t, x: -np.eye(3))
    refused(lambda: build(f, jacobian), "`jacobian`", "(3, 3)", "(2, 2)", what)
    assert (f.calls, jacobian.calls) == (1, 1)


def test_jacobian_pair_with_wrong_velocity_block_is_refused():
    """For a damped force, a wrong ∂F/∂v block is named as such."""
    force = counted(lambda t, q, v: -q - 0.1 * v)
    refused(
        lambda: SecondOrderProblem(
            force, [1.0, 0.5], [0.0, 0.0], jacobian=lambda t, q, v: (-np.eye(2), np.eye(3))
        ),
        "`jacobian`",
        "(3, 3)",
        "(2, 2)",
        "dF/dv",
    )
    assert force.calls == 1


@pytest.mark.parametrize(
    ("result", "type_name"),
    [(-np.eye(2), "ndarray"), ([-np.eye(2), -0.1 * np.eye(2)], "list")],
    ids=["one-matrix", "list"],
)
def test_velocity_dependent_jacobian_must_return_a_pair(result, type_name):
    """jacobian(t, q, v) of a damped force must return the tuple (dF/dq, dF/dv)."""
    force = counted(lambda t, q, v: -q - 0.1 * v)
    refused(
        lambda: SecondOrderProblem(force, [1.0, 0.5], [0.0, 0.0], jacobian=lambda t, q, v: result),
        "`jacobian(t, q, v)`",
        "pair",
        "dF/dv",
        type_name,
    )
    assert force.calls == 1


def test_position_only_jacobian_for_velocity_dependent_force_is_refused():
    """A damped force needs jacobian(t, q, v); jacobian(t, q) would silently drop ∂F/∂v."""
    refused(
        lambda: SecondOrderProblem(
            lambda t, q, v: -q - 0.1 * v, [1.0], [0.0], jacobian=lambda t, q: -np.eye(1)
        ),
        "`jacobian`",
        "jacobian(t, q, v)",
        "jacobian(t, q)",
    )


@pytest.mark.parametrize(
    ("build", "shape", "expected"),
    [
        (lambda: FirstOrderProblem(restoring, [1.0, 0.5], energy=lambda t, y: y), "(2,)", "()"),
        (
            lambda: SecondOrderProblem(restoring, [1.0, 0.5], [0.0, 0.0], energy=lambda t, q, v: q),
            "(2,)",
            "()",
        ),
        (
            lambda: SecondOrderProblem(
                restoring, np.ones((3, 2)), np.zeros((3, 2)), energy=lambda t, q, v: np.sum(q)
            ),
            "()",
            "(3,)",
        ),
    ],
    ids=["first-order-vector", "second-order-vector", "batch-returns-one-number"],
)
def test_energy_of_wrong_shape_is_refused(build, shape, expected):
    """The energy is one value per system: a vector, or one number for a batch, is refused."""
    refused(build, "`energy`", shape, expected, "one value per system")


@pytest.mark.parametrize(
    ("mass", "fragments"),
    [
        (-1.0, ("positive", "-1.0")),
        (0.0, ("positive", "0.0")),
        (math.nan, ("finite", "nan")),
        ([1.0, -2.0], ("positive", "-2.0")),
        ([1.0, math.nan], ("finite", "nan")),
        ([[1.0, 0.5], [0.0, 1.0]], ("symmetric", "0.5")),
        ([[1.0, 2.0], [2.0, 1.0]], ("positive definite",)),
        ([1.0, 2.0, 3.0], ("(3,)", "(2,)")),
        (np.ones((3, 3)), ("(3, 3)", "(..., 2, 2)")),
        (np.ones((2, 2, 2, 2)), ("(2, 2, 2, 2)",)),
        ("heavy", ("'heavy'",)),
    ],
    ids=[
        "negative",
        "zero",
        "nan",
        "negative-entry",
        "nan-entry",
        "non-symmetric",
        "not-positive-definite",
        "diagonal-wrong-length",
        "matrix-wrong-size",
        "4-d",
        "string",
    ],
)
def test_bad_mass_is_refused(mass, fragments):
    """Mass must be finite, positive (definite), symmetric and fit q0; the force never runs."""
    force = counted(restoring)
    refused(
        lambda: SecondOrderProblem.from_force(force, mass, [1.0, 0.5], [0.0, 0.0]),
        "`mass`",
        *fragments,
    )
    assert force.calls == 0


def test_sparse_mass_for_a_batch_is_refused():
    """A sparse mass describes one large system; for a batch the message says what to pass."""
    force = counted(restoring)
    refused(
        lambda: SecondOrderProblem.from_force(
            force, sp.identity(2, format="csc"), np.ones((3, 2)), np.zeros((3, 2))
        ),
        "sparse",
        "`mass`",
        "(3, 2)",
        "(batch, n, n)",
    )
    assert force.calls == 0


@pytest.mark.parametrize(
    ("t0", "shown"),
    [(math.nan, "nan"), (math.inf, "inf"), ("0", "'0'"), (10**400, "`t0`")],
    ids=["nan", "inf", "string", "int-beyond-float"],
)
@pytest.mark.parametrize("kind", ["first-order", "second-order"])
def test_bad_initial_time_is_refused(kind, t0, shown):
    """t0 must be a finite real number; even an int too large for a float is a ModelError."""
    f = counted(restoring)
    build = (
        (lambda: FirstOrderProblem(f, [1.0], t0=t0))
        if kind == "first-order"
        else (lambda: SecondOrderProblem(f, [1.0], [0.0], t0=t0))
    )
    refused(build, "`t0`", shown)
    assert f.calls == 0


# --------------------------------------------------------------------------------------------
# vv.solve: every invalid argument refused before f is called.


@pytest.mark.parametrize("method", ["rk4", "dopri5", "backward_euler"])
@pytest.mark.parametrize(
    ("dt", "shown"),
    [
        (0, "0"),
        (-1, "-1"),
        (-0.0, "-0.0"),
        (math.nan, "nan"),
        (math.inf, "inf"),
        ("0.1", "'0.1'"),
        (True, "True"),
        (1j, "1j"),
    ],
    ids=["zero", "negative", "negative-zero", "nan", "inf", "string", "True", "complex"],
)
def test_solve_refuses_bad_dt(decay, method, dt, shown):
    """dt ≤ 0, non-finite or not a real number is named with its value; f is never called."""
    problem, f = decay
    refused(lambda: vv.solve(problem, method, dt=dt, until=1.0), "`dt`", shown)
    assert f.calls == 0


def test_solve_refuses_dt_too_small_to_count_the_steps(decay):
    """A denormal dt gives an infinite number of steps: refused as a bad `dt`, not an overflow."""
    problem, f = decay
    refused(lambda: vv.solve(problem, "rk4", dt=5e-324, until=1.0), "`dt`", "5e-324")
    assert f.calls == 0


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
@pytest.mark.parametrize(
    ("until", "fragments"),
    [(-1.0, ("-1.0", "t0", "0.0")), (math.nan, ("nan",)), ("1", ("'1'",)), (10**400, ())],
    ids=["before-t0", "nan", "string", "int-beyond-float"],
)
def test_solve_refuses_bad_until(decay, method, until, fragments):
    """until before t0 or not a finite number is named with its value; f is never called."""
    problem, f = decay
    refused(lambda: vv.solve(problem, method, dt=0.1, until=until), "`until`", *fragments)
    assert f.calls == 0


@pytest.mark.parametrize(
    ("typo", "suggestion"),
    [("rk5", "'rk4'"), ("velocity_verlett", "'velocity_verlet'"), ("leap_frog", "'leapfrog'")],
)
def test_unknown_method_lists_valid_names_and_suggests_the_closest(spring, typo, suggestion):
    """A misspelt method gets "Did you mean" plus every valid name; nothing is integrated."""
    problem, acceleration = spring
    message = refused(
        lambda: vv.solve(problem, typo, dt=0.1, until=1.0),
        repr(typo),
        f"Did you mean {suggestion}?",
    )
    for name in vv.integrators.names():
        assert name in message
    assert acceleration.calls == 0


def test_unknown_method_far_from_every_name_lists_the_valid_ones(decay):
    """A name close to nothing gets the list of valid names and no misleading suggestion."""
    problem, f = decay
    message = refused(
        lambda: vv.solve(problem, "no_such_method", dt=0.1, until=1.0),
        "'no_such_method'",
        "rk4",
        "velocity_verlet",
        "dopri5",
    )
    assert "Did you mean" not in message
    assert f.calls == 0


@pytest.mark.parametrize(
    ("method", "type_name"), [(4, "int"), (None, "NoneType"), (["rk4"], "list")]
)
def test_method_that_is_not_a_name_is_refused(decay, method, type_name):
    """method must be a name or an Integrator; the type received is named."""
    problem, f = decay
    refused(lambda: vv.solve(problem, method, dt=0.1, until=1.0), "`method`", type_name)
    assert f.calls == 0


@pytest.mark.parametrize("method", ["velocity_verlet", "symplectic_euler", "leapfrog", "taylor"])
def test_split_state_method_on_first_order_problem_is_refused(decay, method):
    """Symplectic (q, v) methods need a SecondOrderProblem; the message says how to build one."""
    problem, f = decay
    refused(
        lambda: vv.solve(problem, method, dt=0.1, until=1.0),
        repr(method),
        "second-order",
        "SecondOrderProblem",
    )
    assert f.calls == 0


@pytest.mark.parametrize(
    ("option", "value"),
    [("rtol", 1e-6), ("atol", 1e-9), ("t_eval", [0.5, 1.0]), ("dense_output", True)],
)
def test_adaptive_options_are_refused_for_fixed_step_methods(decay, option, value):
    """rtol/atol/t_eval/dense_output would be silently ignored by rk4: refused instead."""
    problem, f = decay
    refused(
        lambda: vv.solve(problem, "rk4", dt=0.1, until=1.0, **{option: value}),
        f"`{option}`",
        "adaptive",
    )
    assert f.calls == 0


def test_fixed_step_method_needs_dt(decay):
    """rk4 without dt is refused, naming dt and the method."""
    problem, f = decay
    refused(lambda: vv.solve(problem, "rk4", until=1.0), "`dt`", "required", "'rk4'")
    assert f.calls == 0


def test_adaptive_run_needs_a_method_with_error_control(decay):
    """adaptive=True for rk4 is refused and the adaptive methods are listed."""
    problem, f = decay
    refused(
        lambda: vv.solve(problem, "rk4", dt=0.1, until=1.0, adaptive=True),
        "'rk4'",
        "error control",
        "dopri5",
    )
    assert f.calls == 0


@pytest.mark.parametrize(
    ("option", "value", "shown"),
    [
        ("record_every", 0, "0"),
        ("record_every", 1.5, "1.5"),
        ("record_every", -2, "-2"),
        ("substeps", 0, "0"),
        ("substeps", 2.0, "2.0"),
    ],
)
def test_record_every_and_substeps_must_be_positive_whole_numbers(decay, option, value, shown):
    """Frame and substep counts are whole numbers ≥ 1; a bad one is named with its value."""
    problem, f = decay
    refused(
        lambda: vv.solve(problem, "rk4", dt=0.1, until=1.0, **{option: value}), f"`{option}`", shown
    )
    assert f.calls == 0


@pytest.mark.parametrize(
    ("t_eval", "fragments"),
    [
        ([-0.5, 0.5], ("[t0, until]", "-0.5")),
        ([0.5, 2.0], ("[t0, until]", "2.0")),
        ([0.5, 0.2], ("increasing", "0.2")),
        ([0.5, 0.5, 0.7], ("increasing", "0.5")),
        ([], ("empty",)),
        ([0.5, math.nan], ("finite", "nan")),
    ],
    ids=["before-t0", "after-until", "decreasing", "repeated", "empty", "nan"],
)
def test_dopri5_refuses_bad_t_eval(decay, t_eval, fragments):
    """Output times must be finite, strictly increasing and inside [t0, until]; the offending
    time is shown."""
    problem, f = decay
    refused(lambda: vv.solve(problem, "dopri5", until=1.0, t_eval=t_eval), "`t_eval`", *fragments)
    assert f.calls == 0


@pytest.mark.parametrize(
    ("option", "value"),
    [("rtol", 0.0), ("rtol", math.nan), ("atol", -1e-9)],
)
def test_dopri5_refuses_bad_tolerances(decay, option, value):
    """Tolerances must be finite, rtol > 0 and atol ≥ 0."""
    problem, f = decay
    refused(
        lambda: vv.solve(problem, "dopri5", until=1.0, **{option: value}),
        f"`{option}`",
        repr(value),
    )
    assert f.calls == 0


@pytest.mark.parametrize(
    ("method", "fragments"), [("rk4", ("'rk4'", "Numba")), ("dopri5", ("fixed-step",))]
)
def test_compiled_true_that_cannot_be_honoured_is_refused(decay, method, fragments):
    """compiled=True with a NumPy f, or with an adaptive method, is refused, not ignored."""
    problem, f = decay
    refused(
        lambda: vv.solve(problem, method, dt=0.1, until=1.0, compiled=True),
        "compiled=True",
        *fragments,
    )
    assert f.calls == 0


def test_something_that_is_not_a_problem_is_refused():
    """Passing the right-hand side itself instead of a problem is a ModelError naming `problem`."""
    refused(
        lambda: vv.solve(restoring, "rk4", dt=0.1, until=1.0),
        "`problem`",
        "function",
        "FirstOrderProblem",
    )


def test_simulate_is_gone_and_says_what_replaced_it():
    with pytest.raises(AttributeError, match=r"merged into vv.solve: .*raise_for_status"):
        vv.simulate  # noqa: B018


# --------------------------------------------------------------------------------------------
# vv.solve with a fixed-step method: the same core cases as the loop sees them.


@pytest.mark.parametrize(
    ("arguments", "fragments"),
    [
        ({"dt": 0.0}, ("`dt`", "0.0")),
        ({"dt": -0.1}, ("`dt`", "-0.1")),
        ({"dt": math.nan}, ("`dt`", "nan")),
        ({"dt": math.inf}, ("`dt`", "inf")),
        ({"dt": "0.1"}, ("`dt`", "'0.1'")),
        ({"dt": True}, ("`dt`", "True")),
        ({"until": -1.0}, ("`until`", "-1.0", "t0")),
        ({"until": math.nan}, ("`until`", "nan")),
        ({"method": "rk5"}, ("'rk5'", "Did you mean 'rk4'?", "velocity_verlet")),
        ({"method": 4}, ("`method`", "int")),
        ({"record_every": 0}, ("`record_every`", "0")),
        ({"record_every": 1.5}, ("`record_every`", "1.5")),
        ({"substeps": 0}, ("`substeps`", "0")),
        ({"compiled": True}, ("compiled=True", "'rk4'")),
        ({"divergence_limit": -1.0}, ("`divergence_limit`", "-1.0")),
    ],
    ids=lambda value: (
        "-".join(f"{k}={v}" for k, v in value.items()) if isinstance(value, dict) else None
    ),
)
def test_fixed_step_solve_refuses_bad_arguments(decay, arguments, fragments):
    """vv.solve names the bad argument and its value, and never calls f."""
    problem, f = decay
    options = {"method": "rk4", "dt": 0.1, "until": 1.0} | arguments
    method = options.pop("method")
    refused(lambda: vv.solve(problem, method, **options), *fragments)
    assert f.calls == 0


# --------------------------------------------------------------------------------------------
# The integrator registry.


class _NotAnIntegrator:
    name = "not_an_integrator"
    order = 1


@pytest.mark.parametrize(
    ("candidate", "type_name"),
    [
        (object(), "object"),
        ("rk4", "str"),
        (lambda system, state, dt: state, "function"),
        (_NotAnIntegrator, "_NotAnIntegrator"),
    ],
    ids=["object", "name", "function", "look-alike-class"],
)
def test_register_refuses_what_is_not_an_integrator(candidate, type_name):
    """register() takes Integrator instances or subclasses; the registry is left unchanged."""
    before = vv.integrators.names()
    try:
        refused(lambda: vv.integrators.register(candidate), "Integrator", type_name)
    finally:
        for name in set(vv.integrators.names()) - set(before):
            vv.integrators.unregister(name)
    assert vv.integrators.names() == before


@pytest.mark.parametrize(
    "candidate",
    [vv.integrators.RungeKutta4, vv.integrators.RungeKutta4()],
    ids=["class", "instance"],
)
def test_register_refuses_a_taken_name(candidate):
    """A second 'rk4' needs replace=True; the registered method stays the original."""
    original = vv.integrators.get("rk4")
    refused(
        lambda: vv.integrators.register(candidate), "'rk4'", "already registered", "replace=True"
    )
    assert vv.integrators.get("rk4") is original


@pytest.mark.parametrize(("typo", "suggestion"), [("rk5", "'rk4'"), ("leap_frog", "'leapfrog'")])
def test_get_unknown_name_suggests_and_lists(typo, suggestion):
    """vv.integrators.get names the unknown method, suggests the closest, lists all."""
    message = refused(lambda: vv.integrators.get(typo), repr(typo), f"Did you mean {suggestion}?")
    for name in vv.integrators.names():
        assert name in message


# --------------------------------------------------------------------------------------------
# Analysis entry points.


@pytest.mark.parametrize(
    "sources",
    [{}, {"eigenvalues": [-1.0], "jacobian": -np.eye(1)}],
    ids=["neither", "both"],
)
def test_max_stable_dt_needs_exactly_one_spectrum_source(sources):
    """The largest stable step comes from eigenvalues or a Jacobian: exactly one of them."""
    refused(lambda: vv.analysis.max_stable_dt("rk4", **sources), "`eigenvalues`", "`jacobian`")


@pytest.mark.parametrize(
    ("jacobian", "shown"),
    [(np.array([[-1.0, math.nan], [0.0, -1.0]]), "nan"), (np.ones((2, 3)), "(2, 3)")],
    ids=["nan", "non-square"],
)
def test_max_stable_dt_refuses_a_bad_jacobian(jacobian, shown):
    """A Jacobian holding nan (a blown-up state) or not square is a user error naming it."""
    refused(lambda: vv.analysis.max_stable_dt("rk4", jacobian=jacobian), "`jacobian`", shown)


def test_max_stable_dt_blames_the_eigenvalues_it_was_given():
    """Non-finite eigenvalues are reported as such, not as a Jacobian the user never passed."""
    message = refused(
        lambda: vv.analysis.max_stable_dt("rk4", eigenvalues=[-1.0, math.nan]),
        "`eigenvalues`",
        "nan",
    )
    assert "jacobian" not in message.lower()


@pytest.mark.parametrize("axis", ["diagonal", "imag", ""])
def test_stability_interval_names_the_valid_axes(axis):
    """Only the real and imaginary axes have intervals; the message lists both."""
    refused(
        lambda: vv.analysis.stability_interval("rk4", axis=axis),
        "`axis`",
        repr(axis),
        "'real'",
        "'imaginary'",
    )


def test_stability_interval_of_unknown_method_suggests_the_closest():
    """Analysis functions resolve methods through the registry: same message as solve."""
    refused(lambda: vv.analysis.stability_interval("rk5"), "'rk5'", "Did you mean 'rk4'?")


# --------------------------------------------------------------------------------------------
# Messages show values as the user wrote them.


@pytest.mark.parametrize(
    ("call", "shown"),
    [
        (lambda: FirstOrderProblem(restoring, [1.0, math.nan]), "entry 1 is nan"),
        (
            lambda: FirstOrderProblem(lambda t, y: np.array([-y[0], math.inf]), [1.0, 0.5]),
            "returned inf",
        ),
        (
            lambda: vv.solve(
                FirstOrderProblem(restoring, [1.0]), "dopri5", until=1.0, t_eval=[0.5, 2.0]
            ),
            "[0.5, 2.0]",
        ),
    ],
    ids=["initial-state", "function-result", "t_eval-range"],
)
def test_values_in_messages_read_as_the_user_wrote_them(call, shown):
    """Messages say ``nan`` or ``[0.5, 2.0]``, not NumPy reprs such as ``np.float64(nan)``."""
    message = refused(call, shown)
    assert "np.float64(" not in message


# --------------------------------------------------------------------------------------------
# Property: any bad time step is a ModelError about `dt`, never another exception.

BAD_DT = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, 0, 1e400]),
    st.floats(max_value=0.0, allow_nan=False),  # zero and negative, down to -inf
    st.integers(max_value=0),
    st.integers(min_value=2**1024),  # too large for a float
    st.integers(max_value=-(2**1024)),
    st.floats(max_value=0.0, allow_nan=False, width=32).map(np.float32),
    st.integers(min_value=-(2**62), max_value=0).map(np.int64),
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dt=BAD_DT, method=st.sampled_from(["rk4", "velocity_verlet", "dopri5", "trapezoidal"]))
def test_any_bad_dt_is_a_model_error_about_dt(dt, method):
    """nan, ±inf, 0, negative or out-of-range dt: always ModelError naming dt, no step taken."""
    acceleration = counted(restoring)
    problem = SecondOrderProblem(acceleration, [1.0], [0.0])
    acceleration.calls = 0
    with pytest.raises(ModelError) as caught:
        vv.solve(problem, method, dt=dt, until=1.0)
    assert "dt" in str(caught.value)
    assert acceleration.calls == 0
