"""Particle scenes in batches: runs of one particle scene with other values advance as the
particle spans of one merged model (issue 14: "where the model allows (ODEs, Lagrangian
systems, particles), N copies advance in one vectorized state ... the batch path agrees with
separate runs to round-off").

Each particle of the merged model feels its own member's forces and colliders in its own run's
order, so most members move bit for bit as alone; where the merged model sums a force by
another path (a field whose values differ per member is evaluated by its law rather than folded
into the compiled step, a cloth's springs spring by spring rather than by its lattice stencil)
the last bits may differ, and the comparisons below allow round-off there only.
"""

from __future__ import annotations

import copy
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

import visviva as vv
from visviva.errors import ModelError
from visviva.io.recording import load_recording
from visviva.model.build import build_model
from visviva.model.replicas import Replicas, replica_capacity, replica_key
from visviva.model.scene import Scene
from visviva.simulation import Simulation
from visviva.simulation.ensemble import (
    MAX_MEMBER_PARTICLES,
    ensemble_capacity,
    ensemble_key,
    run_ensemble,
)
from visviva.sweeps import parse_sweep

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "sweeps"
#: Fields of a results row that may differ between a batch and runs alone.
_NOT_PHYSICS = ("wall_time_s", "batch_size")


def scene(
    method: str = "symplectic_euler",
    restitution: float = 0.5,
    drag: float = 0.1,
    stiffness: float = 500.0,
    duration: float = 1.0,
) -> dict:
    """Two balls over a floor and a rope hanging from a pin, in light drag."""
    return {
        "integration": {"method": method, "dt": 0.002, "duration": duration},
        "entities": [
            {
                "type": "particles",
                "name": "balls",
                "positions": [[0.0, 1.0, 0.0], [0.3, 1.2, 0.0]],
                "velocities": [[0.5, 0.0, 0.0], [0.0, 0.0, 0.2]],
                "radius": 0.05,
            },
            {
                "type": "rope",
                "points": [[0.0, 1.5, 0.0], [0.1, 1.5, 0.0], [0.2, 1.5, 0.0]],
                "mass": 0.1,
                "stiffness": stiffness,
                "pinned": [0],
            },
            {"type": "force", "kind": "drag", "coefficient": drag},
            {"type": "collider", "shape": "plane", "restitution": restitution},
        ],
    }


def model(**values) -> vv.Model:
    return build_model(Scene.model_validate(scene(**values)))


def frames_alone(member: vv.Model, until: float) -> list[tuple[float, np.ndarray, float]]:
    simulation = Simulation(member)
    frames = [(0.0, simulation.raw_state.parts[0].copy(), simulation.energy())]

    def keep(state, energy):
        frames.append((state.t, state.parts[0].copy(), float(energy)))

    simulation.run(until, record_every=member.integration.record_every, on_frame=keep)
    return frames


def frames_together(members: list[vv.Model], until: float):
    seen: dict[int, list[tuple[float, np.ndarray, float]]] = {i: [] for i in range(len(members))}

    def keep(frame):
        for k, member in enumerate(frame.members):
            state = frame.state(k)
            seen[member].append((frame.t, state.parts[0], float(frame.energy[k])))

    return run_ensemble(members, until, on_frame=keep), seen


# ---------------------------------------------------------------- who can be replicated


def test_particle_scenes_with_the_same_entities_share_a_key_whatever_their_values():
    key = ensemble_key(model(restitution=0.2))
    assert key is not None
    assert ensemble_key(model(restitution=0.9, drag=0.0, stiffness=50.0)) == key
    assert ensemble_key(model(duration=2.0)) != key  # a member must stop when its run does
    assert ensemble_key(model(method="rk4")) != key
    assert ensemble_key(model(method="backward_euler")) is None  # Newton would couple them
    big = scene()
    big["entities"].append({"type": "particle_cloud", "count": MAX_MEMBER_PARTICLES})
    assert ensemble_key(build_model(Scene.model_validate(big))) is None  # batches stop paying


@pytest.mark.parametrize(
    "entity",
    [
        {"type": "force", "kind": "gravitation"},
        {"type": "particle_collisions"},
        {"type": "emitter", "rate": 10.0},
        {"type": "system", "system": "pendulum"},
    ],
)
def test_scenes_whose_particles_interact_or_hold_more_than_particles_are_not_replicated(entity):
    data = scene()
    data["entities"].append(entity)
    assert replica_key(Scene.model_validate(data)) is None


