"""Bad scenes: every case exits 2 from ``visviva run``, names the path and value, writes nothing."""

from __future__ import annotations

import copy
import json
import sys
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import visviva as vv
from visviva.cli.main import main
from visviva.entities import ENTITY_KINDS
from visviva.entities.system.schema import RENAMED_PARAMETERS
from visviva.entities.system.systems import SYSTEMS
from visviva.io.scene_files import MAX_SCENE_BYTES, dump_scene, parse_scene
from visviva.model import build_model

VALID = """\
[scene]
name = "valid"

[integration]
method = "symplectic_euler"
dt = 0.01
duration = 0.1

[[entities]]
type = "particles"
name = "ball"
positions = [[0.0, 1.0, 0.0]]
mass = 1.0

[[entities]]
type = "particle_cloud"
name = "cloud"
count = 10
"""


def run_cli(monkeypatch, capsys, tmp_path, text: str | bytes, suffix: str = ".toml"):
    """``visviva run`` on the scene ``text``; returns (status, stderr, output directory)."""
    scene = tmp_path / f"scene{suffix}"
    if isinstance(text, bytes):
        scene.write_bytes(text)
    else:
        scene.write_text(text)
    output = tmp_path / "out"
    monkeypatch.setattr(sys, "argv", ["visviva", "run", str(scene), "-o", str(output)])
    try:
        main()
        status = 0
    except SystemExit as exit_:
        status = exit_.code
    return status, capsys.readouterr().err, output


def refused(monkeypatch, capsys, tmp_path, text, *fragments: str, suffix: str = ".toml") -> str:
    status, err, output = run_cli(monkeypatch, capsys, tmp_path, text, suffix)
    assert status == 2, err
    assert "Traceback" not in err
    missing = [f for f in fragments if f not in err]
    assert not missing, f"{err!r} does not mention {missing}"
    assert not output.exists() or not any(output.rglob("*")), "a refused scene wrote files"
    return err


def replaced(old: str, new: str) -> str:
    assert old in VALID
    return VALID.replace(old, new, 1)


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        (
            replaced("mass = 1.0", "mass = -2.0"),
            ["entities[0].mass", "greater than 0", "-2.0", ":13:"],
        ),
        (replaced("mass = 1.0", "mass = 0.0"), ["entities[0].mass", "greater than 0", "0.0"]),
        (replaced("mass = 1.0", "mass = nan"), ["entities[0].mass", "finite", "nan"]),
        (replaced("mass = 1.0", "mass = inf"), ["entities[0].mass", "finite", "inf"]),
        (replaced("[0.0, 1.0, 0.0]", "[0.0, 1e400, 0.0]"), ["positions[0][1]", "finite", "inf"]),
        (replaced("dt = 0.01", "dt = 0.0"), ["integration.dt", "greater than 0", "0.0"]),
        (replaced("dt = 0.01", "dt = -0.01"), ["integration.dt", "-0.01"]),
        (replaced("dt = 0.01", "dt = 1.0"), ["integration.dt", "longer than the duration", "1.0"]),
        (replaced("duration = 0.1", "duration = -5.0"), ["integration.duration", "-5.0"]),
        (replaced("mass = 1.0", "masss = 1.0"), ["entities[0].masss", "unknown key", "'mass'"]),
        (replaced("[integration]", "[integraton]"), ["integraton", "unknown key", "'integration'"]),
        (replaced("mass = 1.0", 'mass = "heavy"'), ["entities[0].mass", "'heavy'"]),
        (replaced("count = 10", "count = 2.5"), ["entities[1].count", "2.5"]),
        (replaced('name = "cloud"', 'name = "ball"'), ["entities[1].name", "duplicate", "'ball'"]),
        (replaced('type = "particle_cloud"', 'type = "partcle_cloud"'), ["entities[1]", "type"]),
        (replaced("count = 10", "count = 10000000000000"), ["entities[1].count", "10000000000000"]),
        (replaced('method = "symplectic_euler"', 'method = "rk5"'), ["integration.method", "rk4"]),
        (replaced('method = "symplectic_euler"', 'method = "dopri5"'), ["fixed-step", "dopri5"]),
        ('[scene]\nname = "empty"\n', ["entities", "empty"]),
        (replaced("mass = 1.0", "mass = [1.0, 2.0]"), ["entities[0].mass", "2 entries for 1"]),
        (
            VALID + '\n[[entities]]\ntype = "system"\nsystem = "test-equation"\n',
            ["entities[2]", "test equation", "scene of its own"],
        ),
    ],
    ids=[
        "negative-mass",
        "zero-mass",
        "nan",
        "inf",
        "1e400",
        "zero-dt",
        "negative-dt",
        "dt-above-duration",
        "negative-duration",
        "unknown-key",
        "unknown-table",
        "wrong-type",
        "fractional-count",
        "duplicate-name",
        "unknown-entity-type",
        "absurd-count",
        "unknown-method",
        "adaptive-method",
        "empty-scene",
        "list-length",
        "first-order-system-mixed-with-particles",
    ],
)
def test_bad_scene_is_refused(monkeypatch, capsys, tmp_path, text, fragments):
    refused(monkeypatch, capsys, tmp_path, text, *fragments)


