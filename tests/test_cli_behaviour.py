"""Commands that behave: sensible defaults, help that reads right, and refusals that say why.

Each test is one finding of the end-to-end trial of the command line (issue: "Commands that
behave"), run in-process through the entry point ``main()`` so the exit status is the real one.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from test_cli import run_main


def refused(monkeypatch, capsys, *args) -> str:
    """Run a command that must exit 2 with one ``error:`` line; return that line."""
    status, _, err = run_main(monkeypatch, capsys, *args)
    assert "Traceback" not in err
    assert status == 2, err
    (line,) = err.strip().splitlines()[-1:]
    assert line.startswith("error: ")
    return line


def test_convergence_of_a_first_order_problem_uses_the_methods_that_apply(monkeypatch, capsys):
    status, out, err = run_main(
        monkeypatch, capsys, "convergence", "--problem", "first-order", "--levels", "4", "--json"
    )
    assert status == 0, err
    methods = {row["method"] for row in json.loads(out)["methods"]}
    assert "taylor" not in methods and "velocity_verlet" not in methods
    assert {"explicit_euler", "rk4", "backward_euler"} <= methods


@pytest.mark.parametrize("levels", ["25", "2000"])
def test_convergence_levels_are_bounded(monkeypatch, capsys, levels):
    assert "at most 14" in refused(monkeypatch, capsys, "convergence", "--levels", levels)


def test_did_you_mean_ignores_case(monkeypatch, capsys):
    assert "Did you mean 'rk4'?" in refused(monkeypatch, capsys, "stability", "RK4")


def test_help_shows_units_and_no_type_tags_on_flags(monkeypatch, capsys):
    for command in ("run", "demo", "export", "compare"):
        status, out, _ = run_main(monkeypatch, capsys, command, "--help")
        assert status == 0
        assert "<bool>" not in out and not re.search(r"\w \.(\s|$)", out)
    _, out, _ = run_main(monkeypatch, capsys, "demo", "--help")
    assert "Simulated duration [s]" in " ".join(out.split())


def _recording(tmp_path: Path, **fields) -> Path:
    time = np.linspace(0.0, 1.0, 5)
    recording = vv.Recording(time, fields)
    return vv.io.save_recording(recording, tmp_path / "recording.h5")


def test_plot_refuses_a_recording_without_energy_or_momenta(monkeypatch, capsys, tmp_path):
    path = _recording(tmp_path, particle_position=np.zeros((5, 2, 3)))
    line = refused(monkeypatch, capsys, "plot", path, "--energy")
    assert "no energy to plot" in line and "(fields: particle_position)" in line
    for flags in ((), ("--momentum",)):
        line = refused(monkeypatch, capsys, "plot", path, *flags)
        assert "neither energy nor momenta" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["recording.h5"]


def test_plot_momentum_of_a_recording_with_energy_alone_offers_its_energy(
    monkeypatch, capsys, tmp_path
):
    """A named system's recording (examples/scenes/kepler.toml) has energy but no momenta:
    --momentum used to say it had neither."""
    path = _recording(tmp_path, energy=np.ones(5), system_points=np.zeros((5, 2, 3)))
    line = refused(monkeypatch, capsys, "plot", path, "--momentum")
    assert "has no momenta to plot" in line and "without --momentum, its energy" in line


def test_plot_draws_what_the_recording_has(monkeypatch, capsys, tmp_path):
    recording = vv.Recording(
        np.linspace(0.0, 1.0, 5),
        {"particle_position": np.zeros((5, 2, 3)), "particle_velocity": np.ones((5, 2, 3))},
        static={"particle_mass": np.ones(2)},
    )
    path = vv.io.save_recording(recording, tmp_path / "recording.h5")
    status, out, err = run_main(monkeypatch, capsys, "plot", path)
    assert status == 0 and "momentum.png" in out, err
    assert (tmp_path / "momentum.png").read_bytes()[:4] == b"\x89PNG"


def test_several_runs_are_chosen_with_the_run_flag(monkeypatch, capsys, tmp_path):
    time = np.linspace(0.0, 1.0, 3)
    points = {"particle_position": np.zeros((3, 1, 3))}
    runs = {name: vv.Recording(time, points) for name in ("a", "b")}
    path = vv.io.write_recordings(tmp_path / "recording.h5", runs)
    line = refused(monkeypatch, capsys, "view", path)
    assert "--run NAME" in line and "run=" not in line.replace("(in Python: run=NAME)", "")


def test_compare_names_what_is_wrong_with_its_own_options(monkeypatch, capsys):
    line = refused(monkeypatch, capsys, "compare", "pendulm")
    assert "Did you mean 'pendulum'?" in line and "problem in the scene" not in line
    assert "--dt" in refused(monkeypatch, capsys, "compare", "pendulum", "--dt", "nan")
    assert "--duration" in refused(monkeypatch, capsys, "compare", "pendulum", "--duration", "inf")
    assert "limit" in refused(monkeypatch, capsys, "compare", "pendulum", "--duration", "1e308")


def test_compare_keeps_a_hostile_scene_name_inside_out(monkeypatch, capsys, tmp_path):
    builder = vv.SceneBuilder(name="../../escape")
    builder.set_integration(method="rk4", dt=0.01, duration=0.2)
    builder.add_system("oscillator")
    scene = tmp_path / "work" / "escape.toml"
    scene.parent.mkdir()
    scene.write_text(vv.io.dump_scene(builder.scene))
    monkeypatch.chdir(scene.parent)
    status, _, err = run_main(
        monkeypatch, capsys, "compare", scene, "rk4", "--convergence-duration", "0.1"
    )
    assert status == 0, err
    assert (scene.parent / "out" / "compare-escape" / "summary.json").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["work"]


@pytest.mark.parametrize("target", ["afile/x", "/proc/visviva-out"])
def test_an_unwritable_output_is_refused_before_the_run(monkeypatch, capsys, tmp_path, target):
    (tmp_path / "afile").write_text("not a directory")
    monkeypatch.chdir(tmp_path)
    scene = Path(__file__).parents[1] / "examples" / "scenes" / "pendulum.toml"
    line = refused(monkeypatch, capsys, "run", scene, "-o", target, "--duration", "1000")
    assert "cannot create" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_a_figure_needs_an_image_suffix_and_may_go_into_a_new_folder(monkeypatch, capsys, tmp_path):
    assert ".png" in refused(monkeypatch, capsys, "stability", "rk4", "-o", tmp_path / "s.txt")
    target = tmp_path / "out" / "figures" / "regions.png"
    status, _, err = run_main(monkeypatch, capsys, "stability", "rk4", "-o", target)
    assert status == 0, err
    assert target.read_bytes()[:4] == b"\x89PNG"


def test_export_to_obj_prints_one_line(monkeypatch, capsys, tmp_path):
    path = _recording(tmp_path, particle_position=np.zeros((5, 2, 3)))
    status, out, err = run_main(monkeypatch, capsys, "export", path, "--to", "obj", "--fps", "4")
    assert status == 0, err
    assert out.splitlines() == [f"wrote 5 OBJ files into {tmp_path / 'obj'}/ (frame_0000.obj …)"]


def test_export_plays_at_the_speed_its_run_was_made_with(monkeypatch, capsys, tmp_path):
    """A year of orbit recorded by a run that plays a week per second: `export --to gif` uses
    that speed, as `run -f gif` did, instead of refusing a year of video at speed 1."""
    year, week = 365.25 * 86_400.0, 7 * 86_400.0
    t = np.linspace(0.0, year, 53)
    points = np.zeros((53, 1, 3))
    points[:, 0, 0] = np.cos(2 * np.pi * t / year)
    recording = vv.Recording(
        t,
        {"particle_position": points},
        attrs={"playback_speed": week, "playback_trail": 8 * week},
    )
    path = vv.io.save_recording(recording, tmp_path / "recording.h5")
    status, out, err = run_main(monkeypatch, capsys, "export", path, "--to", "gif", "--fps", "2")
    assert status == 0, err
    assert "animation.gif" in out
    line = refused(
        monkeypatch,
        capsys,
        "export",
        path,
        "--to",
        "gif",
        "--speed",
        "1",
        "-o",
        tmp_path / "slow.gif",
    )
    assert "output frames" in line and "speed" in line
    from visviva.viz.outputs import playback

    assert playback(recording, None, None)[:3] == (week, 8 * week, "scene")
    assert playback(recording, 1.0, 0.0, "speed")[:3] == (1.0, 0.0, "speed")


def test_demos_record_how_they_play(tmp_path):
    from visviva.demos import demos, run_demo

    run_demo("kepler", tmp_path, duration=6.0)
    kepler = demos()["kepler"]
    for run in vv.io.read_recordings(tmp_path / "recording.h5").values():
        assert run.attrs["playback_speed"] == kepler.speed
        assert run.attrs["playback_trail"] == kepler.trail > 0.0  # Kepler's ellipse is drawn
        assert run.static["system_color"].shape == (2, 3)


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["export", "--to", "mp4", "--speed", "1e308"], "less than 0.001 s"),
        (["export", "--to", "glb", "--speed", "1e-300"], "output frames"),
        (["view", "--speed", "1e308"], "less than 0.001 s"),
        (["view", "--speed", "1e-300"], ""),  # the viewer lowers its rate to fit, with a warning
        (["export", "--to", "gif", "--fps", "0.001"], "at least 0.0015"),
        (["export", "--to", "mp4", "--trail", "nan"], "`trail` must be finite"),
        # --fps 0 is refused as view and demo refuse it (it used to give a 30 fps video).
        (["export", "--to", "mp4", "--fps", "0"], "`fps` must be"),
        (["export", "--to", "gif", "--fps", "0"], "`fps` must be"),
        (["view", "--fps", "0"], "`fps` must be"),
    ],
)
def test_playback_numbers_at_the_edge_of_a_float(monkeypatch, capsys, tmp_path, args, fragment):
    path = _recording(tmp_path, particle_position=np.zeros((5, 2, 3)))
    command, *options = args
    status, _, err = run_main(monkeypatch, capsys, command, path, *options)
    assert "Traceback" not in err
    if fragment:
        assert status == 2 and fragment in err, err
    else:
        assert status == 0, err


def test_full_is_refused_by_a_demo_without_a_long_version(monkeypatch, capsys, tmp_path):
    status, _, err = run_main(monkeypatch, capsys, "demo", "pendulum", "--full", "-o", tmp_path)
    assert status == 2 and "demo 'pendulum' has no long version" in err
    assert not any(tmp_path.iterdir())


def test_fps_zero_is_refused_by_demo_as_by_export_and_view(monkeypatch, capsys, tmp_path):
    status, _, err = run_main(
        monkeypatch, capsys, "demo", "kepler", "-f", "mp4", "--fps", "0", "-o", tmp_path / "k"
    )
    assert status == 2 and "`fps` must be" in err and not (tmp_path / "k").exists()
