"""Gravitation through the shared pipeline: scene systems, demos and played-faster outputs."""

from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import visviva as vv
from visviva.demos import run_demo
from visviva.errors import SceneError
from visviva.io.scene_files import parse_scene
from visviva.model import build_model


def summary(directory: Path) -> dict:
    return json.loads((directory / "summary.json").read_text())


def test_kepler_demo_keeps_energy_bounded_and_angular_momentum_exact(tmp_path):
    run_demo("kepler", tmp_path, duration=30.0)
    methods = summary(tmp_path)["methods"]
    verlet = methods["velocity_verlet"]
    # Leapfrog at 1000 steps per orbit, e = 0.5: bounded O(h²) energy error, L to rounding.
    assert verlet["max_energy_error"] < 2e-4
    assert verlet["max_angular_momentum_error"] < 1e-11
    assert methods["rk4"]["final_position_error_m"] < 1e-5
    assert methods["explicit_euler"]["max_energy_error"] > 0.1


def test_sun_earth_moon_year_and_month_with_a_video_a_week_per_second(tmp_path):
    run_demo("sun-earth-moon", tmp_path, duration=60 * 86_400.0, formats=["gif"], fps=5)
    data = summary(tmp_path)
    # Two months in: the month is measured over two whole turns (observed 27.322 d; the
    # truncated lunar theory of the start is good to ~0.1%).
    assert data["sidereal_month_days"] == pytest.approx(27.322, abs=0.05)
    assert data["max_energy_error"] < 1e-8
    # 60 days at a week per second and 5 frames/s: floor(60/7 · 5) + 1 = 43 frames.
    assert iio.imread(tmp_path / "animation.gif", index=None).shape[0] == 43


def test_galaxy_demo_runs(tmp_path):
    run_demo("galaxy", tmp_path, duration=0.5)
    data = summary(tmp_path)
    assert data["bodies"] == 6002
    # Tree forces are not the gradient of the tree potential: the energy wanders at about the
    # force error (1.7e-3 of the initial kinetic energy over the demo's full 15 time units).
    assert data["max_energy_change_over_initial_kinetic"] < 1e-3
    tree = data["barnes_hut_force_error"]
    assert tree["theta"] == 0.5
    assert 0.0 < tree["median"] <= vv.mechanics.barnes_hut.ERROR_BOUNDS[0.5][0]


def scene(system: str, parameters: str, duration: float = 1.0) -> str:
    return (
        f'[integration]\nmethod = "velocity_verlet"\ndt = 0.01\nduration = {duration}\n'
        f'[[entities]]\ntype = "system"\nsystem = "{system}"\nparameters = {{ {parameters} }}\n'
    )


def test_kepler_scene_follows_the_ellipse(tmp_path):
    model = build_model(parse_scene(scene("kepler", "eccentricity = 0.3, mass2 = 0.5", 6.0)))
    out = tmp_path / "run"
    vv.run_scene(model, out)
    recording = vv.io.load_recording(out / "recording.h5")
    orbit = vv.mechanics.kepler_orbit(1.0, 0.3, masses=(1.0, 0.5), G=1.0)
    points = recording["system_points"]  # the bodies' positions, recorded once
    # Verlet, h = 0.01 s over about one orbit: position error ~h² · (n² a) · t ≈ 1e-3 m.
    np.testing.assert_allclose(points, orbit.positions(recording.time), atol=3e-3)


def test_galaxy_scene_counts_are_checked_before_allocation():
    with pytest.raises(SceneError) as error:
        build_model(
            parse_scene(
                scene("galaxy", "bodies_per_disk = 1e9, seed = 0.5, softening = -1, theta = 1.5")
            )
        )
    message = str(error.value)
    assert "bodies_per_disk: must be at most 5e+06 (got 1000000000.0)" in message
    assert "seed: must be a whole number (got 0.5)" in message
    assert "softening: must be at least 0 (got -1.0)" in message
    assert "theta: must be at most 1 (got 1.5)" in message


