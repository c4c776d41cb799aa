"""The numeric functions of a Lagrangian system, written as source from its derived equations.

Every function has the form the foundation expects (:mod:`visviva.ode.functions`), identical
for both flavours: ``acceleration(t, q[, v], out)``, ``jacobian(t, q[, v])``,
``energy(t, q, v)``, and Hamilton's ``f(t, y, out)`` / ``hamiltonian(t, y)`` in ``y = (q, p)``.
For ``"numba"`` they are compiled for one system; for ``"numpy"`` they take a batch.

Notation in the generated code: ``M_i_j`` (``i ≥ j``) the mass matrix, ``F_i`` the force,
``a_i`` the acceleration, ``dFq_i_k = ∂F_i/∂q_k``, ``dMq_k_i_j = ∂M_ij/∂q_k`` (and ``v`` for
velocity derivatives), ``b_i`` the momentum offset ``p = M q̇ + b``, ``g_i = ∂L/∂q_i + Q_i``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import sympy

from .codegen import SourceWriter, UnrolledLDLT

__all__ = ["Derived", "EquationsCode"]


@dataclass(frozen=True)
class Derived:
    """The Euler–Lagrange equations in internal symbols (see :mod:`.lagrangian`).

    Attributes:
        q, v: Coordinate and velocity symbols.
        t: Time symbol.
        mass: ``M = ∂²L/∂q̇∂q̇``, ``(n, n)``.
        force: ``F``, with ``M q̈ = F``, ``(n, 1)``.
        momentum: ``p = ∂L/∂q̇``, ``(n, 1)``.
        energy: ``E = q̇·p − L``.
        potential_force: ``∂L/∂q + Q``, ``(n, 1)``: ``ṗ`` in Hamilton's equations.
    """

    q: tuple[sympy.Symbol, ...]
    v: tuple[sympy.Symbol, ...]
    t: sympy.Symbol
    mass: sympy.Matrix
    force: sympy.Matrix
    momentum: sympy.Matrix
    energy: sympy.Expr
    potential_force: sympy.Matrix

    @property
    def size(self) -> int:
        return len(self.q)

    @cached_property
    def velocity_dependent(self) -> bool:
        """``M`` or ``F`` depends on the velocities (so the acceleration does)."""
        return bool((self.mass.free_symbols | self.force.free_symbols) & set(self.v))

    @cached_property
    def quadratic(self) -> bool:
        """The kinetic energy is quadratic in the velocities: ``M`` does not depend on them."""
        return not self.mass.free_symbols & set(self.v)

    @cached_property
    def offset(self) -> sympy.Matrix:
        """``b`` in ``p = M q̇ + b`` (for a kinetic energy quadratic in the velocities)."""
        rest = (self.momentum - self.mass * sympy.Matrix(self.v)).applyfunc(sympy.expand)
        return rest.xreplace(dict.fromkeys(self.v, 0))


def _lower(matrix: sympy.Matrix, name: str) -> dict[str, sympy.Expr]:
    """``{name_i_j: entry}`` for the nonzero entries of the lower triangle (``i ≥ j``)."""
    n = matrix.shape[0]
    return {
        f"{name}_{i}_{j}": matrix[i, j] for i in range(n) for j in range(i + 1) if matrix[i, j] != 0
    }


def _vector(vector: Any, name: str) -> dict[str, sympy.Expr]:
    return {f"{name}_{i}": entry for i, entry in enumerate(vector) if entry != 0}


class EquationsCode:
    """Generates and caches the numeric functions of one derived system in one flavour.

    Args:
        derived: The equations.
        constants: Parameter symbol → value, written into the source as literals.
        flavour: ``"numba"`` or ``"numpy"``.
        points: Positions ``(x, y, z)`` of the drawn points as expressions of ``q`` and ``t``.
    """

    def __init__(
        self,
        derived: Derived,
        constants: Mapping[sympy.Symbol, float],
        flavour: str,
        *,
        points: Sequence[Sequence[sympy.Expr]] = (),
    ) -> None:
        self.derived, self.constants, self.flavour = derived, constants, flavour
        self.n = derived.size
        self._points = points

    def _writer(self, name: str, arguments: tuple[str, ...]) -> SourceWriter:
        return SourceWriter(name, arguments, flavour=self.flavour, constants=self.constants)

    def _read_state(self, writer: SourceWriter, *, velocities: bool) -> None:
        writer.read("q", self.derived.q)
        if velocities:
            writer.read("v", self.derived.v)

    def _factor_mass(self, writer: SourceWriter) -> UnrolledLDLT:
        named = _lower(self.derived.mass, "M")
        return UnrolledLDLT(writer, {_index(k): k for k in named}, self.n)

    def _names(self, name: str, present: Mapping[str, Any]) -> list[str | None]:
        return [f"{name}_{i}" if f"{name}_{i}" in present else None for i in range(self.n)]

    # --- (q, v) form -----------------------------------------------------------------------

    @cached_property
    def acceleration(self) -> Callable[..., Any]:
        """``acceleration(t, q[, v], out)``: ``out = M⁻¹ F``."""
        d, n = self.derived, self.n
        moving = d.velocity_dependent
        w = self._writer("acceleration", ("q", "v", "out") if moving else ("q", "out"))
        self._read_state(w, velocities=moving)
        force = _vector(d.force, "F")
        w.assign(_lower(d.mass, "M") | force)
        accelerations = [f"a_{i}" for i in range(n)]
        self._factor_mass(w).solve(self._names("F", force), accelerations)
        w.write("out", {(i,): accelerations[i] for i in range(n)})
        return w.compile()

    @cached_property
    def jacobian(self) -> Callable[..., Any]:
        """``jacobian(t, q)`` → ``∂a/∂q``, or ``jacobian(t, q, v)`` → ``(∂a/∂q, ∂a/∂v)``.

        ``∂a/∂x_k = M⁻¹(∂F/∂x_k − (∂M/∂x_k) a)``, from differentiating ``M a = F``.
        """
        d, n = self.derived, self.n
        moving = d.velocity_dependent
        w = self._writer("jacobian", ("q", "v") if moving else ("q",))
        self._read_state(w, velocities=moving)
        kinds = [("q", d.q)] + ([("v", d.v)] if moving else [])
        named = _lower(d.mass, "M") | _vector(d.force, "F")
        for kind, symbols in kinds:
            named |= {
                f"dF{kind}_{i}_{k}": e for (i, k), e in _entries(d.force.jacobian(symbols)).items()
            }
            for k, x in enumerate(symbols):
                named |= {
                    f"dM{kind}_{k}_{key[2:]}": e for key, e in _lower(d.mass.diff(x), "M").items()
                }
        w.assign(named)
        factor = self._factor_mass(w)
        accelerations = [f"a_{i}" for i in range(n)]
        factor.solve(self._names("F", named), accelerations)
        results = []
        for kind, _ in kinds:
            for k in range(n):
                residual = []
                for i in range(n):
                    terms = [f"dF{kind}_{i}_{k}"] if f"dF{kind}_{i}_{k}" in named else []
                    terms += [
                        f"- dM{kind}_{k}_{max(i, j)}_{min(i, j)}*a_{j}"
                        for j in range(n)
                        if f"dM{kind}_{k}_{max(i, j)}_{min(i, j)}" in named
                    ]
                    if terms:
                        w.line(f"r_{i} = {' '.join(terms)}")
                    residual.append(f"r_{i}" if terms else None)
                factor.solve(residual, [f"J{kind}_{i}_{k}" for i in range(n)])
            w.new_array(f"J{kind}", (n, n))
            w.write(f"J{kind}", {(i, k): f"J{kind}_{i}_{k}" for i in range(n) for k in range(n)})
            results.append(f"J{kind}")
        w.line(f"return {', '.join(results)}")
        return w.compile()

    @cached_property
    def energy(self) -> Callable[..., Any]:
        """``energy(t, q, v)``: ``E = q̇·∂L/∂q̇ − L``, one value per system."""
        w = self._writer("energy", ("q", "v"))
        self._read_state(w, velocities=True)
        w.assign({"E": self.derived.energy})
        w.line(f"return {w.scalar('E')}")
        return w.compile()

    @cached_property
    def mass_matrix(self) -> Callable[..., Any]:
        """``mass_matrix(t, q, v, out)``: the full ``(n, n)`` matrix ``M`` into ``out``."""
        w = self._writer("mass_matrix", ("q", "v", "out"))
        self._read_state(w, velocities=True)
        named = _lower(self.derived.mass, "M")
        w.assign(named)
        w.write(
            "out",
            {
                (i, j): f"M_{max(i, j)}_{min(i, j)}"
                if f"M_{max(i, j)}_{min(i, j)}" in named
                else "0.0"
                for i in range(self.n)
                for j in range(self.n)
            },
        )
        return w.compile()

    @cached_property
    def momenta(self) -> Callable[..., Any]:
        """``momenta(t, q, v, out)``: ``p = ∂L/∂q̇``."""
        w = self._writer("momenta", ("q", "v", "out"))
        self._read_state(w, velocities=True)
        named = _vector(self.derived.momentum, "p")
        w.assign(named)
        w.write("out", {(i,): n or "0.0" for i, n in enumerate(self._names("p", named))})
        return w.compile()

    @cached_property
    def points(self) -> Callable[..., Any]:
        """``points(t, q, out)``: the drawn points' positions into ``out[..., P, 3]``."""
        w = self._writer("points", ("q", "out"))
        self._read_state(w, velocities=False)
        named = {
            f"x_{i}_{c}": e for i, point in enumerate(self._points) for c, e in enumerate(point)
        }
        w.assign(named)
        w.write("out", {(i, c): f"x_{i}_{c}" for i in range(len(self._points)) for c in range(3)})
        return w.compile()

    # --- (q, p) form -----------------------------------------------------------------------

    def _canonical_velocities(self, w: SourceWriter, *, stacked: bool) -> UnrolledLDLT:
        """Read ``q`` and ``p`` (from ``y = (q, p)`` if ``stacked``, else from arrays ``q``
        and ``p``) and solve ``M q̇ = p − b`` into the velocity locals; return ``M``'s factor."""
        d, n = self.derived, self.n
        w.read("y" if stacked else "q", d.q)
        momenta = [sympy.Dummy(f"p{i}") for i in range(n)]
        w.read("y" if stacked else "p", momenta, offset=n if stacked else 0)
        offset = _vector(d.offset, "b")
        w.assign(_lower(d.mass, "M") | offset)
        rest = []
        for i in range(n):
            w.line(f"r_{i} = {w.local(momenta[i])}" + (f" - b_{i}" if f"b_{i}" in offset else ""))
            rest.append(f"r_{i}")
        velocities = [f"v_{i}" for i in range(n)]
        factor = self._factor_mass(w)
        factor.solve(rest, velocities)
        for symbol, local in zip(d.v, velocities, strict=True):
            w.name_local(symbol, local)
        return factor

    @cached_property
    def canonical(self) -> tuple[Callable[..., Any], Callable[..., Any]]:
        """``f(t, y, out)`` (Hamilton's equations) and ``hamiltonian(t, y)`` in ``y = (q, p)``."""
        n = self.n
        w = self._writer("hamilton", ("y", "out"))
        self._canonical_velocities(w, stacked=True)
        named = _vector(self.derived.potential_force, "g")
        w.assign(named)
        w.write("out", {(i,): f"v_{i}" for i in range(n)})
        w.write("out", {(n + i,): g or "0.0" for i, g in enumerate(self._names("g", named))})
        h = self._writer("hamiltonian", ("y",))
        self._canonical_velocities(h, stacked=True)
        h.assign({"E": self.derived.energy})
        h.line(f"return {h.scalar('E')}")
        return w.compile(), h.compile()

    @cached_property
    def canonical_jacobian(self) -> Callable[..., Any]:
        """``jacobian(t, y)``: ``∂f/∂y`` of Hamilton's equations, ``(2n, 2n)``.

        With ``q̇ = M⁻¹(p − b)`` and ``ṗ = g(q, q̇)``: ``∂q̇/∂p = M⁻¹``,
        ``∂q̇/∂q_k = −M⁻¹(∂b/∂q_k + (∂M/∂q_k) q̇)``, and by the chain rule
        ``∂ṗ/∂q = ∂g/∂q + (∂g/∂q̇)(∂q̇/∂q)``, ``∂ṗ/∂p = (∂g/∂q̇) M⁻¹``.
        """
        d, n = self.derived, self.n
        w = self._writer("hamilton_jacobian", ("y",))
        factor = self._canonical_velocities(w, stacked=True)
        named: dict[str, sympy.Expr] = {}
        for k, x in enumerate(d.q):
            named |= {f"dMq_{k}_{key[2:]}": e for key, e in _lower(d.mass.diff(x), "M").items()}
        for name, matrix in (
            ("dbq", d.offset.jacobian(d.q)),
            ("Gq", d.potential_force.jacobian(d.q)),
            ("Gv", d.potential_force.jacobian(d.v)),
        ):
            named |= {f"{name}_{i}_{k}": e for (i, k), e in _entries(matrix).items()}
        w.assign(named)
        entries: dict[tuple[int, ...], str] = {}
        for k in range(n):
            rhs: list[str | None] = []
            for i in range(n):
                terms = [f"- dbq_{i}_{k}"] if f"dbq_{i}_{k}" in named else []
                terms += [
                    f"- dMq_{k}_{max(i, j)}_{min(i, j)}*v_{j}"
                    for j in range(n)
                    if f"dMq_{k}_{max(i, j)}_{min(i, j)}" in named
                ]
                if terms:
                    w.line(f"r_{i} = 0.0 {' '.join(terms)}")
                rhs.append(f"r_{i}" if terms else None)
            factor.solve(rhs, [f"Vq_{i}_{k}" for i in range(n)])
            factor.solve(
                ["1.0" if i == k else None for i in range(n)], [f"Vp_{i}_{k}" for i in range(n)]
            )
            for i in range(n):
                entries[i, k], entries[i, n + k] = f"Vq_{i}_{k}", f"Vp_{i}_{k}"
                chain = [m for m in range(n) if f"Gv_{i}_{m}" in named]
                own = [f"Gq_{i}_{k}"] if f"Gq_{i}_{k}" in named else []
                entries[n + i, k] = (
                    " + ".join(own + [f"Gv_{i}_{m}*Vq_{m}_{k}" for m in chain]) or "0.0"
                )
                entries[n + i, n + k] = " + ".join(f"Gv_{i}_{m}*Vp_{m}_{k}" for m in chain) or "0.0"
        w.new_array("J", (2 * n, 2 * n))
        w.write("J", entries)
        w.line("return J")
        return w.compile()

    @cached_property
    def velocities(self) -> Callable[..., Any]:
        """``velocities(t, q, p, out)``: ``q̇`` from the momenta."""
        w = self._writer("velocities", ("q", "p", "out"))
        self._canonical_velocities(w, stacked=False)
        w.write("out", {(i,): f"v_{i}" for i in range(self.n)})
        return w.compile()


def _index(name: str) -> tuple[int, int]:
    """``"M_2_1"`` → ``(2, 1)``."""
    _, i, j = name.split("_")
    return int(i), int(j)


def _entries(matrix: sympy.Matrix) -> dict[tuple[int, int], sympy.Expr]:
    return {
        (i, j): matrix[i, j]
        for i in range(matrix.shape[0])
        for j in range(matrix.shape[1])
        if matrix[i, j] != 0
    }
