"""End to end: ``visviva run scene.toml -f ...`` writes every output, and each one reads back.

One small scene is run once through the CLI with every output format; each file is then opened
with an independent reader (imageio/ffmpeg, the viewer's embedded JSON, pxr, pygltflib, plain
text and ``struct``) and compared with the recording at the frames the output rate selects.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
from typer.testing import CliRunner

import visviva as vv
from test_export import FLOAT32_RTOL, gltf_frames, read_obj, read_pc2, usd_points
from visviva.cli.main import app, main
from visviva.io.timeline import frames_at_rate
from visviva.viz.viewer._payload import decoded_positions

FPS = 20.0
FORMATS = ("mp4", "gif", "html", "usd", "glb", "obj", "pc2")
OUTPUTS = (
    "animation.mp4",
    "animation.gif",
    "viewer.html",
    "scene.usdc",
    "scene.glb",
    "obj",
    "points.pc2",
)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, vv.Recording]:
    """A 0.5 s thrown cloud of 40 particles run with every format; the folder and recording."""
    builder = vv.SceneBuilder(name="every output")
    builder.set_integration(method="symplectic_euler", dt=0.005, duration=0.5, record_every=2)
    builder.set_output(fps=FPS)
    builder.add_particle_cloud(
        name="cloud",
        count=40,
        center=(0.0, 1.0, 0.0),
        size=(0.4, 0.4, 0.4),
        velocity=(0.5, 3.0, 0.0),
        velocity_jitter=0.5,
        radius=0.03,
        seed=3,
    )
    folder = tmp_path_factory.mktemp("run")
    scene = folder / "scene.toml"
    scene.write_text(vv.io.dump_scene(builder.scene, "toml"))
    out = folder / "out"
    arguments = ["run", str(scene), "-o", str(out)]
    for format in FORMATS:
        arguments += ["-f", format]
    result = CliRunner().invoke(app, arguments)
    assert result.exit_code == 0, result.output
    return out, vv.io.load_recording(out / "recording.h5")


def shown_positions(recording: vv.Recording) -> tuple[np.ndarray, list[int], float]:
    """Positions [m] at each output frame, three frames to check and a float32 tolerance [m]."""
    shown = frames_at_rate(recording.time, FPS)
    positions = recording["particle_position"][shown]
    checked = [0, shown.size // 2, shown.size - 1]
    return positions, checked, FLOAT32_RTOL * float(np.abs(positions).max())


def test_every_output_is_written_with_the_summary(run):
    out, recording = run
    assert sorted(p.name for p in out.iterdir()) == sorted(
        (*OUTPUTS, "recording.h5", "summary.json")
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 100 and summary["warnings"] == []
    assert recording.attrs["success"] is True
    # 0.5 s at 20 frames/s: frames at t = 0, 0.05, …, 0.5.
    assert frames_at_rate(recording.time, FPS).size == 11


def test_videos_have_one_frame_per_output_time(run):
    out, recording = run
    count = frames_at_rate(recording.time, FPS).size
    for name in ("animation.mp4", "animation.gif"):
        frames = iio.imread(out / name, index=None)
        assert frames.shape[0] == count and frames.shape[-1] == 3
        # The cloud moves: the first and last frames differ.
        assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).sum() > 0


def test_viewer_embeds_the_resampled_frames_and_loads_nothing_from_the_network(run):
    out, recording = run
    html = (out / "viewer.html").read_text()
    assert not re.search(r"""(src|href)=["']?https?:""", html)
    data = re.search(r'<script type="application/json" id="visviva-data">(.*?)</script>', html)
    assert data is not None
    payload = json.loads(data.group(1))
    positions, checked, tolerance = shown_positions(recording)
    assert payload["frames"] == positions.shape[0] and payload["fps"] == FPS
    stored = decoded_positions(payload["layers"]["points"], payload["frames"])
    # Quantized to a 16-bit grid over the points' box: within half a grid step (viewer docs).
    half_step = 0.5 * np.ptp(positions.reshape(-1, 3), axis=0) / 65535
    for k in checked:
        assert np.all(np.abs(stored[k] - positions[k]) <= half_step * (1 + 1e-9) + tolerance)


