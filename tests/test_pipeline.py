"""The one pipeline: mixed scenes, named parts, implicit methods on sparse Jacobians without
anything N², penalty contact as a force, memory that does not grow with the frames."""

import json
import subprocess
import sys
import textwrap
import tracemalloc

import numpy as np
import pytest
from typer.testing import CliRunner

import visviva as vv
from visviva.cli.main import app
from visviva.forces import ForceSum

MIXED = """
[scene]
name = "mixed"

[integration]
method = "symplectic_euler"
dt = 0.002
duration = 0.5

[[entities]]
type = "emitter"
name = "spray"
rate = 200.0
speed = [2.0, 3.0]
spread_deg = 20.0
lifetime = 0.4
color_ramp = [[0.0, 1.0, 0.9, 0.2], [1.0, 0.8, 0.1, 0.0]]

[[entities]]
type = "particles"
name = "planets"
positions = [[-1.0, 2.0, 0.0], [1.0, 2.0, 0.0], [0.0, 2.5, 0.0]]
velocities = [[0.0, 0.0, 0.3], [0.0, 0.0, -0.3], [0.2, 0.0, 0.0]]
mass = 5.0

[[entities]]
type = "force"
kind = "gravitation"
targets = ["planets"]
G = 0.1
softening = 0.05

[[entities]]
type = "force"
kind = "drag"
coefficient = 0.001
targets = ["spray"]

[[entities]]
type = "system"
name = "swing"
system = "pendulum"
parameters = { length = 0.5, theta0 = 0.6 }

[[entities]]
type = "collider"
shape = "plane"
restitution = 0.5
friction = 0.1
"""


def test_a_mixed_scene_runs_through_visviva_run(tmp_path):
    """Emitter + drag + gravitating particles + a named pendulum + a plane, one run."""
    scene = tmp_path / "mixed.toml"
    scene.write_text(MIXED)
    result = CliRunner().invoke(app, ["run", str(scene), "-o", str(tmp_path / "out"), "-f", "html"])
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["success"] and summary["steps"] == 250
    recording = vv.io.load_recording(tmp_path / "out" / "recording.h5")
    model = vv.load_model(scene)
    geometry = recording.geometry()
    # Points: the spray's slots, the three planets, then the pendulum's pivot and bob.
    assert geometry.points.shape[1] == model.particle_count + 2
    assert geometry.alive is not None and geometry.color is not None
    spray = model.particle_groups[0]
    assert not geometry.alive[0, : spray.count].any()  # nothing born yet
    assert geometry.alive[-1, : spray.count].sum() == pytest.approx(200 * 0.4, abs=2)
    assert geometry.alive[:, spray.count :].all()  # planets and pendulum always exist
    # The pendulum keeps its rod length inside the mixed scene.
    rod = np.linalg.norm(geometry.points[:, -1] - geometry.points[:, -2], axis=1)
    np.testing.assert_allclose(rod, 0.5, rtol=1e-12)
    assert (tmp_path / "out" / "viewer.html").stat().st_size > 0


def test_state_parts_are_named_views_of_the_integrated_arrays():
    model = vv.SceneBuilder.from_scene(vv.io.parse_scene(MIXED)).build()
    state = model.initial_state()
    assert np.shares_memory(state["particle_position"], state.parts[0])
    assert state["particle_position"].shape == (model.particle_count, 3)
    assert state["generalized_position"].shape == (1,)
    np.testing.assert_array_equal(state["generalized_position"], [0.6])
    assert set(state.names()) >= {"particle_alive", "particle_radius", "emitter_serial"}


def _drag_and_attractors(count: int) -> vv.Model:
    builder = vv.SceneBuilder(name="implicit")
    builder.set_integration(method="backward_euler", dt=0.01, duration=0.1)
    builder.add_particle_cloud(count, size=(4.0, 4.0, 4.0), velocity_jitter=1.0, seed=2)
    builder.add_force("drag", coefficient=0.5)
    builder.add_force("attractor", point=(1.0, 1.0, 0.0), strength=5.0, softening=0.2)
    builder.add_force("attractor", point=(-1.0, 0.5, 0.0), strength=-2.0, softening=0.3)
    return builder.build()


def test_backward_euler_on_ten_thousand_particles_allocates_nothing_n_squared():
    """3·10⁴ unknowns: a dense Newton matrix would be 7.2 GB; the sparse one is 9 numbers a
    row. Peak traced memory stays a few times the state."""
    model = _drag_and_attractors(10_000)
    simulation = vv.Simulation(model)
    tracemalloc.start()
    simulation.step(2)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 100e6, f"{peak / 1e6:.0f} MB"
    counters = simulation.system.counters
    assert counters.jacobian_evaluations == counters.newton_iterations >= 2
    assert counters.krylov_iterations == 0  # direct sparse solves on the analytic Jacobian


