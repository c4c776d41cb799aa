"""Points that are born and die, in every output: video, web viewer, USD, glTF, OBJ, PC2.

One small recording drives every test: 3 frames × 5 point slots at 10 Hz, with

    alive = [[1, 1, 0, 0, 0],
             [0, 1, 1, 1, 0],
             [1, 0, 0, 1, 1]]

radii and colours that change every frame, and dead slots parked at the origin with a radius of
9 m, both meaningless: nothing of a dead slot may be drawn, written as a point, or widen a box.
Slot 0 dies after frame 0 and is reused at frame 2 far from where it was: its trail must start
afresh. Each output is read back (pixels, the page's own read-back in Chromium, pxr, pygltflib,
text and bytes) and compared with the recording, frame by frame.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pygltflib
import pytest
from playwright.sync_api import sync_playwright
from pxr import Usd, UsdGeom

import visviva as vv
from test_export import gltf_accessor, read_obj, read_pc2
from test_viewer import CHROMIUM, CHROMIUM_FLAGS, Opened
from visviva.io.export import export_recording
from visviva.simulation.lifetimes import held_frames, life_starts
from visviva.viz.frame import FramePainter, drawn_bounds
from visviva.viz.video import Camera, render_video
from visviva.viz.viewer import write_viewer

ALIVE = np.array([[1, 1, 0, 0, 0], [0, 1, 1, 1, 0], [1, 0, 0, 1, 1]], dtype=bool)
FRAMES, SLOTS = ALIVE.shape
RATE = 10.0
#: Saturated, far-apart hues; slot p shows PALETTE[(p + k) % 5] in frame k.
PALETTE = np.array(
    [[0.9, 0.1, 0.1], [0.1, 0.75, 0.1], [0.1, 0.2, 0.9], [0.85, 0.75, 0.05], [0.8, 0.1, 0.8]]
)
DEAD_RADIUS = 9.0
SIZE = (480, 270)


def live_positions() -> np.ndarray:
    """Where each slot is in each frame if alive: a row at z = −2, rising; slot 0's second
    life (frame 2) is at z = +2, 4 m from its first."""
    k, p = np.meshgrid(np.arange(FRAMES), np.arange(SLOTS), indexing="ij")
    points = np.stack([-3.0 + 1.5 * p, 1.0 + 0.8 * k, np.full(k.shape, -2.0)], axis=-1)
    points[2, 0, 2] = 2.0
    return points


def live_radius() -> np.ndarray:
    k, p = np.meshgrid(np.arange(FRAMES), np.arange(SLOTS), indexing="ij")
    return 0.15 + 0.03 * p + 0.05 * k


def live_colour() -> np.ndarray:
    k, p = np.meshgrid(np.arange(FRAMES), np.arange(SLOTS), indexing="ij")
    return PALETTE[(p + k) % SLOTS].astype(np.float32)


def lifecycle(alive: np.ndarray = ALIVE) -> vv.Recording:
    """The recording of the module docstring (``alive`` may add frames: they repeat the last)."""
    frames = alive.shape[0]
    repeat = np.minimum(np.arange(frames), FRAMES - 1)
    points = np.where(alive[..., None], live_positions()[repeat], 0.0)  # dead: at the origin
    radius = np.where(alive, live_radius()[repeat], DEAD_RADIUS)
    colour = np.where(alive[..., None], live_colour()[repeat], np.float32(0.5))
    return vv.Recording(
        np.arange(frames) / RATE,
        {
            "particle_position": points,
            "particle_alive": alive,
            "particle_radius": radius,
            "particle_color": colour,
        },
        units={"particle_position": "m", "particle_radius": "m"},
    )


def expected_bounds() -> tuple[np.ndarray, np.ndarray]:
    positions, radius = live_positions()[ALIVE], live_radius()[ALIVE][:, None]
    return (positions - radius).min(axis=0), (positions + radius).max(axis=0)


# --- the shared rules ----------------------------------------------------------------------


def test_life_starts_and_held_frames():
    starts = life_starts(ALIVE)
    assert starts[2, 0] == 2  # slot 0 reborn: its trail starts at frame 2, not 0
    assert starts[2, 3] == 1 and starts[1, 1] == 0
    # Dead slots are held where they were last alive, or where they are first born.
    np.testing.assert_array_equal(
        held_frames(ALIVE), [[0, 0, 1, 1, 2], [0, 1, 1, 1, 2], [2, 1, 1, 2, 2]]
    )


# --- video ---------------------------------------------------------------------------------


def project(camera: Camera, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel (x, y) and distance from the eye of world points, derived independently."""
    eye, target = np.array(camera.eye), np.array(camera.target)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    focal = 0.5 * SIZE[1] / math.tan(math.radians(camera.field_of_view) / 2)
    d = np.atleast_2d(points) - eye
    depth = d @ forward
    pixels = np.stack(
        [SIZE[0] / 2 + focal * (d @ right) / depth, SIZE[1] / 2 - focal * (d @ up) / depth], 1
    )
    return pixels, np.linalg.norm(d, axis=1)


