"""Batched ensembles: runs that share their equations advance together and change nothing.

The promise (issue 14): where the model allows, N copies advance in one batched state instead of
N processes, and "the batch path agrees with separate runs to round-off". Here it is stronger:
every member's recording and figures are bit for bit those of its own run, because each batch
row is evaluated by the member's own compiled function and every stage sum is taken entry by
entry (implicit methods, whose Newton iterations would run until every member converged, do not
batch). A member that diverges leaves the batch and runs alone, failing exactly as it would
have; the batch goes on.
"""

from __future__ import annotations

import copy
import json
import os
import signal
import tomllib
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from test_sweeps import run_main
from visviva.errors import ModelError
from visviva.io.recording import load_recording
from visviva.model.build import build_model
from visviva.model.scene import Scene
from visviva.ode import FirstOrderProblem, SecondOrderProblem
from visviva.ode.stacking import equations_key, stack
from visviva.simulation import Simulation
from visviva.simulation.ensemble import ensemble_key, run_ensemble
from visviva.sweeps import BatchTask, RunTask, SweepInterrupted, expand, parse_sweep
from visviva.sweeps.runner import MIN_BATCH, _plan

#: Three releases of seed 001's double pendulum (1 kg, 1 m) for half a second.
PENDULUMS = """
[sweep]
name = "pendulums"
[scene.integration]
method = "{method}"
dt = {dt}
duration = 0.5
[[scene.entities]]
type = "system"
system = "double-pendulum"
parameters = {{ theta1 = 2.0, theta2 = 1.0 }}
[[parameters]]
path = "entities[0].parameters.theta1"
values = [0.5, 1.5, 2.5]
[[parameters]]
path = "entities[0].parameters.omega2"
values = [0.0, 3.0]
[outputs]
recordings = true
"""

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "sweeps"
#: Fields of a results row that may differ between a batch and runs alone.
_NOT_PHYSICS = ("wall_time_s", "batch_size")


def sweep_text(method: str, dt: float = 0.01) -> str:
    return PENDULUMS.format(method=method, dt=dt)


def run_both(tmp_path, text):
    """The sweep in batches and with every run alone (both in this process)."""
    description = parse_sweep(text)
    together = vv.sweep(description, tmp_path / "batch", executor="serial")
    alone = vv.sweep(description, tmp_path / "alone", executor="serial", batch=False)
    return together, alone


def assert_same_runs(together, alone) -> None:
    for one, other in zip(together.rows, alone.rows, strict=True):
        assert {k: v for k, v in one.items() if k not in _NOT_PHYSICS} == {
            k: v for k, v in other.items() if k not in _NOT_PHYSICS
        }
        first = load_recording(together.directory / "runs" / one["run"] / "recording.h5")
        second = load_recording(alone.directory / "runs" / other["run"] / "recording.h5")
        np.testing.assert_array_equal(first.time, second.time)
        assert first.fields.keys() == second.fields.keys()
        for name, values in first.fields.items():
            np.testing.assert_array_equal(values, second.fields[name], err_msg=name)
        assert first.static.keys() == second.static.keys()
        attrs = {k: v for k, v in first.attrs.items() if k != "wall_time_s"}
        assert attrs == {k: v for k, v in second.attrs.items() if k != "wall_time_s"}


@pytest.mark.parametrize(
    "method", ["rk4", "midpoint", "explicit_euler", "symplectic_euler", "velocity_verlet"]
)
def test_a_batch_writes_bit_for_bit_what_runs_alone_write(tmp_path, method):
    together, alone = run_both(tmp_path, sweep_text(method))
    assert together.ran == alone.ran == 6 and together.failed == 0
    assert {row["batch_size"] for row in together.rows} == {6}
    assert all("batch_size" not in row for row in alone.rows)
    assert_same_runs(together, alone)
    # Each row ends with the pendulum's final state: the recording's last frame.
    last = load_recording(together.directory / "runs" / together.rows[4]["run"] / "recording.h5")
    assert together.rows[4]["final.generalized_position[1]"] == last["generalized_position"][-1, 1]
    assert together.rows[4]["final.generalized_velocity[0]"] == last["generalized_velocity"][-1, 0]


