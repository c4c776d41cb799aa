"""The single-file web viewer, opened from ``file://`` in real headless Chromium.

One Chromium (Debian's ``/usr/bin/chromium``, driven by Playwright, SwiftShader WebGL) serves
every test of this module. Without it the tests fail: CI installs it (``.ci/run``).
"""

from __future__ import annotations

import base64
import io
import math
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image
from playwright.sync_api import Browser, Page, sync_playwright

import visviva as vv
from visviva.io.timeline import frames_at_rate
from visviva.viz.viewer import MAX_POSITION_BYTES, default_fps, write_viewer

CHROMIUM = Path("/usr/bin/chromium")
#: From NOTES.md ("Files, formats, viewers"); Playwright makes its own temporary profile
#: (it refuses --user-data-dir in launch()).
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-quic",
]
#: The page's background colour, #eef1f5.
BACKGROUND = (238, 241, 245)


def falling_recording() -> vv.Recording:
    """Three points 1 m apart, dropped from 2 m: y = 2 − g t²/2, 50 frames at 25 Hz."""
    t = np.arange(50) / 25.0
    points = np.zeros((50, 3, 3))
    points[:, :, 0] = [0.0, 1.0, 2.0]
    points[:, :, 1] = 2.0 - 4.9 * t[:, None] ** 2
    return vv.Recording(
        t,
        {"particle_position": points},
        static={"particle_radius": np.full(3, 0.1), "edges": np.array([[0, 1], [1, 2]])},
        units={"particle_position": "m", "particle_radius": "m"},
        attrs={"method": "velocity_verlet", "dt": 0.01, "substeps": 4},
    )


def waving_cloth(n: int = 64, frames: int = 300) -> vv.Recording:
    """An n×n grid, 1 m square, waving in y: 300 frames at 30 Hz, 2(n−1)² triangles."""
    u, w = np.meshgrid(np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, n), indexing="ij")
    t = np.arange(frames) / 30.0
    points = np.empty((frames, n * n, 3))
    points[:, :, 0] = u.ravel()
    points[:, :, 1] = 1.0 + 0.1 * np.sin(2.0 * np.pi * (u.ravel()[None, :] - t[:, None]))
    points[:, :, 2] = w.ravel()
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + n], 1), np.stack([a + 1, a + n + 1, a + n], 1)])
    return vv.Recording(
        t, {"particle_position": points}, static={"faces": faces}, units={"particle_position": "m"}
    )


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    if not CHROMIUM.is_file():
        pytest.fail(
            f"the viewer tests need Debian's Chromium at {CHROMIUM} (not found); install it "
            "with `sudo apt-get install -y chromium` (.ci/run does this)",
            pytrace=False,
        )
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        yield chromium
        chromium.close()


@pytest.fixture(scope="module")
def falling_page_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_viewer(falling_recording(), tmp_path_factory.mktemp("viewer") / "falling.html")


class Opened:
    """A page opened on a viewer file, with everything it logged and requested."""

    def __init__(self, browser: Browser, path: Path, *, before: str | None = None) -> None:
        self.page: Page = browser.new_page(viewport={"width": 800, "height": 600})
        if before is not None:
            self.page.add_init_script(before)
        self.errors: list[str] = []
        self.requests: list[str] = []
        self.page.on(
            "console",
            lambda message: self.errors.append(message.text) if message.type == "error" else None,
        )
        self.page.on("pageerror", lambda error: self.errors.append(str(error)))
        self.page.on("request", lambda request: self.requests.append(request.url))
        self.page.goto(path.as_uri())
        self.page.wait_for_function("window.visviva && window.visviva.ready === true")

    def js(self, expression: str) -> Any:
        return self.page.evaluate(expression)

    def image(self, frame: int) -> np.ndarray:
        """The canvas after showing ``frame``: RGB array (height, width, 3)."""
        url = self.js(
            f"visviva.pause(), visviva.setFrame({frame}), "
            "document.getElementById('view').toDataURL('image/png')"
        )
        png = base64.b64decode(url.split(",", 1)[1])
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int16)


@pytest.fixture
def falling(browser: Browser, falling_page_path: Path) -> Iterator[Opened]:
    opened = Opened(browser, falling_page_path)
    yield opened
    opened.page.close()


