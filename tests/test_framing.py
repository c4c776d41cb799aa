"""What videos and the viewer show: a scene's camera, --camera and --frame, and framings that
keep every body and particle of the example scenes in the picture for the whole run."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from test_cli import run_main
from visviva.errors import ModelError
from visviva.viz.framing import chosen_camera, framed_bounds, parse_camera
from visviva.viz.outputs import playback

EXAMPLES = Path(__file__).parents[1] / "examples" / "scenes"


def in_picture(camera: vv.viz.video.Camera, points: np.ndarray, aspect: float) -> np.ndarray:
    """Whether each point ``(..., 3)`` [m] projects inside a picture of ``aspect`` seen by
    ``camera``: in front of it, within the half-angles tan(fov/2) up and aspect·tan(fov/2)
    across (the pinhole model the renderer uses)."""
    eye = np.array(camera.eye)
    forward = np.subtract(camera.target, eye)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = points - eye
    depth = d @ forward
    half = math.tan(math.radians(camera.field_of_view) / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        across = np.abs(d @ right) / (depth * half * aspect)
        upward = np.abs(d @ up) / (depth * half)
    return (depth > 0) & (across <= 1.0) & (upward <= 1.0)


def drawn_points(recording: vv.Recording) -> np.ndarray:
    """Every live point and every body vertex of every frame, ``(n, 3)`` [m]."""
    geometry = recording.geometry()
    found = []
    if geometry.points.shape[1]:
        live = (
            np.ones(geometry.points.shape[:2], bool) if geometry.alive is None else geometry.alive
        )
        found.append(geometry.points[live])
    if geometry.bodies is not None:
        found += [geometry.bodies.world_vertices(k) for k in range(recording.frames)]
    return np.concatenate(found)


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("target=1,2,3", "give eye"),
        ("eye=1,2", "eye takes 3"),
        ("eye=1,2,3 target=0,0", "target takes 3"),
        ("eye=1,2,3 target=a,b,c", "numbers separated by commas"),
        ("eye=1,2,3 target=0,0,0 fob=40", "Did you mean 'fov'"),
        ("eye=0,0,0 target=0,0,0", "must differ"),
        ("eye=1,2,3 target=0,0,0 fov=180", "below 180"),
    ],
)
def test_a_bad_camera_is_refused_naming_what_is_wrong(text, fragment):
    with pytest.raises(ModelError, match=fragment):
        parse_camera(text)


def test_the_scene_camera_is_kept_with_the_recording_and_replaced_from_the_cli(
    tmp_path, monkeypatch, capsys
):
    # spinning_bodies.toml sets [output] camera: the recording keeps it for later outputs.
    out = tmp_path / "out"
    status, _, err = run_main(
        monkeypatch, capsys, "run", EXAMPLES / "spinning_bodies.toml", "-o", out,
        "--duration", "0.3", "-f", "html",
    )  # fmt: skip
    assert status == 0, err
    recording = vv.io.load_recording(out / "recording.h5")
    kept = playback(recording, None, None).camera
    assert kept is not None and kept.eye == (0.0, 0.8, 2.1) and kept.field_of_view == 40.0
    # The viewer's first view is that camera: its distance and target.
    page = (out / "viewer.html").read_text()
    view = json.loads(page.split('"view":', 1)[1].split("}", 1)[0] + "}")
    assert view["target"] == [0.0, 0.45, 0.0]
    assert view["distance"] == pytest.approx(math.hypot(0.35, 2.1))
    # --frame replaces the kept camera with a framing of one body; --camera with another view.
    assert playback(recording, None, None, frame="bottle").camera is None
    assert playback(recording, None, None, camera="eye=0,5,5 target=0,0,0").camera.eye == (
        0.0, 5.0, 5.0,
    )  # fmt: skip
    for bad, fragment in (("--frame", "'brik' is neither 'all' nor"), ("--camera", "give")):
        value = "brik" if bad == "--frame" else "eye=1,1,1"
        status, _, err = run_main(
            monkeypatch, capsys, "export", out / "recording.h5", "--to", "mp4", bad, value
        )
        assert status == 2 and fragment in err, err
    status, _, err = run_main(
        monkeypatch, capsys, "run", EXAMPLES / "spinning_bodies.toml", "-o", tmp_path / "x",
        "--frame", "brik",
    )  # fmt: skip
    assert status == 2 and "Did you mean 'brick'" in err and not (tmp_path / "x").exists()


def test_framing_one_body_keeps_that_body_and_not_the_rest(tmp_path):
    builder = vv.SceneBuilder(name="two")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=500.0, name="near", position=(0, 1, 0))
    builder.add_body("sphere", radius=0.1, density=500.0, name="far", position=(30, 1, 0),
                     velocity=(0, 5, 0))  # fmt: skip
    recording = vv.Simulation(builder.build()).record(until=1.0)
    geometry = recording.geometry()
    low, high = framed_bounds(geometry, "near")
    assert np.all(high - low < 6.0)  # the box's fall alone: 4.9 m, not the 30 m between them
    camera = chosen_camera(geometry, None, "near", 16 / 9)
    split = geometry.bodies.vertex_start[1]  # the box's vertices, then the ball's
    frames = [geometry.bodies.world_vertices(k) for k in range(recording.frames)]
    box = np.concatenate([vertices[:split] for vertices in frames])
    assert in_picture(camera, box, 16 / 9).all()
    ball = np.concatenate([vertices[split:] for vertices in frames])
    assert not in_picture(camera, ball, 16 / 9).any()


@pytest.mark.parametrize("name", ["spinning_bodies", "falling_particles", "ball_pit"])
def test_every_body_and_particle_of_an_example_scene_stays_in_the_picture(tmp_path, name):
    """The scene's camera or framing, over the whole run: nothing drawn leaves the video."""
    model = vv.load_model(EXAMPLES / f"{name}.toml")
    recording = vv.Simulation(model).record(until=model.integration.duration)
    view = playback(recording, None, None)
    camera = chosen_camera(recording.geometry(), view.camera, view.frame, 960 / 540)
    points = drawn_points(recording)
    inside = in_picture(camera, points, 960 / 540)
    assert inside.all(), f"{(~inside).sum()} of {inside.size} points leave the picture"


