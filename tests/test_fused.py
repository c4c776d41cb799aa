"""The fused particle step computes what the generic pipeline computes (forces, symplectic
Euler, collision stage, emission stage, divergence watch), to round-off."""

import numba
import numpy as np
import pytest

import visviva as vv


def _scene(**extra) -> vv.Model:
    builder = vv.SceneBuilder(name="fused")
    builder.set_integration(method="symplectic_euler", dt=1 / 240, duration=2.0)
    builder.add_emitter(
        rate=400,
        speed=[3.0, 4.0],
        spread_deg=20,
        lifetime=[0.5, 0.9],
        size_ramp=[[0.0, 1.0], [1.0, 0.3]],
        seed=5,
        name="jet",
    )
    builder.add_particle_cloud(
        300, center=(0.0, 1.5, 0.0), velocity_jitter=1.0, seed=2, name="cloud"
    )
    builder.add_force("drag", coefficient=0.002)
    builder.add_force("damping", rate=0.05, targets=["cloud"])
    builder.add_force("wind", velocity=(1.0, 0.0, 0.0), coefficient=0.001)
    builder.add_force("attractor", point=(0.5, 1.0, 0.0), strength=0.5, softening=0.3)
    builder.add_force("vortex", circulation=1.0, coefficient=0.001, targets=["jet"])
    builder.add_force("quadratic_drag", coefficient=0.0005)
    builder.add_collider("plane", restitution=0.5, friction=0.3)
    builder.add_collider("plane", point=(1.0, 0.0, 0.0), normal=(-1.0, 0.0, 0.0), thickness=0.05)
    builder.add_collider("sphere", center=(0.0, 0.7, 0.3), radius=0.25, restitution=0.8)
    builder.add_collider("box", center=(-0.6, 0.3, 0.0), size=(0.4, 0.2, 0.6), friction=0.5)
    for key, value in extra.items():
        getattr(builder, key)(**value)
    return builder.build()


@pytest.mark.parametrize("steps", [1, 240])
def test_fused_and_generic_steps_agree_to_round_off(steps):
    model = _scene()
    fused, generic = vv.Simulation(model), vv.Simulation(model, compiled=False)
    assert fused.compiled and not generic.compiled
    fused.step(steps)
    generic.step(steps)
    for name in ("particle_alive", "emitter_serial", "emitter_dropped"):
        np.testing.assert_array_equal(fused.raw_state[name], generic.raw_state[name], err_msg=name)
    alive = generic.raw_state["particle_alive"]
    for name in ("particle_position", "particle_velocity", "particle_radius", "particle_age"):
        np.testing.assert_allclose(
            fused.raw_state[name][alive],
            generic.raw_state[name][alive],
            rtol=0,
            atol=1e-9,
            err_msg=name,
        )
    assert fused.energy() == pytest.approx(generic.energy(), rel=1e-9)


_FIELDS = {
    "drag": {"coefficient": 0.02},
    "wind": {"velocity": (2.0, 0.0, -1.0), "coefficient": 0.03},
    "damping": {"rate": 0.4},
    "quadratic_drag": {"coefficient": 0.01, "velocity": (0.5, 0.0, 0.0)},
    "attractor": {"point": (0.3, 1.0, 0.0), "strength": 2.0, "softening": 0.2},
    "vortex": {"circulation": 3.0, "coefficient": 0.05, "core_radius": 0.3},
}


@pytest.mark.parametrize("targets", [None, ["heavy"]], ids=["everything", "some"])
@pytest.mark.parametrize("kind", sorted(_FIELDS))
def test_each_field_law_steps_alike_on_both_roads(kind, targets):
    """One field alone, on every particle (gravity, drag, wind and damping fold into pass 1's
    acceleration) or on some (every law by :func:`~visviva.forces.laws.field_force`, as the
    field's own ``accumulate``): the fused step and the generic pipeline's symplectic Euler
    take the same kicks and drifts, so after 200 steps they agree to round-off."""
    builder = vv.SceneBuilder(name=kind)
    builder.set_integration(method="symplectic_euler", dt=1 / 200, duration=1.0)
    builder.add_particle_cloud(
        40, center=(0.0, 1.0, 0.0), velocity_jitter=2.0, seed=1, name="light"
    )
    builder.add_particle_cloud(
        40, center=(0.5, 1.2, 0.0), velocity_jitter=2.0, mass=3.0, seed=2, name="heavy"
    )
    builder.add_force(kind, targets=targets, **_FIELDS[kind])
    model = builder.build()
    fused, generic = vv.Simulation(model), vv.Simulation(model, compiled=False)
    assert fused.compiled
    fused.step(200)
    generic.step(200)
    for name in ("particle_position", "particle_velocity"):
        np.testing.assert_allclose(
            fused.raw_state[name], generic.raw_state[name], rtol=1e-12, atol=1e-12, err_msg=name
        )