def test_page_loads_from_file_with_no_error_and_no_other_request(falling, falling_page_path):
    falling.js("visviva.play()")
    falling.page.wait_for_timeout(300)
    falling.page.mouse.move(400, 300)
    falling.page.mouse.wheel(0, -200)
    assert falling.errors == []
    assert falling.requests == [falling_page_path.as_uri()]
    html = falling_page_path.read_text(encoding="utf-8")
    assert "<script src" not in html and "<link" not in html


def test_embedded_frames_are_the_recording_resampled(falling):
    recording = falling_recording()
    shown = frames_at_rate(recording.time, 25.0)
    assert falling.js("[visviva.frames, visviva.fps]") == [50, 25]
    np.testing.assert_array_equal(falling.js("visviva.times"), recording.time[shown])
    for k in (0, 17, 49):
        points = np.array(falling.js(f"visviva.points({k})")).reshape(3, 3)
        assert_quantized(
            points, recording["particle_position"][shown[k]], recording["particle_position"][shown]
        )
    assert falling.js("document.getElementById('legend').textContent").count("velocity_verlet")


def test_base64_fallback_for_browsers_without_uint8array_frombase64(browser, falling_page_path):
    # Uint8Array.fromBase64 is recent (Chromium 140); older browsers decode through atob.
    opened = Opened(browser, falling_page_path, before="delete Uint8Array.fromBase64")
    try:
        assert opened.errors == []
        assert opened.js("typeof Uint8Array.fromBase64") == "undefined"
        recording = falling_recording()
        np.testing.assert_array_equal(opened.js("visviva.times"), recording.time)
        points = np.array(opened.js("visviva.points(49)")).reshape(3, 3)
        assert_quantized(points, recording["particle_position"][49], recording["particle_position"])
    finally:
        opened.page.close()


def assert_quantized(decoded: np.ndarray, exact: np.ndarray, every_frame: np.ndarray) -> None:
    """The page's positions are the recording's to half a quantization step per axis, the
    step being the points' extent over 65535 (plus float32 rounding of the result)."""
    flat = every_frame.reshape(-1, 3)
    half_step = 0.5 * (flat.max(axis=0) - flat.min(axis=0)) / 65535
    rounding = np.finfo(np.float32).eps * np.abs(exact)
    assert np.all(np.abs(decoded - exact) <= half_step * (1 + 1e-9) + rounding)


def _blue(image: np.ndarray) -> np.ndarray:
    """Mask of the points' blue (#2f6fb3, shaded): not the grey grid or background."""
    red, blue = image[..., 0], image[..., 2]
    return (blue - red) > 60


def test_first_and_last_frames_draw_the_points_where_they_are(falling):
    first, last = falling.image(0), falling.image(49)
    assert falling.js("visviva.frame()") == 49
    drawn = np.any(first != BACKGROUND, axis=2)
    assert drawn.sum() > 2000  # grid, spheres and lines
    blue_first, blue_last = _blue(first), _blue(last)
    assert blue_first.sum() > 30 and blue_last.sum() > 10
    # The points fell 18.8 m (the scene is ~19 m tall): on screen they moved down, a lot.
    rows_first = np.nonzero(blue_first)[0].mean()
    rows_last = np.nonzero(blue_last)[0].mean()
    assert rows_last - rows_first > 0.3 * first.shape[0]
    # Where the points were in frame 0 the image changed: they are no longer drawn there.
    changed = np.any(first != last, axis=2)
    assert changed[blue_first].mean() > 0.95
    assert not blue_last[blue_first].any()


#: The viewer's clock and frame as its next redraw sets them: an animation-frame callback runs
#: after the viewer's own in the same redraw, with the same timestamp. (Read between redraws, the
#: frame lags the clock by as much as a redraw is late, which a busy machine makes long.)
AT_NEXT_REDRAW = (
    "new Promise((done) => requestAnimationFrame((now) => done([now, visviva.frame()])))"
)


