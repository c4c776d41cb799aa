"""Warnings that mean something: energy drift of conservative scenes, counts, the printed summary.

A conservative scene's energy changes only through the integrator's error, so a relative change
beyond ``energy_tolerance`` (1 % by default) is reported in ``summary.json`` and printed with
the stability advisor's advice. Dissipative scenes (a damped oscillator) lose energy by design
and are not warned about.
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

import visviva as vv
from visviva.cli.main import app

runner = CliRunner()


def _pendulum(method: str, dt: float, duration: float = 10.0) -> vv.Model:
    builder = vv.SceneBuilder(name="pendulum")
    builder.set_integration(method=method, dt=dt, duration=duration)
    builder.add_system("pendulum", {"length": 1.0, "theta0": 1.0})
    return builder.build()


def _energy_warnings(summary: dict) -> list[dict]:
    return [w for w in summary["warnings"] if w["kind"] == "energy_drift"]


def test_explicit_euler_pendulum_at_a_large_step_warns_with_the_advisors_advice(tmp_path):
    report = vv.run_scene(_pendulum("explicit_euler", 0.5), tmp_path)
    summary = report.summary
    # Explicit Euler multiplies the energy of an undamped oscillation by 1 + (ωh)² per step
    # in the linear limit (|R(iωh)|² = 1 + ω²h², ω² = g/L ≈ 9.81): a growth far beyond 1 %.
    assert summary["energy_drift"] > 1.0
    (warning,) = _energy_warnings(summary)
    assert "+" in warning["message"] and "tolerance 1 %" in warning["message"]
    assert "unstable for every step" in warning["message"]
    assert "velocity_verlet" in warning["message"]
    assert json.loads((tmp_path / "summary.json").read_text())["warnings"] == summary["warnings"]


def test_velocity_verlet_at_a_small_step_does_not_warn(tmp_path):
    summary = vv.run_scene(_pendulum("velocity_verlet", 0.005), tmp_path).summary
    # Verlet's energy error is O(h²): about (ωh)²/8 ≈ 3e-5 here, far below 1 %.
    assert abs(summary["energy_drift"]) < 1e-4
    assert _energy_warnings(summary) == []


def test_a_stable_but_inaccurate_method_is_told_to_reduce_dt(tmp_path):
    # Backward Euler is stable for every step but damps the pendulum: energy falls.
    summary = vv.run_scene(_pendulum("backward_euler", 0.05), tmp_path).summary
    assert summary["energy_drift"] < -0.01
    (warning,) = _energy_warnings(summary)
    assert "reduce dt" in warning["message"]


def test_the_tolerance_is_settable_in_the_scene_and_per_run(tmp_path):
    model = _pendulum("symplectic_euler", 0.05)
    loose = vv.run_scene(model, tmp_path / "a", energy_tolerance=0.5).summary
    assert loose["energy_tolerance"] == 0.5 and _energy_warnings(loose) == []
    tight = vv.run_scene(model, tmp_path / "b", energy_tolerance=1e-6).summary
    (warning,) = _energy_warnings(tight)
    assert "symplectic_euler" in warning["message"] and "bounded" in warning["message"]
    builder = vv.SceneBuilder(name="p")
    builder.set_integration(method="symplectic_euler", dt=0.05, energy_tolerance=1e-6)
    builder.add_system("pendulum")
    assert builder.build().integration.energy_tolerance == 1e-6
    with pytest.raises(vv.ModelError, match="energy_tolerance"):
        vv.run_scene(model, tmp_path / "c", energy_tolerance=-1.0)


def test_a_damped_system_losing_energy_is_not_warned_about(tmp_path):
    builder = vv.SceneBuilder(name="damped")
    builder.set_integration(method="rk4", dt=0.01, duration=10.0)
    builder.add_system("damped-oscillator", {"damping": 0.4})
    summary = vv.run_scene(builder.build(), tmp_path).summary
    assert summary["energy_drift"] < -0.5  # e^{-c t/m} decay: the physics, not an error
    assert _energy_warnings(summary) == []


def test_summary_counts_what_the_scene_holds(tmp_path):
    builder = vv.SceneBuilder(name="cluster")
    builder.set_integration(method="velocity_verlet", dt=0.01, duration=0.02)
    builder.add_system("cluster", {"bodies": 300, "softening": 0.05})
    summary = vv.run_scene(builder.build(), tmp_path / "c").summary
    assert summary["counts"] == {"degrees_of_freedom": 900, "points": 300}
    builder = vv.SceneBuilder(name="spray")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=0.02)
    builder.add_particle_cloud(count=123)
    summary = vv.run_scene(builder.build(), tmp_path / "p").summary
    assert summary["counts"] == {"particles": 123}


def test_run_prints_a_short_summary_with_the_warning(tmp_path):
    scene = tmp_path / "euler.toml"
    scene.write_text(vv.io.dump_scene(_pendulum("explicit_euler", 0.5).scene))
    result = runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].startswith("pendulum: 20 steps of explicit_euler (dt = 0.5 s) in ")
    assert lines[1].startswith("energy drift: +")
    assert lines[2].startswith("warning: the energy of this conservative scene changed by")
    assert lines[-1] == f"wrote recording.h5, summary.json into {tmp_path / 'out'}/"
    quiet = runner.invoke(
        app, ["run", str(scene), "-o", str(tmp_path / "q"), "--energy-tolerance", "100"]
    )
    assert quiet.exit_code == 0 and "warning" not in quiet.stdout


def test_demo_prints_a_short_summary(tmp_path):
    result = runner.invoke(app, ["demo", "rock", "-o", str(tmp_path), "--duration", "1"])
    assert result.exit_code == 0, result.output
    first, *_, last = result.stdout.splitlines()
    assert first.startswith("rock: ") and " steps in " in first
    assert last.startswith("wrote recording.h5, summary.json") and last.endswith(f"{tmp_path}/")