def test_every_problem_is_reported_at_once(monkeypatch, capsys, tmp_path):
    text = VALID.replace("mass = 1.0", "mass = -1.0").replace("count = 10", "count = 0")
    err = refused(monkeypatch, capsys, tmp_path, text.replace("dt = 0.01", "dtt = 0.01"))
    assert "3 problems" in err
    assert all(p in err for p in ("entities[0].mass", "entities[1].count", "integration.dtt"))


def test_unknown_system_and_parameter_suggest_names(monkeypatch, capsys, tmp_path):
    text = '[[entities]]\ntype = "system"\nsystem = "pendulm"\n'
    refused(monkeypatch, capsys, tmp_path, text, "entities[0].system", "'pendulum'")
    text = '[[entities]]\ntype = "system"\nsystem = "pendulum"\nparameters = { lenght = 2.0 }\n'
    refused(monkeypatch, capsys, tmp_path, text, "parameters.lenght", "'length'", ":4:")


def test_toml_syntax_error_gives_line_and_column(monkeypatch, capsys, tmp_path):
    text = VALID.replace("dt = 0.01", "dt = = 0.01")
    refused(monkeypatch, capsys, tmp_path, text, "TOML syntax error", "line 6", "column")


def test_json_scene_errors_carry_lines(monkeypatch, capsys, tmp_path):
    scene = parse_scene(VALID)
    text = dump_scene(scene, "json").replace('"mass": 1.0', '"mass": -1.0')
    err = refused(monkeypatch, capsys, tmp_path, text, "entities[0].mass", "-1.0", suffix=".json")
    line = next(i for i, row in enumerate(text.splitlines(), 1) if '"mass": -1.0' in row)
    assert f":{line}:" in err
    refused(monkeypatch, capsys, tmp_path, "{ not json", "JSON syntax error", suffix=".json")


def test_non_utf8_file_is_refused(monkeypatch, capsys, tmp_path):
    text = VALID.encode().replace(b'"valid"', b'"caf\xe9"')
    refused(monkeypatch, capsys, tmp_path, text, "not UTF-8", "0xe9", ":2:")


def test_file_above_the_size_limit_is_refused_unread(monkeypatch, capsys, tmp_path):
    text = VALID + "# " + "x" * MAX_SCENE_BYTES + "\n"
    refused(monkeypatch, capsys, tmp_path, text, "bytes", str(MAX_SCENE_BYTES))


def test_wrong_suffix_and_missing_file(monkeypatch, capsys, tmp_path):
    refused(monkeypatch, capsys, tmp_path, VALID, ".toml or .json", suffix=".yaml")
    monkeypatch.setattr(sys, "argv", ["visviva", "validate", str(tmp_path / "nope.toml")])
    with pytest.raises(SystemExit) as exit_:
        main()
    assert exit_.value.code == 2
    assert "cannot read" in capsys.readouterr().err


def test_existing_outputs_need_force(monkeypatch, capsys, tmp_path):
    status, err, output = run_cli(monkeypatch, capsys, tmp_path, VALID)
    assert status == 0, err
    before = (output / "recording.h5").stat().st_mtime_ns
    status, err, _ = run_cli(monkeypatch, capsys, tmp_path, VALID)
    assert status == 2 and "--force" in err
    assert (output / "recording.h5").stat().st_mtime_ns == before


# Hypothesis: mutate a valid scene; the only exception allowed is SceneError with a path.

MUTATIONS = st.sampled_from(["delete", "rename", "nan", "negative", "zero", "huge", "string"])
BAD_VALUES = {"nan": float("nan"), "negative": -1, "zero": 0, "huge": 1e308, "string": "x"}


def _keys(data, prefix=()):
    """Every (path, container) pair of the parsed scene."""
    if isinstance(data, dict):
        for key, value in data.items():
            yield (*prefix, key), data
            yield from _keys(value, (*prefix, key))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            yield (*prefix, index), data
            yield from _keys(value, (*prefix, index))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(choices=st.lists(st.tuples(st.integers(0, 10**6), MUTATIONS), min_size=1, max_size=4))
