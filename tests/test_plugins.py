"""Extending visviva from outside: a package's entity kind, registered by its entry point, is
read from scene files, added by the builder, built, run and recorded like the built-in kinds;
a plugin that is wrong is refused with its name and what to fix, and the built-in kinds keep
working (docs/extending.md).

The worked example, ``examples/plugins/visviva-magnetic`` (a uniform magnetic field on charged
particles, the Lorentz force ``q v × B``), is installed with pip into a folder of its own and
run in fresh interpreters that have that folder on their path.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any, ClassVar, Literal

import numpy as np
import pytest
from pydantic import BaseModel

import visviva as vv
from visviva.entities import ENTITY_KINDS, EntityKind, KindBuild, stage_kind
from visviva.errors import ModelError
from visviva.ode.stage import Phase

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = ROOT / "examples" / "plugins" / "visviva-magnetic"
SRC = ROOT / "src"


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example plugin installed (as pip installs any package) into a folder of its own."""
    target = tmp_path_factory.mktemp("plugins")
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--target", str(target), str(PLUGIN)],
        check=True, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    return target


def run_with(paths: list[Path], program: str, *args: str) -> Any:
    """Run ``program`` in a fresh interpreter with ``paths`` first on its path; the JSON it
    prints last."""
    env = {"PYTHONPATH": ":".join(str(p) for p in [*paths, SRC]), "PATH": "/usr/bin:/bin"}
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(program), *args],
        capture_output=True, text=True, timeout=600, env=env | _numba_cache(),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def _numba_cache() -> dict[str, str]:
    import os

    return {k: v for k, v in os.environ.items() if k in ("NUMBA_CACHE_DIR", "HOME")}


CYCLOTRON = """
import json, sys, warnings
import numpy as np
import visviva as vv
warnings.simplefilter("error")  # a plugin left out would warn
model = vv.load_model(sys.argv[1])
sim = vv.Simulation(model)
energy = [sim.energy()]
radius = []
def keep(state, e):
    radius.append(float(np.hypot(*state["particle_position"][0, [0, 2]])))
    energy.append(float(e))
sim.run(until=model.integration.duration, on_frame=keep)
builder = vv.SceneBuilder()
builder.add_particles([[0.0, 0.0, 0.0]], name="ion")
index = builder.add_magnetic_field(field=(0.0, 1.0, 0.0), charge=1.0, targets=["ion"])
import inspect
fields = sorted(inspect.signature(builder.add_magnetic_field).parameters)
print(json.dumps({
    "kinds": list(vv.entities.entity_kinds()),
    "end": sim.state["particle_position"][0].tolist(),
    "radius": [min(radius), max(radius)],
    "energy": [min(energy), max(energy)],
    "index": index,
    "fields": fields,
    "forces": [type(f).__name__ for f in model.forces],
}))
"""


def test_the_example_plugin_runs_a_cyclotron_orbit(installed):
    """q = 2 mC, m = 1 g, B = 0.5 T, v = 1 m/s across the field: a circle of radius
    m v/(q B) = 1 m, one turn in 2π m/(q B) = 2π s (Jackson §12.2). RK4 at ω h = 0.01: the
    orbit closes to its global error, O((ω h)⁴) per unit time; the magnetic force does no work,
    so the kinetic energy ½ m v² = 0.5 mJ stays to RK4's error too."""
    report = run_with([installed], CYCLOTRON, str(PLUGIN / "cyclotron.toml"))
    assert "magnetic_field" in report["kinds"]
    assert report["forces"] == ["MagneticField"]
    np.testing.assert_allclose(report["end"], [1.0, 0.0, 0.0], atol=1e-7)
    low, high = report["radius"]
    assert abs(low - 1.0) < 1e-8 and abs(high - 1.0) < 1e-8
    low, high = report["energy"]
    assert abs(low - 5e-4) < 5e-4 * 1e-9 and abs(high - 5e-4) < 5e-4 * 1e-9
    # The builder offers the kind's method, its keywords the table's fields.
    assert report["index"] == 1
    assert report["fields"] == ["charge", "field", "name", "targets"]


