"""Shared test setup: the documented custom integrator joins every conformance test."""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "examples"))

import custom_integrator

custom_integrator.register()

# Run by tests/test_blender.py under Blender's own Python (it imports bpy): not a test module.
collect_ignore = ["blender_probe.py"]