def test_named_systems_that_differ_only_in_duration_do_not_share_a_batch():
    # A member runs to its own end: runs of other durations cannot advance together.
    def pendulum(duration):
        data = {
            "integration": {"method": "rk4", "dt": 0.01, "duration": duration},
            "entities": [{"type": "system", "system": "pendulum"}],
        }
        return build_model(Scene.model_validate(data))

    assert ensemble_key(pendulum(1.0)) == ensemble_key(pendulum(1.0))
    assert ensemble_key(pendulum(1.0)) != ensemble_key(pendulum(2.0))


def test_replicas_share_what_is_the_same_and_copy_what_differs():
    members = [model(restitution=e) for e in (0.2, 0.5, 0.8)]
    replicas = Replicas.of(members)
    assert replicas.spans == ((0, 5), (5, 5), (10, 5))
    merged = replicas.model
    assert merged.particle_count == 15
    forces = [type(f).__name__ for f in merged.forces]
    assert forces == ["UniformGravity", "Drag", "Springs"]  # one drag, one set of springs
    (collisions,) = merged.stages
    assert len(collisions.colliders) == 3  # a floor for each restitution
    for k in range(3):  # each member's balls meet its own floor only
        np.testing.assert_array_equal(collisions.masks[5 * k : 5 * k + 2], 1 << k)


def test_capacity_counts_the_copies_a_member_adds():
    # A merged model holds at most 64 impulse colliders (a bit mask per particle) and 64
    # fields evaluated by their law: one floor per member leaves room for 64 members, one
    # floor and one drag per member too; the same floor for all takes one slot.
    same = [Scene.model_validate(scene()) for _ in range(100)]
    floors = [Scene.model_validate(scene(restitution=i / 100)) for i in range(100)]
    both = [Scene.model_validate(scene(restitution=i / 100, drag=i / 100)) for i in range(100)]
    assert replica_capacity(same) == 100
    assert replica_capacity(floors) == 64
    assert replica_capacity(both) == 64
    models = [build_model(s) for s in floors[:70]]
    assert ensemble_capacity(models) == 64
    with pytest.raises(ModelError, match="exceed the 64"):
        run_ensemble(models, 0.01)


# ---------------------------------------------------------------- the same motion as alone


@pytest.mark.parametrize("method", ["rk4", "velocity_verlet", "midpoint", "symplectic_euler"])
def test_each_member_moves_as_it_does_alone(method):
    # 0.6 s: both balls land (after 0.42 s and 0.47 s) and bounce.
    members = [
        model(method=method, restitution=e, drag=d, stiffness=k, duration=0.6)
        for e, d, k in [(0.1, 0.1, 500.0), (0.9, 0.0, 800.0), (0.5, 0.3, 200.0)]
    ]
    result, seen = frames_together(members, 0.6)
    assert result.failed == {}
    assert result.counters["accepted_steps"] == 300
    exact = True
    for i, member in enumerate(members):
        alone = frames_alone(member, 0.6)
        assert len(alone) == len(seen[i])
        for (t, q, energy), (t2, q2, energy2) in zip(alone, seen[i], strict=True):
            assert t == t2
            # Round-off only: a field whose values differ per member is evaluated by its
            # law in the compiled step instead of folded with gravity (symplectic Euler).
            np.testing.assert_allclose(q2, q, rtol=0, atol=1e-12)
            assert energy2 == pytest.approx(energy, rel=1e-12, abs=1e-12)
            exact &= bool(np.array_equal(q, q2)) and energy == energy2
    if method != "symplectic_euler":  # every force summed by the same path: bit for bit
        assert exact


def test_cloths_batch_to_round_off():
    # A cloth's springs sum by its lattice's stencil alone and spring by spring in the merged
    # model: the same forces, added in another order.
    def cloth(stiffness):
        data = {
            "integration": {"method": "symplectic_euler", "dt": 0.002, "duration": 0.5},
            "entities": [
                {
                    "type": "cloth",
                    "resolution": [6, 5],
                    "stiffness": stiffness,
                    "pinned": [0, 5],
                    "damping": 0.01,
                },
                {"type": "collider", "shape": "sphere", "center": [0.5, 0.6, 0.5], "radius": 0.3},
            ],
        }
        return build_model(Scene.model_validate(data))

    members = [cloth(k) for k in (200.0, 400.0, 800.0)]
    result, seen = frames_together(members, 0.5)
    assert result.failed == {}
    for i, member in enumerate(members):
        alone = frames_alone(member, 0.5)
        for (_, q, energy), (_, q2, energy2) in zip(alone, seen[i], strict=True):
            np.testing.assert_allclose(q2, q, rtol=0, atol=1e-10)
            assert energy2 == pytest.approx(energy, rel=1e-9)


