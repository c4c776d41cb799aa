"""SymPy expressions → Python source → functions for NumPy (a whole batch) or Numba (one system).

A derived system is a handful of expressions (mass matrix, forces, their derivatives, the
energy) in the coordinates, the velocities and the time. :class:`SourceWriter` writes a Python
function that evaluates them with the common subexpressions computed once (``sympy.cse``) and
solves the small symmetric systems ``M x = b`` with an unrolled LDLᵀ factorisation, using
scalar arithmetic only. The same text then serves both flavours:

* ``"numpy"``: the inputs carry a leading batch axis (``q[..., i]``) and every line evaluates
  the whole batch at once;
* ``"numba"``: the inputs describe one system (``q[i]``) and the function is compiled with
  ``numba.njit``. Straight-line scalar code compiles in a fraction of a second, where array
  temporaries, slice stores and calls into other compiled functions cost Numba seconds.

The generated source is registered with :mod:`linecache`, so a traceback through it shows the
line that failed.
"""

from __future__ import annotations

import hashlib
import linecache
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import PRECEDENCE

from ..errors import ModelError

__all__ = ["FLAVOURS", "SourceWriter", "UnrolledLDLT"]

FLAVOURS = ("numba", "numpy")


class _Printer(NumPyPrinter):
    """NumPy printing with exact float literals and integer powers kept integer.

    SymPy prints a float with 15 significant digits, which does not always round-trip a float64;
    ``repr`` does. ``x**2`` stays an integer power (Numba turns it into multiplications) where the
    stock printer writes ``x**(-1.0)``, a call to ``pow``.
    """

    def _print_Float(self, expr: sympy.Float) -> str:
        value = float(expr)
        if not math.isfinite(value):
            # SymPy folds the parameters exactly (m L² with L = 1e200 is 1e400); a float can't.
            raise ModelError(
                f"the parameter values make a coefficient of the equations {expr:.4g}, beyond "
                "the range of a float (±1.8e308): use smaller values or other units"
            )
        return repr(value)

    def _print_Pow(self, expr: sympy.Pow, rational: bool = False) -> str:
        if expr.exp.is_Integer:
            base = self.parenthesize(expr.base, PRECEDENCE["Pow"])
            exponent = int(expr.exp)
            return f"{base}**{exponent}" if exponent >= 0 else f"{base}**({exponent})"
        return str(super()._print_Pow(expr, rational=rational))


class SourceWriter:
    """Builds the text of one generated function, line by line.

    Args:
        name: Function name.
        arguments: Argument names after ``t`` (for example ``("q", "v", "out")``).
        flavour: ``"numpy"`` or ``"numba"`` (see the module docstring).
        constants: Symbols replaced by numbers (the parameters): they are written into the
            source as exact literals.
    """

    def __init__(
        self,
        name: str,
        arguments: Sequence[str],
        *,
        flavour: str,
        constants: Mapping[sympy.Symbol, float],
    ) -> None:
        self.name = name
        self.batched = flavour == "numpy"
        self.flavour = flavour
        self._lines = [f"def {name}(t, {', '.join(arguments)}):"]
        self._locals: dict[sympy.Symbol, sympy.Symbol] = {}
        self._constants = {s: sympy.Float(v) for s, v in constants.items()}
        self._printer = _Printer()
        self._cse_count = 0
        self._first_state: str | None = None

    def _index(self, *indices: int) -> str:
        inner = ", ".join(map(str, indices))
        return f"[..., {inner}]" if self.batched else f"[{inner}]"

    def line(self, text: str) -> None:
        """Append one line of the body (indented here)."""
        self._lines.append(f"    {text}")

    def read(self, array: str, symbols: Sequence[sympy.Symbol], *, offset: int = 0) -> None:
        """Unpack ``array[offset + i]`` into a local for each symbol."""
        if self._first_state is None:
            self._first_state = array
        for i, symbol in enumerate(symbols):
            self.name_local(symbol, f"{array}_{offset + i}")
            self.line(f"{self._locals[symbol]} = {array}{self._index(offset + i)}")

    def local(self, symbol: sympy.Symbol) -> str:
        """The local variable that holds ``symbol``."""
        return str(self._locals[symbol])

    def name_local(self, symbol: sympy.Symbol, local: str) -> None:
        """From now on ``symbol`` is the local variable ``local`` (e.g. a solved velocity)."""
        self._locals[symbol] = sympy.Symbol(local)

    def assign(self, named: Mapping[str, sympy.Expr]) -> None:
        """``name = expression`` for each entry, common subexpressions computed once."""
        replace = dict(self._constants) | dict(self._locals)
        expressions = [sympy.sympify(e).xreplace(replace) for e in named.values()]
        prefix = f"c{self._cse_count}_"
        self._cse_count += 1
        common, reduced = sympy.cse(expressions, symbols=sympy.numbered_symbols(prefix))
        for symbol, expression in common:
            self.line(f"{symbol} = {self._printer.doprint(expression)}")
        for name, expression in zip(named, reduced, strict=True):
            self.line(f"{name} = {self._printer.doprint(expression)}")

    def write(self, array: str, values: Mapping[tuple[int, ...], str]) -> None:
        """``array[index] = value`` for each entry (values are local names or literals)."""
        for index, value in values.items():
            self.line(f"{array}{self._index(*index)} = {value}")

    def new_array(self, name: str, shape: tuple[int, ...]) -> None:
        """``name = numpy.empty(<batch shape> + shape)``: fill every entry with :meth:`write`."""
        lead = f"{self._first_state}.shape[:-1] + " if self.batched else ""
        self.line(f"{name} = numpy.empty({lead}{shape!r})")

    def scalar(self, value: str) -> str:
        """``value`` as a float of the batch's shape (a constant energy still needs one per
        system), or a plain float for one system."""
        if self.batched:
            return f"numpy.zeros({self._first_state}.shape[:-1]) + {value}"
        return f"float({value})"

    def source(self) -> str:
        return "\n".join(self._lines) + "\n"

    def compile(self) -> Any:
        """The function: plain Python for ``"numpy"``, a Numba dispatcher for ``"numba"``."""
        source = self.source()
        digest = hashlib.sha1(source.encode()).hexdigest()[:12]
        filename = f"<visviva generated {self.name} {digest}>"
        linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
        namespace: dict[str, Any] = {"numpy": np}
        exec(compile(source, filename, "exec"), namespace)
        function = namespace[self.name]
        if self.flavour == "numba":
            import numba

            # Division by zero gives inf/NaN as in NumPy (the divergence watch reports it)
            # instead of raising inside a compiled loop.
            return numba.njit(function, error_model="numpy")
        return function


