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

Numba functions are compiled once per machine: their source is written to a file named by its
digest in the equations cache (:func:`equations_cache`) and compiled with ``cache=True``, so
another process — a worker of a sweep's pool, the next ``visviva run`` — loads the machine code
instead of compiling the same text again (seconds for a double pendulum). Where the cache cannot
be written, the function is compiled from the text in memory. The source of a NumPy function is
registered with :mod:`linecache`, so a traceback through it shows the line that failed (a file
in the cache shows its lines by itself).
"""

from __future__ import annotations

import hashlib
import importlib.util
import linecache
import math
import os
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import sympy
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import PRECEDENCE

from ..errors import ModelError

__all__ = ["FLAVOURS", "SourceWriter", "UnrolledLDLT", "equations_cache"]

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
        """The function: plain Python for ``"numpy"``, a Numba dispatcher for ``"numba"``
        (compiled once per machine, see the module docstring)."""
        source = "import numpy\n\n\n" + self.source()
        digest = hashlib.sha256(source.encode()).hexdigest()[:24]
        if self.flavour == "numba":
            import numba

            cached = _cached_function(self.name, digest, source)
            # Division by zero gives inf/NaN as in NumPy (the divergence watch reports it)
            # instead of raising inside a compiled loop.
            if cached is not None:
                return numba.njit(cached, error_model="numpy", cache=True)
            return numba.njit(_function(self.name, digest, source), error_model="numpy")
        return _function(self.name, digest, source)


def equations_cache() -> Path:
    """Where generated equations are kept: ``$NUMBA_CACHE_DIR/visviva-equations`` if Numba's
    cache is moved there, else ``visviva/equations`` in the user's cache directory
    (``$XDG_CACHE_HOME``, by default ``~/.cache``)."""
    numba_cache = os.environ.get("NUMBA_CACHE_DIR")
    if numba_cache:
        return Path(numba_cache) / "visviva-equations"
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(home) / "visviva" / "equations"


def _function(name: str, digest: str, source: str) -> Any:
    """Function ``name`` of ``source``, compiled in memory."""
    filename = f"<visviva generated {name} {digest[:12]}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    namespace: dict[str, Any] = {}
    exec(compile(source, filename, "exec"), namespace)
    return namespace[name]


def _cached_function(name: str, digest: str, source: str) -> Any | None:
    """Function ``name`` of ``source`` from its file in the equations cache (written first if
    it is not there, atomically: processes that write it at once write the same text), or
    ``None`` if the cache cannot be written or read."""
    path = equations_cache() / f"{name}_{digest}.py"
    try:
        if not path.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
            handle, temporary = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
            with os.fdopen(handle, "w") as file:
                file.write(source)
            os.replace(temporary, path)
        elif path.read_text() != source:
            return None  # not ours after all: compile from memory
        spec = importlib.util.spec_from_file_location(f"visviva_equations_{digest}", path)
        if spec is None or spec.loader is None:
            return None
        module = importlib.util.module_from_spec(spec)
        # Importable by name: Numba's cache refers to the function's module by it.
        sys.modules[spec.name] = module
        spec.loader.exec_module(module)
    except (OSError, SyntaxError, UnicodeDecodeError):
        return None
    return getattr(module, name, None)


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
