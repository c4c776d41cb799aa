"""Many points without a size (a galaxy, a star cluster) are drawn as a star field: spots of
light that add up on a night sky, framed where nearly all of them are."""

import numpy as np
import pytest

import visviva as vv
from visviva.viz import raster
from visviva.viz.frame import FramePainter, is_star_field
from visviva.viz.framing import chosen_camera


def _disk(count: int, frames: int = 3) -> vv.Recording:
    rng = np.random.default_rng(7)
    radius = rng.uniform(0.2, 1.0, count)
    angle = rng.uniform(0.0, 2 * np.pi, count)
    points = np.stack([radius * np.cos(angle), 0.02 * rng.normal(size=count),
                       radius * np.sin(angle)], axis=-1)  # fmt: skip
    points[0] = (500.0, 0.0, 0.0)  # one star flung far out
    return vv.Recording(
        np.arange(float(frames)), {"system_points": np.tile(points, (frames, 1, 1))}
    )


def test_splatted_light_adds_up_and_is_exposed_without_clipping():
    screen = np.array([[4.0, 4.0, 1.0], [4.0, 4.0, 1.0], [np.nan, np.nan, 1.0]])
    colour = np.ones((3, 3), np.float32)
    one, both = np.zeros((8, 8, 3), np.float32), np.zeros((8, 8, 3), np.float32)
    raster.splat_points(one, screen, np.arange(1), colour, 1.0)
    raster.splat_points(both, screen, np.arange(3), colour, 1.0)
    # Two stars on one spot: twice one star's light; the NaN one (behind the camera) adds none.
    np.testing.assert_allclose(both, 2.0 * one, rtol=1e-6)
    # A star's total light is its gain: the 4 × 4 spot holds 99 % of its Gaussian.
    np.testing.assert_allclose(one[..., 0].sum(), 0.99, rtol=0.02)
    light = both
    color = np.zeros_like(light)
    raster.expose(light, color)
    assert 0.0 < color.max() < 1.0 and color.min() >= 0.0  # film's curve, never clipped


def test_a_star_field_is_dark_with_bright_stars_and_framed_on_the_disk():
    recording = _disk(3000)
    geometry = recording.geometry()
    assert is_star_field(geometry) and not is_star_field(_disk(999).geometry())
    camera = chosen_camera(geometry, None, "all", 16 / 9)
    # Framed on the disk (about 2 m across), not on the star 500 m out.
    assert np.linalg.norm(np.subtract(camera.eye, camera.target)) < 10.0
    image = FramePainter(geometry, (320, 180), camera, recording.time).paint(0, 0.0)
    brightness = image.mean(axis=2)
    assert np.median(brightness) < 20  # a night sky
    assert brightness.max() > 200  # the dense middle of the disk glows


def test_a_style_chooses_night_or_day_whatever_the_points_are():
    recording = _disk(3000)
    for style, stars in (("day", False), ("night", True), ("auto", True)):
        recording.attrs["playback_style"] = style
        assert is_star_field(recording.geometry()) is stars
    small = _disk(50)
    small.attrs["playback_style"] = "night"  # fireworks: few sparks, with radii, at night
    assert is_star_field(small.geometry())
    small.attrs["playback_style"] = "dusk"
    with pytest.raises(vv.ModelError, match="not one of auto, day, night"):
        small.geometry()
