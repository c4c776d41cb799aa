"""Scene files, the builder and the Model: same model either way, exact round trips, physics."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.io.scene_files import dump_scene, load_scene, parse_scene
from visviva.io.writer import RecordingWriter
from visviva.scenes import dry_run

EXAMPLES_DIR = Path(__file__).parents[1] / "examples" / "scenes"
EXAMPLES = sorted(EXAMPLES_DIR.glob("*.toml"))


def build_in_python() -> vv.SceneBuilder:
    builder = vv.SceneBuilder(name="two balls", description="thrown and dropped")
    builder.set_world(gravity=(0.0, -9.81, 0.0))
    builder.set_integration(method="velocity_verlet", dt=1e-3, duration=1.0, record_every=10)
    builder.add_particles(
        name="balls",
        positions=[[0.0, 2.0, 0.0], [1.0, 0.1, 0.3]],
        velocities=[[0.0, 0.0, 0.0], [0.5, 4.0, 0.0]],
        mass=[0.5, 2.0],
        radius=0.1,
    )
    return builder


SAME_SCENE_TOML = """
[scene]
name = "two balls"
description = "thrown and dropped"

[integration]
method = "velocity_verlet"
dt = 1e-3
duration = 1.0
record_every = 10

[[entities]]
type = "particles"
name = "balls"
positions = [[0.0, 2.0, 0.0], [1.0, 0.1, 0.3]]
velocities = [[0.0, 0.0, 0.0], [0.5, 4.0, 0.0]]
mass = [0.5, 2.0]
radius = 0.1
"""


def test_builder_and_file_give_the_same_model():
    from_python = build_in_python().build()
    from_file = vv.model.build_model(parse_scene(SAME_SCENE_TOML))
    for name in ("particle_position", "particle_velocity", "particle_mass", "particle_radius"):
        np.testing.assert_array_equal(getattr(from_python, name), getattr(from_file, name))
    assert from_python.integration == from_file.integration
    np.testing.assert_array_equal(from_python.gravity, from_file.gravity)


def test_model_is_frozen():
    model = build_in_python().build()
    with pytest.raises(ValueError, match="read-only"):
        model.particle_mass[0] = 3.0
    with pytest.raises(AttributeError):
        model.name = "other"  # type: ignore[misc]


@pytest.mark.parametrize("format", ["toml", "json"])
def test_dump_and_load_round_trip_every_float_bit_for_bit(format):
    rng = np.random.default_rng(3)
    # Awkward doubles: random mantissas, tiny and huge exponents, values like 0.1 + 0.2.
    positions = (rng.standard_normal((20, 3)) * 10.0 ** rng.integers(-300, 300, (20, 3))).tolist()
    positions[0] = [0.1 + 0.2, 1 / 3, 5e-324]
    builder = vv.SceneBuilder(name="awkward")
    builder.set_integration(method="rk4", dt=0.1 + 0.2, duration=7 / 3)
    builder.add_particles(positions=positions, mass=np.pi, radius=2.0**-40)
    text = vv.io.dump_scene(builder.scene, format)
    again = parse_scene(text, format)
    assert again == builder.scene
    assert dump_scene(again, format) == text
    # Bit-identical, not just equal: compare the raw bytes of every float.
    original = np.array(positions)
    loaded = np.array(again.entities[0].positions)
    assert original.tobytes() == loaded.tobytes()


def test_example_scenes_validate_and_run_shortened(tmp_path):
    assert len(EXAMPLES) >= 2, "examples/scenes must hold at least one scene per entity type"
    kinds = set()
    for path in EXAMPLES:
        model = vv.load_model(path)
        kinds |= {type(e).__name__ for e in load_scene(path)[0].entities}
        duration = 5 * model.integration.dt * model.integration.record_every
        written = vv.run_scene(model, tmp_path / path.stem, duration=duration).files
        summary = json.loads((tmp_path / path.stem / "summary.json").read_text())
        assert summary["success"] is True
        steps = round(duration / model.integration.dt) * model.integration.substeps
        assert summary["steps"] == steps  # integrator steps, substeps included
        assert {p.name for p in written} >= {"recording.h5", "summary.json"}
    assert kinds >= {"Particles", "ParticleCloud", "System", "Cloth"}


def test_free_fall_matches_the_parabola(tmp_path):
    """Velocity Verlet is exact for constant acceleration: x(t) = x0 + v0 t + ½ g t²."""
    builder = build_in_python()
    vv.run_scene(builder.build(), tmp_path)
    recording = vv.io.load_recording(tmp_path / "recording.h5")
    t = recording.time[:, None, None]
    x0 = np.array([[0.0, 2.0, 0.0], [1.0, 0.1, 0.3]])
    v0 = np.array([[0.0, 0.0, 0.0], [0.5, 4.0, 0.0]])
    g = np.array([0.0, -9.81, 0.0])
    exact = x0 + v0 * t + 0.5 * g * t**2
    np.testing.assert_allclose(recording["particle_position"], exact, atol=1e-12)
    # Energy is conserved to round-off for this exact integration: E = ½mv² − m g·x.
    assert np.ptp(recording["energy"]) < 1e-12 * np.abs(recording["energy"]).max()
    assert recording.units["particle_position"] == "m" and recording.units["energy"] == "J"
    assert recording.attrs["scene"].startswith("[scene]")
    assert recording.attrs["method"] == "velocity_verlet" and recording.attrs["dt"] == 1e-3
    assert recording.attrs["success"] is True
    np.testing.assert_array_equal(recording.static["particle_radius"], [0.1, 0.1])


def test_pendulum_system_keeps_its_rod_length(tmp_path):
    builder = vv.SceneBuilder(name="pendulum")
    builder.set_integration(method="rk4", dt=0.01, duration=2.0)
    builder.add_system("pendulum", {"length": 0.7, "theta0": 0.4})
    vv.run_scene(builder.build(), tmp_path)
    geometry = vv.io.load_recording(tmp_path / "recording.h5").geometry()
    rod = np.linalg.norm(geometry.points[:, 1] - geometry.points[:, 0], axis=-1)
    np.testing.assert_allclose(rod, 0.7, rtol=1e-12)
    np.testing.assert_array_equal(geometry.edges, [[0, 1]])


def test_particle_cloud_is_reproducible_and_inside_its_box():
    builder = vv.SceneBuilder()
    builder.add_particle_cloud(count=500, center=[1.0, 2.0, 3.0], size=[0.2, 0.4, 0.6], seed=5)
    first, second = builder.build(), builder.build()
    np.testing.assert_array_equal(first.particle_position, second.particle_position)
    offset = np.abs(first.particle_position - [1.0, 2.0, 3.0])
    assert np.all(offset <= np.array([0.1, 0.2, 0.3]))


def test_dry_run_counts_and_advises():
    builder = vv.SceneBuilder()
    builder.set_integration(method="explicit_euler", dt=0.01, duration=1.0, record_every=7)
    builder.add_system("oscillator", {"omega": 10.0})
    report = dry_run(builder.build())
    assert report.steps == 100
    assert report.frames == 100 // 7 + 2  # initial frame, 14 full frames, the final state
    # Explicit Euler is unstable on every undamped oscillation: no stable step at all.
    assert report.max_stable_dt == 0.0
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
    # Symplectic Euler on q'' = −ω²q is stable for ωh ≤ 2.
    assert dry_run(builder.build()).max_stable_dt == pytest.approx(0.2, rel=1e-6)


def test_streamed_frames_survive_a_crash(tmp_path):
    """A process killed mid-run leaves a readable file holding every flushed frame."""
    path = tmp_path / "crash.h5"
    script = f"""
