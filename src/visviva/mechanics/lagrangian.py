"""Lagrangian mechanics: from kinetic and potential energy to a problem every integrator runs.

Seed 001's recipe — pick generalized coordinates ``q``, write the kinetic energy ``K(q, q̇)``
and the potential ``U(q)``, form ``L = K − U`` and apply the Euler–Lagrange equations
``d/dt ∂L/∂q̇ − ∂L/∂q = Q`` — is carried out here symbolically. Expanding the time derivative
gives the equations in the form the integrators need,

    M(q, q̇) q̈ = F(q, q̇, t),
    M = ∂²L/∂q̇∂q̇,   F = Q + ∂L/∂q − (∂²L/∂q̇∂q) q̇ − ∂²L/∂q̇∂t,

which :meth:`LagrangianSystem.problem` turns into a :class:`~visviva.ode.SecondOrderProblem`
(``q̈ = M⁻¹F`` solved numerically at each evaluation, with its analytic Jacobian and the energy
``E = q̇·∂L/∂q̇ − L``). :meth:`LagrangianSystem.canonical_problem` gives Hamilton's equations in
``(q, p)`` with ``p = ∂L/∂q̇`` instead, the form in which implicit midpoint is symplectic even
when ``M`` depends on ``q`` (the double pendulum).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import sympy
from sympy.core.function import AppliedUndef

from .._memo import Memo
from .._registry import did_you_mean
from .._validation import describe, real_number, state_array
from ..errors import ModelError
from ..ode.problems import FirstOrderProblem, SecondOrderProblem
from .codegen import FLAVOURS
from .equations_code import Derived, EquationsCode

__all__ = ["LagrangianSystem"]

#: Smallest ratio of the smallest to the largest eigenvalue of M(q0) accepted as invertible.
MASS_MATRIX_CONDITION = 1e-12


class LagrangianSystem:
    """A mechanical system given by its energies in generalized coordinates.

    Args:
        coordinates: The generalized coordinates ``q``: SymPy functions of time
            (``sympy.Function("theta")(t)`` or ``sympy.physics.mechanics.dynamicsymbols``),
            whose ``.diff(t)`` are the velocities, or plain symbols together with
            ``velocities``.
        kinetic: Kinetic energy ``K(q, q̇, t)`` [J], a SymPy expression.
        potential: Potential energy ``U(q, t)`` [J]; it may not depend on the velocities.
        velocities: Symbols for ``q̇``, one per coordinate, when the coordinates are symbols.
        parameters: Values of the other symbols, by symbol or name, e.g. ``{"m": 1.0}``.
            Every symbol that is not a coordinate, velocity or the time needs one.
        forces: Generalized non-conservative forces ``Q_i(q, q̇, t)`` (damping, drive), one
            per coordinate, in the units of ``∂L/∂q_i``.
        time: The time symbol, if ``K``, ``U`` or ``forces`` depend on time explicitly and
            the coordinates are plain symbols (with functions of time it is their argument).
        points: Where the bodies are, for pictures: ``(x, y)`` or ``(x, y, z)`` [m] per point,
            as expressions of the coordinates (and parameters, time), world Y up. Recordings
            of the system then carry ``points`` and the video, viewer and exporters draw them.
        edges: Pairs of point indices drawn as lines (rods, springs).
        name: Short description for messages and recordings.

    Example:
        >>> import sympy, visviva as vv
        >>> t, m, L, g = sympy.symbols("t m L g")
        >>> theta = sympy.Function("theta")(t)
        >>> pendulum = vv.mechanics.LagrangianSystem(
        ...     [theta],
        ...     kinetic=m * L**2 * theta.diff(t) ** 2 / 2,
        ...     potential=-m * g * L * sympy.cos(theta),
        ...     parameters={"m": 1.0, "L": 2.0, "g": 9.81},
        ... )
        >>> pendulum.equations()[0]
        Eq(L**2*m*Derivative(theta(t), (t, 2)), -L*g*m*sin(theta(t)))
        >>> problem = pendulum.problem(q0=[0.1], v0=[0.0])
    """

    def __init__(
        self,
        coordinates: Sequence[Any],
        kinetic: Any,
        potential: Any = 0,
        *,
        velocities: Sequence[Any] | None = None,
        parameters: Mapping[Any, float] | None = None,
        forces: Sequence[Any] | None = None,
        time: Any = None,
        points: Sequence[Sequence[Any]] | None = None,
        edges: Sequence[tuple[int, int]] = (),
        name: str = "Lagrangian system",
    ) -> None:
        self.name = str(name)
        self._t, self._q, self._v, self._shown = _read_coordinates(coordinates, velocities, time)
        n = len(self._q)
        self._to_internal = _internal_substitution(
            list(coordinates), velocities, self._t, self._q, self._v
        )
        kinetic_energy = self._internal("kinetic", kinetic)
        potential_energy = self._internal("potential", potential)
        if forces is None:
            generalized = [sympy.Integer(0)] * n
        else:
            if isinstance(forces, (str, bytes)) or len(forces) != n:
                raise ModelError(
                    f"`forces` must hold one generalized force per coordinate ({n}) "
                    f"(got {describe(forces)})"
                )
            generalized = [self._internal(f"forces[{i}]", f) for i, f in enumerate(forces)]
        moving = set(self._v)
        if potential_energy.free_symbols & moving:
            used = sorted(
                str(self._shown_velocity(s)) for s in potential_energy.free_symbols & moving
            )
            raise ModelError(
                f"`potential` depends on the velocities {', '.join(used)}: a potential energy "
                "U(q, t) depends on positions only; velocity-dependent terms belong in `kinetic` "
                "(or as generalized `forces`)"
            )
        self._constants = _read_parameters(
            parameters,
            [kinetic_energy, potential_energy, *generalized],
            {self._t, *self._q, *moving},
        )
        #: Parameter name → value.
        self.parameters = {s.name: value for s, value in self._constants.items()}
        self._derived = _derive(
            self._q, self._v, self._t, kinetic_energy, potential_energy, generalized
        )
        for i, row in enumerate(self._derived.mass.tolist()):
            if all(entry == 0 for entry in row):
                raise ModelError(
                    f"the kinetic energy does not depend on the velocity of {self._shown[i]}: "
                    "the mass matrix has a zero row and q̈ cannot be solved for; give every "
                    "coordinate a kinetic term (or remove the coordinate)"
                )
        #: The acceleration depends on the velocities (``acceleration(t, q, v)``).
        self.velocity_dependent = self._derived.velocity_dependent
        self._points = self._read_points(points or ())
        self.edges = _read_edges(edges, len(self._points))
        # Each flavour's code, built once even when many runs ask for it at once.
        self._compiled: Memo[EquationsCode] = Memo(len(FLAVOURS))

    # --- symbols --------------------------------------------------------------------------

    @property
    def size(self) -> int:
        """Number of generalized coordinates ``n``."""
        return len(self._q)

    @property
    def coordinates(self) -> tuple[sympy.Expr, ...]:
        """The coordinates as given (functions of time shown as such)."""
        return tuple(self._shown)

    def _shown_velocity(self, symbol: sympy.Symbol) -> sympy.Expr:
        return sympy.Derivative(self._shown[self._v.index(symbol)], self._t)

    def _internal(self, what: str, expression: Any) -> sympy.Expr:
        """``expression`` as a SymPy expression in the internal symbols, or a clear error."""
        if isinstance(expression, (int, float)) and not isinstance(expression, bool):
            expression = sympy.sympify(expression)
        if not isinstance(expression, sympy.Expr):
            raise ModelError(
                f"`{what}` must be a SymPy expression (got {type(expression).__name__} "
                f"{describe(expression)}); build it from sympy symbols, e.g. "
                "m * L**2 * theta.diff(t)**2 / 2"
            )
        allowed = self._to_internal[0] if len(self._to_internal) == 2 else {}
        derivatives = [d for d in expression.atoms(sympy.Derivative) if d not in allowed]
        if derivatives:
            raise ModelError(
                f"`{what}` contains {derivatives[0]}: only the coordinates' first time "
                "derivatives (the velocities) may appear"
            )
        internal = expression
        for substitution in self._to_internal:
            internal = internal.xreplace(substitution)
        if not internal.is_finite and internal.is_number:
            raise ModelError(f"`{what}` is not finite (got {expression})")
        return internal

    def _read_points(self, points: Sequence[Sequence[Any]]) -> list[list[sympy.Expr]]:
        """Each point as three internal expressions of ``q``, ``t`` and the parameters."""
        read = []
        allowed = {self._t, *self._q, *self._constants}
        for i, point in enumerate(points):
            if isinstance(point, (str, bytes)) or len(point) not in (2, 3):
                raise ModelError(
                    f"`points[{i}]` must be (x, y) or (x, y, z) (got {describe(point)})"
                )
            xyz = [self._internal(f"points[{i}][{c}]", e) for c, e in enumerate(point)]
            xyz += [sympy.Integer(0)] * (3 - len(xyz))
            stray = set().union(*(e.free_symbols for e in xyz)) - allowed
            if stray:
                names = sorted(
                    str(self._shown_velocity(s)) if s in self._v else str(s) for s in stray
                )
                raise ModelError(
                    f"`points[{i}]` uses {', '.join(names)}: a point's position may depend on "
                    "the coordinates, the time and the parameters only"
                )
            read.append(xyz)
        return read

    def _shown_expression(self, expression: sympy.Expr) -> sympy.Expr:
        """An internal expression written back in the user's coordinates and parameters."""
        back = {q: shown for q, shown in zip(self._q, self._shown, strict=True)}
        back |= {v: sympy.Derivative(s, self._t) for v, s in zip(self._v, self._shown, strict=True)}
        return expression.xreplace(back)

    # --- the derived equations ----------------------------------------------------------------

    def equations(self, *, simplify: bool = True) -> list[sympy.Eq]:
        """The Euler–Lagrange equations ``Σ_j M_ij q̈_j = F_i``, one per coordinate.

        Args:
            simplify: Tidy each side with ``sympy.simplify`` (for display: the numeric code
                does not depend on it; it can take seconds for large systems).
        """
        accelerations = [sympy.Derivative(s, (self._t, 2)) for s in self._shown]
        derived = self._derived
        result = []
        for i in range(self.size):
            left = sum(
                (
                    self._shown_expression(derived.mass[i, j]) * accelerations[j]
                    for j in range(self.size)
                ),
                sympy.Integer(0),
            )
            right = self._shown_expression(derived.force[i])
            if simplify:
                left, right = _tidy(left), _tidy(right)
            result.append(sympy.Eq(left, right))
        return result

    def latex(self, *, simplify: bool = True) -> str:
        """The equations of motion as LaTeX (dots for time derivatives), one per line."""
        from sympy.physics.vector.printing import vlatex

        lines = [vlatex(eq) for eq in self.equations(simplify=simplify)]
        return " \\\\\n".join(lines)

    def text(self, *, simplify: bool = True) -> str:
        """The equations of motion as plain text (``theta''`` for a second derivative)."""
        from sympy.physics.vector.printing import vsstrrepr

        return "\n".join(
            f"{vsstrrepr(eq.lhs)} = {vsstrrepr(eq.rhs)}" for eq in self.equations(simplify=simplify)
        )

    def __str__(self) -> str:
        return f"{self.name}:\n{self.text()}"

    def __repr__(self) -> str:
        shown = ", ".join(map(str, self._shown))
        return f"LagrangianSystem({self.name!r}, coordinates [{shown}])"

    # --- numbers ------------------------------------------------------------------------------

    def mass_matrix(self, q: Any, v: Any = None, t: float = 0.0) -> np.ndarray:
        """``M(q, q̇, t)`` evaluated: shape ``(n, n)``, or ``(batch, n, n)`` for a batch of q.

        ``v`` is needed only if the kinetic energy is not quadratic in the velocities.
        """
        q = self._state("q", q)
        v = np.zeros_like(q) if v is None else self._state("v", v)
        out = np.empty(q.shape + q.shape[-1:])
        self._code("numpy").mass_matrix(t, q, v, out)
        return out

    def energy(self, q: Any, v: Any, t: float = 0.0) -> Any:
        """The energy ``E = q̇·∂L/∂q̇ − L`` [J] (``K + U`` when K is quadratic in q̇)."""
        q, v = self._state("q", q), self._state("v", v)
        return self._code("numpy").energy(t, q, v)

    def momenta(self, q: Any, v: Any, t: float = 0.0) -> np.ndarray:
        """The generalized momenta ``p = ∂L/∂q̇`` at ``(q, q̇)``, shape of ``q``."""
        q, v = self._state("q", q), self._state("v", v)
        out = np.empty(np.broadcast_shapes(q.shape, v.shape))
        self._code("numpy").momenta(t, q, v, out)
        return out

    def velocities(self, q: Any, p: Any, t: float = 0.0) -> np.ndarray:
        """The velocities ``q̇`` with momenta ``p`` at ``q`` (inverse of :meth:`momenta`)."""
        self._require_canonical()
        q, p = self._state("q", q), self._state("p", p)
        out = np.empty(np.broadcast_shapes(q.shape, p.shape))
        self._code("numpy").velocities(t, q, p, out)
        return out

    def points(self, q: Any, t: Any = 0.0) -> np.ndarray:
        """The positions of the system's ``points`` [m]: shape ``(frames, P, 3)`` for ``q`` of
        shape ``(frames, n)`` (or ``(P, 3)`` for one state); ``t`` [s] per frame or one value.
        """
        q = self._state("q", q)
        if not self._points:
            raise ModelError(f"{self.name} was built without `points`: nothing to draw")
        out = np.empty(q.shape[:-1] + (len(self._points), 3))
        self._code("numpy").points(np.asarray(t, dtype=float), q, out)
        return out

    def _state(self, name: str, value: Any) -> np.ndarray:
        array = state_array(name, value)
        if array.shape[-1] != self.size:
            raise ModelError(
                f"`{name}` must have {self.size} entries, one per coordinate "
                f"({', '.join(map(str, self._shown))}) (got shape {array.shape})"
            )
        return array

    # --- problems -----------------------------------------------------------------------------

    def problem(
        self,
        q0: Any,
        v0: Any,
        t0: float = 0.0,
        *,
        backend: str = "numba",
        name: str | None = None,
    ) -> SecondOrderProblem:
        """The equations of motion as a second-order problem ``q̈ = M(q)⁻¹ F(q, q̇, t)``.

        The acceleration is position-only (``acceleration(t, q)``, which symplectic methods
        need) when neither ``M`` nor ``F`` depends on the velocities. The analytic Jacobian
        ``∂q̈/∂x = M⁻¹(∂F/∂x − (∂M/∂x) q̈)`` (x = q, q̇) serves the implicit methods, and the
        energy is recorded every frame.

        Args:
            q0: Initial coordinates, shape ``(n,)`` or ``(batch, n)``.
            v0: Initial velocities ``q̇(t0)``, same shape.
            t0: Initial time [s].
            backend: ``"numba"`` (compiled, one system per call; the foundation's compiled
                loops run the whole simulation in machine code) or ``"numpy"`` (vectorised
                over the batch, no compilation).
            name: Problem name (default: the system's).

        Raises:
            ModelError: For a wrong shape, non-finite values or a mass matrix that is not
                positive definite at ``q0`` (a coordinate singularity, or a kinetic energy
                that is not a positive quadratic form).
        """
        q0, v0, t0 = self._initial_state(q0, v0, t0)
        code = self._code(backend)
        return SecondOrderProblem(
            code.acceleration,
            q0,
            v0,
            t0,
            jacobian=code.jacobian,
            energy=code.energy,
            name=name or self.name,
        )

    def canonical_problem(
        self,
        q0: Any,
        v0: Any,
        t0: float = 0.0,
        *,
        backend: str = "numba",
        name: str | None = None,
    ) -> FirstOrderProblem:
        """Hamilton's equations in ``y = (q, p)``: ``q̇ = M⁻¹(p − b)``, ``ṗ = ∂L/∂q + Q``.

        ``p = ∂L/∂q̇ = M(q) q̇ + b(q)`` are the generalized momenta. In these variables the
        flow is symplectic, so implicit midpoint (a symplectic Runge–Kutta method) keeps the
        energy of a conservative system bounded for any ``M(q)``; in ``(q, q̇)`` no method
        can promise that when ``M`` depends on ``q``. Needs a kinetic energy quadratic in the
        velocities. The state starts from ``(q0, p(q0, v0))``; :meth:`velocities` maps
        recorded momenta back. The analytic Jacobian serves the implicit methods.

        Args:
            q0, v0, t0, backend, name: As for :meth:`problem`.
        """
        self._require_canonical()
        q0, v0, t0 = self._initial_state(q0, v0, t0)
        y0 = np.concatenate([q0, self.momenta(q0, v0, t0)], axis=-1)
        code = self._code(backend)
        f, hamiltonian = code.canonical
        return FirstOrderProblem(
            f,
            y0,
            t0,
            jacobian=code.canonical_jacobian,
            energy=hamiltonian,
            name=name or f"{self.name} (q, p)",
        )

    def _require_canonical(self) -> None:
        if not self._derived.quadratic:
            raise ModelError(
                f"{self.name}: the kinetic energy is not quadratic in the velocities (M depends "
                "on them), so p = ∂L/∂q̇ cannot be inverted in closed form; use problem()"
            )

    def _initial_state(self, q0: Any, v0: Any, t0: Any) -> tuple[np.ndarray, np.ndarray, float]:
        """Checked initial state: shapes, finite values and an invertible mass matrix."""
        q0, v0 = self._state("q0", q0), self._state("v0", v0)
        if q0.shape != v0.shape:
            raise ModelError(f"`q0` and `v0` must have the same shape (got {q0.shape}, {v0.shape})")
        t0 = real_number("t0", t0, unit=" s")
        self._check_mass_matrix(q0, v0, t0)
        return q0, v0, t0

    def _check_mass_matrix(self, q0: np.ndarray, v0: np.ndarray, t0: float) -> None:
        mass = self.mass_matrix(q0, v0, t0)
        eigenvalues = np.linalg.eigvalsh(0.5 * (mass + np.swapaxes(mass, -1, -2)))
        smallest, largest = eigenvalues[..., 0], np.abs(eigenvalues).max(axis=-1)
        bad = ~(smallest > MASS_MATRIX_CONDITION * largest)
        if np.any(bad):
            index = np.flatnonzero(np.atleast_1d(bad))[0]
            where = np.atleast_2d(q0)[index]
            values = np.atleast_2d(eigenvalues)[index]
            raise ModelError(
                f"{self.name}: the mass matrix M(q0) is singular or not positive definite at "
                f"q0 = {describe(where)} (eigenvalues {describe(values)}); "
                "these coordinates cannot describe that configuration (a coordinate "
                "singularity), or the kinetic energy is not a positive quadratic form in the "
                "velocities"
            )

    # --- generated functions ----------------------------------------------------------------

    def _code(self, flavour: str) -> EquationsCode:
        """The numeric functions in one flavour, generated (and compiled) once and kept."""
        if flavour not in FLAVOURS:
            raise ModelError(
                f"unknown `backend` {flavour!r}.{did_you_mean(flavour, FLAVOURS)} "
                f"Valid: {', '.join(FLAVOURS)}"
            )
        return self._compiled.get(
            flavour,
            lambda: EquationsCode(self._derived, self._constants, flavour, points=self._points),
        )