def test_play_pause_button_space_bar_and_speed(falling):
    page = falling.page
    assert falling.js("visviva.playing()") is True  # an opened animation plays
    page.click("#play")
    assert falling.js("visviva.playing()") is False
    assert page.inner_text("#play") == "Play"
    held = falling.js("visviva.frame()")
    page.wait_for_timeout(250)
    assert falling.js("visviva.frame()") == held

    for option, speed in (("1", 1.0), ("2", 2.0)):
        page.select_option("#speed", option)
        falling.js("visviva.setFrame(0)")
        page.click("#play")
        start = falling.js(AT_NEXT_REDRAW)
        page.wait_for_timeout(600)
        end = falling.js(AT_NEXT_REDRAW)
        page.click("#play")
        # Real time: frame = floor(elapsed · fps · speed), from the clock (not redraws).
        expected = (end[0] - start[0]) / 1000.0 * 25.0 * speed
        assert abs((end[1] - start[1]) - expected) <= 3, (speed, start, end)

    falling.js("document.activeElement.blur()")
    page.keyboard.press("Space")
    assert falling.js("visviva.playing()") is True
    page.keyboard.press("Space")
    assert falling.js("visviva.playing()") is False
    falling.js("visviva.setFrame(10)")
    page.keyboard.press("ArrowRight")
    assert falling.js("visviva.frame()") == 11
    page.keyboard.press("ArrowLeft")
    page.keyboard.press("ArrowLeft")
    assert falling.js("visviva.frame()") == 9
    assert falling.js("visviva.playing()") is False


def test_slider_sets_the_frame_and_follows_playback(falling):
    page = falling.page
    falling.js("visviva.pause(); visviva.setFrame(0)")
    box = page.locator("#slider").bounding_box()
    assert box is not None
    page.mouse.click(box["x"] + 0.75 * box["width"], box["y"] + box["height"] / 2)
    frame = falling.js("visviva.frame()")
    assert abs(frame - 0.75 * 49) <= 2
    assert int(page.input_value("#slider")) == frame
    assert page.inner_text("#time").startswith(f"t = {frame / 25.0:.3f} s")
    page.keyboard.press("End")
    assert falling.js("visviva.frame()") == 49
    page.keyboard.press("Home")
    assert falling.js("visviva.frame()") == 0
    falling.js("visviva.setFrame(30)")
    assert int(page.input_value("#slider")) == 30
    with pytest.raises(Exception, match=r"whole number in 0\.\.49"):
        falling.js("visviva.setFrame(50)")


def test_drag_wheel_and_pan_move_the_camera_and_double_click_restores_it(falling):
    page = falling.page
    home = falling.image(20)

    def changed_pixels() -> int:
        return int(np.any(falling.image(20) != home, axis=2).sum())

    page.mouse.move(400, 300)
    page.mouse.down()
    page.mouse.move(480, 260, steps=4)
    page.mouse.up()
    orbited = changed_pixels()
    page.mouse.dblclick(400, 300)
    assert changed_pixels() == 0
    page.mouse.wheel(0, 300)  # zoom out
    page.wait_for_timeout(100)  # wheel events are delivered asynchronously
    zoomed = changed_pixels()
    page.mouse.dblclick(400, 300)
    page.keyboard.down("Shift")
    page.mouse.move(400, 300)
    page.mouse.down()
    page.mouse.move(300, 300, steps=4)
    page.mouse.up()
    page.keyboard.up("Shift")
    panned = changed_pixels()
    page.mouse.dblclick(400, 300)
    assert changed_pixels() == 0
    assert min(orbited, zoomed, panned) > 2000, (orbited, zoomed, panned)


def test_title_is_text_not_markup(browser, tmp_path):
    title = "</script><b>cloth & rope</b>"
    path = write_viewer(falling_recording(), tmp_path / "title.html", title=title)
    opened = Opened(browser, path)
    try:
        assert opened.errors == []
        assert opened.page.title() == title
        assert opened.page.inner_text("#title") == title
    finally:
        opened.page.close()


def test_a_single_still_point_loads_and_does_not_play(browser, tmp_path):
    recording = vv.Recording(np.array([0.5]), {"particle_position": np.array([[[0.0, 1.0, 0.0]]])})
    opened = Opened(browser, write_viewer(recording, tmp_path / "still.html"))
    try:
        assert opened.errors == []
        assert opened.js("[visviva.frames, visviva.playing(), visviva.times]") == [1, False, [0.5]]
        blue = _blue(opened.image(0))
        assert blue.sum() > 20  # the default radius of a scene with no extent, 0.05 m
    finally:
        opened.page.close()