def test_without_recordings_a_batch_gives_the_same_table(tmp_path):
    # Then the batch follows every member's energy and final state as arrays over the members,
    # never drawing a frame: the same figures, by the same arithmetic.
    text = sweep_text("velocity_verlet").replace("recordings = true", "recordings = false")
    together, alone = run_both(tmp_path, text)
    assert not list((tmp_path / "batch" / "runs").glob("*/recording.h5"))
    assert {row["batch_size"] for row in together.rows} == {6}
    for one, other in zip(together.rows, alone.rows, strict=True):
        assert {k: v for k, v in one.items() if k not in _NOT_PHYSICS} == {
            k: v for k, v in other.items() if k not in _NOT_PHYSICS
        }
        assert one["counts.points"] == 3 and "final.generalized_position[0]" in one


def test_implicit_methods_run_alone(tmp_path):
    # Newton's iterations in a batch run until every member converged: a member would take
    # other iterations than alone, so implicit runs never batch.
    runs = expand(parse_sweep(sweep_text("backward_euler", dt=0.02)))
    assert {run.batch_key for run in runs} == {None}


#: Explicit Euler on the spring pendulum (k = 40 N/m, m = 1 kg) at h = 0.02 s: released
#: stretched to r0 = 3 m, it blows up within half a second; from 0.5-1.5 m it lasts 2 s.
STRETCHED = """
[sweep]
name = "stretched"
[scene.integration]
method = "explicit_euler"
dt = 0.02
duration = 2.0
[[scene.entities]]
type = "system"
system = "spring-pendulum"
[[parameters]]
path = "entities[0].parameters.r0"
values = [0.5, 3.0, 1.5, 1.0]
[outputs]
recordings = true
"""


def test_a_member_that_diverges_runs_alone_and_the_batch_goes_on(tmp_path):
    together, alone = run_both(tmp_path, STRETCHED)
    assert [row["success"] for row in together.rows] == [True, False, True, True]
    diverged = together.rows[1]
    assert "diverged" in diverged["error"] and diverged["t_reached_s"] < 0.5
    assert "batch_size" not in diverged  # it ran alone
    assert {together.rows[i]["batch_size"] for i in (0, 2, 3)} == {4}
    assert diverged["error"] == alone.rows[1]["error"]
    assert_same_runs(together, alone)


def test_runs_alone_on_a_pool_match_the_batch(tmp_path):
    description = parse_sweep(sweep_text("rk4"))
    together = vv.sweep(description, tmp_path / "batch", executor="serial")
    pool = vv.sweep(description, tmp_path / "pool", workers=2, batch=False)
    assert_same_runs(together, pool)


def test_a_batched_sweep_resumes_like_any_other(tmp_path):
    description = parse_sweep(sweep_text("symplectic_euler"))
    first = vv.sweep(description, tmp_path / "out", executor="serial")
    again = vv.sweep(description, tmp_path / "out", executor="serial")
    assert (again.ran, again.skipped) == (0, 6) and again.rows == first.rows
    for run in first.rows[2:]:
        (tmp_path / "out" / "runs" / run["run"] / "run.json").unlink()
    resumed = vv.sweep(description, tmp_path / "out", executor="serial")
    assert (resumed.ran, resumed.skipped) == (4, 2)
    assert [r["energy_drift"] for r in resumed.rows] == [r["energy_drift"] for r in first.rows]


def test_an_interrupt_in_a_batch_keeps_nothing_half_done(tmp_path, monkeypatch):
    from visviva.sweeps import tasks

    frames = 0
    append = tasks._Frames.append

    def interrupting(self, t, fields):
        nonlocal frames
        frames += 1
        if frames == 40:  # mid-run: as Ctrl-C at the terminal would
            os.kill(os.getpid(), signal.SIGINT)
        append(self, t, fields)

    monkeypatch.setattr(tasks._Frames, "append", interrupting)
    description = parse_sweep(sweep_text("rk4"))
    with pytest.raises(SweepInterrupted, match="0 of 6 runs finished"):
        vv.sweep(description, tmp_path / "out", executor="serial")
    assert not list((tmp_path / "out" / "runs").iterdir())
    monkeypatch.setattr(tasks._Frames, "append", append)
    resumed = vv.sweep(description, tmp_path / "out", executor="serial")
    assert resumed.ran == 6 and resumed.failed == 0