# --- reading the user's description ---------------------------------------------------------


def _read_coordinates(
    coordinates: Sequence[Any], velocities: Sequence[Any] | None, time: Any
) -> tuple[sympy.Symbol, tuple[sympy.Symbol, ...], tuple[sympy.Symbol, ...], list[sympy.Expr]]:
    """Internal symbols ``(t, q, v)`` and the coordinates as shown (functions of time)."""
    if isinstance(coordinates, (str, bytes)) or not isinstance(coordinates, Iterable):
        raise ModelError(
            f"`coordinates` must be a list of SymPy symbols or functions of time (got "
            f"{describe(coordinates)})"
        )
    coordinates = list(coordinates)
    if not coordinates:
        raise ModelError("`coordinates` is empty: a system needs at least one coordinate")
    functions = [c for c in coordinates if isinstance(c, AppliedUndef)]
    if functions and len(functions) != len(coordinates):
        raise ModelError(
            "`coordinates` mixes functions of time and plain symbols; write them all as "
            "functions of time (theta(t)) or all as symbols with `velocities`"
        )
    if functions:
        arguments = {c.args for c in functions}
        if len(arguments) != 1 or len(next(iter(arguments))) != 1:
            raise ModelError(
                f"`coordinates` must all be functions of one time symbol (got {coordinates})"
            )
        (t,) = next(iter(arguments))
        if not isinstance(t, sympy.Symbol):
            raise ModelError(f"`coordinates` must be functions of a time symbol (got {t})")
        if velocities is not None:
            raise ModelError(
                "`velocities` is for plain-symbol coordinates; with functions of time the "
                "velocities are their derivatives (theta.diff(t))"
            )
        shown = coordinates
        names = [c.func.__name__ for c in coordinates]
    else:
        for i, c in enumerate(coordinates):
            if not isinstance(c, sympy.Symbol):
                raise ModelError(
                    f"`coordinates[{i}]` must be a SymPy symbol or a function of time "
                    f"(got {type(c).__name__} {describe(c)})"
                )
        if velocities is None or len(list(velocities)) != len(coordinates):
            raise ModelError(
                "plain-symbol `coordinates` need `velocities`, one symbol per coordinate "
                f"(got {describe(velocities)}); or write the coordinates as functions of time"
            )
        t = sympy.Symbol("t") if time is None else time
        if not isinstance(t, sympy.Symbol):
            raise ModelError(f"`time` must be a SymPy symbol (got {describe(time)})")
        names = [c.name for c in coordinates]
        shown = [sympy.Function(name)(t) for name in names]
    if len(set(names)) != len(names):
        raise ModelError(f"`coordinates` repeats a name (got {', '.join(names)})")
    q = tuple(sympy.Dummy(f"q_{name}", real=True) for name in names)
    v = tuple(sympy.Dummy(f"v_{name}", real=True) for name in names)
    return t, q, v, shown