def test_a_ball_landing_within_a_step_bounces_for_the_rest_of_it():
    """With only a floor, the fused step's first pass takes the floor's contact itself; a
    ball that lands within a step must still take the time-of-impact path (seed 003), as the
    generic pipeline does: on the step's chord y(λ) = s + λ h u, with u = v − g h the
    symplectic Euler velocity, it touches at y(λ) = r, its velocity there v + λ (u − v)
    reflects to e |·|, and it flies the rest of the step, (1 − λ) h, under gravity."""
    builder = vv.SceneBuilder(name="bounce")
    dt, e, r, g = 0.002, 0.9, 0.05, 9.81
    builder.set_integration(method="symplectic_euler", dt=dt, duration=1.0)
    builder.add_particles([[0.0, 1.0, 0.0]], radius=r)
    builder.add_collider("plane", restitution=e)
    model = builder.build()
    fused, generic = vv.Simulation(model), vv.Simulation(model, compiled=False)
    assert fused.compiled
    for _ in range(300):
        s, v = (
            generic.raw_state["particle_position"][0, 1],
            generic.raw_state["particle_velocity"][0, 1],
        )
        fused.step()
        generic.step()
        np.testing.assert_array_equal(fused.raw_state.parts[0], generic.raw_state.parts[0])
        np.testing.assert_array_equal(fused.raw_state.parts[1], generic.raw_state.parts[1])
        if generic.raw_state["particle_velocity"][0, 1] > 0.0:
            break
    else:
        pytest.fail("the ball never bounced")
    u = v - g * dt
    fraction = (s - r) / (-u * dt)
    assert 0.0 < fraction < 1.0  # it landed within the step, not at its end
    rest = (1.0 - fraction) * dt
    out = e * abs(v + fraction * (u - v))
    y, vy = (
        generic.raw_state["particle_position"][0, 1],
        generic.raw_state["particle_velocity"][0, 1],
    )
    assert vy == pytest.approx(out - g * rest, rel=1e-6)
    assert y == pytest.approx(r + out * rest - 0.5 * g * rest**2, abs=1e-7)


def test_fused_step_is_taken_only_where_it_applies():
    model = _scene()
    assert vv.Simulation(model).compiled
    assert not vv.Simulation(model, method="velocity_verlet").compiled
    with pytest.raises(vv.ModelError, match="compiled=True"):
        vv.Simulation(model, method="rk4", compiled=True)
    gravitating = _scene(
        add_force={"kind": "gravitation", "targets": ["cloud"], "G": 1e-3, "softening": 0.1}
    )
    assert not vv.Simulation(gravitating).compiled  # n-body gravitation is not a field


@pytest.mark.parametrize("steps", [1, 400])
def test_fused_cloth_with_pins_and_colliders_agrees_with_the_generic_step(steps):
    """Springs join the fused step (a lattice's by its stencil, see test_lattice_springs.py),
    pinned points take pass 2 and stay where they are: the same cloth as the
    generic pipeline's to round-off, falling onto a floor and a ball in light wind."""
    builder = vv.SceneBuilder(name="fused cloth")
    builder.set_integration(method="symplectic_euler", dt=1e-4, duration=1.0)
    builder.add_cloth(
        (12, 12), stiffness=500.0, shear=50.0, bending=1.0, damping=0.01, areal_density=0.1,
        origin=(-0.5, 0.4, -0.5), along=(1.0, 0.0, 0.0), across=(0.0, 0.0, 1.0),
        pinned=[0, 11], name="sheet",
    )  # fmt: skip
    builder.add_particles(positions=[[0.0, 1.0, 0.0]], name="pebble")
    builder.add_force("wind", coefficient=1e-4, velocity=(0.5, 0.0, 0.0))
    builder.add_collider("plane", restitution=0.2, friction=0.3)
    builder.add_collider("sphere", center=(0.0, 0.1, 0.0), radius=0.2, friction=0.5)
    model = builder.build()
    fused, generic = vv.Simulation(model), vv.Simulation(model, compiled=False)
    assert fused.compiled and not generic.compiled
    start = fused.state["particle_position"][[0, 11]].copy()
    fused.step(steps)
    generic.step(steps)
    for name in ("particle_position", "particle_velocity"):
        np.testing.assert_allclose(
            fused.raw_state[name], generic.raw_state[name], rtol=0, atol=1e-9, err_msg=name
        )
    assert np.array_equal(fused.state["particle_position"][[0, 11]], start)