def test_mutated_scenes_fail_only_with_a_located_scene_error(choices):
    data = copy.deepcopy(tomllib.loads(VALID))
    for pick, mutation in choices:
        paths = list(_keys(data))
        if not paths:
            break
        path, container = paths[pick % len(paths)]
        key = path[-1]
        if mutation == "delete":
            del container[key]
        elif mutation == "rename" and isinstance(container, dict):
            container[f"{key}_x"] = container.pop(key)
        elif mutation in BAD_VALUES:
            container[key] = BAD_VALUES[mutation]
    try:
        scene = parse_scene(_to_toml(data))
        build_model(scene)
    except vv.SceneError as error:
        assert error.problems
        for problem in error.problems:
            assert problem.path or problem.message, error
        assert any(p.path for p in error.problems) or "empty" in str(error) or "table" in str(error)


def _to_toml(data) -> str:
    """Write mutated data back as TOML: tables, arrays of tables and inline values."""
    lines = []
    for key, value in data.items():
        if isinstance(value, dict):
            lines.append(f"[{_quoted(key)}]")
            lines += [f"{_quoted(k)} = {_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                lines.append(f"[[{_quoted(key)}]]")
                lines += [f"{_quoted(k)} = {_value(v)}" for k, v in item.items()]
        else:
            lines.insert(0, f"{_quoted(key)} = {_value(value)}")
    return "\n".join(lines) + "\n"


def _quoted(key) -> str:
    import json

    return json.dumps(str(key))


def _value(value) -> str:
    from visviva.io.scene_files import _toml_value

    if isinstance(value, float) and value != value:
        return "nan"
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_quoted(k)} = {_value(v)}" for k, v in value.items()) + "}"
    return _toml_value(value)


def entity(text: str) -> str:
    """The valid scene with one more ``[[entities]]`` table (it becomes entities[2])."""
    return VALID + "\n[[entities]]\n" + text


