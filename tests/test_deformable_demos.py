"""The deformable demos (cloth, flag, hair, jelly, the stiffness and refinement studies): each
runs, shortened where it can be, and its summary holds the physics it shows."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.demos import jelly, run_demo
from visviva.io.scene_files import load_scene

EXAMPLES = Path(__file__).parents[1] / "examples" / "scenes"


def summary(directory: Path) -> dict:
    return json.loads((directory / "summary.json").read_text())


def outputs(directory: Path, figure: str) -> vv.simulation.Recording:
    """The demo wrote its recording, summary and figure, and finished; its first run, read
    back, has points that moved."""
    for file in ("recording.h5", "summary.json", f"{figure}.png"):
        assert (directory / file).stat().st_size > 1000, file
    assert summary(directory)["complete"] is True
    recording = next(iter(vv.io.read_recordings(directory / "recording.h5").values()))
    points = recording["particle_position"]
    assert points.shape[0] > 10 and points.shape[1] > 0
    assert np.abs(points[-1] - points[0]).max() > 1e-3
    return recording


def test_cloth_hang_never_gains_energy_and_rests_on_its_pins(tmp_path):
    run_demo("cloth-hang", tmp_path)  # its full 8 s: the swing has died out by then
    recording = outputs(tmp_path, "cloth_hang")
    data = summary(tmp_path)
    # Backward Euler only dissipates: no step gains energy.
    assert data["largest_energy_rise_per_step_J"] <= data["energy_rise_tolerance_J"]
    assert data["energy_J"]["end"] < data["energy_J"]["start"]
    # At rest the pins carry the whole weight, and pull straight up.
    assert data["kinetic_energy_at_end_J"] < 1e-5
    load = data["load_on_pins_N"]
    assert load["relative_error"] < 1e-3
    assert load["springs_pull_down"] == pytest.approx(load["free_points_weight"], rel=1e-3)
    assert load["springs_pull_sideways"] < 1e-3 * load["cloth_weight_M_g"]
    # The pins stay where they are to the last bit; the fabric stretches by about 1 %.
    pins = recording["particle_position"][:, [0, 19]]
    assert np.array_equal(pins, np.broadcast_to(pins[0], pins.shape))
    assert 0.0 < data["largest_stretch_at_rest"] < 0.02
    assert 0.0 < data["sag_at_rest_m"]["top_edge_middle"] < 0.05


def test_cloth_drape_stays_outside_the_ball_which_carries_it_within_coulombs_cone(tmp_path):
    run_demo("cloth-drape", tmp_path)  # its full 3 s: at rest by then
    outputs(tmp_path, "cloth_drape")
    data = summary(tmp_path)
    assert data["deepest_inside_ball_m"] <= data["inside_tolerance_m"]
    assert data["largest_energy_rise_per_step_J"] <= data["energy_rise_tolerance_J"]
    assert data["kinetic_energy_at_end_J"] < 1e-5
    # Dozens of points rest on the ball (of 256), down to near its equator.
    contacts = data["contacts_at_rest"]
    assert contacts["resting"] >= 30 and contacts["colliding"] == 0
    assert data["lowest_contact_from_top_deg"] > 60.0
    # The ball carries the whole cloth, and static friction stays inside Coulomb's cone.
    carried = data["ball_carries_N"]
    assert carried["relative_error"] < 1e-3
    assert carried["sideways"] < 1e-3 * carried["cloth_weight_M_g"]
    friction = data["friction_at_rest"]
    assert friction["pressed_contacts"] >= 30
    assert friction["largest_along_over_pressing"] <= friction["mu"]


def test_flag_leans_where_the_wind_and_its_weight_balance(tmp_path):
    run_demo("flag", tmp_path)  # its full 4 s: settled by 2 s
    recording = outputs(tmp_path, "flag")
    data = summary(tmp_path)
    assert data["kinetic_energy_at_end_J"] < 1e-6
    # Exact at rest: the staff's load leans by atan(drag / weight).
    pull = data["pull_on_staff"]
    assert pull["angle_from_vertical_deg"] == pytest.approx(
        pull["atan_drag_over_weight_deg"], abs=0.01
    )
    assert abs(pull["along_staff_N"]) < 1e-9
    # The sheet settles within a degree of the rigid plate's angle, after overshooting it.
    angle = data["deflection_deg"]
    assert abs(angle["mean_second_half"] - angle["rigid_plate"]) < angle["tolerance"]
    assert angle["drag_over_weight"] < angle["mean_second_half"] < angle["largest"]
    staff = recording["particle_position"][:, :16]
    assert np.array_equal(staff, np.broadcast_to(staff[0], staff.shape))


def test_hair_swings_from_the_turning_head_with_the_period_of_a_hanging_chain(tmp_path):
    run_demo("hair", tmp_path)  # its full 8 s: the turn, then four swings of the longest strand
    recording = outputs(tmp_path, "hair")
    data = summary(tmp_path)
    # The roots ride the head: on the hairline circle, turned together, still before and
    # after the turn, and turned by exactly the head's angle.
    roots = data["roots"]
    assert roots["off_hairline_m"] <= roots["tolerance_m"]
    assert roots["turn_spread_rad"] < 1e-12 and roots["turn_error_rad"] < 1e-12
    assert roots["still_before_turn"] is True and roots["still_after_stop"] is True
    t, velocities = recording.time, recording["particle_velocity"][:, [0, 8, 18, 30, 44]]
    turn = data["head_turn"]
    during = (t > turn["start"] + turn["ramp"]) & (t < turn["stop"] - turn["ramp"])
    # At full speed each root moves at ω R along the hairline, and before and after, not at all.
    speed = np.linalg.norm(velocities, axis=-1)
    assert speed[during] == pytest.approx(turn["angular_velocity"] * 0.1, rel=1e-12)
    assert not speed[(t < turn["start"]) | (t >= turn["stop"])].any()
    # Suddenly loaded: at most twice the static stretch (plus the swing's pull).
    stretch = data["largest_stretch"]
    assert stretch["static"] < stretch["measured"] <= stretch["bound_2_static_1_plus_amplitude2"]
    # Periods: a chain's (to 1 %), 2 % slower than the strand made rigid, growing as √L.
    assert data["dt"] / data["substeps"] < data["advisor_largest_stable_step_s"]
    ratios = []
    for strand in data["strands"]:
        assert strand["amplitude_rad"] < 0.15  # small swings
        period = strand["period_s"]
        assert period == pytest.approx(
            strand["hanging_chain_period_s"], rel=data["period_tolerance"]
        )
        rigid = strand["compound_pendulum_period_s"]
        assert rigid < period < (1.0 + data["compound_tolerance"]) * rigid
        ratios.append(period / np.sqrt(strand["length_m"]))
    assert max(ratios) / min(ratios) < 1.03


def test_jelly_falls_freely_never_sinks_and_rests_squashed_as_linear_elasticity_says(tmp_path):
    run_demo("jelly", tmp_path)  # its full 3 s
    outputs(tmp_path, "jelly")
    data = summary(tmp_path)
    touch = data["first_touch_s"]
    assert abs(touch["measured"] - touch["free_fall_sqrt_2h_over_g"]) <= touch["frame_s"]
    assert data["lowest_below_floor_m"] <= data["floor_tolerance_m"]
    assert data["cube_height_m"]["smallest"] < 0.95 * data["cube_height_m"]["undeformed"]
    # At rest: squashed between the linear estimates with the bottom held and sliding, the
    # shape kept to 1 %, the drop's energy gone down to the squashed cube's static energy.
    assert data["kinetic_energy_at_end_J"] < 1e-3
    squash = data["compression_at_rest_m"]
    low, high = squash["linear_bottom_held"], squash["linear_bottom_sliding"]
    assert 0.99 * low < squash["measured"] < 1.01 * high
    top = data["top_height_at_rest_m"]
    assert top["measured"] == pytest.approx(top["size_plus_radius_minus_compression"], abs=1e-4)
    assert data["largest_stretch_at_rest"] < 0.01
    energy = data["energy_J"]
    share = energy["undeformed_on_the_floor"] - energy["at_rest_linear_elasticity"]
    assert abs(energy["end"] - energy["at_rest_linear_elasticity"]) < 0.1 * share


def test_the_jelly_scene_file_is_the_demo_s_scene():
    """``examples/scenes/jelly.toml`` and the demo describe the same scene, and their models
    step bit for bit alike."""
    path = EXAMPLES / "jelly.toml"
    from_file, _ = load_scene(path)
    from_demo = jelly.build_scene()
    assert from_file == from_demo.scene
    states = []
    for model in (vv.load_model(path), from_demo.build()):
        simulation = vv.Simulation(model)
        simulation.step(30)  # past the first touch
        states.append(simulation.raw_state)
    for a, b in zip(states[0].parts, states[1].parts, strict=True):
        assert a.tobytes() == b.tobytes()


def test_stiffness_study_symplectic_euler_survives_exactly_where_the_advisor_says(tmp_path):
    run_demo("stiffness-study", tmp_path, duration=1.0)  # every blow-up comes within 0.4 s
    outputs(tmp_path, "stiffness_study")
    data = summary(tmp_path)
    assert data["all_predictions_hold"] is True
    table = data["stiffness"]
    assert [row["k_N_per_m"] for row in table] == [3.0, 10.0, 100.0, 1000.0, 10000.0]
    for row in table:
        stable = row["h_over_h_max"] < 1.0
        assert (row["symplectic_euler"] == "survived") == stable, row
        assert abs(np.log(row["h_over_h_max"])) > np.log(1.2)  # no case on the fence
        for method in ("projected_newton", "linearly_implicit_euler"):
            assert row[method]["survived"], (method, row["k_N_per_m"])
        assert row["projected_newton"]["largest_energy_rise_per_step_J"] <= 1e-9
    # Both sides are shown, h_max falls as 1/√k, and stiff cloth barely stretches.
    assert {row["predicted"] for row in table} == {"stable", "unstable"}
    limits = np.array([row["advisor_h_max_s"] for row in table])
    k = np.array([row["k_N_per_m"] for row in table])
    np.testing.assert_allclose(limits * np.sqrt(k), limits[0] * np.sqrt(k[0]), rtol=0.02)
    assert table[-1]["projected_newton"]["largest_stretch_at_end"] < 0.01
    assert table[0]["projected_newton"]["largest_stretch_at_end"] > 0.2
    runs = summary(tmp_path)["runs"]
    assert next(iter(runs)) == "projected_newton_k10000"  # the video's run
    assert runs["symplectic_euler_k10000"]["success"] is False


def test_refinement_study_a_curtain_converges_a_cloth_held_at_two_points_does_not(tmp_path):
    run_demo("refinement-study", tmp_path)  # its full 4 s: every run at rest
    outputs(tmp_path, "refinement_study")
    data = summary(tmp_path)
    assert data["largest_speed_at_rest_m_per_s"] < 1e-3
    # The curtain: each refinement changes the drop about half as much as the last, and the
    # finest lies between the membrane's estimates held from contracting and free to.
    curtain = data["curtain_bottom_drop_m"]
    first, second = curtain["successive_changes"]
    assert 0.0 < second < 0.7 * first
    finest = curtain["per_resolution"]["21"]
    assert curtain["held_from_contracting_rho_g_H2_over_2C11"] < finest
    assert finest < curtain["free_to_contract_rho_g_H2_over_2E"]
    # Two corners: about 2 mm more at every doubling, of the order of (F/E) ln 2.
    corners = data["two_corners_top_middle_sag_m"]
    first, second = corners["successive_changes"]
    assert second > 0.8 * first > 1e-3
    assert 0.5 < corners["growth_per_doubling"] / corners["scale_F_over_E_ln2"] < 2.0
    assert corners["spread_max_minus_min"] > 10 * curtain["spread_max_minus_min"]
    # Seed 001: only shear springs resist shear; bend springs (and only they) resist bending.
    study = data["structure_study"]
    for springs, droop in study.items():
        resists_shear = "shear" in springs
        assert (droop["in_plane_shear_droop_m"] < 0.01) == resists_shear, springs
        assert (droop["in_plane_shear_droop_m"] > 0.9) == (not resists_shear), springs
    limp = study["structural"]["bending_droop_m"]
    assert study["structural+shear"]["bending_droop_m"] == pytest.approx(limp, rel=1e-3)
    assert study["structural+bend"]["bending_droop_m"] < 0.9 * limp
    assert study["structural+shear+bend"]["bending_droop_m"] < 0.9 * limp