def test_cloth_of_4096_vertices_and_300_frames_loads_quickly(browser, tmp_path):
    recording = waving_cloth()
    path = write_viewer(recording, tmp_path / "cloth.html")
    # Quantized and compressed: less than half of what float32 base64 would take (300 frames ×
    # 4096 points × 12 bytes × 4/3), page included.
    as_float32 = 4 * math.ceil(300 * 4096 * 12 / 3)
    assert path.stat().st_size < as_float32 / 2
    started = time.perf_counter()
    opened = Opened(browser, path)
    wall = time.perf_counter() - started
    try:
        ready = opened.js("visviva.readyTime") / 1000.0  # [s] from navigation start
        assert opened.errors == []
        assert opened.js("visviva.frames") == 300
        # Measured ~0.4–0.7 s here (benchmarks/bench_viewer.py); the bound only catches
        # pathologies on a slow, shared machine.
        assert ready < 10.0 and wall < 15.0
        last = np.array(opened.js("visviva.points(299)")).reshape(-1, 3)
        assert_quantized(last, recording["particle_position"][299], recording["particle_position"])
        image = opened.image(150)
        orange = (image[..., 0] - image[..., 2]) > 80  # the cloth, #d9822b shaded
        assert orange.sum() > 0.05 * orange.size
    finally:
        opened.page.close()


def test_default_rate():
    even = falling_recording()
    assert default_fps(even) == pytest.approx(25.0, rel=1e-12)
    fast = vv.Recording(np.arange(1001) * 1e-3, {"particle_position": np.zeros((1001, 1, 3))})
    assert default_fps(fast) == pytest.approx(1000.0 / 17.0, rel=1e-12)
    np.testing.assert_array_equal(frames_at_rate(fast.time, default_fps(fast)), np.arange(59) * 17)
    # A shortened last interval still counts as even; uneven frames play at 30 fps.
    short_end = vv.Recording(
        np.array([0.0, 0.1, 0.2, 0.25]), {"particle_position": np.zeros((4, 1, 3))}
    )
    assert default_fps(short_end) == pytest.approx(10.0, rel=1e-12)
    uneven = vv.Recording(
        np.array([0.0, 0.1, 0.3, 0.35]), {"particle_position": np.zeros((4, 1, 3))}
    )
    assert default_fps(uneven) == 30.0


def test_default_rate_is_lowered_to_fit_the_size_cap():
    # 2¹⁸ points = 3 MiB per frame: 21 frames fit the 64 MiB cap; 100 s at 10 Hz do not.
    # (A broadcast view: the 6 GB of positions are never allocated.)
    points = np.broadcast_to(np.zeros((1, 1, 3)), (1001, 2**18, 3))
    recording = vv.Recording(np.linspace(0.0, 100.0, 1001), {"particle_position": points})
    with pytest.warns(UserWarning, match="frames/s"):
        fps = default_fps(recording)
    frames = frames_at_rate(recording.time, fps).size
    assert frames * 2**18 * 12 <= MAX_POSITION_BYTES
    assert frames == MAX_POSITION_BYTES // (2**18 * 12)


def blown_up(recording: vv.Recording) -> vv.Recording:
    points = recording["particle_position"].copy()
    points[26:, 1] = np.inf
    return vv.Recording(recording.time, {"particle_position": points})


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda r, p: write_viewer("rec.h5", p), "`recording` must be a visviva Recording"),
        (
            lambda r, p: write_viewer(vv.Recording(r.time, {"q": r["particle_position"]}), p),
            "no `particle_position` or `system_points` field",
        ),
        (
            lambda r, p: write_viewer(
                vv.Recording(np.zeros(0), {"particle_position": np.zeros((0, 1, 3))}), p
            ),
            "no frames",
        ),
        (lambda r, p: write_viewer(r, p, fps=0.0), "`fps` must be positive"),
        (lambda r, p: write_viewer(r, p, fps=True), "`fps` must be a real number"),
        (lambda r, p: write_viewer(r, p, title=3), "`title` must be a string"),
        (lambda r, p: write_viewer(r, p.parent / "missing" / "x.html"), "does not exist"),
        (lambda r, p: write_viewer(r, p.parent), "is a directory"),
        (lambda r, p: write_viewer(blown_up(r), p), "recorded frame 26 are not finite"),
        (
            lambda r, p: write_viewer(
                vv.Recording(np.array([0.0, 10.0]), {"particle_position": np.zeros((2, 2**18, 3))}),
                p,
                fps=10.0,
            ),
            "lower fps",
        ),
    ],
)
def test_bad_input_is_refused_before_anything_is_written(tmp_path, change, message):
    target = tmp_path / "viewer.html"
    with pytest.raises(vv.ModelError, match=message):
        change(falling_recording(), target)
    assert list(tmp_path.iterdir()) == []