import os, numpy as np
from visviva.io.writer import RecordingWriter
writer = RecordingWriter({str(path)!r}, units={{"particle_position": "m"}}, flush_every=10)
for k in range(25):
    writer.append(0.1 * k, {{"particle_position": np.full((4, 3), float(k))}})
os._exit(9)  # die without closing the file
"""
    result = subprocess.run([sys.executable, "-c", script], check=False)
    assert result.returncode == 9
    recording = vv.io.load_recording(path)
    assert recording.frames >= 20  # the frames up to the last flush (20) at least
    np.testing.assert_array_equal(recording["particle_position"][:20, 0, 0], np.arange(20.0))
    assert recording.attrs["success"] is False
    assert "did not finish" in recording.attrs["message"]


def test_writer_final_attributes_replace_the_provisional_ones(tmp_path):
    with RecordingWriter(tmp_path / "r.h5", attrs={"method": "rk4"}) as writer:
        writer.append(0.0, {"q": np.zeros(2)})
        writer.finish({"success": True, "message": "completed"}, {"energy": np.ones(1)})
    recording = vv.io.load_recording(tmp_path / "r.h5")
    assert recording.attrs["success"] is True and recording.attrs["method"] == "rk4"
    np.testing.assert_array_equal(recording["energy"], [1.0])


def test_cli_validate_schema_dry_run_and_plot(tmp_path):
    from typer.testing import CliRunner

    from visviva.cli.main import app

    runner = CliRunner()
    scene = EXAMPLES_DIR / "falling_particles.toml"
    result = runner.invoke(app, ["validate", str(scene)])
    assert result.exit_code == 0 and "valid" in result.stdout
    schema = json.loads(runner.invoke(app, ["schema"]).stdout)
    assert schema["additionalProperties"] is False
    discriminator = schema["properties"]["entities"]["items"]["discriminator"]
    assert discriminator["propertyName"] == "type"
    assert set(discriminator["mapping"]) == {
        "particles",
        "particle_cloud",
        "rope",
        "hair",
        "springs",
        "cloth",
        "cloth_mesh",
        "soft_lattice",
        "soft_mesh",
        "body",
        "emitter",
        "system",
        "force",
        "collider",
        "boids",
        "crowd",
        "particle_collisions",
        "body_contacts",
    }
    assert schema["$defs"]["Particles"]["additionalProperties"] is False
    out = tmp_path / "dry"
    result = runner.invoke(app, ["run", str(scene), "-o", str(out), "--dry-run"])
    assert result.exit_code == 0 and "would write" in result.stdout
    assert not out.exists()
    result = runner.invoke(app, ["run", str(scene), "-o", str(out), "--duration", "0.05"])
    assert result.exit_code == 0, result.output
    for kind in ("energy", "momentum"):
        result = runner.invoke(app, ["plot", str(out / "recording.h5"), f"--{kind}"])
        assert result.exit_code == 0, result.output
        assert (out / f"{kind}.png").stat().st_size > 10_000


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_scenes_run_to_the_end(tmp_path, path):
    """Every example scene at its full length (``pytest -m slow``; the star cluster's 20,000
    stars take half a minute): it completes, its energy stays within its tolerance, the
    summary counts what it holds, and its video's view keeps everything in the picture."""
    report = vv.run_scene(vv.load_model(path), tmp_path)
    summary = report.summary
    assert summary["complete"] and summary["success"] and summary["counts"]
    assert not [w for w in summary["warnings"] if w["kind"] == "energy_drift"], summary
    # And the video's view keeps every body and particle in the picture over the whole run
    # (a star field is framed on 98 % of its stars, by design: its stragglers may leave).
    from test_framing import drawn_points, in_picture
    from visviva.viz.frame import is_star_field
    from visviva.viz.framing import chosen_camera
    from visviva.viz.outputs import playback

    recording = vv.io.load_recording(tmp_path / "recording.h5")
    geometry = recording.geometry()
    if geometry.points.shape[1] or geometry.bodies is not None:
        view = playback(recording, None, None)
        camera = chosen_camera(geometry, view.camera, view.frame, 960 / 540)
        inside = in_picture(camera, drawn_points(recording), 960 / 540)
        assert is_star_field(geometry) or inside.all(), f"{(~inside).sum()} points leave"