def test_large_galaxy_scene_runs_on_the_tree_and_follows_direct_summation(tmp_path):
    """Above 4000 bodies a galaxy scene uses Barnes–Hut. Over 10 steps of h = 0.01 a star's
    position departs from direct summation's by about its force error times ½ |a| t², so that
    ratio obeys the tree's documented error bounds (θ = 0.5: median 5e-4, 99th percentile 5e-3)."""
    parameters = "bodies_per_disk = 2100, disk_mass = 0.2, theta = 0.5"
    model = build_model(parse_scene(scene("galaxy", parameters, duration=0.1)))
    out = tmp_path / "run"
    vv.run_scene(model, out)
    recording = vv.io.load_recording(out / "recording.h5")
    tree = recording["system_points"][-1]
    assert tree.shape == (4202, 3) and recording.time[-1] == pytest.approx(0.1)
    bodies = vv.mechanics.colliding_disks(
        2100,
        central_mass=1.0,
        disk_mass=0.2,
        radius=1.0,
        separation=6.0,
        pericenter=1.5,
        G=1.0,
        softening=0.05,
        seed=0,
    )
    direct = vv.solve(bodies.problem(softening=0.05), "velocity_verlet", dt=0.01, until=0.1)
    a = vv.mechanics.gravity_accelerations(bodies.positions, bodies.masses, G=1.0, softening=0.05)
    departure = np.linalg.norm(tree - direct.q[-1].reshape(-1, 3), axis=1)
    ratio = departure / (0.5 * np.linalg.norm(a, axis=1) * 0.1**2)
    median, p99 = vv.mechanics.barnes_hut.ERROR_BOUNDS[0.5]
    assert np.median(ratio) <= median and np.percentile(ratio, 99) <= p99
    assert np.median(ratio) > 1e-6  # the tree's own error: direct summation would give 0


def test_cluster_scene_stays_in_virial_equilibrium(tmp_path):
    """A Plummer sphere starts in virial equilibrium (2K + U = 0) and stays near it: after a
    crossing time (≈ 3 units) K/|U| is ½ within three times the sampling scatter (≈ 0.32/√N =
    0.014 at N = 500; measured 0.515). With softening 0.05 no encounter is sharper than
    h = 0.01 can follow, and velocity Verlet keeps the energy to 1e-4 (measured 1.3e-5)."""
    parameters = "bodies = 500, softening = 0.05, seed = 3"
    model = build_model(parse_scene(scene("cluster", parameters, duration=3.0)))
    out = tmp_path / "run"
    vv.run_scene(model, out)
    recording = vv.io.load_recording(out / "recording.h5")
    energy = recording["energy"]
    assert np.abs(energy - energy[0]).max() <= 1e-4 * abs(energy[0])
    x = recording["system_points"][-1]
    m = np.full(500, 1.0 / 500)
    potential = vv.mechanics.gravitational_potential_energy(x, m, G=1.0, softening=0.05)
    kinetic = energy[-1] - potential
    assert kinetic / abs(potential) == pytest.approx(0.5, abs=0.042)


def test_gravitating_bodies_are_recorded_once(tmp_path):
    """The bodies' coordinates are their positions: a recording holds them once, as the
    systems' points and velocities [(frames, N, 3)], not again as q and v (the star cluster's
    721 MB became 481 MB), and the points are the positions themselves, with no offset for the
    picture."""
    model = build_model(parse_scene(scene("cluster", "bodies = 64, softening = 0.05", 0.1)))
    vv.run_scene(model, tmp_path / "scene")
    recording = vv.io.load_recording(tmp_path / "scene" / "recording.h5")
    assert set(recording.fields) == {"system_points", "system_velocity", "energy"}
    assert recording.units["system_points"] == "m"
    assert recording.units["system_velocity"] == "m/s"
    start = vv.mechanics.plummer_sphere(64, total_mass=1.0, scale_radius=1.0, G=1.0, seed=0)
    np.testing.assert_array_equal(recording["system_points"][0], start.positions)
    run_demo("kepler", tmp_path / "demo", duration=6.0)
    for run in vv.io.read_recordings(tmp_path / "demo" / "recording.h5").values():
        assert set(run.fields) == {"system_points", "system_velocity", "energy"}