def test_labels_name_each_body_above_it():
    from visviva.viz.frame import FramePainter

    builder = vv.SceneBuilder(name="named")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    builder.add_body("box", size=(0.3, 0.3, 0.3), density=500.0, name="left", position=(-1, 0, 0))
    builder.add_body("box", size=(0.3, 0.3, 0.3), density=500.0, name="right", position=(1, 0, 0))
    recording = vv.Simulation(builder.build()).record(until=0.01)
    geometry = recording.geometry()
    camera = chosen_camera(geometry, None, "all", 16 / 9)
    plain, named = (
        FramePainter(geometry, (320, 180), camera, recording.time, labels=labels).paint(0, 0.0)
        for labels in (False, True)
    )
    changed = np.abs(named.astype(int) - plain.astype(int)).sum(axis=2) > 30
    _rows, columns = np.nonzero(changed[40:])  # below the time label in the corner
    # Two labels, one over each box: changed pixels left and right of the middle.
    assert (columns < 160).any() and (columns >= 160).any()


def test_a_followed_body_stays_at_the_centre_of_a_moving_view(tmp_path, monkeypatch, capsys):
    from visviva.viz.framing import following

    builder = vv.SceneBuilder(name="thrown")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=500.0, name="ball",
                     velocity=(3.0, 4.0, 0.0))  # fmt: skip
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=500.0, name="still",
                     position=(-1.0, 0.0, 0.0))  # fmt: skip
    recording = vv.Simulation(builder.build()).record(until=1.0)
    geometry = recording.geometry()
    camera_at = following(geometry, "ball", 16 / 9)
    first, last = camera_at(0), camera_at(recording.frames - 1)
    # The target is the box's centre in each frame (x = 3 t, y = 4 t − g t²/2), the eye keeps
    # its offset from it.
    t = recording.time[-1]
    np.testing.assert_allclose(last.target, (3.0 * t, 4.0 * t - 0.5 * 9.81 * t * t, 0.0), atol=0.05)
    np.testing.assert_allclose(
        np.subtract(last.eye, last.target), np.subtract(first.eye, first.target)
    )
    path = tmp_path / "thrown.h5"
    vv.io.write_recordings(path, {"thrown": recording})
    status, _, err = run_main(monkeypatch, capsys, "export", path, "--to", "gif", "--follow",
                              "ball", "--fps", "10", "-o", tmp_path / "f.gif")  # fmt: skip
    assert status == 0 and (tmp_path / "f.gif").stat().st_size > 1000, err
    status, _, err = run_main(monkeypatch, capsys, "view", path, "--follow", "bal")
    assert status == 2 and "Did you mean 'ball'" in err
    status, _, err = run_main(monkeypatch, capsys, "view", path, "--follow", "ball")
    assert status == 0, err
    page = (tmp_path / "viewer.html").read_text()
    assert '"follow":{"body":0' in page


def test_labels_travel_with_the_recording_to_later_exports():
    # `visviva export --to mp4` of a demo that names its bodies names them too: the
    # recording's playback_labels reaches the video through playback().
    recording = vv.Recording(np.arange(2.0), {"particle_position": np.zeros((2, 1, 3))})
    assert not playback(recording, None, None).labels
    recording.attrs["playback_labels"] = True
    assert playback(recording, None, None).labels
