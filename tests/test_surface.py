"""The package's surface: after ``import visviva as vv`` every subpackage is ``vv.<name>``.

Subpackages load on first use (``visviva/__init__.py``), so a new one is easily left out of
``__all__`` and ``dir(vv)``; these tests find the subpackages on disk, so a forgotten one fails
here. The packages that load their names on first use (:mod:`visviva._lazy`) are checked too.
"""

from __future__ import annotations

import importlib
import pkgutil

import pytest

import visviva as vv

SUBPACKAGES = sorted(info.name for info in pkgutil.iter_modules(vv.__path__) if info.ispkg)
PACKAGES = ["visviva", *(f"visviva.{name}" for name in SUBPACKAGES)]


def test_the_subpackages_are_found():
    assert {"cli", "collision", "deformables", "geometry", "simulation", "sweeps"} <= set(
        SUBPACKAGES
    )


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_every_subpackage_is_an_attribute_listed_in_dir_and_all(name):
    # Through the module's __getattr__ itself: once imported (by another test), a subpackage is
    # an attribute of its parent anyway, and plain getattr would not see a missing entry.
    assert vv.__getattr__(name) is importlib.import_module(f"visviva.{name}")
    assert getattr(vv, name) is importlib.import_module(f"visviva.{name}")
    assert name in dir(vv)
    assert name in vv.__all__


def test_every_public_name_resolves_and_dir_is_all():
    assert dir(vv) == sorted(vv.__all__)
    for name in vv.__all__:
        assert getattr(vv, name) is not None, name


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="'visviva' has no attribute 'nonesuch'"):
        vv.nonesuch  # noqa: B018


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_every_name_a_subpackage_exports_resolves(name):
    # Packages that load their names on first use (visviva._lazy) list where each one lives;
    # a wrong entry shows only when the name is looked up.
    package = importlib.import_module(f"visviva.{name}")
    for public in vars(package).get("__all__", []):
        assert getattr(package, public) is not None, f"visviva.{name}.{public}"


@pytest.mark.parametrize("name", PACKAGES)
def test_no_name_loaded_on_first_use_is_also_a_module_of_its_package(name):
    # Importing a submodule binds it on its package: a name loaded on first use that is also a
    # submodule's name (a function `solve` in a module `solve.py`) would turn into the module
    # once anything imported that module. (Packages that import their names at once rebind
    # them after their submodules load.)
    package = importlib.import_module(name)
    if "__getattr__" not in vars(package):
        pytest.skip("imports its names at once")
    modules = {info.name for info in pkgutil.iter_modules(package.__path__)}
    for public in set(package.__all__) & modules:
        module = importlib.import_module(f"{name}.{public}")
        assert package.__getattr__(public) is module, f"{name}.{public}"


@pytest.mark.parametrize("name", PACKAGES)
def test_a_package_loading_names_on_first_use_reaches_its_modules_as_attributes(name):
    # As when the package imported them all: the docs write vv.simulation.interrupt.StopOnSignal.
    package = importlib.import_module(name)
    if "__getattr__" not in vars(package):
        pytest.skip("imports its names at once")
    for info in pkgutil.iter_modules(package.__path__):
        if not info.name.startswith("__"):
            module = importlib.import_module(f"{name}.{info.name}")
            assert package.__getattr__(info.name) is module


def test_a_dunder_is_never_looked_up_as_a_module():
    # visviva/__main__.py runs the command line when imported.
    with pytest.raises(AttributeError):
        vv.__getattr__("__main__")
