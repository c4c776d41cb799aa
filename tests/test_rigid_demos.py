"""The rigid-body demos: each runs (shortened) and its summary holds the physics it shows."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from visviva.demos import run_demo


def summary(directory: Path) -> dict:
    return json.loads((directory / "summary.json").read_text())


def test_dzhanibekov_only_the_intermediate_axis_flips_and_l_is_kept(tmp_path):
    """6 s of the three T-handles: the spin about the intermediate moment changes sign (the
    first flip comes after about 1.3 s at 8 rad/s with a 1 % nudge), the other two never;
    L is kept exactly and the kinetic energy within 1e-6 (O(h²) at h = 1/480 s)."""
    run_demo("dzhanibekov", tmp_path, duration=6.0)
    data = summary(tmp_path)
    flips = data["sign_changes_of_the_spin_axis"]
    assert flips["intermediate moment (y)"] >= 2
    assert flips["smallest moment (x)"] == flips["largest moment (z)"] == 0
    assert data["max_angular_momentum_change"] == 0.0
    assert data["max_relative_energy_change"] < 1e-6
    moments = data["principal_moments_kg_m2"]
    assert moments == sorted(moments)  # the mesh's x, y, z are its principal axes, in order


def test_top_precesses_at_the_steady_rate_and_does_not_topple(tmp_path):
    """1 s of the spinning top: the mean precession rate is within 2 % of the slow steady
    precession Ω = (I₃ω − √(I₃²ω² − 4 I₁' M g d cos θ)) / (2 I₁' cos θ) (0.3 % measured over
    4 s) and within 10 % of the fast-top M g d / (I₃ ω); the tilt stays within 0.3 ± 0.05 rad;
    the apex's spring holds the centre of mass at d = 3h/4 to 0.1 %."""
    run_demo("top", tmp_path, duration=1.0)
    data = summary(tmp_path)
    rate = data["precession_rate_rad_per_s"]
    assert abs(rate / data["steady_precession_rad_per_s"] - 1.0) < 0.02
    assert abs(rate / data["gyroscopic_formula_rad_per_s"] - 1.0) < 0.10
    low, high = data["tilt_range_deg"]
    assert low > np.degrees(0.25) and high < np.degrees(0.35)
    near, far = data["apex_distance_to_centre_m"]
    assert abs(near / 0.09 - 1.0) < 1e-3 and abs(far / 0.09 - 1.0) < 1e-3


def test_rotation_drift_renormalizing_keeps_rotations_and_the_splitting_keeps_energy(tmp_path):
    """5 s at h = 0.01 s: explicit Euler's matrix and quaternion are no longer rotations
    (‖RᵀR − E‖ > 0.1); renormalized they are, to round-off, but explicit Euler's energy has
    grown (> 1 %); the splitting stays a rotation with its energy within 1e-5 and is the
    closest to the reference (by a factor 100 at least)."""
    run_demo("rotation-drift", tmp_path, duration=5.0)
    data = summary(tmp_path)
    shape, energy = data["final_not_a_rotation"], data["final_energy_error"]
    error = data["final_orientation_error"]
    assert shape["matrix"] > 0.1 and shape["quaternion"] > 0.1
    for kept in ("matrix + Gram–Schmidt", "quaternion + normalization", "splitting"):
        assert shape[kept] < 1e-14
    assert energy["quaternion + normalization"] > 0.01
    assert abs(energy["splitting"]) < 1e-5
    assert 100 * error["splitting"] < min(v for k, v in error.items() if k != "splitting")


def test_bunny_throw_flies_the_parabola_exactly_and_keeps_l(tmp_path):
    """0.5 s of the thrown rabbit mesh: velocity Verlet keeps its centre of mass on
    x₀ + v₀t + ½gt² to round-off, gravity (no torque) leaves L as it was, and 200,000
    Monte-Carlo samples agree with Mirtich's mass and inertia within 4 standard errors."""
    run_demo("bunny-throw", tmp_path, duration=0.5)
    data = summary(tmp_path)
    assert data["max_distance_from_parabola_m"] < 1e-12
    assert data["max_angular_momentum_change"] < 1e-15
    mass, error = data["sampled_mass_kg"]
    assert abs(mass - data["mass_kg"]) < 4 * error
    assert max(abs(z) for z in data["sampled_inertia_z_scores"]) < 4
    assert data["triangles"] > 5000


def test_bottle_flip_same_flick_different_inertia(tmp_path):
    """The flick chosen for one turn lands the bottle upright within 10° (it turns a little
    while pushed); the same flick turns the other bottles in inverse proportion to their
    moments of inertia (same L, ω = L / I, within 1 %), L is constant in flight and ω is L / I
    to round-off."""
    run_demo("bottle-flip", tmp_path)
    data = summary(tmp_path)
    turned, moments = data["turned_at_landing_deg"], data["moment_about_flip_axis_kg_m2"]
    assert abs(turned["just right"] - 360.0) < 10.0
    for other in ("slimmer, taller", "squatter"):
        expected = turned["just right"] * moments["just right"] / moments[other]
        assert turned[other] == pytest.approx(expected, rel=0.01)
    assert data["angular_momentum_change_in_flight"] == 0.0
    assert data["max_spin_error_vs_L_over_I_rad_per_s"] < 1e-12


def test_bunny_drop_bunnies_rest_on_their_pieces(tmp_path):
    """3 s of the bunny drop: the bunny is cut into a few convex pieces (its body and ears);
    the three decomposed bunnies come to rest (kinetic energy below 1e-9 J) with their lowest
    surface point at the floor to within the pieces' approximation (5 mm), none sunk through;
    the recording keeps each frame's contacts for the viewer."""
    run_demo("bunny-drop", tmp_path, duration=3.0)
    data = summary(tmp_path)
    assert 2 <= data["pieces"] <= 6
    for name in ("upright", "on its side", "off the step's edge"):
        assert abs(data["lowest_point_at_rest_m"][name]) < 5e-3
        assert data["kinetic_energy_at_rest_J"][name] < 1e-9
    assert data["contacts_at_rest"]["colliding"] == 0
    from visviva.io import load_recording

    recording = load_recording(tmp_path / "recording.h5")
    assert "body_contact_point" in recording
