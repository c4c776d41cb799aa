"""Points coloured by speed (``color_by = "speed"``): the colours, the scale, and every road to
them — Python, scene files, demos and the CLI's ``view`` / ``export``."""

from __future__ import annotations

import base64
import json
import re
import zlib

import numpy as np
import pytest
from matplotlib import colormaps
from PIL import Image

import visviva as vv
from visviva.errors import ModelError
from visviva.viz.speed_colors import TOP_PERCENTILE, colored_by_speed
from visviva.viz.video import render_video
from visviva.viz.viewer import write_viewer


def _viridis(fraction: np.ndarray) -> np.ndarray:
    """The colour the scale gives a speed at ``fraction`` of its top (256 levels, rounded
    down, as the module samples the map)."""
    level = np.minimum(np.floor(fraction * 255), 255) / 255
    return colormaps["viridis"](level)[..., :3]


def racing(frames: int = 20, count: int = 50) -> vv.Recording:
    """``count`` points on lines, point ``i`` at speed ``i`` m/s along x."""
    t = np.linspace(0.0, 1.0, frames)
    speed = np.arange(count, dtype=float)
    points = np.zeros((frames, count, 3))
    points[:, :, 0] = t[:, None] * speed
    points[:, :, 2] = np.arange(count)
    velocities = np.zeros_like(points)
    velocities[:, :, 0] = speed
    return vv.Recording(t, {"particle_position": points, "particle_velocity": velocities})


def test_each_point_takes_the_colour_of_its_speed_on_one_scale_for_the_clip():
    recording = racing()
    geometry, scale = colored_by_speed(recording, recording.geometry())
    speeds = np.arange(50.0)
    # The top of the scale is the 99.5th percentile of every live (frame, point) speed.
    assert scale.top == pytest.approx(np.percentile(np.tile(speeds, 20), TOP_PERCENTILE))
    assert geometry.color.shape == (20, 50, 3) and geometry.color.dtype == np.float32
    expected = _viridis(np.minimum(speeds / scale.top, 1.0))
    np.testing.assert_allclose(geometry.color[7], expected, atol=1e-6)
    np.testing.assert_array_equal(geometry.color[0], geometry.color[-1])  # speeds never change
    assert scale.caption() == f"speed 0 (purple) to {scale.top:.3g} m/s (yellow)"


def test_dead_points_do_not_stretch_the_scale_and_points_without_velocity_keep_colour():
    recording = racing(frames=4, count=3)
    fields = {
        "particle_position": recording["particle_position"][:, :2],
        "particle_velocity": recording["particle_velocity"][:, :2] * 1.0,
        "system_points": recording["particle_position"][:, 2:],  # the third point: a system's
        "particle_alive": np.array([[True, True]] * 3 + [[True, False]]),
    }
    fields["particle_velocity"][:, 1, 0] = [1.0, 1.0, 1.0, 1000.0]  # dead when it is fast
    colours = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    static = {"particle_color": colours[:2], "system_color": colours[2:]}
    recording = vv.Recording(recording.time, fields, static=static)
    geometry, scale = colored_by_speed(recording, recording.geometry())
    assert scale.top <= 1.0  # the 1000 m/s of a dead slot is not on the scale
    np.testing.assert_array_equal(geometry.color[:, 2], np.tile(colours[2], (4, 1)))


def test_a_still_scene_is_drawn_at_the_bottom_of_the_scale_not_divided_by_zero():
    t = np.linspace(0.0, 1.0, 3)
    still = {"particle_position": np.zeros((3, 2, 3)), "particle_velocity": np.zeros((3, 2, 3))}
    recording = vv.Recording(t, still)
    geometry, scale = colored_by_speed(recording, recording.geometry())
    assert scale.top == 1.0
    np.testing.assert_allclose(geometry.color, np.broadcast_to(_viridis(np.zeros(1)), (3, 2, 3)))


def test_the_video_draws_fast_points_yellow_and_labels_the_scale(tmp_path):
    recording = racing(frames=6, count=2)
    fields = dict(recording.fields)
    fields["particle_velocity"] = fields["particle_velocity"] * 1.0
    fields["particle_velocity"][:, 1, 0] = 10.0
    fields["particle_position"] = fields["particle_position"] * 0.0
    fields["particle_position"][:, 1, 0] = 2.0
    radius = {"particle_radius": np.array([0.4, 0.4])}
    recording = vv.Recording(recording.time, fields, static=radius)
    path = render_video(recording, tmp_path / "v.gif", fps=5, size=(160, 96), color_by="speed")
    image = np.asarray(Image.open(path).convert("RGB")).astype(int)
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    # viridis' top is yellow (0.99, 0.91, 0.14); its bottom dark purple (0.27, 0.00, 0.33).
    assert ((red > 150) & (green > 140) & (blue < 90)).sum() > 20
    assert ((blue > green + 30) & (red > green + 20)).sum() > 20  # the slow one, purple
    from visviva.viz.frame import FramePainter
    from visviva.viz.video import Camera

    geometry, scale = colored_by_speed(recording, recording.geometry())
    camera = Camera.framing((np.full(3, -1.0), np.full(3, 3.0)), aspect=1.0)
    painter = FramePainter(geometry, (64, 64), camera, recording.time, 0.0, scale.caption())
    assert painter.label(0.0).endswith("speed 0 (purple) to 10 m/s (yellow)")