def _internal_substitution(
    coordinates: Sequence[Any],
    velocities: Sequence[Any] | None,
    t: sympy.Symbol,
    q: tuple[sympy.Symbol, ...],
    v: tuple[sympy.Symbol, ...],
) -> list[dict[Any, Any]]:
    """User symbols → internal ones, as substitutions applied in order.

    With functions of time the derivatives go first, so that ``theta(t)`` is not replaced
    inside ``Derivative(theta(t), t)``.
    """
    if velocities is None:
        derivatives = {c.diff(t): vi for c, vi in zip(coordinates, v, strict=True)}
        return [derivatives, dict(zip(coordinates, q, strict=True))]
    velocities = list(velocities)
    for i, w in enumerate(velocities):
        if not isinstance(w, sympy.Symbol) or w in coordinates or w == t:
            raise ModelError(
                f"`velocities[{i}]` must be a SymPy symbol distinct from the coordinates and "
                f"the time (got {describe(w)})"
            )
    return [dict(zip(coordinates, q, strict=True)) | dict(zip(velocities, v, strict=True))]


def _read_edges(edges: Sequence[tuple[int, int]], count: int) -> tuple[tuple[int, int], ...]:
    read = []
    for i, edge in enumerate(edges):
        pair = tuple(edge) if not isinstance(edge, (str, bytes)) else ()
        if len(pair) != 2 or not all(
            isinstance(k, (int, np.integer)) and 0 <= k < count and not isinstance(k, bool)
            for k in pair
        ):
            raise ModelError(
                f"`edges[{i}]` must be two point indices in 0..{count - 1} (got {describe(edge)})"
            )
        read.append((int(pair[0]), int(pair[1])))
    return tuple(read)


