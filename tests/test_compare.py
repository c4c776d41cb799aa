"""The comparison harness: one problem, several methods, energy, measured order and cost."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import visviva as vv
from visviva.cli.main import app
from visviva.mechanics import classic
from visviva.viz.plots import comparison_figures


@pytest.fixture(scope="module")
def comparison() -> vv.studies.Comparison:
    problem = classic.pendulum(length=1.0).problem([1.0], [0.0], backend="numpy")
    methods = ["explicit_euler", "symplectic_euler", "velocity_verlet", "rk4"]
    return vv.studies.compare_methods(problem, methods, dt=0.01, until=20.0, levels=5)


def test_measured_orders_match_the_declared_ones(comparison):
    for result in comparison.results:
        assert abs(result.measured_order - result.declared_order) < 0.3, result


def test_energy_columns_tell_the_families_apart(comparison):
    by_name = {r.method: r for r in comparison.results}
    # Explicit Euler gains energy every step; the symplectic methods keep it within O(h^p).
    assert by_name["explicit_euler"].energy_drift > 0.1
    assert by_name["symplectic_euler"].max_energy_error < 0.05
    assert by_name["velocity_verlet"].max_energy_error < 1e-3
    assert by_name["rk4"].max_energy_error < 1e-6
    # Work: 2000 steps; Verlet reuses its last force (1 per step), RK4 needs 4.
    assert by_name["velocity_verlet"].f_evaluations in (2000, 2001)
    assert by_name["rk4"].f_evaluations == 8000


def test_table_figures_and_summary(comparison):
    table = comparison.table().splitlines()
    assert table[0].split()[:3] == ["method", "order", "measured"]
    assert len(table) == 2 + len(comparison.results)
    figures = comparison_figures(comparison)
    assert list(figures) == ["energy", "convergence"]
    assert all(figure.axes for figure in figures.values())
    summary = comparison.as_dict()
    assert summary["dt_s"] == 0.01 and len(summary["methods"]) == 4
    assert np.isfinite([m["measured_order"] for m in summary["methods"]]).all()


def test_cli_compare_a_named_system_and_a_scene_file(tmp_path):
    runner = CliRunner()
    out = tmp_path / "cmp"
    result = runner.invoke(
        app, ["compare", "pendulum", "rk4", "leapfrog", "--duration", "2", "-o", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "leapfrog" in result.stdout
    names = {p.name for p in out.iterdir()}
    assert names == {"recording.h5", "summary.json", "energy.png", "convergence.png"}
    summary = json.loads((out / "summary.json").read_text())
    assert [m["method"] for m in summary["methods"]] == ["rk4", "leapfrog"]
    assert set(vv.io.read_recordings(out / "recording.h5")) == {"rk4", "leapfrog"}
    scene = tmp_path / "spring.toml"
    scene.write_text(
        '[integration]\nmethod = "rk4"\ndt = 0.01\nduration = 3.0\n'
        '[[entities]]\ntype = "system"\nsystem = "oscillator"\n'
    )
    result = runner.invoke(app, ["compare", str(scene), "rk4", "-o", str(tmp_path / "c2")])
    assert result.exit_code == 0, result.output