def _embedded_positions(page: Path) -> tuple[np.ndarray, np.ndarray]:
    """The page's frame times and positions, decoded in Python as viewer.js does."""
    import base64
    import json
    import re

    from visviva.viz.viewer._payload import decoded_positions

    text = page.read_text(encoding="utf-8")
    data = json.loads(re.search(r'id="visviva-data"[^>]*>(.*?)</script>', text, re.S).group(1))
    times = np.frombuffer(base64.b64decode(data["times"]), "<f8")
    return times, decoded_positions(data["layers"]["points"], data["frames"])


def test_galaxy_viewer_is_quantized_to_under_12_megabytes(tmp_path):
    """6002 stars at the demo's own length: 44 MB of float32 base64 before quantization."""
    from visviva.demos import run_demo

    run_demo("galaxy", tmp_path, formats=["html"])
    page = tmp_path / "viewer.html"
    assert page.stat().st_size <= 12_000_000
    recording = vv.io.load_recording(tmp_path / "recording.h5")
    times, decoded = _embedded_positions(page)
    shown = np.searchsorted(recording.time, times)
    np.testing.assert_array_equal(recording.time[shown], times)
    stars = recording["system_points"]
    assert_quantized(decoded, stars[shown], stars[shown])
    # The documented precision: half a step of a ~20 m box is about 0.15 mm.
    flat = stars.reshape(-1, 3)
    assert np.max(flat.max(axis=0) - flat.min(axis=0)) / 65535 / 2 < 2.5e-4


def test_colours_display_radii_trails_and_time_unit_reach_the_page(browser, tmp_path):
    """A year of a planet about a sun, coloured and drawn at display radii with a trail: the
    page says the time in days and that sizes are not to scale, and draws the sun yellow."""
    year = 365.25 * 86_400.0
    t = np.linspace(0.0, year, 61)
    points = np.zeros((61, 2, 3))
    points[:, 1, 0], points[:, 1, 2] = np.cos(2 * np.pi * t / year), -np.sin(2 * np.pi * t / year)
    recording = vv.Recording(
        t,
        {"particle_position": points},
        static={
            "particle_color": np.array([[1.0, 0.78, 0.18], [0.16, 0.42, 0.86]]),
            "display_radius": np.array([0.15, 0.06]),
        },
    )
    page = write_viewer(recording, tmp_path / "orbit.html", fps=10.0, speed=year / 6, trail=year)
    opened = Opened(browser, page)
    try:
        assert opened.errors == []
        image = opened.image(40)
        text = opened.js("document.getElementById('time').textContent")
        assert text.startswith("t = 243.5 days, sizes not to scale")
        red, green, blue = (image[..., i].astype(int) for i in range(3))
        assert ((red > 170) & (green > 120) & (blue < 110)).sum() > 50  # the sun, yellow
    finally:
        opened.page.close()


