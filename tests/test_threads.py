"""One Model, many runs at once: a model and the integrators are shared, a run's storage is not.

A Model holds nothing that changes while it runs (its forces and stages keep their scratch
arrays, neighbour grids and warm starts in each run's workspace, :mod:`visviva.ode.workspace`),
and integrators are stateless singletons. So simulations of one model stepped in four threads
at once, or in turns in one thread, must each end with the bits of the same run done alone.
Before the workspace, a cloth under RK4 diverged in threads, boids ended metres away and a ball
pit crashed the interpreter.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.collision.particle_contacts import ParticleContacts

SCENES = Path(__file__).resolve().parents[1] / "examples" / "scenes"
THREADS = 4

#: (example scene, method or None for the scene's, compiled, steps): each integrator family
#: whose solver keeps something between steps, and each kind of stage with scratch.
CASES = [
    ("cloth_hang", "rk4", None, 4),  # springs' scratch arrays (80 substeps a step)
    ("cloth_hang", "backward_euler", None, 1),  # Newton's multigrid hierarchy
    ("cloth_hang", "linearly_implicit_euler", None, 1),
    ("cloth_hang", "fast_mass_springs", None, 2),  # factorizations per run and step size
    ("boids", None, None, 20),  # neighbour grids, steering buffers
    ("crowd", None, None, 40),
    ("ball_pit", None, None, 40),  # contact grid and warm-started impulses
    ("spinning_bodies", None, None, 100),  # rigid bodies with pushes and an anchor
    ("fountain", None, None, 40),  # emitters, fused particle step
    ("fountain", None, False, 40),  # the same through the generic pipeline
    ("star_cluster", None, None, 5),  # gravitation's scratch
]


def final_arrays(simulation: vv.Simulation) -> list[np.ndarray]:
    state = simulation.raw_state
    return [np.array(part) for part in (*state.parts, *state.carried.values())]


def run_alone(model: vv.Model, method: str | None, compiled: bool | None, steps: int) -> list:
    simulation = vv.Simulation(model, method=method, compiled=compiled)
    simulation.step(steps)
    return final_arrays(simulation)


def assert_same_bits(got: list[np.ndarray], expected: list[np.ndarray]) -> None:
    assert len(got) == len(expected)
    for a, b in zip(got, expected, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(("scene", "method", "compiled", "steps"), CASES)
def test_runs_in_threads_give_the_bits_of_a_run_alone(scene, method, compiled, steps):
    model = vv.load_model(SCENES / f"{scene}.toml")
    alone = run_alone(model, method, compiled, steps)
    assert_same_bits(run_alone(model, method, compiled, steps), alone)  # deterministic alone
    start = threading.Barrier(THREADS)

    def in_thread() -> list[np.ndarray]:
        simulation = vv.Simulation(model, method=method, compiled=compiled)
        start.wait()  # every thread steps at once
        simulation.step(steps)
        return final_arrays(simulation)

    with ThreadPoolExecutor(THREADS) as pool:
        results = [pool.submit(in_thread) for _ in range(THREADS)]
        for result in results:
            assert_same_bits(result.result(), alone)


@pytest.mark.parametrize("scene", ["ball_pit", "boids", "crowd"])
def test_runs_stepped_in_turns_in_one_thread_keep_their_own_warm_starts(scene):
    """Two simulations of one model stepped alternately (a GUI with two previews) each end as
    if alone: nothing one leaves between steps (a contact grid, warm starts) reaches the
    other."""
    model = vv.load_model(SCENES / f"{scene}.toml")
    alone = run_alone(model, None, False, 30)
    first, second = vv.Simulation(model, compiled=False), vv.Simulation(model, compiled=False)
    second.step(7)  # the second is ahead of the first: their states differ at every step
    for _ in range(30):
        first.step()
        second.step()
    assert_same_bits(final_arrays(first), alone)


def test_the_solved_contacts_are_each_runs_own():
    model = vv.load_model(SCENES / "ball_pit.toml")
    stage = next(s for s in model.stages if isinstance(s, ParticleContacts))
    early, late = vv.Simulation(model), vv.Simulation(model)
    late.step(200)
    early.step(1)
    assert stage.solved(early.system.workspace) is not stage.solved(late.system.workspace)
    # Balls dropped in a heap touch at once; after 200 steps they rest on one another.
    assert stage.solved(late.system.workspace).first.shape[0] > 0


def test_a_sweep_on_a_thread_pool_gives_the_bits_of_a_serial_one(tmp_path):
    text = f"""
[sweep]
name = "cloth_threads"
scene = "{(SCENES / "cloth_hang.toml").as_posix()}"

[[parameters]]
path = "integration.method"
values = ["symplectic_euler", "rk4"]

[[parameters]]
path = "entities[sheet].damping"
values = [0.01, 0.02, 0.04]

[[parameters]]
path = "integration.duration"
values = [0.05]

[outputs]
recordings = false
"""
    path = tmp_path / "sweep.toml"
    path.write_text(text)
    serial = vv.sweep(path, tmp_path / "serial", executor="serial", batch=False)
    with ThreadPoolExecutor(THREADS) as pool:
        threaded = vv.sweep(path, tmp_path / "threads", executor=pool, batch=False)
    assert serial.ran == threaded.ran == 6 and serial.failed == threaded.failed == 0
    physics = ("steps", "t_reached_s", "energy_drift", "max_energy_error", "success")
    for one, other in zip(serial.rows, threaded.rows, strict=True):
        assert {k: one[k] for k in physics} == {k: other[k] for k in physics}