def _read_parameters(
    parameters: Mapping[Any, float] | None,
    expressions: list[sympy.Expr],
    known: set[sympy.Symbol],
) -> dict[sympy.Symbol, float]:
    """Parameter symbol → value (sorted by name), checked against the symbols the energies use."""
    free = set().union(*(e.free_symbols for e in expressions)) - known
    given: dict[str, float] = {}
    for key, value in (parameters or {}).items():
        label = key.name if isinstance(key, sympy.Symbol) else str(key)
        given[label] = real_number(f"parameters[{label!r}]", value)
    by_name = {s.name: s for s in free}
    missing = sorted(set(by_name) - set(given))
    if missing:
        raise ModelError(
            f"the energies use the symbols {', '.join(missing)}, which are not coordinates, "
            f"velocities or the time: give their values in `parameters` (e.g. "
            f"parameters={{{', '.join(repr(m) + ': ...' for m in missing)}}})"
        )
    unused = sorted(set(given) - set(by_name))
    if unused:
        hint = did_you_mean(unused[0], by_name)
        raise ModelError(
            f"`parameters` gives {', '.join(unused)}, which the energies do not use.{hint}"
        )
    return {s: given[s.name] for s in sorted(free, key=lambda s: s.name)}


def _derive(
    q: tuple[sympy.Symbol, ...],
    v: tuple[sympy.Symbol, ...],
    t: sympy.Symbol,
    kinetic: sympy.Expr,
    potential: sympy.Expr,
    generalized: list[sympy.Expr],
) -> Derived:
    """The Euler–Lagrange equations with the total time derivative expanded (module docstring)."""
    lagrangian = kinetic - potential
    momentum = sympy.Matrix([lagrangian.diff(vi) for vi in v])
    mass = momentum.jacobian(v)
    dl_dq = sympy.Matrix([lagrangian.diff(qi) for qi in q]) + sympy.Matrix(generalized)
    force = dl_dq - momentum.jacobian(q) * sympy.Matrix(v) - momentum.diff(t)
    energy = (sympy.Matrix(v).T * momentum)[0, 0] - lagrangian
    return Derived(q, v, t, mass, force, momentum, energy, dl_dq)


def _tidy(expression: sympy.Expr) -> sympy.Expr:
    return sympy.simplify(sympy.trigsimp(expression))