def test_a_member_that_diverges_leaves_and_the_others_go_on():
    # Explicit Euler on the rope: unstable for every step (its springs are undamped
    # oscillators), the stiffest rope blows up first; the others are watched with its limit.
    members = [model(method="explicit_euler", stiffness=k, duration=0.5) for k in (5.0, 1e6, 1.0)]
    result, seen = frames_together(members, 0.5)
    assert set(result.failed) == {1} and "diverged" in result.failed[1]
    for i in (0, 2):
        alone = frames_alone(members[i], 0.5)
        assert len(alone) == len(seen[i])
        for (_, q, energy), (_, q2, energy2) in zip(alone, seen[i], strict=True):
            np.testing.assert_array_equal(q2, q)
            assert energy2 == energy


# ---------------------------------------------------------------- sweeps


def bounce_sweep(**changes) -> dict:
    data = tomllib.loads((EXAMPLES / "bounce_restitution.toml").read_text())
    data.update(changes)
    return data


def test_the_bounce_example_keeps_e_squared_of_the_energy_each_bounce(tmp_path):
    """A ball of radius r dropped from rest at height h bounces once within the run: the
    floor gives back e² of its kinetic energy at impact, m g (h − r) (seed 002: v' = −e v),
    so its energy drift over the run is (E − E0)/E0 = −(1 − e²)(1 − r/h)."""
    path = tmp_path / "bounce.json"
    path.write_text(json.dumps(bounce_sweep()))
    result = vv.sweep(path, tmp_path / "out", executor="serial")
    assert result.failed == 0 and {row["batch_size"] for row in result.rows} == {len(result.rows)}
    data = bounce_sweep()
    ball = data["scene"]["entities"][0]
    h, r = ball["positions"][0][1], ball["radius"]
    for row in result.rows:
        e = row["entities[floor].restitution"]
        # Velocity Verlet is exact in free fall; the bisection finds the impact to 1e-6 r.
        assert row["energy_drift"] == pytest.approx(-(1.0 - e * e) * (1.0 - r / h), abs=1e-6)
    assert (tmp_path / "out" / "plots" / "energy_lost.png").stat().st_size > 0


def test_a_particle_sweep_in_batches_writes_what_runs_alone_write(tmp_path):
    data = bounce_sweep()
    data["outputs"] = {"recordings": True}
    data["parameters"] = [{"path": "entities[floor].restitution", "values": [0.3, 0.6, 0.9]}]
    description = parse_sweep(json.dumps(data), format="json")
    together = vv.sweep(description, tmp_path / "batch", executor="serial")
    alone = vv.sweep(copy.deepcopy(description), tmp_path / "alone", executor="serial", batch=False)
    assert {row["batch_size"] for row in together.rows} == {3}
    for one, other in zip(together.rows, alone.rows, strict=True):
        assert {k: v for k, v in one.items() if k not in _NOT_PHYSICS} == {
            k: v for k, v in other.items() if k not in _NOT_PHYSICS
        }
        first = load_recording(tmp_path / "batch" / "runs" / one["run"] / "recording.h5")
        second = load_recording(tmp_path / "alone" / "runs" / other["run"] / "recording.h5")
        for name, values in first.fields.items():
            np.testing.assert_array_equal(values, second.fields[name], err_msg=name)


def test_a_batch_that_cannot_be_made_runs_its_members_alone(tmp_path, monkeypatch):
    def broken(members):
        raise RuntimeError("no room")

    monkeypatch.setattr(Replicas, "of", broken)
    data = bounce_sweep()
    data["parameters"] = [{"path": "entities[floor].restitution", "values": [0.3, 0.6]}]
    result = vv.sweep(parse_sweep(json.dumps(data), format="json"), tmp_path, executor="serial")
    assert result.failed == 0 and result.ran == 2
    assert all("batch_size" not in row for row in result.rows)