def _payload(page) -> dict:
    text = page.read_text(encoding="utf-8")
    return json.loads(re.search(r'id="visviva-data"[^>]*>(.*?)</script>', text, re.S).group(1))


def test_the_viewer_embeds_colours_per_frame_and_the_scale_in_its_legend(tmp_path):
    page = write_viewer(racing(), tmp_path / "v.html", fps=19.0, color_by="speed")
    data = _payload(page)
    top = np.percentile(np.tile(np.arange(50.0), 20), TOP_PERCENTILE)
    assert ["colour", f"speed 0 (purple) to {top:.3g} m/s (yellow)"] in data["legend"]
    layer = data["layers"]["points"]
    # zlib-compressed 8-bit frame differences: the first frame is its own difference from 0.
    packed = zlib.decompress(base64.b64decode(layer["frame_colors"]))
    first = np.frombuffer(packed, np.uint8)[: 50 * 3]
    expected = np.round(255 * _viridis(np.minimum(np.arange(50.0) / top, 1.0)))
    np.testing.assert_allclose(first.reshape(50, 3), expected, atol=1)
    plain = _payload(write_viewer(racing(), tmp_path / "plain.html", fps=19.0))
    assert "frame_colors" not in plain["layers"]["points"]


@pytest.mark.parametrize("mode", ["fast", 1, None])
def test_an_unknown_mode_is_refused_before_anything_is_written(tmp_path, mode):
    for write, name in ((render_video, "v.gif"), (write_viewer, "v.html")):
        with pytest.raises(ModelError, match="`color_by` must be one of 'scene', 'speed'"):
            write(racing(), tmp_path / name, fps=10, color_by=mode)
        assert not (tmp_path / name).exists()


def test_a_recording_without_velocities_is_refused_with_the_way_out(tmp_path):
    recording = vv.Recording(np.linspace(0, 1, 3), {"particle_position": np.zeros((3, 2, 3))})
    with pytest.raises(
        ModelError, match=r"needs the velocities of the drawn points.*color_by = \""
    ):
        write_viewer(recording, tmp_path / "v.html", color_by="speed")
    assert not (tmp_path / "v.html").exists()


def test_a_scene_asks_for_it_and_later_exports_remember_it(tmp_path, monkeypatch, capsys):
    from typer.testing import CliRunner

    from visviva.cli.main import app

    scene = tmp_path / "gas.toml"
    scene.write_text(
        """
[integration]
dt = 0.01
duration = 0.2
[output]
formats = ["html"]
color_by = "speed"
[[entities]]
type = "particle_cloud"
count = 40
velocity_jitter = 2.0
"""
    )
    runner = CliRunner()
    result = runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert any(row[0] == "colour" for row in _payload(tmp_path / "out" / "viewer.html")["legend"])
    recording = vv.io.load_recording(tmp_path / "out" / "recording.h5")
    assert recording.attrs["playback_color_by"] == "speed"
    view = runner.invoke(
        app, ["view", str(tmp_path / "out" / "recording.h5"), "-o", str(tmp_path / "again.html")]
    )
    assert view.exit_code == 0, view.output
    assert any(row[0] == "colour" for row in _payload(tmp_path / "again.html")["legend"])
    plain = runner.invoke(
        app,
        [
            "view",
            str(tmp_path / "out" / "recording.h5"),
            "--color-by",
            "scene",
            "-o",
            str(tmp_path / "plain.html"),
        ],
    )
    assert plain.exit_code == 0, plain.output
    assert not any(row[0] == "colour" for row in _payload(tmp_path / "plain.html")["legend"])
    from test_cli import assert_user_error, run_main

    target = tmp_path / "hue.html"
    status, _, stderr = run_main(
        monkeypatch, capsys, "view", tmp_path / "out" / "recording.h5", "--color-by", "hue",
        "-o", target,
    )  # fmt: skip
    assert_user_error(status, stderr, "`color_by` must be one of 'scene', 'speed'", "'hue'")
    assert not target.exists()