def test_the_chaos_example_shortened_is_smooth_for_small_releases_and_chaotic_for_large(
    tmp_path,
):
    """The double pendulum released at rest with both arms at angle a, 10 s later: for small a
    it is close to a linear system and the lower arm's final angle changes smoothly with a;
    beyond about 1.5 rad (seed 001) neighbouring releases end far apart. 63 releases, 0.048
    rad apart, instead of the example's 1000."""
    data = tomllib.loads((EXAMPLES / "double_pendulum_chaos.toml").read_text())
    for parameter in data["parameters"]:
        parameter["range"] = [0.0, 3.0, 63]
    path = tmp_path / "chaos.json"
    path.write_text(json.dumps(data))
    result = vv.sweep(path, tmp_path / "out", executor="serial")
    assert result.failed == 0 and {row["batch_size"] for row in result.rows} == {63}
    a = np.array([row["entities[0].parameters.theta1"] for row in result.rows])
    end = np.array([row["final.generalized_position[1]"] for row in result.rows])
    assert end[0] == 0.0  # released hanging straight down, it never moves
    change = np.abs(np.diff(end))
    smooth, chaotic = a[1:] <= 1.0, a[:-1] >= 2.0
    assert change[smooth].max() < 4.0 * (a[1] - a[0])  # |d(end)/da| below 4
    assert np.median(change[chaotic]) > np.pi  # neighbours end half a turn or more apart
    # RK4 at h = 2 ms: the energy error is O(h^4) per unit time, here below 1e-4 of E.
    assert max(row["max_energy_error"] for row in result.rows[1:]) < 1e-4
    assert (tmp_path / "out" / "plots" / "final_angle.png").stat().st_size > 0


def test_the_command_says_which_runs_batch_and_no_batch_runs_them_alone(
    tmp_path, monkeypatch, capsys
):
    path = tmp_path / "pendulums.toml"
    path.write_text(sweep_text("rk4").replace("recordings = true", "recordings = false"))
    status, stdout, _ = run_main(monkeypatch, capsys, "sweep", path, "--dry-run")
    assert status == 0
    assert "6 runs would advance together in batches (1 group of" in stdout
    out = tmp_path / "out"
    status, stdout, _ = run_main(monkeypatch, capsys, "sweep", path, "-o", out, "--no-batch")
    assert status == 0 and "6 runs; 6 succeeded, 0 failed" in stdout
    rows = json.loads((out / "results.json").read_text())["runs"]
    assert all("batch_size" not in row for row in rows)


# ---------------------------------------------------------------- who joins a batch


def pendulum_model(**parameters: float):
    """Seed 001's double pendulum with RK4 at h = 0.01 s (the sweeps' base scene)."""
    scene = {
        "integration": {"method": "rk4", "dt": 0.01, "duration": 0.5},
        "entities": [{"type": "system", "system": "double-pendulum", "parameters": parameters}],
    }
    return build_model(Scene.model_validate(scene))


def test_only_runs_with_the_same_equations_share_a_batch_key():
    start = pendulum_model(theta1=1.0)
    assert ensemble_key(start) == ensemble_key(pendulum_model(theta1=2.0, omega2=1.0))
    assert ensemble_key(start) != ensemble_key(pendulum_model(theta1=1.0, m2=2.0))
    builder = vv.SceneBuilder(name="pendulum and ball")
    builder.add_system("pendulum")
    builder.add_particles([[0.0, 1.0, 0.0]])
    assert ensemble_key(builder.build()) is None