HAIR = (
    'type = "hair"\npoints = [[0, 0, 0], [0, -1, 0]]\nmass = 0.1\nstiffness = 10.0\nbending = 1.0\n'
)
SPRINGS = 'type = "springs"\npoints = [[0, 0, 0], [1, 0, 0]]\nmass = 1.0\nstiffness = 10.0\n'
CLOTH_MESH = (
    'type = "cloth_mesh"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 0, 1]]\n'
    "areal_density = 0.1\nstiffness = 1.0\n"
)
SOFT_MESH = (
    'type = "soft_mesh"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\ndensity = 1.0\n'
    "stiffness = 1.0\n"
)
OPEN_MESH = """type = "collider"
shape = "mesh"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
triangles = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 1]]
"""


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        (entity('type = "emitter"\nrate = -5.0'), ["entities[2].rate", "-5.0"]),
        (entity('type = "emitter"\nrate = 5.0\nlifetime = 0.0'), ["entities[2].lifetime", "0.0"]),
        (
            entity('type = "emitter"\nrate = 5.0\nlifetime = [2.0, 1.0]'),
            ["entities[2]", "`lifetime`", "low > high"],
        ),
        (entity('type = "emitter"\nspread_deg = 10.0'), ["entities[2]", "emits nothing", "rate"]),
        (
            entity('type = "emitter"\nrate = 5.0\ncapacity = 1000000000'),
            ["entities[2].capacity", "1000000000"],
        ),
        (
            entity('type = "emitter"\nrate = 5.0\ndirection = [0.0, 0.0, 0.0]'),
            ["entities[2]", "`direction`", "zero vector"],
        ),
        (
            entity('type = "emitter"\nrate = 5.0\ncolor_ramp = [[0.5, 1, 0, 0], [0.1, 0, 0, 1]]'),
            ["entities[2]", "color_ramp", "increasing"],
        ),
        (replaced("mass = 1.0", "mass = 1.0\nradius = -0.1"), ["entities[0].radius", "-0.1"]),
        (
            entity('type = "collider"\nshape = "plane"\nrestitution = 1.5'),
            ["entities[2].restitution", "1.5"],
        ),
        (
            entity('type = "collider"\nshape = "plane"\nfriction = -0.2'),
            ["entities[2].friction", "-0.2"],
        ),
        (
            entity('type = "collider"\nshape = "plane"\nnormal = [0.0, 0.0, 0.0]'),
            ["entities[2]", "`normal`", "zero"],
        ),
        (entity('type = "collider"\nshape = "sphere"'), ["entities[2]", "needs `radius`"]),
        (entity(OPEN_MESH), ["entities[2]", "edge"]),
        (
            entity(
                'type = "collider"\nshape = "box"\nsize = [1, 1, 1]\norientation = [2, 0, 0, 0]'
            ),
            ["entities[2]", "orientation", "normalize"],
        ),
        (
            entity('type = "collider"\nshape = "plane"\nstiffness = 10.0'),
            ["entities[2]", "stiffness", "penalty"],
        ),
        (
            entity('type = "force"\nkind = "drag"\ncoefficient = 0.1\ntargets = ["bal"]'),
            ["entities[2].targets[0]", "'bal'", "'ball'"],
        ),
        (entity('type = "force"\nkind = "drgа"\ncoefficient = 0.1'), ["entities[2].kind"]),
        (entity('type = "force"\nkind = "drag"'), ["entities[2]", "needs `coefficient`"]),
        (
            entity('type = "force"\nkind = "drag"\ncoefficient = 0.1\nstrength = 2.0'),
            ["entities[2].strength", "not a parameter of a drag force"],
        ),
        (
            entity(
                'type = "force"\nkind = "attractor"\npoint = [0, 0, 0]\nstrength = 1.0\n'
                "softening = 0.0"
            ),
            ["entities[2]", "softening", "positive"],
        ),
        (
            entity('type = "emitter"\nname = "spray"\nrate = 5.0')
            + '\n[[entities]]\ntype = "force"\nkind = "gravitation"\ntargets = ["spray"]',
            ["entities[3].targets[0]", "born and die"],
        ),
        (entity(HAIR + "pinned = [2]"), ["entities[2]", "pinned index 2", "hair strand"]),
        (entity(HAIR + "torsion = -1.0"), ["entities[2].torsion", "-1.0"]),
        (entity(SPRINGS + "pairs = [[0, 1], [1, 1]]"), ["entities[2].pairs[1]", "to itself"]),
        (
            entity(SPRINGS + "pairs = [[0, 1]]\nrest_length = [1.0, 2.0]"),
            ["entities[2].rest_length", "2 values for 1 springs"],
        ),
        (
            entity(CLOTH_MESH + "triangles = [[0, 1, 2], [2, 1, 0]]"),
            ["entities[2].triangles[1]", "the same vertices"],
        ),
        (
            entity(CLOTH_MESH + "triangles = [[0, 1, 3]]"),
            ["entities[2].triangles[0]", "names a vertex past the 3"],
        ),
        (
            entity(SOFT_MESH + "tetrahedra = [[0, 2, 1, 3]]"),
            ["entities[2].tetrahedra[0]", "inside out", "swap two vertices of tetrahedron 0"],
        ),
        (
            entity(SOFT_MESH.replace("[0, 0, 1]", "[1, 1, 0]") + "tetrahedra = [[0, 1, 2, 3]]"),
            ["entities[2].tetrahedra[0]", "no volume"],
        ),
    ],
    ids=[
        "negative-rate",
        "zero-lifetime",
        "lifetime-range-reversed",
        "emitter-emits-nothing",
        "capacity-above-limit",
        "zero-direction",
        "ramp-out-of-order",
        "negative-radius",
        "restitution-above-one",
        "negative-friction",
        "zero-normal",
        "sphere-without-radius",
        "open-mesh-collider",
        "non-unit-quaternion",
        "stiffness-without-penalty",
        "unknown-target",
        "unknown-force-kind",
        "missing-force-parameter",
        "parameter-of-another-kind",
        "attractor-without-softening",
        "gravitation-among-emitted",
        "hair-pin-past-the-strand",
        "negative-torsion",
        "spring-to-itself",
        "rest-lengths-not-one-per-spring",
        "duplicate-triangle",
        "triangle-index-past-the-vertices",
        "inside-out-tetrahedron",
        "flat-tetrahedron",
    ],
)
def test_bad_particle_entity_is_refused(monkeypatch, capsys, tmp_path, text, fragments):
    refused(monkeypatch, capsys, tmp_path, text, *fragments)


# ------------------------------------------------------------------------------------------
# Renamed fields (issue 26, "One vocabulary"): an old name is refused at its field, naming the
# new one, from a scene file and from the builder alike.

