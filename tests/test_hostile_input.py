"""Hostile input: every file, number and call a user (or a fuzzer) can throw is refused cleanly.

The promise: a refusal is a :class:`~visviva.errors.ModelError` (exit status 2 from the CLI)
that names the field and the value; never a traceback, never a hang, never a file left behind;
and what ``visviva validate`` accepts, ``visviva run`` runs.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import os
import sys
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import visviva as vv
from visviva.cli.main import main
from visviva.io.job import STAGING_PREFIX

EXAMPLES = Path(__file__).parents[1] / "examples" / "scenes"
PENDULUM = (EXAMPLES / "pendulum.toml").read_text()


def refused(path: Path, *fragments: str) -> vv.SceneError:
    """``load_model(path)`` (what ``validate`` and ``run`` do first) refuses with fragments."""
    with pytest.raises(vv.SceneError) as caught:
        vv.load_model(path)
    text = str(caught.value)
    for fragment in fragments:
        assert fragment in text, text
    return caught.value


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# Files that are not scene files.


@pytest.mark.parametrize(
    "name, text",
    [
        ("deep.toml", PENDULUM + "\n[output]\nformats = " + "[" * 500 + "]" * 500 + "\n"),
        ("deep.json", '{"scene": {"name": ' + "[" * 5000 + "]" * 5000 + "}}"),
        ("dotted.toml", PENDULUM + "\n" + ".".join(f"k{i}" for i in range(1000)) + " = 1\n"),
        ("dotted.toml", ".".join(f"k{i}" for i in range(50_000)) + " = 1\n"),
        ("quoted.toml", '"a".' * 1000 + "b = 1\n"),
        ("inline.toml", "x = " + "{a = " * 300 + "1" + "}" * 300 + "\n"),
        (
            "mesh.toml",
            (EXAMPLES / "flag.toml")
            .read_text()
            .replace("triangles = [[0, 1, 7]", "triangles = " + "[" * 20 + "0" + "]" * 20 + " #"),
        ),
    ],
)
def test_deep_nesting_is_refused_at_once(tmp_path, name, text):
    refused(write(tmp_path, name, text), "nest")


def test_an_integer_beyond_python_s_digit_limit_is_refused(tmp_path):
    text = PENDULUM.replace("duration = 10.0", "duration = 1" + "0" * 4300)
    refused(write(tmp_path, "big.toml", text), "more than 4300 digits")
    refused(write(tmp_path, "big.json", '{"integration": {"dt": 1' + "0" * 5000 + "}}"), "4300")


def test_special_files_are_refused_without_reading_them(tmp_path):
    (tmp_path / "dir.toml").mkdir()
    refused(tmp_path / "dir.toml", "a directory")
    os.mkfifo(tmp_path / "fifo.toml")  # opening it to read would block until a writer comes
    refused(tmp_path / "fifo.toml", "not a regular file")
    (tmp_path / "zero.toml").symlink_to("/dev/zero")  # its size says 0; it never ends
    refused(tmp_path / "zero.toml", "not a regular file")


def test_a_file_above_the_limit_is_refused_after_reading_only_the_limit(tmp_path):
    from visviva.io.scene_files import MAX_SCENE_BYTES

    path = tmp_path / "huge.toml"
    with path.open("wb") as handle:
        handle.truncate(MAX_SCENE_BYTES + 1)
    refused(path, f"larger than {MAX_SCENE_BYTES} bytes")


# Values that validate used to accept and run refused (or crashed on).


def replaced(old: str, new: str, source: str = PENDULUM) -> str:
    assert old in source
    return source.replace(old, new)


CLUSTER = (EXAMPLES / "star_cluster.toml").read_text().replace("bodies = 20000", "bodies = 50")
KEPLER = (EXAMPLES / "kepler.toml").read_text()
OSCILLATOR = replaced(
    'system = "pendulum"\nparameters = { length = 1.0, theta0 = 1.0, omega0 = 0.0 }',
    'system = "oscillator"\nparameters = { omega = 1e200 }',
)


@pytest.mark.parametrize(
    "text, fragments",
    [
        (replaced("seed = 1", "seed = -1", CLUSTER), ["parameters.seed", "at least 0"]),
        (OSCILLATOR, ["entities[0].parameters", "overflow"]),
        (replaced("semi_major_axis = 1.0", "semi_major_axis = 1e103", KEPLER), ["overflow"]),
        (replaced("eccentricity = 0.5", "eccentricity = 1", KEPLER), ["eccentricity", "below 1"]),
        (replaced("length = 1.0", "length = 1e200"), ["entities[0].parameters", "1.8e308"]),
        (PENDULUM + "\n[world]\ngravity = [0.0, 0.0, 0.0]\n", ["world.gravity", "not be zero"]),
        (
            replaced("duration = 10.0", "duration = 10.0\nrecord_every = 18446744073709551616"),
            ["integration.record_every"],
        ),
        (PENDULUM + '\n[output]\nformats = ["gif"]\nfps = 0.001\n', ["output.fps", "GIF"]),
        (PENDULUM + '\n[output]\nformats = ["gif"]\nfps = 60.0\n', ["output.fps", "GIF"]),
        (
            replaced("duration = 10.0", "duration = 1e6") + '\n[output]\nformats = ["mp4"]\n',
            ["output.speed", "more than 1000000"],
        ),
        (replaced("dt = 0.005", 'dt = "0.005"'), ["integration.dt", "'0.005'"]),
        (replaced("duration = 10.0", "duration = true"), ["integration.duration", "True"]),
        (replaced("dt = 0.005", "dt = 1e-10"), ["integration.dt", "limit"]),
    ],
)
def test_validate_refuses_what_run_would_refuse(tmp_path, text, fragments):
    path = write(tmp_path, "scene.toml", text)
    error = refused(path, *fragments)
    assert all(p.line is not None for p in error.problems), error  # each with its line


HAIR = (EXAMPLES / "hair.toml").read_text()
TRUSS = (EXAMPLES / "truss.toml").read_text()
FLAG = (EXAMPLES / "flag.toml").read_text()
SOFT_CUBE = (EXAMPLES / "soft_cube.toml").read_text()
FLAG_TRIANGLES = "triangles = [[0, 1, 7], [0, 7, 6],"


@pytest.mark.parametrize(
    "text, fragments",
    [
        (replaced("[-0.0911, 0.6405", "[nan, 0.6405", SOFT_CUBE), ["vertices[0][0]", "finite"]),
        (replaced("[-0.0911, 0.6405", "[-inf, 0.6405", SOFT_CUBE), ["vertices[0][0]", "finite"]),
        (replaced("[-0.0911, 0.6405", "[-1e300, 0.6405", SOFT_CUBE), ["entities[0]", "a float"]),
        (replaced("[0.019, 1.500", "[1e308, 1.500", HAIR), ["entities[1].points", "a float"]),
        (replaced("[0.25, 1.4, 0.0]", "[0.25, 1e200, 0.0]", TRUSS), ["entities[0]", "a float"]),
        (replaced("[0, 5, 3, 6]", "[0, 5, 3, 18446744073709551616]", SOFT_CUBE), ["less than"]),
        (replaced("[0, 5, 3, 6]", "[0, 5, 3, 6.0]", SOFT_CUBE), ["tetrahedra[0][3]", "integer"]),
        (replaced("[0, 5, 3, 6]", "[0, 5, 6, 3]", SOFT_CUBE), ["tetrahedra[0]", "swap two"]),
        (replaced(FLAG_TRIANGLES, "triangles = [", FLAG), ["vertices[0]", "in no triangle"]),
        (replaced("pairs = [[0, 1],", "pairs = [[0, 0],", TRUSS), ["pairs[0]", "to itself"]),
        (
            replaced("points = [[-0.100", "points = [] #", HAIR),
            ["entities[0].points", "at least 2"],
        ),
        (
            replaced("pairs = [[0, 1], [1, 2]", "pairs = [] # [1, 2]", TRUSS),
            ["pairs", "at least 1"],
        ),
        (replaced("mass = [2.0, 2.0, 20.0,", "mass = [2.0, 20.0,", TRUSS), ["mass", "8 entries"]),
        (replaced("pinned = [0, 6, 12, 18]", "pinned = [24]", FLAG), ["pinned index 24"]),
    ],
)
def test_deformable_bodies_refuse_hostile_values_at_their_line(tmp_path, text, fragments):
    error = refused(write(tmp_path, "scene.toml", text), *fragments)
    assert all(p.line is not None for p in error.problems), error


def test_a_count_given_as_text_is_refused(tmp_path):
    text = (EXAMPLES / "falling_particles.toml").read_text().replace("count = 2000", 'count = "3"')
    refused(write(tmp_path, "scene.toml", text), "entities[0].count", "'3'")


# Nothing left behind.


def test_a_demo_that_fails_midway_leaves_nothing(tmp_path):
    from visviva.demos import demos

    def run_then_fail(output, duration):
        output.stage("equations.tex").write_text("half")
        raise vv.ModelError("stopped for the test")

    demo = demos()["pendulum"]
    vv.demos.register_demo(dataclasses.replace(demo, run=run_then_fail), replace=True)
    try:
        with pytest.raises(vv.ModelError, match="stopped for the test"):
            vv.demos.run_demo("pendulum", tmp_path / "out")
    finally:
        vv.demos.register_demo(demo, replace=True)
    assert list((tmp_path / "out").iterdir()) == []


def test_an_output_that_fails_after_the_run_keeps_the_recording(tmp_path, monkeypatch):
    import visviva.viz.outputs as outputs

    def fail(recording, path, fps, *playback):
        raise vv.ModelError("cannot frame this scene")

    monkeypatch.setattr(outputs, "write_output", fail)
    builder = vv.SceneBuilder(name="drop")
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=0.1)
    builder.add_particles(positions=[[0.0, 1.0, 0.0]])
    with pytest.raises(vv.ModelError, match=r"animation\.mp4 was not written") as caught:
        vv.run_scene(builder.build(), tmp_path, formats=["mp4"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["recording.h5", "summary.json"]
    assert caught.value.report.summary["warnings"][0]["kind"] == "output"


# Malformed recordings.


def _malformed(tmp_path: Path, damage: str) -> Path:
    path = tmp_path / f"{damage}.h5"
    with h5py.File(path, "w") as file:
        file.attrs["format"] = "visviva.recording"
        file.attrs["format_version"] = 1
        if damage == "no-runs":
            return path
        file.attrs["runs"] = '["run"]'
        group = file.create_group("run")
        group.create_dataset("time", data=np.arange(3.0))
        if damage == "no-fields":
            return path
        group.create_group("fields").create_dataset("points", data=np.zeros((2, 1, 3)))
    return path


@pytest.mark.parametrize("damage", ["no-runs", "no-fields", "short-field"])
def test_a_malformed_recording_is_refused_by_every_reader(tmp_path, damage, monkeypatch, capsys):
    path = _malformed(tmp_path, damage)
    with pytest.raises(vv.ModelError, match="damaged visviva recording"):
        vv.io.load_recording(path)
    for command in (["export", path, "--to", "usd"], ["view", path], ["plot", path]):
        monkeypatch.setattr(sys, "argv", ["visviva", *map(str, command)])
        with pytest.raises(SystemExit) as exit_:
            main()
        assert exit_.value.code == 2
        assert "damaged visviva recording" in capsys.readouterr().err


# The Python API.


def test_python_api_refuses_runs_that_would_never_end():
    problem = vv.ode.FirstOrderProblem(lambda t, y: -y, [1.0, 0.0])
    with pytest.raises(vv.ModelError, match="substep"):
        vv.solve(problem, method="rk4", dt=0.1, until=1.0, substeps=10**30)
    with pytest.raises(vv.ModelError, match="limit is 1e"):
        vv.solve(problem, method="rk4", dt=1e-10, until=1.0)
    with pytest.raises(vv.ModelError, match="`atol` must be positive"):
        vv.solve(problem, method="dopri5", until=1.0, atol=0.0)


def test_a_function_that_changes_its_shape_is_named():
    problem = vv.ode.FirstOrderProblem(lambda t, y: -y if t == 0 else np.zeros(3), [1.0, 0.0])
    with pytest.raises(vv.ModelError, match=r"returned shape \(3,\) at t = 0\.05"):
        vv.solve(problem, method="rk4", dt=0.1, until=1.0)


# Hypothesis: mutated example scenes are refused cleanly or run; validate and run agree.

HOSTILE_VALUES = st.sampled_from(
    [
        -1,
        0,
        -0.0,
        1e-300,
        1e200,
        1.7976931348623157e308,
        -1.7976931348623157e308,
        2**64,
        10**30,
        "3",
        "",
        True,
        [],
        [[[[[[1.0]]]]]],
        {},
    ]
)


def _paths(data, prefix=()):
    if isinstance(data, dict):
        for key, value in data.items():
            yield (*prefix, key), data
            yield from _paths(value, (*prefix, key))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            yield (*prefix, index), data
            yield from _paths(value, (*prefix, index))


def _base_scenes() -> list[dict]:
    scenes = []
    for path in sorted(EXAMPLES.glob("*.toml")):
        data = tomllib.loads(path.read_text())
        for entity in data["entities"]:
            parameters = entity.get("parameters", {})
            if "bodies" in parameters:
                parameters["bodies"] = 40  # the same code paths, at a size a fuzzer can afford
        scenes.append(data)
    return scenes


BASES = _base_scenes()


HOSTILE_NUMBERS = st.sampled_from(
    [-1, 0, -0.0, 1e-300, 1e-12, 1e12, 1e200, 1.7976931348623157e308, -1e308, 2**62, 7]
)


def _mutated(base: int, edits, numbers_only: bool) -> dict:
    data = copy.deepcopy(BASES[base])
    for pick, value in edits:
        paths = [
            (path, container)
            for path, container in _paths(data)
            if not numbers_only
            or (
                isinstance(container[path[-1]], (int, float))
                and not isinstance(container[path[-1]], bool)
            )
        ]
        if paths:
            path, container = paths[pick % len(paths)]
            container[path[-1]] = copy.deepcopy(value)
    return data


def _refused_cleanly_or_runs(folder: Path, data: dict) -> None:
    """The property: a SceneError naming its problems, or a run that writes its outputs (or
    stops with a SimulationError after writing them), leaving no staging behind."""
    scene = folder / "scene.json"  # JSON carries every mutated value (TOML has no empty key...)
    scene.write_text(json.dumps(data))
    try:
        model = vv.load_model(scene)
    except vv.SceneError as error:
        assert error.problems and all(p.message for p in error.problems)
        return
    out = folder / "out"
    # A mutated scene may blow up: that is a result, reported after its recording is written.
    with contextlib.suppress(vv.SimulationError):
        settings = model.integration
        vv.run_scene(model, out, duration=min(settings.duration, 3 * settings.dt))
    assert (out / "summary.json").exists() and (out / "recording.h5").exists()
    assert not list(out.glob(f"{STAGING_PREFIX}*"))


SETTINGS = settings(
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.shrink],
)


@SETTINGS
@given(
    base=st.integers(0, len(BASES) - 1),
    edits=st.lists(st.tuples(st.integers(0, 10**6), HOSTILE_VALUES), min_size=1, max_size=3),
)
def test_scenes_mutated_anywhere_are_refused_cleanly_or_run(tmp_path_factory, base, edits):
    _refused_cleanly_or_runs(tmp_path_factory.mktemp("fuzz"), _mutated(base, edits, False))


@SETTINGS
@given(
    base=st.integers(0, len(BASES) - 1),
    edits=st.lists(st.tuples(st.integers(0, 10**6), HOSTILE_NUMBERS), min_size=1, max_size=2),
)
def test_scenes_with_extreme_numbers_are_refused_cleanly_or_run(tmp_path_factory, base, edits):
    _refused_cleanly_or_runs(tmp_path_factory.mktemp("fuzz"), _mutated(base, edits, True))


@pytest.mark.slow
@settings(SETTINGS, max_examples=1500)
@given(
    base=st.integers(0, len(BASES) - 1),
    edits=st.lists(st.tuples(st.integers(0, 10**6), HOSTILE_VALUES), min_size=1, max_size=4),
)
def test_many_scenes_mutated_anywhere(tmp_path_factory, base, edits):
    """The property above at length (``pytest -m slow``): several minutes."""
    _refused_cleanly_or_runs(tmp_path_factory.mktemp("fuzz"), _mutated(base, edits, False))


@pytest.mark.slow
@settings(SETTINGS, max_examples=1500)
@given(
    base=st.integers(0, len(BASES) - 1),
    edits=st.lists(st.tuples(st.integers(0, 10**6), HOSTILE_NUMBERS), min_size=1, max_size=3),
)
def test_many_scenes_with_extreme_numbers(tmp_path_factory, base, edits):
    """The property above at length (``pytest -m slow``)."""
    _refused_cleanly_or_runs(tmp_path_factory.mktemp("fuzz"), _mutated(base, edits, True))