def test_expand_gives_starts_a_key_and_other_parameters_none(tmp_path):
    runs = expand(parse_sweep(sweep_text("rk4")))
    assert len({run.batch_key for run in runs}) == 1 and runs[0].batch_key is not None
    masses = sweep_text("rk4").replace("parameters.omega2", "parameters.m2")
    keys = {run.batch_key for run in expand(parse_sweep(masses.replace("0.0, 3.0", "1.0, 3.0")))}
    assert len(keys) == 2  # one batch per mass


def task(index: int) -> RunTask:
    return RunTask(index, f"{index}", f"/tmp/{index}", {}, {}, "")


class FakeRun:
    def __init__(self, key):
        self.batch_key = key


def test_plan_batches_groups_split_over_the_workers():
    pending = [(FakeRun("a" if i % 3 else None), task(i)) for i in range(12)]
    plan = _plan(pending, slots=2)
    batches = [t for t in plan if isinstance(t, BatchTask)]
    assert [[r.index for r in b.runs] for b in batches] == [[1, 2, 4, 5], [7, 8, 10, 11]]
    alone = [t.index for t in plan if isinstance(t, RunTask)]
    assert alone == [0, 3, 6, 9]
    few = [(FakeRun("b"), task(i)) for i in range(MIN_BATCH - 1)]
    assert all(isinstance(t, RunTask) for t in _plan(few, slots=1))


# ---------------------------------------------------------------- the pieces underneath


def test_run_ensemble_frames_are_those_of_each_simulation():
    models = [pendulum_model(theta1=a, theta2=0.3) for a in (0.2, 1.1, 2.9)]
    seen: dict[int, list[tuple[float, np.ndarray, float]]] = {i: [] for i in range(3)}

    def keep(frame):
        for k, member in enumerate(frame.members):
            position = frame.state(k)["generalized_position"]
            seen[member].append((frame.t, position, float(frame.energy[k])))

    result = run_ensemble(models, 0.5, on_frame=keep)
    assert result.failed == {} and result.counters["accepted_steps"] == 50
    for member, model in enumerate(models):
        simulation = Simulation(model)
        alone = [(0.0, np.array(simulation.state["generalized_position"]), simulation.energy())]

        def record(state, energy, alone=alone):
            alone.append((state.t, np.array(state["generalized_position"]), float(energy)))

        simulation.run(0.5, record_every=model.integration.record_every, on_frame=record)
        assert len(alone) == len(seen[member])
        for (t, q, e), (t2, q2, e2) in zip(alone, seen[member], strict=True):
            assert t == t2 and e == e2
            np.testing.assert_array_equal(q, q2)


def test_run_ensemble_refuses_models_that_do_not_share_equations():
    with pytest.raises(ModelError, match="cannot advance in one batch"):
        run_ensemble([pendulum_model(theta1=1.0), pendulum_model(m1=3.0)], 0.5)
    builder = vv.SceneBuilder(name="falling")
    builder.add_particles([[0.0, 1.0, 0.0]])
    with pytest.raises(ModelError, match="cannot advance in one batch"):
        run_ensemble([pendulum_model(theta1=1.0), builder.build()], 0.5)
    with pytest.raises(ModelError, match="empty"):
        run_ensemble([], 0.5)


def test_stack_keeps_each_member_as_its_row_and_refuses_other_equations():
    def decay(t, y):
        return -y

    one = FirstOrderProblem(decay, [1.0])
    batch = stack([one, FirstOrderProblem(decay, [2.0]), FirstOrderProblem(decay, [3.0])])
    assert batch.batch_size == 3 and batch.y0[:, 0].tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(ModelError, match="problem 1 does not share the equations"):
        stack([one, FirstOrderProblem(lambda t, y: -y, [2.0])])
    spring = SecondOrderProblem.from_force(lambda t, q: -q, 2.0, [1.0], [0.0])
    pair = stack([spring, copy.copy(spring)])
    assert pair.batch_size == 2 and pair.mass is not None
    assert equations_key(pair) is None  # a batch is not stacked again
    with pytest.raises(ModelError, match="empty"):
        stack([])
