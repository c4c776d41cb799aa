"""What a user's function takes, and how to call it on a whole batch.

A problem's functions come in two flavours, told apart by their type:

* **NumPy functions** (any Python callable) are called once per evaluation with the whole state:
  ``y`` of shape ``(n,)`` for one system or ``(batch, n)`` for a batch, and must return an array
  of the same shape (vectorise over the leading axis with ``y[..., 0]`` style indexing).
* **Numba functions** (``@numba.njit``) describe *one* system: they receive ``y`` of shape
  ``(n,)``. visviva runs the loop over the batch itself in compiled code, in parallel, and, for
  the explicit methods, compiles the whole time loop around the function.

Either kind may write its result into a last parameter named ``out`` instead of returning it,
which saves an allocation per call.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..errors import ModelError

__all__ = ["UserFunction", "is_numba_function"]


def is_numba_function(func: Any) -> bool:
    """True if ``func`` is a Numba CPU dispatcher (made by ``@njit`` / ``@jit``)."""
    return type(func).__module__.startswith("numba") and hasattr(func, "py_func")


@dataclass(frozen=True)
class UserFunction:
    """A user callable with the facts the integrators need about its signature.

    Attributes:
        func: The callable itself.
        name: Name used in error messages (``"f"``, ``"acceleration"``, ...).
        state_arguments: How many state arrays follow ``t``: 1 for ``f(t, y)`` or a
            position-only ``acceleration(t, q)``, 2 for ``acceleration(t, q, v)``.
        writes_out: The function fills a last argument ``out`` instead of returning.
        compiled: The function is a Numba dispatcher describing one system.
    """

    func: Callable[..., Any]
    name: str
    state_arguments: int
    writes_out: bool
    compiled: bool

    @classmethod
    def inspect(cls, name: str, func: Any, *, forms: dict[int, str]) -> UserFunction:
        """Read the signature of ``func`` and check that it has an accepted form.

        Args:
            name: The argument name of ``func`` in the public API.
            func: The user's callable.
            forms: Accepted numbers of state arrays after ``t``, each with its form as shown
                to the user, e.g. ``{1: "acceleration(t, q)", 2: "acceleration(t, q, v)"}``.
        """
        if not callable(func):
            raise ModelError(f"`{name}` must be callable (got {type(func).__name__})")
        compiled = is_numba_function(func)
        target = func.py_func if compiled else func
        try:
            parameters = list(inspect.signature(target).parameters.values())
        except (TypeError, ValueError):
            # Builtins and some C callables hide their signature: assume the fullest form.
            return cls(func, name, max(forms), False, compiled)
        if any(p.kind is p.VAR_POSITIONAL for p in parameters):
            return cls(func, name, max(forms), False, compiled)
        required = [
            p
            for p in parameters
            if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.default is p.empty
        ]
        writes_out = bool(required) and required[-1].name == "out"
        state_arguments = len(required) - 1 - int(writes_out)
        if state_arguments not in forms:
            accepted = " or ".join(forms.values())
            got = ", ".join(p.name for p in required)
            raise ModelError(
                f"`{name}` must have the form {accepted} (optionally with a last argument `out` "
                f"to write into); got {name}({got})"
            )
        return cls(func, name, state_arguments, writes_out, compiled)
