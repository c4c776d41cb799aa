"""Blender, for real: visviva's USD and glTF exports imported into Blender 5 agree with the
recording at the first, middle and last frames.

Blender runs as a Python module (``bpy`` 5.0 from PyPI) in its own environment, .venv-blender,
made by ``tools/install-blender`` (bpy needs NumPy below 2); ``.ci/run`` makes it, and this test
is skipped, saying so, where it is missing. Each import runs in a subprocess
(``tests/blender_probe.py``) that sets the scene's frame rate to the export's, as
docs/export.md tells users to, and prints the world positions Blender shows at given frames.

Blender is Z-up: an exported point (x, y, z) (Y up) appears at (x, −z, y). Positions travel as
float32, so they agree to float32 rounding of the scene's size.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.io.export import export_recording
from visviva.io.timeline import frames_at_rate

ROOT = Path(__file__).parents[1]
BLENDER_PYTHON = Path(
    os.environ.get("VISVIVA_BLENDER_PYTHON", ROOT / ".venv-blender" / "bin" / "python")
)
PROBE = Path(__file__).with_name("blender_probe.py")
FPS = 25.0

pytestmark = pytest.mark.skipif(
    not BLENDER_PYTHON.exists(),
    reason=f"Blender's Python {BLENDER_PYTHON} is missing: run tools/install-blender",
)


def blender_view(path: Path, frames: list[int]) -> dict:
    """What Blender shows of the export at ``path`` at each frame (see blender_probe.py)."""
    result = subprocess.run(
        [str(BLENDER_PYTHON), str(PROBE), str(path), str(int(FPS)), *map(str, frames)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    (line,) = [x for x in result.stdout.splitlines() if x.startswith("PROBE ")]
    return json.loads(line.removeprefix("PROBE "))


def y_up(blender: list) -> np.ndarray:
    """Blender's Z-up positions back in visviva's Y-up frame: (x, y, z) = (x_b, z_b, −y_b)."""
    xyz = np.asarray(blender, dtype=np.float64).reshape(-1, 3)
    return np.stack([xyz[:, 0], xyz[:, 2], -xyz[:, 1]], axis=1)


def assert_same_points(actual: np.ndarray, expected: np.ndarray, tolerance: float) -> None:
    """The same points in any order: as many, each within ``tolerance`` of a different one."""
    assert actual.shape == expected.shape
    distance = np.linalg.norm(actual[:, None, :] - expected[None, :, :], axis=-1)
    nearest = distance.argmin(axis=1)
    assert sorted(nearest) == list(range(len(expected)))
    assert distance.min(axis=1).max() <= tolerance


def falling_points() -> vv.Recording:
    """Four spheres falling and swaying, 50 Hz."""
    t = np.arange(60) / 50.0
    points = np.zeros((60, 4, 3))
    points[:, :, 0] = [0.0, 1.0, 2.0, 3.0] + 0.1 * np.cos(3.0 * t[:, None])
    points[:, :, 1] = 2.0 - 4.9 * t[:, None] ** 2
    points[:, :, 2] = np.sin(t[:, None] * np.array([1.0, 2.0, 3.0, 4.0]))
    radius = np.array([0.1, 0.05, 0.2, 0.1])
    return vv.Recording(t, {"particle_position": points}, static={"particle_radius": radius})


def folding_quad_and_a_ball() -> vv.Recording:
    """Two triangles over points 1-4 that fold and rise, and point 0 on no face."""
    t = np.arange(60) / 50.0
    corners = np.array(
        [[3.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]]
    )
    points = np.repeat(corners[None], t.size, axis=0)
    points[:, 4, 1] = np.sin(2.0 * t)
    points[:, :, 1] += 0.5 * t[:, None]
    faces = np.array([[1, 3, 2], [2, 3, 4]])
    return vv.Recording(t, {"particle_position": points}, static={"faces": faces})


def _checked(recording: vv.Recording) -> tuple[np.ndarray, list[int], float]:
    shown = frames_at_rate(recording.time, FPS)
    points = recording.geometry().points
    tolerance = 2e-6 * max(1.0, float(np.abs(points).max()))  # float32, twice
    return points[shown], [0, shown.size // 2, shown.size - 1], tolerance


def test_points_in_usd_and_gltf(tmp_path):
    recording = falling_points()
    expected, frames, tolerance = _checked(recording)
    (usd,) = export_recording(recording, tmp_path / "fall.usdc", fps=FPS)
    (glb,) = export_recording(recording, tmp_path / "fall.glb", fps=FPS)
    usd_view, glb_view = blender_view(usd, frames), blender_view(glb, frames)
    # USD carries the frame range (time code k is frame k); neither format makes Blender take
    # the rate (docs/export.md says to set it), so the probe set it first.
    assert usd_view["range"] == [0, expected.shape[0] - 1]
    for k in frames:
        points = y_up(usd_view["frames"][str(k)]["points"])  # a point cloud, widths = 2 radii
        np.testing.assert_allclose(points, expected[k], rtol=0, atol=tolerance)
        bodies = y_up(glb_view["frames"][str(k)]["bodies"])  # one sphere object per point
        np.testing.assert_allclose(bodies, expected[k], rtol=0, atol=tolerance)


def test_meshes_in_usd_and_gltf(tmp_path):
    recording = folding_quad_and_a_ball()
    expected, frames, tolerance = _checked(recording)
    (usd,) = export_recording(recording, tmp_path / "quad.usdc", fps=FPS)
    (glb,) = export_recording(recording, tmp_path / "quad.glb", fps=FPS)
    usd_view, glb_view = blender_view(usd, frames), blender_view(glb, frames)
    for k in frames:
        shown = usd_view["frames"][str(k)]
        # The mesh holds the four points of its faces, and no stray vertex for point 0.
        np.testing.assert_allclose(y_up(shown["mesh"]), expected[k][1:], rtol=0, atol=tolerance)
        np.testing.assert_allclose(y_up(shown["points"]), expected[k][:1], rtol=0, atol=tolerance)
        # glTF: one mesh of every point, animated by morph targets with sparse STEP weights
        # (Blender orders the vertices by primitive: triangles' first, then the loose point).
        (mesh,) = glb_view["frames"][str(k)].values()
        assert_same_points(y_up(mesh), expected[k], tolerance)


def test_kepler_demo_glb_is_small_and_right_in_blender(tmp_path):
    from visviva.demos import run_demo

    run_demo("kepler", tmp_path, formats=["glb", "usd"], fps=FPS)
    glb = tmp_path / "scene.glb"
    assert glb.stat().st_size <= 1_000_000  # 21 MB with dense morph weights before
    (run, *_) = vv.io.read_recordings(tmp_path / "recording.h5").values()
    expected, frames, tolerance = _checked(run)
    tolerance = 1e-6 * float(np.abs(run["system_points"]).max()) * 4
    for path, key in ((glb, "bodies"), (tmp_path / "scene.usdc", "points")):
        view = blender_view(path, frames)
        for k in frames:
            np.testing.assert_allclose(
                y_up(view["frames"][str(k)][key]), expected[k], rtol=0, atol=tolerance
            )


def test_rigid_bodies_in_usd_and_gltf(tmp_path):
    """Each body is one object named after it, placed by its transform: USD's time-sampled
    translate and orient (read through a Transform Cache constraint), glTF's node channels."""
    from test_rigid_outputs import NAMES, placed, scene, surfaces

    recording = vv.Simulation(scene().build()).record(until=0.5)
    shown = frames_at_rate(recording.time, FPS)
    frames = [0, shown.size // 2, shown.size - 1]
    (usd,) = export_recording(recording, tmp_path / "bodies.usdc", fps=FPS)
    (glb,) = export_recording(recording, tmp_path / "bodies.glb", fps=FPS)
    origin, orientation = recording["body_origin"][shown], recording["body_orientation"][shown]
    tolerance = 2e-6 * max(1.0, float(np.abs(origin).max()))  # float32 vertices and transforms
    for view in (blender_view(usd, frames), blender_view(glb, frames)):
        for k in frames:
            objects = view["frames"][str(k)]
            for b, (name, (vertices, _)) in enumerate(zip(NAMES, surfaces(), strict=True)):
                expected = placed(origin[k, b], orientation[k, b], vertices)
                actual = y_up(objects[name])
                # A box's corners are three vertices each (flat faces), so match both ways
                # rather than one to one.
                assert actual.shape == expected.shape
                distance = np.linalg.norm(actual[:, None, :] - expected[None, :, :], axis=-1)
                assert distance.min(axis=0).max() <= tolerance
                assert distance.min(axis=1).max() <= tolerance
