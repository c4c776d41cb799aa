"""The mechanics demos: each runs (shortened) and its summary holds the physics it shows."""

from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import pytest

from visviva.demos import run_demo
from visviva.errors import ModelError


def summary(directory: Path) -> dict:
    return json.loads((directory / "summary.json").read_text())


def test_rock_verlet_is_exact_and_euler_off_by_half_g_h_t(tmp_path):
    run_demo("rock", tmp_path, duration=1.0)
    errors = summary(tmp_path)["max_position_error_m"]
    assert errors["velocity_verlet"] < 1e-12 and errors["rk4"] < 1e-12
    # ½ g h t at t = 1 s, h = 0.05 s
    assert errors["explicit_euler"] == pytest.approx(0.5 * 9.80665 * 0.05 * 1.0, rel=1e-9)


def test_pendulum_period_and_equations(tmp_path):
    run_demo("pendulum", tmp_path, duration=5.0, formats=["gif"], fps=10)
    data = summary(tmp_path)
    assert data["period_relative_error"] < 1e-9  # RK4 at h = 1 ms
    assert (tmp_path / "equations.txt").read_text().strip() == data["equations"]
    assert "\\ddot{\\theta}" in (tmp_path / "equations.tex").read_text()
    # 5 s at 10 frames/s: frames at 0, 0.1, …, 5.0
    assert iio.imread(tmp_path / "animation.gif", index=None).shape[0] == 51


def test_constrained_pendulum_drift_shrinks_with_stabilisation(tmp_path):
    run_demo("constrained-pendulum", tmp_path, duration=5.0)
    drift = summary(tmp_path)["max_rod_length_error_m"]
    assert drift["alpha=10"] < drift["none"] < 1e-4


def test_double_pendulum_is_chaotic(tmp_path):
    run_demo("double-pendulum", tmp_path, duration=8.0)
    data = summary(tmp_path)
    assert data["lyapunov_exponent_per_s"] > 0.5
    assert "theta1''" in data["equations"]


def test_spring_pendulum_conserves_energy(tmp_path):
    run_demo("spring-pendulum", tmp_path, duration=5.0)
    assert abs(summary(tmp_path)["energy_drift"]) < 1e-9


def test_a_demo_without_a_picture_refuses_video_before_running(tmp_path):
    with pytest.raises(ModelError, match=r"has no picture.*demos with one: .*pendulum"):
        run_demo("oscillator", tmp_path / "out", formats=["mp4"])
    assert not (tmp_path / "out").exists()
