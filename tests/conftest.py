"""Shared test setup: the documented custom integrator joins every conformance test, and the
suite runs on every core when pytest-xdist is installed (it is in the ``test`` extra)."""

import sys
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "examples"))

import custom_integrator

custom_integrator.register()

# Run by tests/test_blender.py under Blender's own Python (it imports bpy): not a test module.
collect_ignore = ["blender_probe.py"]


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config: pytest.Config) -> None:
    """``python -m pytest`` runs on one worker per core (``-n auto``), each worker taking whole
    test files (``--dist loadfile``): a file's module fixtures are made once and the Numba
    kernels it compiles stay in its worker's memory. About half of a run with an empty Numba
    cache is compilation, which the workers share out. Runs before pytest-xdist's own hook,
    which reads these options; ``-n 0`` (or ``-p no:xdist``) runs in one process, and an
    explicit ``-n``/``--dist`` is kept. Without pytest-xdist nothing changes."""
    if not config.pluginmanager.has_plugin("xdist") or hasattr(config, "workerinput"):
        return
    if config.option.numprocesses is None and not config.option.tx:
        config.option.numprocesses = "auto"
        if config.option.dist == "no":
            config.option.dist = "loadfile"
