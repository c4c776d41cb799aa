"""Videos: frames read back from mp4 and GIF files, measured in pixels."""

import math
from pathlib import Path

import imageio.v2 as imageio_v2
import imageio.v3 as iio
import numpy as np
import pytest
from PIL import Image

import visviva as vv
from visviva.io.timeline import frames_at_rate
from visviva.viz import frame as frame_module
from visviva.viz.frame import drawn_bounds
from visviva.viz.video import Camera, render_video

SIZE = (160, 96)
FPS = 25.0
RADIUS = 0.25


def falling_and_resting() -> vv.Recording:
    """40 frames at 25 Hz: sphere 0 falls from 1.8 m to 0.34 m, sphere 1 rests on the ground."""
    t = np.arange(40) / FPS
    points = np.zeros((40, 2, 3))
    points[:, 0, 0], points[:, 1, 0] = -0.6, 0.6
    points[:, 0, 1] = 1.8 - 0.6 * t**2
    points[:, 1, 1] = RADIUS
    return vv.Recording(
        t,
        {"particle_position": points},
        static={"particle_radius": np.full(2, RADIUS)},
        units={"particle_position": "m"},
    )


def project(camera: Camera, points: np.ndarray, size=SIZE) -> np.ndarray:
    """Pixel (x, y) of world points through a pinhole camera, derived independently."""
    eye, target = np.array(camera.eye), np.array(camera.target)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    focal = 0.5 * size[1] / math.tan(math.radians(camera.field_of_view) / 2)
    d = np.atleast_2d(points) - eye
    depth = d @ forward
    return np.stack(
        [size[0] / 2 + focal * (d @ right) / depth, size[1] / 2 - focal * (d @ up) / depth], 1
    )


def read_frames(path: Path) -> np.ndarray:
    if path.suffix == ".gif":
        return iio.imread(path, plugin="pillow", mode="RGB", index=None)
    with imageio_v2.get_reader(path, format="FFMPEG") as reader:
        return np.stack([np.asarray(f) for f in reader])


def sphere_mask(image: np.ndarray) -> np.ndarray:
    """Pixels of the blue spheres, lit or in shade: saturated blue, darker than the sky."""
    r, b = image[..., 0].astype(float), image[..., 2].astype(float)
    return (b - r > 0.45 * b) & (b > 25.0) & (r < 110.0)


def centroid(mask: np.ndarray) -> np.ndarray:
    rows, columns = np.nonzero(mask)
    return np.array([columns.mean() + 0.5, rows.mean() + 0.5])


@pytest.fixture(scope="module")
def videos(tmp_path_factory) -> dict[str, np.ndarray]:
    folder = tmp_path_factory.mktemp("videos")
    recording = falling_and_resting()
    out = {}
    for suffix in ("mp4", "gif"):
        path = render_video(recording, folder / f"drop.{suffix}", fps=FPS, size=SIZE)
        assert path == folder / f"drop.{suffix}"
        out[suffix] = read_frames(path)
    out["gif_path"] = folder / "drop.gif"
    return out


@pytest.mark.parametrize("suffix", ["mp4", "gif"])
def test_frame_count_and_size(videos, suffix):
    expected = len(frames_at_rate(falling_and_resting().time, FPS))
    assert expected == 40
    assert videos[suffix].shape == (expected, SIZE[1], SIZE[0], 3)


@pytest.mark.parametrize("suffix", ["mp4", "gif"])
def test_spheres_are_where_the_camera_puts_them(videos, suffix):
    recording = falling_and_resting()
    camera = Camera.framing(drawn_bounds(recording.geometry()), aspect=SIZE[0] / SIZE[1])
    found, expected = {}, {}
    for k in (0, -1):
        expected[k] = project(camera, recording["particle_position"][k])
        mask = sphere_mask(videos[suffix][k])
        split = int(expected[k][:, 0].mean())  # a column between the two spheres
        left, right = mask.copy(), mask.copy()
        left[:, split:], right[:, :split] = False, False
        found[k] = [centroid(left), centroid(right)]
        # Each blob's centroid is the projected centre to within 0.75 px (measured: < 0.25).
        for i in (0, 1):
            assert np.linalg.norm(found[k][i] - expected[k][i]) < 0.75, (k, i, found[k][i])
        # Perspective size: the resting sphere covers π·(f·r/d)² pixels, to within 10 %.
        focal = 0.5 * SIZE[1] / math.tan(math.radians(camera.field_of_view) / 2)
        distance = np.linalg.norm(np.subtract(camera.eye, recording["particle_position"][k, 1]))
        assert right.sum() == pytest.approx(math.pi * (focal * RADIUS / distance) ** 2, rel=0.1)
    # The falling sphere moved down the picture (rows grow downwards) by tens of pixels ...
    assert found[-1][0][1] - found[0][0][1] > 25.0
    # ... and the resting one stayed put.
    assert np.linalg.norm(found[-1][1] - found[0][1]) < 2.0


