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


# --- format 1: the names before the recordings took the state's ---------------------------------


def _scene(kind: str) -> vv.SceneBuilder:
    builder = vv.SceneBuilder(name=kind)
    builder.set_integration(method="rk4", dt=0.01, duration=0.2)
    if kind in ("particles and a pendulum", "an emitter and a pendulum"):
        builder.add_system("pendulum", {"theta0": 0.3})
    if kind == "particles and a pendulum":
        builder.add_particles(
            [[0.0, 1.0, 0.0], [1.0, 2.0, 0.0]], velocities=[[1.0, 0, 0], [0, 1.0, 0]],
            radius=[0.1, 0.2], color=(0.9, 0.2, 0.1),
        )  # fmt: skip
    if kind == "an emitter and a pendulum":
        builder.add_emitter(
            rate=100.0, speed=[1.0, 2.0], spread_deg=20.0, lifetime=[0.05, 0.1],
            particle_radius=[0.01, 0.03], color_ramp=[[0.0, 1.0, 1.0, 0.0], [1.0, 1.0, 0.0, 0.0]],
            size_ramp=[[0.0, 1.0], [1.0, 0.2]],
        )  # fmt: skip
    if kind == "a Kepler orbit":
        builder.add_system("kepler", {"eccentricity": 0.3})
    return builder


def _format_1(recording: vv.Recording) -> vv.Recording:
    """``recording`` under the names of format 1: the particles and the systems' points as one
    ``points`` array, with ``velocities``, ``alive``, ``radius`` and ``color`` over them."""
    fields, static = dict(recording.fields), dict(recording.static)
    n = fields["particle_position"].shape[1] if "particle_position" in fields else 0
    count = n + (fields["system_points"].shape[1] if "system_points" in fields else 0)

    def joined(own, theirs, per_frame):
        parts = [p for p in (own, theirs) if p is not None]
        return np.concatenate(parts, axis=1 if per_frame else 0)

    fields["points"] = joined(
        fields.pop("particle_position", None), fields.pop("system_points", None), True
    )
    fields["velocities"] = joined(
        fields.pop("particle_velocity", None), fields.pop("system_velocity", None), True
    )
    if "particle_alive" in fields:
        ones = np.ones((recording.frames, count - n), dtype=bool)
        fields["alive"] = joined(fields.pop("particle_alive"), ones, True)
    for name in ("radius", "color"):
        theirs = static.pop(f"system_{name}", None)
        if f"particle_{name}" in fields:
            own = fields.pop(f"particle_{name}")
            if theirs is not None:
                theirs = np.broadcast_to(theirs, (recording.frames, *theirs.shape)).astype(
                    own.dtype
                )
            fields[name] = joined(own, theirs, True)
        elif f"particle_{name}" in static or theirs is not None:
            static[name] = joined(static.pop(f"particle_{name}", None), theirs, False)
    if "particle_mass" in static:
        static["mass"] = static.pop("particle_mass")
    units = {"points": "m", "velocities": "m/s", "radius": "m", "mass": "kg"}
    return vv.Recording(recording.time, fields, units=units, attrs=recording.attrs, static=static)


@pytest.mark.parametrize(
    "kind", ["particles and a pendulum", "an emitter and a pendulum", "a Kepler orbit"]
)
def test_a_format_1_file_opens_with_the_new_names(tmp_path, kind):
    """A file written with the names of format 1 reads as the same run recorded today: the
    same fields and static arrays under the state's names, and the same geometry."""
    recording = vv.Simulation(_scene(kind).build()).record(until=0.2)
    path = vv.io.save_recording(_format_1(recording), tmp_path / "old.h5")
    with h5py.File(path, "r+") as file:
        file.attrs["format_version"] = 1
    loaded = vv.io.load_recording(path)
    assert set(loaded.fields) == set(recording.fields)
    assert set(loaded.static) == set(recording.static)
    for name in recording.fields:
        np.testing.assert_array_equal(loaded[name], recording[name], err_msg=name)
        assert loaded[name].dtype == recording[name].dtype, name
    for name in recording.static:
        np.testing.assert_array_equal(loaded.static[name], recording.static[name], err_msg=name)
    for name in ("particle_position", "system_points", "particle_radius", "particle_mass"):
        if name in recording.fields or name in recording.static:
            assert loaded.units[name] == recording.units[name], name
    old, new = loaded.geometry(), recording.geometry()
    for name in ("points", "radius", "color", "alive", "edges"):
        expected = getattr(new, name)
        if expected is None:
            assert getattr(old, name) is None, name
        else:
            np.testing.assert_array_equal(getattr(old, name), expected, err_msg=name)


def test_the_drawn_points_are_the_particles_then_the_systems_points():
    recording = vv.Simulation(_scene("particles and a pendulum").build()).record(until=0.1)
    geometry = recording.geometry()
    assert geometry.points.shape[1] == 4  # two particles, the pendulum's pivot and bob
    np.testing.assert_array_equal(geometry.points[:, :2], recording["particle_position"])
    np.testing.assert_array_equal(geometry.points[:, 2:], recording["system_points"])
    np.testing.assert_array_equal(geometry.radius[:2], [0.1, 0.2])
    assert geometry.radius[2] == geometry.radius[3] == pytest.approx(0.15)  # the median
    np.testing.assert_array_equal(geometry.edges, [[2, 3]])
    assert recording.drawn_velocity().shape[1] == 2  # the pendulum's points have none
    alone = vv.Recording(recording.time, {"particle_position": recording["particle_position"],
                                          "system_points": recording["system_points"]},
                         static={"particle_radius": np.array([0.1, 0.2])})  # fmt: skip
    with pytest.raises(vv.ModelError, match="`particle_radius` needs `system_radius` beside it"):
        alone.geometry()