def test_contacts_are_drawn_when_the_box_is_ticked(browser, tmp_path):
    # A ball dropped on a box on the floor: a recording with its contacts; the page draws
    # them only while the "contacts" box is ticked, as many as the frame holds.
    builder = vv.SceneBuilder(name="contacts")
    builder.set_integration(method="symplectic_euler", dt=1 / 120, duration=1.0)
    builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0))
    builder.add_body("box", size=(0.4, 0.4, 0.4), density=500.0, position=(0, 0.2, 0))
    builder.add_body("sphere", radius=0.1, density=500.0, position=(0.05, 0.8, 0))
    builder.add_body_contacts()
    recording = vv.Simulation(builder.build()).record(until=1.0, record_every=12,
                                                      contacts=True)  # fmt: skip
    kinds = recording["body_contact_class"]
    last = int((kinds[-1] >= 0).sum())
    assert last == 5  # the box's four corners on the floor, the ball on the box
    page = Opened(browser, write_viewer(recording, tmp_path / "contacts.html", fps=10))
    try:
        frames = page.js("visviva.frames")
        assert page.js(f"visviva.pause(), visviva.setFrame({frames - 1}), visviva.contacts()") == {
            "recorded": True,
            "visible": False,
            "shown": last,
        }
        page.page.check("#contacts")
        assert page.js("visviva.contacts()")["visible"] is True
        assert page.errors == []
    finally:
        page.page.close()
    plain = vv.Simulation(builder.build()).record(until=0.1)
    assert "body_contact_point" not in plain
    page = Opened(browser, write_viewer(plain, tmp_path / "plain.html"))
    try:
        assert page.js("visviva.contacts()")["recorded"] is False
        assert page.page.is_hidden("#contacts")
    finally:
        page.page.close()


def test_walls_and_a_scene_camera_reach_the_page(browser, tmp_path):
    """The ball pit's four walls load as translucent meshes, and a scene's camera is the
    page's first view (the camera's distance from its target)."""
    scene = Path(__file__).parents[1] / "examples" / "scenes" / "ball_pit.toml"
    recording = vv.Simulation(vv.load_model(scene)).record(until=0.05)
    camera = vv.viz.video.Camera((0.0, 2.0, 3.0), (0.0, 0.5, 0.0), field_of_view=40.0)
    opened = Opened(browser, write_viewer(recording, tmp_path / "pit.html", camera=camera))
    try:
        assert opened.errors == []
        walls = opened.js("visviva.walls()")
        assert len(walls) == 4 and all(0.0 < wall["opacity"] < 1.0 for wall in walls)
        view = opened.js("visviva.view()")
        assert view["target"] == pytest.approx([0.0, 0.5, 0.0])
        assert view["distance"] == pytest.approx(np.hypot(1.5, 3.0))
    finally:
        opened.page.close()


def test_many_points_without_a_size_are_a_star_field(browser, tmp_path):
    """1500 gravitating bodies (points without a radius): spots of light added together on a
    night sky, not 1500 opaque spheres."""
    rng = np.random.default_rng(3)
    points = rng.normal(size=(4, 1500, 3))
    recording = vv.Recording(np.arange(4.0), {"system_points": points})
    opened = Opened(browser, write_viewer(recording, tmp_path / "stars.html"))
    try:
        assert opened.errors == []
        assert opened.js("visviva.stars()") == {"count": 1500, "additive": True}
        assert opened.js("visviva.drawn().count") == 0  # no spheres
    finally:
        opened.page.close()


def test_the_page_camera_follows_a_body(browser, tmp_path):
    builder = vv.SceneBuilder(name="thrown")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
    builder.add_body("box", size=(0.2, 0.2, 0.2), density=500.0, name="box", velocity=(3, 4, 0))
    recording = vv.Simulation(builder.build()).record(until=1.0)
    opened = Opened(browser, write_viewer(recording, tmp_path / "follow.html", follow="box"))
    try:
        assert opened.errors == []
        frames = opened.js("visviva.frames")
        opened.js(f"visviva.pause(), visviva.setFrame({frames - 1})")
        target = opened.js("visviva.view().target")
        # The box's centre at t = 1 s: x = 3 m, y = 4 − g/2 m (to the recording's frame).
        assert target == pytest.approx([3.0, 4.0 - 0.5 * 9.81, 0.0], abs=0.1)
        assert opened.errors == []
    finally:
        opened.page.close()


def test_a_demo_that_names_its_bodies_names_them_on_the_page(browser, tmp_path):
    builder = vv.SceneBuilder(name="named")
    builder.set_world(gravity=(0.0, 0.0, 0.0))
    for name, x in (("left", -1.0), ("right", 1.0)):
        builder.add_body("box", size=(0.3, 0.3, 0.3), density=500.0, name=name, position=(x, 0, 0))
    recording = vv.Simulation(builder.build()).record(until=0.05)
    recording.attrs["playback_labels"] = True
    opened = Opened(browser, write_viewer(recording, tmp_path / "named.html"))
    try:
        assert opened.errors == []
        assert opened.js("visviva.nameTags()") == ["left", "right"]
    finally:
        opened.page.close()