def test_the_cli_runs_and_records_a_plugins_scene(installed, tmp_path):
    program = """
    import json, sys
    from visviva.cli.main import main
    scene, out = sys.argv[1:]
    sys.argv = ["visviva", "run", scene, "-o", out]
    try:
        main()
    except SystemExit as exit_:
        assert not exit_.code, exit_.code
    import visviva as vv
    recording = vv.io.load_recording(out + "/recording.h5")
    print(json.dumps({"frames": len(recording.time), "fields": sorted(recording.fields)}))
    """
    report = run_with([installed], program, str(PLUGIN / "cyclotron.toml"), str(tmp_path))
    assert report["frames"] > 100
    assert "particle_position" in report["fields"] or "points" in report["fields"]


def _plugin_folder(tmp_path: Path, name: str, module: str, entry: str, group: str) -> Path:
    """A folder holding an installed-looking plugin: its module and its dist-info with one
    entry point ``name = entry`` in ``group``."""
    (tmp_path / f"{name}.py").write_text(textwrap.dedent(module))
    info = tmp_path / f"{name}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[{group}]\n{name} = {entry}\n")
    return tmp_path


PROBE = """
import json, warnings
import visviva as vv
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    kinds = list(vv.entities.entity_kinds())
builder = vv.SceneBuilder()
builder.add_cloth((3, 3), stiffness=100.0, pinned=[0])
builder.build()  # the built-in kinds keep working
print(json.dumps({"kinds": kinds, "warnings": [str(w.message) for w in caught]}))
"""


@pytest.mark.parametrize(
    ("module", "entry", "group", "expected"),
    [
        (
            "import no_such_package\n",
            "broken:KIND",
            "visviva.entities",
            "'broken' (broken:KIND, from the package 'broken') was left out: it failed to import "
            "(ModuleNotFoundError: No module named 'no_such_package')",
        ),
        (
            """
         from typing import Literal
         from pydantic import BaseModel
         from visviva.entities import EntityKind, KindBuild
         class Cloth(BaseModel):
             type: Literal["cloth"]
             name: str | None = None
         KIND = EntityKind("cloth", Cloth, "a clash", KindBuild())
         """,
            "clash:KIND",
            "visviva.entities",
            "its kind 'cloth' clashes with a kind already registered",
        ),
        (
            """
         from typing import Literal
         from pydantic import BaseModel
         from visviva.entities import force_kind
         class Table(BaseModel):
             type: Literal["springy"]
             name: str | None = None
         class Springy:
             conservative = True
             velocity_dependent = False
             linear_damping = False
             compiled = None
             def accumulate(self, t, x, v, out, work=None): ...
             def jacobian_blocks(self): return None
             def add_jacobian(self, t, x, v, dfdx, dfdv, form="exact"): ...
         KIND = force_kind("springy", Table, Springy, lambda e, c: Springy(), summary="s")
         """,
            "energyless:KIND",
            "visviva.forces",
            "Springy claims to be conservative but reports no energy: define `potential(t, x, "
            "alive=None)` returning U [J], or set conservative = False",
        ),
    ],
    ids=["fails to import", "clashes with a built-in kind", "conservative without energy"],
)
def test_a_wrong_plugin_is_left_out_with_its_name_and_the_fix(
    tmp_path, module, entry, group, expected
):
    name = entry.split(":")[0]
    folder = _plugin_folder(tmp_path, name, module, entry, group)
    report = run_with([folder], PROBE)
    assert len(report["warnings"]) == 1, report["warnings"]
    assert expected in report["warnings"][0]
    assert "The other kinds work" in report["warnings"][0]
    assert "cloth" in report["kinds"] and (name == "clash" or name not in report["kinds"])


class _Table(BaseModel):
    type: Literal["marker"]
    name: str | None = None
    targets: list[str] | None = None


class _Slowdown:
    """A stage that halves the targets' velocities after each step (declares everything)."""

    phase: ClassVar[Phase] = Phase.BEHAVIOURS
    order: ClassVar[int] = 0
    compiled: ClassVar[bool] = False
    changes_energy: ClassVar[bool] = True
    kills_particles: ClassVar[bool] = False

    def __init__(self, indices: np.ndarray) -> None:
        self.indices = indices

    def carried_start(self) -> dict[str, np.ndarray]:
        return {}

    def apply(self, before: Any, after: Any, h: float, work: Any) -> Any:
        q, v = after.parts
        v = v.copy()
        v.reshape(-1, 3)[self.indices] *= 0.5
        return after.from_parts(after.t, (q, v))


