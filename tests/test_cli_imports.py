"""The commands that only print (``--help``, ``demo`` without a name, ``schema``) import no
numerical stack: no Numba, SciPy, matplotlib, h5py, sympy, nor NumPy (shared/DESIGN.md: the CLI
is thin, ``--help`` loads no Numba; NumPy alone would take a third of their 0.3 s). Each runs in
a fresh interpreter, which then reports what it imported; these are counts of work, so the
tests hold on a loaded machine too.

``visviva demo`` lists the built-in demos from :mod:`visviva.demos.catalogue` without importing
them; the last tests hold the catalogue to the demos it names.
"""

from __future__ import annotations

import json
import pkgutil
import subprocess
import sys

import pytest

import visviva.demos
from visviva.demos import demo_summaries, demos
from visviva.demos.catalogue import BUILTIN_DEMOS

#: What the printing commands must not import.
HEAVY = ("numba", "scipy", "matplotlib", "h5py", "sympy", "numpy")

#: Run by a fresh interpreter: the command through the entry point ``main()``, then the
#: heavy modules it imported and the loaded demo modules, as the last line of stdout.
PROGRAM = """
import json, sys
from visviva.cli.main import main
args, heavy = map(json.loads, sys.argv[1:])
sys.argv = ["visviva", *args]
try:
    main()
    status = 0
except SystemExit as exit_:
    status = exit_.code or 0
loaded = [name for name in heavy if name in sys.modules]
shown = [name for name in sys.modules if name.startswith("visviva.demos.")]
print(json.dumps({"status": status, "heavy": loaded, "demo_modules": shown}))
"""


def run_fresh(*args: str) -> tuple[str, dict]:
    """Run ``visviva ARGS`` in a new interpreter; return its output and what it imported."""
    completed = subprocess.run(
        [sys.executable, "-c", PROGRAM, json.dumps(args), json.dumps(HEAVY)],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    output, _, report = completed.stdout.rstrip("\n").rpartition("\n")
    return output, json.loads(report)


@pytest.mark.parametrize("args", [("--help",), ("demo",), ("schema",)], ids=" ".join)
def test_printing_commands_import_no_numerical_stack(args):
    output, report = run_fresh(*args)
    assert report["status"] == 0, output
    assert report["heavy"] == [], f"visviva {' '.join(args)} imported {report['heavy']}"
    assert output.strip()


def test_demo_lists_every_builtin_demo_without_importing_one():
    output, report = run_fresh("demo")
    assert report["demo_modules"] == ["visviva.demos.catalogue"]
    listed = [line.split()[0] for line in output.splitlines()]
    assert listed == sorted(BUILTIN_DEMOS)


def test_schema_prints_the_scene_schema():
    output, _ = run_fresh("schema")
    schema = json.loads(output)
    assert schema["title"] == "Scene"
    assert {"entities", "integration"} <= set(schema["properties"])


def test_running_a_demo_imports_only_its_own_module(tmp_path):
    _, report = run_fresh("demo", "test-equation", "-o", str(tmp_path), "--duration", "3")
    assert report["status"] == 0
    assert set(report["demo_modules"]) == {
        "visviva.demos.catalogue",
        "visviva.demos.runner",
        "visviva.demos.dahlquist",
    }


def test_the_catalogue_lists_every_demo_module():
    modules = {
        info.name
        for info in pkgutil.iter_modules(visviva.demos.__path__)
        if not info.name.startswith("_") and info.name not in ("catalogue", "runner")
    }
    assert modules == {builtin.module for builtin in BUILTIN_DEMOS.values()}


@pytest.mark.parametrize("name", sorted(BUILTIN_DEMOS))
def test_each_catalogue_entry_is_the_demo_its_module_registers(name):
    demo = demos()[name]
    builtin = BUILTIN_DEMOS[name]
    assert demo.name == name
    assert demo.summary == builtin.summary == demo_summaries()[name]
    assert demo.run.__module__ == f"visviva.demos.{builtin.module}"
