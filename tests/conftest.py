"""Shared test setup: the documented custom integrator joins every conformance test, and the
suite runs on every core when pytest-xdist is installed (it is in the ``test`` extra)."""

import os
import sys
from pathlib import Path

# Numba's OpenMP threads wait for work by sleeping, not by spinning (GNU OpenMP spins by
# default). Several processes share the cores here: the xdist workers, the process pools and
# Dask workers of the sweep tests, the `visviva` subprocesses. A spinning thread holds a core
# that another process's thread waits for: two workers stepping a 30 × 30 cloth by projected
# Newton took 170 s each against 13 s alone (10 s each with passive waiting). Read when Numba
# first starts its threads, after this module is imported; results do not depend on it.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

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