@pytest.mark.parametrize("suffix", ["mp4", "gif"])
def test_first_and_last_frames_differ_only_where_things_moved(videos, suffix):
    recording = falling_and_resting()
    camera = Camera.framing(drawn_bounds(recording.geometry()), aspect=SIZE[0] / SIZE[1])
    first, last = (videos[suffix][k].astype(float) for k in (0, -1))
    x, y = project(camera, recording["particle_position"][0, 0])[0].astype(int)
    moved = np.abs(first - last)[y - 3 : y + 4, x - 3 : x + 4].mean()
    corner = np.abs(first - last)[-12:, :12].mean()  # bottom-left: ground, far from all
    assert moved > 60.0
    assert corner < 2.0


@pytest.mark.parametrize("suffix", ["mp4", "gif"])
def test_ground_is_checkered_and_not_the_sky(videos, suffix):
    image = videos[suffix][0].astype(float)
    sky = image[:3, SIZE[0] // 2 :].reshape(-1, 3).mean(axis=0)  # top rows, right of the label
    ground = image[-20:, :40]
    assert np.abs(ground.reshape(-1, 3).mean(axis=0) - sky).max() > 20.0
    assert ground.mean(axis=2).std() > 3.0  # the checker: two tones, not one flat colour


def test_gif_delays_keep_time(videos):
    # Delays are whole hundredths of a second; at 25 fps each is 4, summing to 40/25 s.
    with Image.open(videos["gif_path"]) as gif:
        delays = []
        for k in range(gif.n_frames):
            gif.seek(k)
            delays.append(gif.info["duration"])
    assert delays == [40] * 40


def test_gif_at_30_fps_alternates_delays_and_repeated_frames_merge(tmp_path):
    # 10 recorded frames at 10 Hz shown at 30 fps: each recorded frame is shown 3 times
    # (2 for the last); Pillow stores a repeated frame once with the delays added.
    t = np.arange(10) / 10.0
    points = np.zeros((10, 1, 3))
    points[:, 0, 1] = 1.0 - 0.5 * t
    recording = vv.Recording(
        t, {"particle_position": points}, static={"particle_radius": np.array([0.2])}
    )
    path = render_video(recording, tmp_path / "slow.gif", fps=30.0, size=(64, 48))
    shown = frames_at_rate(t, 30.0)
    with Image.open(path) as gif:
        delays = []
        for k in range(gif.n_frames):
            gif.seek(k)
            delays.append(gif.info["duration"])
    assert len(shown) == 28
    assert gif.n_frames == 10
    assert sum(delays) == 930  # round(100 · 28 / 30) hundredths of a second, as 10 ms


def test_edges_are_drawn_as_dark_lines(tmp_path):
    # A square of four points, one edge per side, no radii: the midpoint of each edge is dark.
    square = np.array([[-1.0, 1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]])
    points = np.repeat(square[None], 3, axis=0)
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    recording = vv.Recording(
        np.arange(3) / 10.0, {"particle_position": points}, static={"edges": edges}
    )
    path = render_video(recording, tmp_path / "square.mp4", fps=10.0, size=(320, 192))
    image = read_frames(path)[0].astype(float)
    camera = Camera.framing(drawn_bounds(recording.geometry()), aspect=320 / 192)
    middles = project(camera, 0.5 * (square + np.roll(square, -1, axis=0)), size=(320, 192))
    for x, y in middles.astype(int):
        darkest = image[y - 1 : y + 2, x - 1 : x + 2].mean(axis=2).min()
        assert darkest < 110.0  # the ground around is ~190
    assert image[-10:, :10].mean() > 150.0


@pytest.mark.parametrize(("order", "side"), [([0, 1, 2], "front"), ([0, 2, 1], "back")])
def test_faces_show_their_front_and_back_colours(tmp_path, order, side):
    # One horizontal triangle seen from above: counter-clockwise seen from +Y is the front.
    corners = np.array([[-1.0, 0.5, 1.0], [1.0, 0.5, 1.0], [0.0, 0.5, -1.0]])
    points = np.repeat(corners[None], 2, axis=0)
    recording = vv.Recording(
        np.array([0.0, 0.1]), {"particle_position": points}, static={"faces": np.array([order])}
    )
    path = render_video(recording, tmp_path / "triangle.gif", fps=10.0, size=(160, 96))
    image = read_frames(path)[0].astype(float)
    camera = Camera.framing(drawn_bounds(recording.geometry()), aspect=160 / 96)
    x, y = project(camera, corners.mean(axis=0))[0].astype(int)
    r, g, b = image[y - 2 : y + 3, x - 2 : x + 3].reshape(-1, 3).mean(axis=0)
    if side == "front":  # the web viewer's orange, lit from above
        assert r - b > 100.0 and r > g > b
    else:  # the grey-brown back side
        assert abs(r - b) < 40.0


def test_default_camera_keeps_every_corner_in_view():
    low, high = np.array([-3.0, 0.0, -1.0]), np.array([2.0, 5.0, 0.5])
    camera = Camera.framing((low, high), aspect=16 / 9)
    corners = np.array(
        [[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])]
    )
    pixels = project(camera, corners, size=(960, 540))
    assert (pixels[:, 0] > 0).all() and (pixels[:, 0] < 960).all()
    assert (pixels[:, 1] > 0).all() and (pixels[:, 1] < 540).all()
    # Tight: the box fills at least 80 % of the picture in one direction.
    spread = (pixels.max(axis=0) - pixels.min(axis=0)) / [960, 540]
    assert spread.max() > 0.8
    # Raised three-quarter view, Y up: the eye is above the target, off both X and Z axes.
    offset = np.subtract(camera.eye, camera.target)
    assert offset[1] > 0 and offset[0] > 0 and offset[2] > 0
    assert camera.up == (0.0, 1.0, 0.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"eye": (0, 0, 0), "target": (0, 0, 0)}, "must differ"),
        ({"eye": (0, 1, 0), "target": (0, 0, 0)}, "parallel"),
        ({"eye": (0, 0, 1), "target": (0, 0, 0), "field_of_view": 180}, "below 180"),
        ({"eye": (0, 0, float("nan")), "target": (0, 0, 0)}, "three finite numbers"),
    ],
)
def test_bad_cameras(kwargs, message):
    with pytest.raises(vv.ModelError, match=message):
        Camera(**kwargs)