def test_fused_step_reports_a_blow_up_with_the_offending_part():
    builder = vv.SceneBuilder(name="explodes")
    builder.set_integration(method="symplectic_euler", dt=0.1, duration=10.0)
    builder.add_particles([[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]])
    # A repulsor of absurd strength flings the particles out beyond the divergence limit.
    builder.add_force("attractor", point=(0.0, 1.5, 0.0), strength=-1e15, softening=1e-3)
    simulation = vv.Simulation(builder.build())
    assert simulation.compiled
    with pytest.raises(vv.SimulationDiverged, match=r"particle_(position|velocity)"):
        simulation.run(until=10.0)
    # The simulation keeps the last good state.
    assert np.isfinite(simulation.raw_state.parts[0]).all()


def test_fused_state_reads_are_current_and_copies_stay_put():
    """The fused step works on its own copy; every read of the simulation's state is current,
    and what a caller copied does not change under it."""
    simulation = vv.Simulation(_scene())
    simulation.step(3)
    view = simulation.state
    kept = view["particle_position"]
    raw = simulation.raw_state.parts[0].copy()
    simulation.step()
    assert not np.array_equal(simulation.raw_state.parts[0], raw)
    # The view kept across the step still reads the state of its time.
    np.testing.assert_array_equal(view["particle_position"], kept)
    assert view.t == pytest.approx(3 / 240)
    generic = vv.Simulation(_scene(), compiled=False)
    generic.step(3)
    np.testing.assert_allclose(kept, generic.state["particle_position"], rtol=0, atol=1e-12)
    generic.step()
    np.testing.assert_allclose(
        simulation.state["particle_position"],
        generic.state["particle_position"],
        rtol=0,
        atol=1e-12,
    )


@pytest.mark.parametrize("substeps", [1, 3])
def test_fused_blow_up_keeps_the_last_good_state_bit_for_bit(substeps):
    """After a divergence the simulation holds the state at the end of the last good step,
    replayed from the stepper's journal: exactly the state a run stopped there would have."""
    from visviva.simulation.stepper import JOURNAL_STEPS

    def scene() -> vv.Model:
        builder = vv.SceneBuilder(name="flung")
        builder.set_integration(method="symplectic_euler", dt=0.01, substeps=substeps)
        builder.add_emitter(
            rate=200, position=(0, 1, 0), spread_deg=40, speed=[1, 2], lifetime=60, seed=3
        )
        builder.add_collider("plane", restitution=0.4, friction=0.2)
        # Damping too stiff for the step: symplectic Euler multiplies the velocity by
        # 1 − γh = −1.01 a step, so the oldest particles cross the limit after ~1400 steps.
        builder.add_force("damping", rate=2.01 / (0.01 / substeps))
        return builder.build()

    failing = vv.Simulation(scene(), divergence_limit=1e6)
    with pytest.raises(vv.SimulationDiverged) as caught:
        failing.step(100_000)
    steps = caught.value.step // substeps  # the step the blow-up happened in
    assert steps > JOURNAL_STEPS  # the replay starts from a copy the journal took mid-run
    reference = vv.Simulation(scene(), divergence_limit=1e6)
    reference.step(steps)
    assert failing.time == reference.time
    for name in failing.raw_state.names():
        np.testing.assert_array_equal(
            failing.raw_state[name], reference.raw_state[name], err_msg=name
        )
    # Going on from there meets the same blow-up in the same step.
    with pytest.raises(vv.SimulationDiverged) as again:
        failing.step(10)
    assert again.value.step == caught.value.step


def test_the_general_pass_is_compiled_once_for_every_scene_shape():
    """Pass 2 takes every scene's arrays in one form (empty for what a scene has not), so a
    bare ball and the scene with every field, collider and emitter share one compilation
    (it was compiled once per scene shape: a third of a cold test run's compile time). Its
    arguments' Numba types are compared (its dispatcher's signatures would not tell: a pass 1
    loaded from Numba's cache brings pass 2's code without compiling it)."""
    builder = vv.SceneBuilder(name="ball")
    builder.set_integration(method="symplectic_euler", dt=0.002, duration=1.0)
    builder.add_particles([[0.0, 1.0, 0.0]], radius=0.05)
    builder.add_force("attractor", point=(0.0, 0.0, 0.0), strength=0.5, softening=0.3)
    types = []
    for model in (builder.build(), _scene()):
        sim = vv.Simulation(model)
        assert sim.compiled
        sim.step(3)
        carried = dict(sim.raw_state.carried)
        types.append(numba.typeof(sim._stepper.fused.general_arguments(carried)))
    assert types[0] == types[1]