class UnrolledLDLT:
    """Lines that factor a symmetric ``A = L D Lᵀ`` and solve ``A x = b``, fully unrolled.

    Args:
        writer: Where the lines go.
        matrix: ``(i, j)`` with ``i ≥ j`` → the local holding ``A_ij``; missing entries are zero.
        n: Size of ``A``.

    No pivoting: LDLᵀ is stable for the symmetric positive-definite mass matrices of mechanics
    (the caller checks definiteness at the initial state). Where ``A`` stops being invertible
    the divisions give inf/NaN, which the simulation's divergence watch reports. Zero entries of
    ``A`` and of its factor are known when the code is written, so their terms are left out.
    """

    def __init__(self, writer: SourceWriter, matrix: Mapping[tuple[int, int], str], n: int):
        self.writer, self.n = writer, n
        self.lower: dict[tuple[int, int], str] = {}  # L_ij for i > j, nonzero ones only
        self.diagonal: list[str] = []
        for j in range(n):
            terms = [matrix.get((j, j), "0.0")]
            terms += [
                f"- {self.lower[j, k]}**2*{self.diagonal[k]}"
                for k in range(j)
                if (j, k) in self.lower
            ]
            self.diagonal.append(f"D_{j}")
            writer.line(f"D_{j} = {' '.join(terms)}")
            for i in range(j + 1, n):
                terms = [matrix[i, j]] if (i, j) in matrix else []
                terms += [
                    f"- {self.lower[i, k]}*{self.lower[j, k]}*{self.diagonal[k]}"
                    for k in range(j)
                    if (i, k) in self.lower and (j, k) in self.lower
                ]
                if terms:
                    self.lower[i, j] = f"L_{i}_{j}"
                    writer.line(f"L_{i}_{j} = ({' '.join(terms)})/D_{j}")

    def solve(self, b: Sequence[str | None], x: Sequence[str]) -> None:
        """Lines setting the locals ``x`` to ``A⁻¹ b`` (``None`` in ``b`` is a zero)."""
        lower, line = self.lower, self.writer.line
        # L z = b, then D y = z, then Lᵀ x = y; z and y live in the names of x.
        for i in range(self.n):
            terms = [b[i] or "0.0"] + [
                f"- {lower[i, k]}*{x[k]}" for k in range(i) if (i, k) in lower
            ]
            line(f"{x[i]} = {' '.join(terms)}")
        for i in range(self.n):
            line(f"{x[i]} = {x[i]}/{self.diagonal[i]}")
        for i in reversed(range(self.n)):
            terms = [f"- {lower[k, i]}*{x[k]}" for k in range(i + 1, self.n) if (k, i) in lower]
            if terms:
                line(f"{x[i]} = {x[i]} {' '.join(terms)}")