def no_points() -> vv.Recording:
    return vv.Recording(np.arange(3) / 10.0, {"q": np.zeros((3, 2))})


@pytest.mark.parametrize(
    ("name", "recording", "kwargs", "message"),
    [
        ("drop.avi", falling_and_resting, {}, r"`path` must end in \.mp4 or \.gif"),
        ("drop.mp4", no_points, {}, "no `particle_position` or `system_points` field"),
        ("drop.mp4", falling_and_resting, {"fps": 0.0}, "`fps` must be positive"),
        ("drop.gif", falling_and_resting, {"fps": -5}, "`fps` must be positive"),
        ("drop.gif", falling_and_resting, {"fps": 60.0}, "at most 50"),
        ("drop.mp4", falling_and_resting, {"size": (0, 96)}, "`size` must be positive"),
        ("drop.gif", falling_and_resting, {"size": (160, -2)}, "`size` must be positive"),
        ("drop.mp4", falling_and_resting, {"size": (161, 96)}, r"even.*\(162, 96\)"),
        ("drop.mp4", falling_and_resting, {"size": (160.0, 96)}, "two whole numbers"),
        ("drop.mp4", falling_and_resting, {"camera": "front"}, "`camera` must be"),
    ],
)
def test_bad_input_is_refused_before_writing(tmp_path, name, recording, kwargs, message):
    with pytest.raises(vv.ModelError, match=message):
        render_video(recording(), tmp_path / name, **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_non_finite_points_and_missing_directory(tmp_path):
    recording = falling_and_resting()
    recording.fields["particle_position"][7, 1, 2] = np.nan
    with pytest.raises(vv.ModelError, match="frame 7, point 1"):
        render_video(recording, tmp_path / "drop.mp4")
    with pytest.raises(vv.ModelError, match="does not exist"):
        render_video(falling_and_resting(), tmp_path / "missing" / "drop.mp4")
    assert list(tmp_path.iterdir()) == []


def test_a_failure_while_rendering_leaves_no_file(tmp_path, monkeypatch):
    calls = []

    def failing_paint(self, index, time):
        calls.append(index)
        if len(calls) > 3:
            raise RuntimeError("disk full")
        return np.zeros((self.height, self.width, 3), dtype=np.uint8)

    monkeypatch.setattr(frame_module.FramePainter, "paint", failing_paint)
    with pytest.raises(RuntimeError, match="disk full"):
        render_video(falling_and_resting(), tmp_path / "drop.mp4", size=SIZE)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("suffix", ["mp4", "gif"])
def test_a_still_and_an_empty_scene_render(tmp_path, suffix):
    # One frame of one point without a radius (a scene of no size), and points of no count.
    still = vv.Recording(np.array([0.0]), {"particle_position": np.zeros((1, 1, 3))})
    frames = read_frames(render_video(still, tmp_path / f"still.{suffix}", size=(64, 48)))
    assert frames.shape == (1, 48, 64, 3)
    assert sphere_mask(frames[0]).sum() > 50  # the default camera frames the lone sphere
    empty = vv.Recording(np.arange(3) / 30.0, {"particle_position": np.zeros((3, 0, 3))})
    frames = read_frames(render_video(empty, tmp_path / f"empty.{suffix}", size=(64, 48)))
    assert len(frames) == 3 and sphere_mask(frames[0]).sum() == 0


# Legible pictures: colours and display sizes per point, trails, time in the unit that reads.


def _orbit(frames: int = 121, *, span: float = 365.25 * 86_400.0) -> vv.Recording:
    """A 'sun' at rest and a 'planet' circling it once in the x–z plane over ``span`` [s]."""
    t = np.linspace(0.0, span, frames)
    angle = 2.0 * np.pi * t / span
    points = np.zeros((frames, 2, 3))
    points[:, 1, 0], points[:, 1, 2] = np.cos(angle), -np.sin(angle)
    return vv.Recording(
        t,
        {"particle_position": points},
        static={
            "particle_color": np.array([[1.0, 0.78, 0.18], [0.16, 0.42, 0.86]]),
            "display_radius": np.array([0.15, 0.06]),
        },
    )


def _painter(recording, trail=0.0, size=(320, 180)):
    from visviva.viz.frame import FramePainter, drawn_bounds
    from visviva.viz.video import Camera

    geometry = recording.geometry()
    camera = Camera.framing(drawn_bounds(geometry), aspect=size[0] / size[1])
    return FramePainter(geometry, size, camera, recording.time, trail)


def test_points_are_drawn_in_their_colours_at_their_display_radii():
    image = _painter(_orbit()).paint(0, 0.0).astype(int)
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    yellow = (red > 150) & (green > 100) & (blue < 90)  # the sun, shaded
    planet = (blue - red > 60) & (blue > 110)
    assert yellow.sum() > 2 * planet.sum() > 0  # display radii 0.15 and 0.06: the sun is larger
    cols = np.nonzero(yellow)[1]
    assert abs(cols.mean() - np.nonzero(planet)[1].mean()) > 20  # apart, not one on the other


def test_the_label_says_when_sizes_are_not_to_scale_and_picks_a_readable_unit():
    orbit = _orbit()
    assert _painter(orbit).label(182.625 * 86_400.0) == "t = 182.6 days, sizes not to scale"
    recording = vv.Recording(
        np.linspace(0.0, 2.0, 3),
        {"particle_position": np.zeros((3, 1, 3))},
        static={"particle_radius": [0.1]},
    )
    assert _painter(recording).label(1.5) == "t = 1.500 s"
    from visviva.viz.timescale import format_time

    assert format_time(90.0, 600.0) == "t = 1.50 min"
    assert format_time(7200.0, 86_400.0) == "t = 2.00 h"
    assert format_time(3.0 * 365.25 * 86_400.0, 10 * 365.25 * 86_400.0) == "t = 3.00 years"


def test_trails_draw_the_path_behind_each_point():
    """After three quarters of the orbit with a trail of one orbit, pixels along the planet's
    past path differ from the picture without trail; none differ without a trail."""
    orbit = _orbit()
    span = float(orbit.time[-1])
    plain = _painter(orbit).paint(90, float(orbit.time[90])).astype(int)
    trailed = _painter(orbit, trail=span).paint(90, float(orbit.time[90])).astype(int)
    changed = np.abs(trailed - plain).sum(axis=2) > 30
    assert changed.sum() > 100  # a line along three quarters of a circle
    cols = np.nonzero(changed)[1]
    assert cols.max() - cols.min() > 100  # it spans the picture, not one spot
    again = _painter(orbit).paint(90, float(orbit.time[90])).astype(int)
    assert np.array_equal(again, plain)


def test_trails_are_refused_for_many_points(tmp_path):
    recording = vv.Recording(np.arange(3.0), {"particle_position": np.zeros((3, 1001, 3))})
    with pytest.raises(vv.ModelError, match="at most 1000 points"):
        vv.viz.video.render_video(recording, tmp_path / "a.gif", fps=1.0, trail=1.0)
    assert list(tmp_path.iterdir()) == []