def test_a_stage_kind_registered_from_python_steers_its_targets():
    kind = stage_kind(
        "marker", _Table, _Slowdown,
        lambda entity, context: _Slowdown(context.targets(entity.targets).indices),
        summary="halves its targets' velocities each step",
    )  # fmt: skip
    vv.entities.register_entity_kind(kind)
    try:
        builder = vv.SceneBuilder()
        builder.set_world(gravity=(0.0, 0.0, 0.0))
        builder.set_integration(dt=0.1, duration=1.0)
        builder.add_particles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], velocities=[[1, 0, 0]] * 2,
                              name="slow")  # fmt: skip
        builder.add_particles([[0.0, 1.0, 0.0]], velocities=[[1, 0, 0]], name="free")
        builder.add("marker", targets=["slow"])
        simulation = vv.Simulation(builder.build())
        simulation.step(3)
        v = simulation.state["particle_velocity"][:, 0]
        np.testing.assert_array_equal(v, [0.125, 0.125, 1.0])  # (1/2)³ for the targets
        wrong = vv.SceneBuilder()
        wrong.add_particles([[0.0, 0.0, 0.0]], name="p")
        wrong.add("marker", targets=["nobody"])
        with pytest.raises(vv.SceneError, match=r"entities\[1\].targets\[0\]: no particle"):
            wrong.build()
    finally:
        ENTITY_KINDS.unregister("marker")


def test_kinds_and_classes_are_refused_with_what_to_fix():
    with pytest.raises(ModelError, match="clashes with a kind already registered"):
        vv.entities.register_entity_kind(EntityKind("cloth", _Table, "x", KindBuild()))
    with pytest.raises(ModelError, match=r'must have the field `type: Literal\["other"\]`'):
        vv.entities.register_entity_kind(EntityKind("other", _Table, "x", KindBuild()))

    class Nameless(BaseModel):
        type: Literal["nameless"]

    with pytest.raises(
        ModelError, match=re.escape("must have the field `name: str | None = None`")
    ):
        vv.entities.register_entity_kind(EntityKind("nameless", Nameless, "x", KindBuild()))
    with pytest.raises(ModelError, match="lower-case letters"):
        vv.entities.register_entity_kind(EntityKind("Bad Name", _Table, "x", KindBuild()))

    class Compiled(_Slowdown):
        compiled = True

    with pytest.raises(ModelError, match="must declare compiled = False"):
        stage_kind("marker", _Table, Compiled, lambda e, c: None, summary="x")

    class Phaseless:
        order = 0

    with pytest.raises(ModelError, match="must declare `phase`"):
        stage_kind("marker", _Table, Phaseless, lambda e, c: None, summary="x")
    assert "marker" not in ENTITY_KINDS


def test_the_example_plugins_force_is_its_exact_jacobian(installed):
    """∂F/∂v of q v × B against central differences of the same force (and ∂F/∂x = 0)."""
    program = """
    import json
    import numpy as np
    from visviva.forces import Targets
    from visviva_magnetic import MagneticField
    rng = np.random.default_rng(3)
    force = MagneticField(np.array([0.3, -1.2, 0.7]), 0.4, Targets(5))
    x, v = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    rows, cols = force.jacobian_blocks()
    dfdx, dfdv = np.zeros((5, 3, 3)), np.zeros((5, 3, 3))
    force.add_jacobian(0.0, x, v, dfdx, dfdv)
    worst = 0.0
    for i in range(5):
        for a in range(3):
            e = 1e-6
            up, down = v.copy(), v.copy()
            up[i, a] += e
            down[i, a] -= e
            fu, fd = np.zeros((5, 3)), np.zeros((5, 3))
            force.accumulate(0.0, x, up, fu)
            force.accumulate(0.0, x, down, fd)
            column = (fu - fd)[i] / (2 * e)
            worst = max(worst, float(np.abs(column - dfdv[i][:, a]).max()))
    print(json.dumps({"worst": worst, "dfdx": float(np.abs(dfdx).max())}))
    """
    report = run_with([installed], program)
    assert report["worst"] < 1e-9 and report["dfdx"] == 0.0
    assert math.isfinite(report["worst"])