#: A valid entity of each kind with renamed fields, every renamed field given its new name.
RENAMED_ENTITIES: dict[str, dict[str, object]] = {
    "cloth": {
        "resolution": [3, 3],
        "areal_density": 0.2,
        "stiffness": 100.0,
        "bending": 1.0,
    },
    "cloth_mesh": {
        "vertices": [[0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]],
        "triangles": [[0, 1, 2], [0, 2, 3]],
        "areal_density": 0.2,
        "stiffness": 100.0,
        "bending": 1.0,
    },
    "soft_lattice": {"resolution": [2, 2, 2], "stiffness": 100.0},
    "body": {
        "shape": "sphere",
        "radius": 0.1,
        "density": 1000.0,
        "linear_damping_rate": 0.1,
        "angular_damping_rate": 0.2,
    },
    "emitter": {"rate": 10.0, "spread_deg": 15.0},
    "boids": {
        "targets": ["cloud"],
        "radius": 1.0,
        "separation": 0.5,
        "max_speed": 2.0,
        "max_acceleration": 4.0,
        "fov_deg": 270.0,
    },
}
RENAMED_FIELDS = {kind.name: kind.renamed for kind in ENTITY_KINDS.values() if kind.renamed}
RENAMES = [(kind, old, new) for kind, table in RENAMED_FIELDS.items() for old, new in table.items()]


def test_the_rename_table_names_fields_of_the_schemas():
    """Every new name is a field of its kind, no old name is, and every kind is tested."""
    assert set(RENAMED_ENTITIES) == set(RENAMED_FIELDS)
    for kind, old, new in RENAMES:
        fields = ENTITY_KINDS.get(kind).schema.model_fields
        assert new in fields and old not in fields, (kind, old, new)
        assert new in RENAMED_ENTITIES[kind], (kind, new)
    build_model(parse_scene(VALID + "".join(_entity_toml(k, {}, k) for k in RENAMED_ENTITIES)))


def _entity_toml(kind: str, renamed: dict[str, str], name: str = "thing") -> str:
    """The ``[[entities]]`` table of ``RENAMED_ENTITIES[kind]`` called ``name``, its fields
    under their names in ``renamed`` (new → old)."""
    lines = ["", "[[entities]]", f'type = "{kind}"', f'name = "{name}"']
    for key, value in RENAMED_ENTITIES[kind].items():
        lines.append(f"{renamed.get(key, key)} = {json.dumps(value)}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(("kind", "old", "new"), RENAMES, ids=[f"{k}.{o}" for k, o, _ in RENAMES])
def test_an_old_field_name_in_a_scene_file_names_the_new_one(
    monkeypatch, capsys, tmp_path, kind, old, new
):
    text = VALID + _entity_toml(kind, {new: old})
    line = text.splitlines().index(f"{old} = {json.dumps(RENAMED_ENTITIES[kind][new])}") + 1
    err = refused(
        monkeypatch,
        capsys,
        tmp_path,
        text,
        f':{line}: entities[2].{old}: field "{old}" of {kind} "thing" was renamed; '
        f'did you mean "{new}"?',
    )
    assert err.count("entities[2]") == 1, err  # no "missing field" beside it


@pytest.mark.parametrize(("kind", "old", "new"), RENAMES, ids=[f"{k}.{o}" for k, o, _ in RENAMES])
def test_an_old_field_name_in_a_builder_call_names_the_new_one(kind, old, new):
    builder = vv.SceneBuilder()
    builder.add_particle_cloud(10, name="cloud")
    fields = dict(RENAMED_ENTITIES[kind])
    fields[old] = fields.pop(new)
    with pytest.raises(vv.SceneError) as refusal:
        getattr(builder, f"add_{kind}")(**fields)
    assert [(p.path, p.message) for p in refusal.value.problems] == [
        (
            f"entities[1].{old}",
            f'field "{old}" of the {kind} entity was renamed; did you mean "{new}"?',
        )
    ]
    assert len(builder.scene.entities) == 1  # nothing refused was added


def test_an_unnamed_entity_and_a_renamed_system_parameter(monkeypatch, capsys, tmp_path):
    emitter = '\n[[entities]]\ntype = "emitter"\nrate = 5.0\nspread = 10.0\n'
    message = 'field "spread" of the emitter entity was renamed; did you mean "spread_deg"?'
    refused(monkeypatch, capsys, tmp_path, VALID + emitter, f"entities[2].spread: {message}")
    system = (
        '\n[[entities]]\ntype = "system"\nsystem = "constrained-pendulum"\n'
        "parameters = { stabilization = 2.0 }\n"
    )
    refused(
        monkeypatch,
        capsys,
        tmp_path,
        VALID + system,
        'entities[2].parameters.stabilization: parameter "stabilization" of the '
        'constrained-pendulum system was renamed; did you mean "stabilization_rate"?',
    )
    for system, table in RENAMED_PARAMETERS.items():
        for old, new in table.items():
            assert new in SYSTEMS[system].parameters and old not in SYSTEMS[system].parameters