def test_exports_hold_the_recorded_positions_at_three_frames(run):
    out, recording = run
    positions, checked, tolerance = shown_positions(recording)
    _, _, glb = gltf_frames(out / "scene.glb")
    _, pc2 = read_pc2(out / "points.pc2")
    objs = sorted((out / "obj").glob("*.obj"))
    assert glb.shape == pc2.shape == positions.shape and len(objs) == positions.shape[0]
    for k in checked:
        usd = usd_points(out / "scene.usdc", "/World/points", k)
        np.testing.assert_allclose(usd, positions[k], rtol=0, atol=tolerance)
        np.testing.assert_allclose(glb[k], positions[k], rtol=0, atol=tolerance)
        np.testing.assert_allclose(pc2[k], positions[k], rtol=0, atol=tolerance)
        vertices, _, _ = read_obj(objs[k])
        np.testing.assert_array_equal(vertices, positions[k])  # OBJ keeps every float64 digit


def test_an_existing_output_needs_force(run, monkeypatch, capsys):
    out, _ = run
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    arguments = ["visviva", "run", str(out.parent / "scene.toml"), "-o", str(out), "-f", "pc2"]
    monkeypatch.setattr(sys, "argv", arguments)
    with pytest.raises(SystemExit) as exit_:
        main()
    assert exit_.value.code == 2 and "--force" in capsys.readouterr().err
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before


def run_main(monkeypatch, capsys, *arguments: str | Path) -> tuple[int, str]:
    """``visviva ARGUMENTS`` through the entry point; the exit status and stdout + stderr."""
    monkeypatch.setattr(sys, "argv", ["visviva", *map(str, arguments)])
    try:
        main()
        status = 0
    except SystemExit as exit_:
        status = 0 if exit_.code is None else int(exit_.code)
    captured = capsys.readouterr()
    return status, captured.out + captured.err


def test_export_command_writes_the_run_names_next_to_the_recording(
    run, tmp_path, monkeypatch, capsys
):
    out, recording = run
    source = tmp_path / "recording.h5"
    source.write_bytes((out / "recording.h5").read_bytes())
    for to in ("usd", "glb", "obj", "pc2", "gif"):
        status, output = run_main(monkeypatch, capsys, "export", source, "--to", to)
        assert status == 0, output
    names = {"scene.usdc", "scene.glb", "obj", "points.pc2", "animation.gif"}
    assert {p.name for p in tmp_path.iterdir()} == names | {"recording.h5"}
    # Without --fps the exports play at a whole number of frames per second: the recording's
    # 100 frames/s capped at 60 (docs/export.md).
    _, pc2 = read_pc2(tmp_path / "points.pc2")
    tolerance = FLOAT32_RTOL * float(np.abs(recording["particle_position"]).max())
    expected = recording["particle_position"][frames_at_rate(recording.time, 60.0)]
    np.testing.assert_allclose(pc2, expected, rtol=0, atol=tolerance)
    status, output = run_main(monkeypatch, capsys, "export", source, "--to", "pc2")
    assert status == 2 and "--force" in output
    status, output = run_main(monkeypatch, capsys, "export", source, "--to", "usdz")
    assert status == 2 and "'usdz'" in output and "usd" in output


def test_export_video_size(run, tmp_path, monkeypatch, capsys):
    out, _ = run
    gif = tmp_path / "small.gif"
    status, output = run_main(
        monkeypatch,
        capsys,
        "export",
        out / "recording.h5",
        "--to",
        "gif",
        "--size",
        "160x90",
        "-o",
        gif,
    )
    assert status == 0, output
    assert iio.imread(gif, index=0).shape == (90, 160, 3)
    refused = {
        ("gif", "160y90"): "WIDTHxHEIGHT",
        ("mp4", "161x90"): "even",
        ("usd", "160x90"): "does not apply",
    }
    for (to, size), message in refused.items():
        target = tmp_path / f"refused.{to}"
        arguments = ("export", out / "recording.h5", "--to", to, "--size", size, "-o", target)
        status, output = run_main(monkeypatch, capsys, *arguments)
        assert status == 2 and message in output and size.partition("x")[0] in output
        assert not target.exists()
