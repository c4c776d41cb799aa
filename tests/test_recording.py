"""Recordings survive the trip to HDF5 and back, bit for bit, with their units and attributes."""

import os

import h5py
import numpy as np
import pytest

import visviva as vv
from visviva.io.recording import FORMAT, FORMAT_VERSION


def _solution():
    problem = vv.ode.SecondOrderProblem(
        lambda t, q, v: -q - 0.1 * v,
        q0=[[1.0, 0.0], [0.5, 0.2]],
        v0=[[0.0, 1.0], [0.0, 0.0]],
        energy=lambda t, q, v: 0.5 * (q**2 + v**2).sum(axis=-1),
        name="damped pair",
    )
    return vv.solve(problem, "velocity_verlet", dt=0.01, until=1.0, record_every=10)


def test_round_trip_is_bit_identical(tmp_path):
    """Times, fields, units and attributes come back exactly as written."""
    recording = _solution().recording
    recording.units["q"] = "m"
    path = vv.io.save_recording(recording, tmp_path / "run.h5")
    loaded = vv.io.load_recording(path)
    np.testing.assert_array_equal(loaded.time, recording.time)
    assert set(loaded.fields) == {"q", "v", "energy"}
    for name, values in recording.fields.items():
        np.testing.assert_array_equal(loaded[name], values)
        assert loaded[name].dtype == values.dtype
    assert loaded.units["q"] == "m"
    for key in (
        "method",
        "dt",
        "substeps",
        "record_every",
        "visviva_version",
        "f_evaluations",
        "success",
        "message",
        "batch_size",
        "problem",
    ):
        assert loaded.attrs[key] == recording.attrs[key], key


def test_documented_layout(tmp_path):
    """The file follows the layout in visviva.io.recording's docstring."""
    path = vv.io.save_recording(_solution().recording, tmp_path / "run.h5", run="verlet")
    with h5py.File(path, "r") as file:
        assert file.attrs["format"] == FORMAT
        assert file.attrs["format_version"] == FORMAT_VERSION
        assert file.attrs["runs"] == '["verlet"]'
        run = file["verlet"]
        assert run.attrs["method"] == "velocity_verlet"
        assert run.attrs["dt"] == 0.01
        assert run["time"].attrs["units"] == "s"
        assert run["fields/q"].shape == (11, 2, 2)
        assert run["fields/q"].chunks == (1, 2, 2)


def test_several_runs_in_one_file(tmp_path):
    """A comparison keeps one group per run, in order; load picks one by name."""
    runs = {
        name: vv.solve(
            vv.ode.SecondOrderProblem(lambda t, q: -q, [1.0], [0.0]), name, dt=0.1, until=1.0
        ).recording
        for name in ("rk4", "leapfrog", "backward_euler")
    }
    path = vv.io.write_recordings(tmp_path / "all.h5", runs)
    loaded = vv.io.read_recordings(path)
    assert list(loaded) == ["rk4", "leapfrog", "backward_euler"]
    np.testing.assert_array_equal(
        vv.io.load_recording(path, run="leapfrog")["q"], runs["leapfrog"]["q"]
    )
    with pytest.raises(vv.ModelError, match="holds 3 runs"):
        vv.io.load_recording(path)


def test_complex_states_round_trip(tmp_path):
    """The complex test equation y' = iy records complex128."""
    problem = vv.ode.FirstOrderProblem(lambda t, y: 1j * y, [1.0 + 0j])
    recording = vv.solve(problem, "rk4", dt=0.1, until=1.0).recording
    loaded = vv.io.load_recording(vv.io.save_recording(recording, tmp_path / "c.h5"))
    assert loaded["y"].dtype == np.complex128
    np.testing.assert_array_equal(loaded["y"], recording["y"])


def test_a_failed_write_leaves_no_file(tmp_path, monkeypatch):
    """An exception while writing removes the temporary file and keeps the old target."""
    target = tmp_path / "run.h5"
    target.write_bytes(b"previous")
    recording = _solution().recording
    recording.attrs["unserialisable"] = object()
    with pytest.raises(TypeError):
        vv.io.save_recording(recording, target)
    assert target.read_bytes() == b"previous"
    assert os.listdir(tmp_path) == ["run.h5"]


def test_not_a_recording_is_refused(tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as file:
        file.attrs["format"] = "something else"
    with pytest.raises(vv.ModelError, match="not a visviva recording"):
        vv.io.load_recording(other)
    with pytest.raises(vv.ModelError, match="does not exist"):
        vv.io.load_recording(tmp_path / "missing.h5")
    text = tmp_path / "text.h5"
    text.write_text("hello")
    with pytest.raises(vv.ModelError, match="not an HDF5 file"):
        vv.io.load_recording(text)


def test_a_diverged_run_keeps_its_frames(tmp_path):
    """The frames before a blow-up are saved with success = False and the reason."""
    problem = vv.ode.SecondOrderProblem(lambda t, q: -1e4 * q, [1.0], [0.0])
    solution = vv.solve(problem, "explicit_euler", dt=0.01, until=100.0, record_every=10)
    loaded = vv.io.load_recording(vv.io.save_recording(solution.recording, tmp_path / "failed.h5"))
    assert loaded.attrs["success"] is False
    assert "diverged" in loaded.attrs["message"]
    assert loaded.frames == solution.recording.frames > 1
