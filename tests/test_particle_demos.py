"""The particle-system demos (fountain, fireworks, snow) against the physics they show, and
their example scenes against the demos."""

from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

import visviva as vv
from visviva.demos import fireworks, fountain, run_demo, snow
from visviva.io.scene_files import load_scene

EXAMPLES = Path(__file__).parents[1] / "examples" / "scenes"
DEMOS = {"fountain": fountain, "fireworks": fireworks, "snow": snow}


def summary(directory: Path) -> dict:
    return json.loads((directory / "summary.json").read_text())


def outputs(directory: Path, name: str) -> vv.simulation.Recording:
    """The demo wrote its recording, summary and figure; the recording, read back."""
    for file in ("recording.h5", "summary.json", f"{name}.png"):
        assert (directory / file).stat().st_size > 1000, file
    assert summary(directory)["complete"] is True
    return vv.io.load_recording(directory / "recording.h5")


def test_fountain_fills_to_rate_times_mean_lifetime_and_rises_as_linear_drag_allows(tmp_path):
    run_demo("fountain", tmp_path, duration=3.0, formats=["gif"], fps=5)
    recording = outputs(tmp_path, "fountain")
    data = summary(tmp_path)
    t, live = recording.time, recording["particle_alive"].sum(axis=1)
    # Little's law: after the longest lifetime, rate × mean lifetime = 2400 × 1.8 drops.
    steady = t >= fountain.LIFETIME[1]
    expected = fountain.RATE * np.mean(fountain.LIFETIME)
    assert data["steady_state_alive_expected"] == expected == 4320.0
    assert abs(live[steady].mean() / expected - 1.0) < 0.01
    assert np.abs(live[steady] / expected - 1.0).max() < 0.03
    # Filling up: rate ∫₀ᵗ P(lifetime > age) d age, frame by frame.
    filling = t > 0.2
    assert np.abs(live[filling] / fountain.expected_alive(t[filling]) - 1.0).max() < 0.03
    assert data["drops_born"] == round(fountain.RATE * 3.0) and data["drops_dropped"] == 0
    # The top drop: within 1 % of the linear-drag closed form (the step's error is ~v·dt/2),
    # which is 4 % below v²/(2g).
    apex = data["apex_above_nozzle_m"]
    assert apex["measured"] == pytest.approx(apex["linear_drag_closed_form"], rel=0.01)
    assert apex["measured"] < 0.97 * apex["drag_free_v2_over_2g"]
    # Nothing falls through the basin floor (a drop growing by its size ramp may sink by its
    # growth in one step); drops land and spread over it.
    alive, radius = recording["particle_alive"], recording["particle_radius"]
    gap = np.where(alive, recording["particle_position"][..., 1] - radius, np.inf)
    assert (gap[alive] > -0.01 * radius[alive]).all()
    assert (gap[-1] < 1e-3).sum() > 500
    assert iio.imread(tmp_path / "animation.gif", index=None).shape[0] == 16  # 3 s at 5/s


def test_fireworks_births_drops_and_sparks_that_darken(tmp_path):
    duration = 4.0  # past the last burst (3.84 s)
    run_demo("fireworks", tmp_path, duration=duration)
    recording = outputs(tmp_path, "fireworks")
    data = summary(tmp_path)
    scene = fireworks.build_scene(duration).scene
    bursts = sum(b.count for e in scene.entities if e.type == "emitter" for b in e.bursts)
    assert data["births"] == data["births_expected"] == bursts == 4 * (1 + 1500)
    assert data["dropped"] == 0
    # Shortly after a burst the sparks' mean distance from their centre follows quadratic
    # drag's (m/c) ln(1 + c v₀ t/m).
    for shell in data["sphere_radius_after_burst"].values():
        assert shell["measured_m"] == pytest.approx(shell["drag_law_m"], rel=0.03)
    model = fireworks.build_scene(duration).build()
    alive, color = recording["particle_alive"], recording["particle_color"]
    for spec in model.emitters:
        if not spec.name.endswith("sparks"):
            continue
        slots = slice(spec.first_slot, spec.first_slot + spec.capacity)
        both = alive[1:, slots] & alive[:-1, slots]  # one life per slot: a single burst
        assert both.sum() > 1000 * 10
        change = color[1:, slots] - color[:-1, slots]
        # Every channel of every spark falls (or stays) from frame to frame as it ages.
        assert change[both].max() <= 1e-6, spec.name
        born = int(np.argmax(alive[:, slots].any(axis=1)))
        assert color[born, slots][alive[born, slots]].min() > 0.9  # white-hot at birth
    # The shells die at the top of their flights, U²/(2g) above the ground.
    shells = [s for s in model.emitters if s.name.endswith("shell")]
    for spec, shell in zip(shells, fireworks.SHELLS, strict=True):
        height = recording["particle_position"][:, spec.first_slot, 1][alive[:, spec.first_slot]]
        # First order in the step: symplectic Euler and the straight flight of a newborn's
        # first partial step each shift the apex by about U·dt/2.
        assert height.max() == pytest.approx(shell.burst_point[1], abs=shell.speed * fireworks.DT)


def test_snow_settles_on_the_ball_and_the_ground_without_entering_them(tmp_path):
    run_demo("snow", tmp_path)  # its full 6.5 s: the snowfall stops at 3 s
    recording = outputs(tmp_path, "snow")
    data = summary(tmp_path)
    alive, radius = recording["particle_alive"], recording["particle_radius"]
    ball, ground = snow.gaps(recording["particle_position"], radius)
    # No flake inside a collider by more than 1 % of its radius, in any frame.
    assert (ball[alive] >= -0.01 * radius[alive]).all()
    assert (ground[alive] >= -0.01 * radius[alive]).all()
    assert data["max_penetration_over_radius"] < 0.01
    assert data["flakes_born"] == 3600 and data["flakes_dropped"] == 0
    assert data["fraction_at_rest_at_end"] > 0.9
    assert data["resting_on_ball"] > 200 and data["resting_on_ground"] > 2500
    # Coulomb: a flake held still on the ball is pulled along the surface by at most μ times
    # the force pressing it in; the wind widens the cap on its windward side.
    assert data["max_pull_over_push_held_on_ball"] <= snow.FRICTION
    cap = data["snow_cap_half_angle_deg"]
    assert cap["leeward"] < cap["still_air_atan_mu"] < cap["windward"]
    # The edges of the cap where the wind alone would put them (the gust pushes a little too).
    assert cap["windward"] == pytest.approx(cap["windward_in_the_wind_alone"], abs=4.0)
    assert cap["leeward"] == pytest.approx(cap["leeward_in_the_wind_alone"], abs=4.0)


@pytest.mark.parametrize("name", DEMOS)
def test_example_scene_is_the_demo_s_scene(name):
    """The file and the demo describe the same scene, and their models step bit for bit alike."""
    path = EXAMPLES / f"{name}.toml"
    from_file, _ = load_scene(path)
    from_demo = DEMOS[name].build_scene()
    assert from_file == from_demo.scene
    states = []
    for model in (vv.load_model(path), from_demo.build()):
        simulation = vv.Simulation(model)
        simulation.step(40)
        states.append(simulation.raw_state)
    first, second = states
    assert first.t == second.t
    for a, b in zip(first.parts, second.parts, strict=True):
        assert a.tobytes() == b.tobytes()
    assert first.carried.keys() == second.carried.keys()
    for key in first.carried:
        assert first.carried[key].tobytes() == second.carried[key].tobytes(), key
    assert first.carried["particle_alive"].any()  # something was born in those steps