def hue_mask(image: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """Saturated pixels whose colour points the way of ``rgb`` (shading scales all channels)."""
    pixels = image.astype(float)
    cosine = (pixels @ rgb) / (np.linalg.norm(pixels, axis=2) * np.linalg.norm(rgb) + 1e-9)
    return (cosine > 0.97) & (np.ptp(pixels, axis=2) > 60)


def painter(recording: vv.Recording, trail: float = 0.0) -> tuple[FramePainter, Camera]:
    geometry = recording.geometry()
    camera = Camera.framing(drawn_bounds(geometry), aspect=SIZE[0] / SIZE[1])
    return FramePainter(geometry, SIZE, camera, recording.time, trail), camera


def test_video_framing_and_ground_ignore_dead_points():
    recording = lifecycle()
    low, high = drawn_bounds(recording.geometry())
    # Dead slots sit at the origin with a 9 m radius: counted, low would be (−9, −9, −9).
    np.testing.assert_allclose(low, expected_bounds()[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(high, expected_bounds()[1], rtol=0, atol=1e-12)
    frame_painter, camera = painter(recording)
    np.testing.assert_allclose(camera.target, 0.5 * (low + high), rtol=0, atol=1e-12)
    assert frame_painter.stage.ground_y == 0.0  # min(0, lowest live point): not −9


def test_video_draws_each_frames_live_points_in_their_colour_and_size():
    recording = lifecycle()
    frame_painter, camera = painter(recording)
    focal = 0.5 * SIZE[1] / math.tan(math.radians(camera.field_of_view) / 2)
    origin, _ = project(camera, np.zeros(3))
    ox, oy = origin[0].astype(int)
    background = np.round(np.clip(frame_painter.background[oy, ox], 0.0, 1.0) * 255.0)
    for k in range(FRAMES):
        image = frame_painter.paint(k, float(recording.time[k]))
        # The dead slots' parked place shows the ground, untouched.
        assert np.abs(image[oy, ox].astype(float) - background).max() <= 2.0, k
        pixels, distance = project(camera, live_positions()[k])
        for p in range(SLOTS):
            mask = hue_mask(image, live_colour()[k, p])
            if not ALIVE[k, p]:
                assert mask.sum() == 0, (k, p)  # its colour appears nowhere
                continue
            x, y = pixels[p].astype(int)
            assert mask[y, x], (k, p)  # its colour at its centre
            r = live_radius()[k, p]
            area = math.pi * (focal * r / math.sqrt(distance[p] ** 2 - r**2)) ** 2
            assert mask.sum() == pytest.approx(area, rel=0.25), (k, p)
        assert sum(hue_mask(image, c).any() for c in PALETTE) == ALIVE[k].sum()


def test_video_trail_of_a_reused_slot_starts_at_its_new_birth():
    recording = lifecycle()
    plain = painter(recording)[0].paint(2, 0.2).astype(int)
    trailed_painter, camera = painter(recording, trail=1.0)
    trailed = trailed_painter.paint(2, 0.2).astype(int)
    changed = np.abs(trailed - plain).sum(axis=2) > 30
    # Slot 0 lived at frame 0 (z = −2) and again at frame 2 (z = +2), parked at the origin in
    # between: no line joins its two lives, directly or through the parking place.
    first, parked, second = live_positions()[0, 0], np.zeros(3), live_positions()[2, 0]
    for start, end in ((first, second), (first, parked), (parked, second)):
        between = start + np.linspace(0.25, 0.75, 11)[:, None] * (end - start)
        for x, y in project(camera, between)[0].astype(int):
            assert not changed[y - 1 : y + 2, x - 1 : x + 2].any(), (start, end, x, y)
    # Slot 3 lived through frames 1 and 2: its trail is drawn between the two places.
    middle = 0.5 * (live_positions()[1, 3] + live_positions()[2, 3])
    x, y = project(camera, middle)[0][0].astype(int)
    lower = project(camera, live_positions()[1, 3])[0][0].astype(int)
    assert changed[min(y, lower[1]) : max(y, lower[1]) + 1, x - 2 : x + 3].any()


@pytest.mark.parametrize("suffix", ["mp4", "gif"])
def test_video_files_show_the_live_points(tmp_path, suffix):
    import imageio.v3 as iio

    path = render_video(lifecycle(), tmp_path / f"life.{suffix}", fps=RATE, size=SIZE)
    frames = iio.imread(path, index=None)
    assert frames.shape[0] == FRAMES
    for k in range(FRAMES):
        shown = {p for p in range(SLOTS) if hue_mask(frames[k], live_colour()[k, p]).sum() > 10}
        assert shown == set(np.flatnonzero(ALIVE[k]).tolist()), (suffix, k)


# --- USD -----------------------------------------------------------------------------------


def test_usd_points_hold_only_live_points_with_ids_widths_and_colours(tmp_path):
    alive = np.concatenate([ALIVE, np.zeros((1, SLOTS), dtype=bool)])  # frame 3: none alive
    recording = lifecycle(alive)
    (path,) = export_recording(recording, tmp_path / "life.usda", fps=RATE)
    stage = Usd.Stage.Open(str(path))
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/points"))
    colour = points.GetDisplayColorPrimvar()
    assert colour.GetInterpolation() == "vertex"
    assert points.GetWidthsInterpolation() == "vertex"
    for k in range(FRAMES):
        live = np.flatnonzero(ALIVE[k])
        np.testing.assert_array_equal(np.array(points.GetIdsAttr().Get(k)), live)
        read = np.array(points.GetPointsAttr().Get(k))
        assert read.shape == (live.size, 3)
        np.testing.assert_allclose(read, live_positions()[k, live], rtol=0, atol=1e-6)
        widths = np.array(points.GetWidthsAttr().Get(k))
        np.testing.assert_allclose(widths, 2 * live_radius()[k, live], rtol=1e-7)
        np.testing.assert_array_equal(np.array(colour.Get(k)), live_colour()[k, live])
        extent = np.array(points.GetExtentAttr().Get(k))
        computed = UsdGeom.Boundable.ComputeExtentFromPlugins(points, Usd.TimeCode(k))
        np.testing.assert_allclose(extent, np.array(computed), rtol=1e-6)
        assert extent[0, 1] > 0.5  # no dead point at the origin, no 9 m radius
    assert len(points.GetPointsAttr().Get(3)) == 0 and len(points.GetIdsAttr().Get(3)) == 0
    empty = np.array(points.GetExtentAttr().Get(3))
    assert (empty[0] > empty[1]).all()  # the empty box usd-core computes for no points


# --- glTF ----------------------------------------------------------------------------------


def linear(srgb: np.ndarray) -> np.ndarray:
    srgb = np.asarray(srgb, dtype=np.float64)
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def test_gltf_bodies_vanish_while_dead_and_hold_their_place(tmp_path):
    (path,) = export_recording(lifecycle(), tmp_path / "life.glb", fps=RATE)
    document = pygltflib.GLTF2.load(str(path))
    blob = document.binary_blob()
    (animation,) = document.animations
    tracks = {}
    for channel in animation.channels:
        sampler = animation.samplers[channel.sampler]
        values = gltf_accessor(document, blob, sampler.output)
        tracks[channel.target.node - 1, channel.target.path] = (sampler.interpolation, values)
    held = held_frames(ALIVE)
    for p in range(SLOTS):
        interpolation, scale = tracks[p, "scale"]
        assert interpolation == "STEP"
        wanted = np.where(ALIVE[:, p], live_radius()[:, p], 0.0)
        np.testing.assert_allclose(scale, np.repeat(wanted[:, None], 3, axis=1), rtol=1e-6)
        interpolation, translation = tracks[p, "translation"]
        assert interpolation == "LINEAR"
        # Dead: where it was last alive, or where it is first born: never at the origin.
        held_at = live_positions()[held[:, p], p]
        np.testing.assert_allclose(translation, held_at, rtol=0, atol=1e-6)
        node = document.nodes[p + 1]
        assert node.scale == [float(wanted[0])] * 3
        # Colour: its first life's, as a material (linear, not metallic).
        material = document.materials[document.meshes[node.mesh].primitives[0].material]
        first = int(np.argmax(ALIVE[:, p]))
        np.testing.assert_allclose(
            material.pbrMetallicRoughness.baseColorFactor[:3],
            linear(live_colour()[first, p]),
            rtol=1e-6,
        )
        assert material.pbrMetallicRoughness.metallicFactor == 0.0


def test_gltf_mesh_layout_collapses_dead_points_onto_live_ones(tmp_path):
    # 300 slots (60 copies of the five, 20 m apart in z): more than MAX_BODY_NODES, so one
    # POINTS mesh with a morph target per frame.
    copies = 60
    base = lifecycle()
    offset = np.repeat(np.arange(copies) * 20.0, SLOTS)
    points = np.tile(base["particle_position"], (1, copies, 1))
    points[..., 2] += np.where(np.tile(ALIVE, copies), offset, 0.0)
    alive = np.tile(ALIVE, copies)
    recording = vv.Recording(
        base.time,
        {
            "particle_position": points,
            "particle_alive": alive,
            "particle_radius": np.tile(base["particle_radius"], copies),
            "particle_color": np.tile(base["particle_color"], (1, copies, 1)),
        },
    )
    (path,) = export_recording(recording, tmp_path / "cloud.glb", fps=RATE)
    document = pygltflib.GLTF2.load(str(path))
    blob = document.binary_blob()
    (primitive,) = document.meshes[0].primitives
    assert primitive.mode == pygltflib.POINTS
    base_positions = gltf_accessor(document, blob, primitive.attributes.POSITION)
    for k, target in enumerate(primitive.targets):
        frame = base_positions + gltf_accessor(document, blob, target["POSITION"])
        live = points[k, alive[k]]
        # Every vertex, dead ones included, is on a live point: no dot of its own.
        nearest = np.min(np.linalg.norm(frame[:, None] - live[None], axis=2), axis=1)
        assert nearest.max() < 1e-4, k
        np.testing.assert_allclose(frame[alive[k]], live, rtol=0, atol=1e-4)
        # The largest live point takes the dead ones.
        radii = np.where(alive[k], recording["particle_radius"][k], -1.0)
        np.testing.assert_allclose(
            frame[~alive[k]] - points[k, np.argmax(radii)], 0.0, rtol=0, atol=1e-4
        )
    # Colours and radii of each point's first life.
    first = np.argmax(alive, axis=0)
    colours = gltf_accessor(document, blob, primitive.attributes.COLOR_0)
    np.testing.assert_allclose(
        colours, linear(recording["particle_color"][first, np.arange(alive.shape[1])]), rtol=1e-6
    )
    radii = gltf_accessor(document, blob, primitive.attributes._RADIUS)
    np.testing.assert_allclose(
        radii, recording["particle_radius"][first, np.arange(alive.shape[1])], rtol=1e-6
    )
    # Bounds: the POSITION accessors never reach the origin's parked points at y = 0.
    assert document.accessors[primitive.attributes.POSITION].min[1] > 0.5


# --- OBJ and PC2 ---------------------------------------------------------------------------


def test_obj_files_hold_only_each_frames_live_points(tmp_path):
    written = export_recording(lifecycle(), tmp_path / "life.obj", fps=RATE)
    assert len(written) == FRAMES
    for k, path in enumerate(written):
        vertices, _, _ = read_obj(path)
        np.testing.assert_array_equal(vertices, live_positions()[k, ALIVE[k]])  # bit for bit
        assert f"# {ALIVE[k].sum()} of {SLOTS} points alive" in path.read_text()


def test_obj_topology_keeps_edges_between_live_points_renumbered(tmp_path):
    recording = lifecycle()
    recording.static["edges"] = np.array([[1, 2], [2, 3], [3, 4]])
    written = export_recording(recording, tmp_path / "rope.obj", fps=RATE)
    assert read_obj(written[0])[1] == []  # frame 0: points 0, 1 alive; no edge whole
    assert read_obj(written[1])[1] == [[1, 2], [2, 3]]  # points 1, 2, 3 → vertices 1, 2, 3
    assert read_obj(written[2])[1] == [[2, 3]]  # points 0, 3, 4: edge 3–4 → 2–3


def test_pc2_holds_dead_points_where_they_last_lived(tmp_path):
    (path,) = export_recording(lifecycle(), tmp_path / "life.pc2", fps=RATE)
    header, samples = read_pc2(path)
    assert header[2] == SLOTS and header[-1] == FRAMES  # the format's fixed count
    held = held_frames(ALIVE)
    wanted = live_positions()[held, np.arange(SLOTS)]
    np.testing.assert_allclose(samples, wanted, rtol=0, atol=1e-6)
    assert np.abs(samples).min(axis=2).max() > 0.0 and (np.abs(samples[..., 1]) > 0.5).all()


# --- web viewer ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.is_file():
        pytest.fail(f"the viewer tests need Debian's Chromium at {CHROMIUM}", pytrace=False)
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_FLAGS)
        yield chromium
        chromium.close()


def test_viewer_draws_each_frames_live_points_at_their_radius_and_colour(browser, tmp_path):
    path = write_viewer(lifecycle(), tmp_path / "life.html", fps=RATE, trail=1.0)
    opened = Opened(browser, path)
    try:
        assert opened.errors == []
        counts = []
        for k in range(FRAMES):
            drawn = opened.js(f"visviva.pause(), visviva.setFrame({k}), visviva.drawn()")
            live = np.flatnonzero(ALIVE[k])
            counts.append(drawn["count"])
            # Positions to the 16-bit grid of the live points' box (a few mm here).
            np.testing.assert_allclose(drawn["centres"], live_positions()[k, live], atol=2e-4)
            np.testing.assert_allclose(drawn["radii"], live_radius()[k, live], rtol=1e-4)
            wanted = np.round(255 * live_colour()[k, live]).astype(int)
            assert np.abs(np.array(drawn["colours"]) - wanted).max() <= 1
            image = opened.image(k)
            shown = {p for p in range(SLOTS) if hue_mask(image, live_colour()[k, p]).sum() > 30}
            assert shown == set(live.tolist()), k
        assert counts == [2, 3, 3]
        bounds = np.array(
            opened.js("JSON.parse(document.getElementById('visviva-data').textContent).bounds")
        )
        np.testing.assert_allclose(bounds, np.stack(expected_bounds()), rtol=1e-12)
    finally:
        opened.page.close()


def test_viewer_trail_of_a_reused_slot_starts_afresh_and_data_stay_compact(browser, tmp_path):
    pages = {
        trail: write_viewer(lifecycle(), tmp_path / f"trail{trail}.html", fps=RATE, trail=trail)
        for trail in (0.0, 1.0)
    }
    images = {}
    for trail, path in pages.items():
        opened = Opened(browser, path)
        try:
            assert opened.errors == []
            images[trail] = opened.image(2)
        finally:
            opened.page.close()
    changed = np.abs(images[1.0] - images[0.0]).sum(axis=2) > 40
    # Slot 3's trail, frames 1 → 2: a short vertical line under its sphere. Joining slot 0's
    # two lives would draw a line across the picture (measured without the birth bits: changes
    # over 330 columns instead of 4).
    assert changed.sum() > 10
    columns = np.nonzero(changed)[1]
    assert columns.max() - columns.min() < 20
    # The bits of births and deaths are a few bytes, not a byte per point per frame.
    text = pages[1.0].read_text(encoding="utf-8")
    data = json.loads(re.search(r'id="visviva-data"[^>]*>(.*?)</script>', text, re.S).group(1))
    layer = data["layers"]["points"]
    assert {"alive", "births", "radii", "frame_colors"} <= set(layer)
    assert "radius" not in layer and "colors" not in layer
    assert len(layer["alive"]) < 20 and len(layer["births"]) < 20
