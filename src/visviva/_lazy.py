"""Packages whose public names load on first use, so that importing one stays cheap.

A package such as :mod:`visviva.simulation` gathers names from modules that bring in Numba's
compiled kernels, SciPy or sympy. Importing it eagerly would make every module below it pay
for them, even one that needs a single light module such as ``visviva.simulation.interrupt``,
and ``visviva --help`` would then take seconds. Such a package instead lists where each public
name is defined and gets a module ``__getattr__`` (PEP 562) that imports the defining module on
the first lookup; its ``TYPE_CHECKING`` block imports the same names for type checkers. Its
modules stay reachable as attributes too (``vv.simulation.interrupt.StopOnSignal``), as they
were when the package imported them all.

A name loaded on first use must not also be the name of one of the package's modules: importing
that module binds it on the package in the name's place (tests/test_surface.py checks).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Collection, Mapping
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(
    package: str, public: Collection[str], attributes: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of a package whose names load on first use.

    Args:
        package: The package's ``__name__``.
        public: Its public names (its ``__all__``), which ``dir()`` lists.
        attributes: Each name loaded on first use and the module of the package that defines
            it, relative to the package: ``{"Recording": "recording"}``. Any other name is
            looked up as a module of the package (``visviva.ode``).

    Returns:
        ``(__getattr__, __dir__)``, to assign at the top level of the package.
    """

    def __getattr__(name: str) -> Any:
        if name in attributes:
            return getattr(importlib.import_module(f"{package}.{attributes[name]}"), name)
        # Never a dunder: `hasattr(package, "__main__")` must not run the command line.
        if not name.startswith("__"):
            try:
                return importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as error:
                if error.name != f"{package}.{name}":
                    raise  # the module exists, and something it imports is missing
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(public)

    return __getattr__, __dir__
