"""Entity kinds as plugins: one registry, one folder per kind, a generic model.

Each built-in kind lives in ``src/visviva/entities/<kind>/`` (its table and builder method in
``schema.py``, its build hooks in ``build.py``) and is one line of the registry; the model's
build, the builder and the scene's validation go over the registry, so that adding a kind is a
folder and a registry line, with no edit to ``model/``.
"""

from __future__ import annotations

import ast
import inspect
import typing
from pathlib import Path

import pytest

import visviva as vv
from visviva.entities import BUILT_IN, ENTITY_KINDS, EntityMethods, KindBuild
from visviva.model.scene import Scene

SOURCE = Path(vv.__file__).parent
KINDS = [kind.name for kind in BUILT_IN]


@pytest.mark.parametrize("kind", KINDS)
def test_each_builder_method_takes_exactly_its_tables_fields(kind):
    """One home per field: ``add_<kind>``'s keywords are the fields of the kind's table (its
    ``type`` aside), typed, with no ``**kwargs``, so a renamed field is renamed in both."""
    signature = inspect.signature(getattr(vv.SceneBuilder, f"add_{kind}"))
    parameters = {n: p for n, p in signature.parameters.items() if n != "self"}
    assert all(p.kind is not p.VAR_KEYWORD for p in parameters.values())
    assert all(p.annotation is not p.empty for p in parameters.values())
    assert set(parameters) == set(ENTITY_KINDS.get(kind).schema.model_fields) - {"type"}


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_is_a_folder_of_its_own(kind):
    """Its table and builder method in ``schema.py``, its hooks in ``build.py``; its table is
    tagged with its name and may be named."""
    folder = SOURCE / "entities" / kind
    assert (folder / "schema.py").is_file() and (folder / "build.py").is_file()
    entity = ENTITY_KINDS.get(kind)
    assert isinstance(entity.hooks, KindBuild)
    assert typing.get_args(entity.schema.model_fields["type"].annotation) == (kind,)
    assert not entity.schema.model_fields["name"].is_required()
    assert entity.summary
    assert any(f"add_{kind}" in vars(base) for base in EntityMethods.__mro__)


def test_the_model_knows_no_kind_but_the_state_blocks():
    """No module of ``model/`` imports a kind's folder — but the named systems', whose
    coordinates are a block of the state layout — so adding a kind edits nothing there."""
    found = []
    for path in (SOURCE / "model").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 2:
                parts = node.module.split(".")
                if parts[0] == "entities" and len(parts) > 1 and parts[1] in KINDS:
                    found.append((path.name, node.module))
    assert {module for _, module in found} <= {"entities.system.block", "entities.system.build"}


def test_the_scene_schema_and_its_errors_go_over_the_registry():
    schema = Scene.model_json_schema()
    mapping = schema["properties"]["entities"]["items"]["discriminator"]["mapping"]
    assert sorted(mapping) == sorted(ENTITY_KINDS.names())
    with pytest.raises(vv.SceneError) as refusal:
        vv.io.parse_scene('[[entities]]\ntype = "clth"\n')
    assert "unknown entity type. Did you mean 'cloth'?" in str(refusal.value)
    with pytest.raises(vv.SceneError, match=r"entities\[0\]\.type: unknown entity type 'clth'"):
        vv.SceneBuilder().add("clth")


def test_an_entity_table_is_located_and_explained_as_before():
    """A kind's table is validated by its schema, located at the entity's index and field."""
    with pytest.raises(vv.SceneError) as refusal:
        vv.io.parse_scene(
            '[[entities]]\ntype = "cloth"\nresolution = [3, 3]\nstiffness = "x"\nbendng = 1.0\n'
        )
    text = str(refusal.value)
    assert "entities[0].stiffness: must be a valid number" in text
    assert "entities[0].bendng: unknown key. Did you mean 'bending'?" in text


def test_the_build_runs_the_kinds_finish_in_the_registry_order():
    """The colliders' stage is made before the sphere–sphere contacts' (which solve the
    colliders with them), whatever the scene's order; the stages then run by phase."""
    builder = vv.SceneBuilder()
    builder.add_particle_collisions(restitution=0.5)
    builder.add_particle_cloud(20, size=(1.0, 1.0, 1.0), name="balls")
    builder.add_collider("plane", point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
    model = builder.build()
    names = [type(s).__name__ for s in model.stages]
    assert names == ["ParticleContacts", "ParticleCollisions"]
    contacts = model.stages[0]
    assert contacts.colliders is model.stages[1]