def test_sparse_newton_agrees_with_the_dense_finite_difference_solve():
    """The same backward Euler steps with the analytic sparse Jacobian and with dense finite
    differences of the same force (the test tool) agree to Newton's tolerance."""
    model = _drag_and_attractors(30)
    sparse = vv.Simulation(model)
    sparse.step(5)
    problem = model.problem()
    dense = vv.ode.SecondOrderProblem.from_force(
        problem.force.func, problem.mass.values, problem.q0, problem.v0
    )
    solution = vv.solve(dense, "backward_euler", dt=0.01, until=0.05)
    np.testing.assert_allclose(sparse.raw_state.parts[0], solution.q[-1], atol=1e-9)
    np.testing.assert_allclose(sparse.raw_state.parts[1], solution.v[-1], atol=1e-9)


@pytest.mark.parametrize("shape", ["plane", "sphere", "box"])
def test_penalty_contact_jacobian_matches_finite_differences(shape):
    builder = vv.SceneBuilder(name="penalty")
    rng = np.random.default_rng(4)
    builder.add_particles(
        rng.uniform(-0.3, 0.3, (12, 3)) + [0.0, 0.5, 0.0],
        radius=0.05,
        velocities=rng.normal(size=(12, 3)),
    )
    settings = {"stiffness": 1e3, "damping": 5.0, "response": "penalty"}
    if shape == "plane":
        builder.add_collider("plane", point=(0.0, 0.5, 0.0), **settings)
    elif shape == "sphere":
        builder.add_collider("sphere", center=(0.0, 0.5, 0.0), radius=0.25, **settings)
    else:
        builder.add_collider("box", center=(0.0, 0.5, 0.0), size=(0.5, 0.4, 0.6), **settings)
    model = builder.build()
    penalty = model.forces[-1]
    total = ForceSum([penalty], model.particle_count)
    x, v = model.particle_position.copy(), model.particle_velocity.copy()
    analytic_x, analytic_v = (m.toarray() for m in total.jacobian(0.0, x, v))
    assert np.abs(analytic_x).max() > 0  # some particles are in contact
    step = 1e-7
    for column in range(3 * model.particle_count):
        shift = np.zeros(3 * model.particle_count)
        shift[column] = step
        shift = shift.reshape(-1, 3)
        for matrix, plus, minus in (
            (analytic_x, (x + shift, v), (x - shift, v)),
            (analytic_v, (x, v + shift), (x, v - shift)),
        ):
            up, down = np.zeros_like(x), np.zeros_like(x)
            penalty.accumulate(0.0, *plus, up)
            penalty.accumulate(0.0, *minus, down)
            np.testing.assert_allclose(
                matrix[:, column], ((up - down) / (2 * step)).ravel(), atol=1e-3, rtol=1e-5
            )


def test_penalty_floor_holds_a_particle_at_its_static_sinking():
    """At rest on a penalty floor the spring carries the weight: it sinks m g / k."""
    builder = vv.SceneBuilder(name="penalty floor")
    builder.set_integration(method="backward_euler", dt=0.002, duration=1.0)
    builder.add_particles([[0.0, 0.2, 0.0]], radius=0.05, mass=2.0)
    builder.add_collider("plane", response="penalty", stiffness=2000.0, damping=40.0)
    simulation = vv.Simulation(builder.build())
    simulation.run(until=3.0)
    sink = 0.05 - simulation.state["particle_position"][0, 1]
    assert sink == pytest.approx(2.0 * 9.81 / 2000.0, rel=1e-3)


_MEMORY = textwrap.dedent(
    """
    import resource, sys
    import visviva as vv
    frames = int(sys.argv[1])
    builder = vv.SceneBuilder(name="memory")
    builder.set_integration(method="symplectic_euler", dt=0.001, duration=frames * 0.001,
                            record_every=1)
    builder.add_particle_cloud(20_000, seed=1)
    builder.add_collider("plane")
    vv.run_scene(builder.build(), sys.argv[2], force=True)
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    """
)


def _peak_kib(frames: int, out) -> int:
    result = subprocess.run(
        [sys.executable, "-c", _MEMORY, str(frames), str(out)], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    return int(result.stdout.split()[-1])


def test_peak_memory_of_a_recording_does_not_grow_with_its_frames(tmp_path):
    """20,000 particles: 100 frames or 800 frames (each 0.96 MB of positions and velocities)
    take the same memory; holding the frames would add 670 MB."""
    short = _peak_kib(100, tmp_path / "short")
    long = _peak_kib(800, tmp_path / "long")
    assert long - short < 40_000, (short, long)
    assert vv.io.load_recording(tmp_path / "long" / "recording.h5").frames == 801


def test_summary_reports_births_and_warns_about_dropped_ones(tmp_path):
    builder = vv.SceneBuilder(name="crowded")
    builder.set_integration(dt=0.01, duration=0.5)
    builder.add_emitter(rate=1000.0, lifetime=1.0, capacity=100, name="jet")
    summary = vv.run_scene(builder.build(), tmp_path).summary
    assert summary["emitters"] == {"jet": {"births": 500, "dropped": 400, "capacity": 100}}
    (warning,) = [w for w in summary["warnings"] if w["kind"] == "dropped_births"]
    assert "'jet'" in warning["message"] and "capacity" in warning["message"]
