"""Kinematic handles: pinned points that follow a prescribed rigid motion of time.

The motion is checked against closed forms (the clock against the integral of its rate, the
velocity against the position's derivative, the turn against SciPy's rotations); every
integrator keeps the handled points on the path to round-off; the coupling is exact within a
step (Runge–Kutta 4 keeps its order with a shaking handle); a rope dragged at constant speed
hangs, in the moving frame, exactly as a rope at rest; and bad handles are refused, naming
the field, the value and the fix.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.spatial.transform import Rotation

import visviva as vv
from visviva.io.scene_files import parse_scene
from visviva.model.build import build_model
from visviva.particles.handles import HandleMotion, Handles

GRAVITY = 9.81


@pytest.fixture(autouse=True)
def one_thread():
    """Small bodies: Numba's parallel kernels cost more to launch than they save."""
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(previous)


def rope(method: str, dt: float, duration: float, handle: dict, *, damping: float = 0.0,
         points: int = 6, pinned: tuple[int, ...] = (0,)) -> vv.Model:  # fmt: skip
    """A rope of ``points`` points 10 cm apart hanging from (0.1, 0, 0), pinned at ``pinned``
    and carried by ``handle``."""
    builder = vv.SceneBuilder(name="handled rope")
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method=method, dt=dt, duration=duration)
    builder.add_rope(
        [[0.1, -0.1 * i, 0.0] for i in range(points)],
        mass=0.05,
        stiffness=50.0,
        damping=damping,
        pinned=list(pinned),
        handle=handle,
    )
    return builder.build()


def stage(model: vv.Model) -> Handles:
    return next(s for s in model.stages if isinstance(s, Handles))


# A motion with everything at once: a translation, a steady turn and an oscillation about a
# tilted axis through a pivot off the rope, on a clock that ramps up and down.
EVERYTHING = {
    "pivot": (0.0, 0.05, 0.02),
    "velocity": (0.3, 0.1, -0.2),
    "axis": (0.0, 2.0, 1.0),
    "angular_velocity": 1.5,
    "amplitude": 0.3,
    "frequency": 2.0,
    "start": 0.02,
    "stop": 0.28,
    "ramp": 0.05,
}


def smoothstep(tau: float) -> float:
    return tau * tau * (3.0 - 2.0 * tau)


def rate(t: float, start: float, stop: float, ramp: float) -> float:
    """The clock's rate, written out piece by piece."""
    if t < start or t >= stop:
        return 0.0
    if ramp > 0.0 and t < start + ramp:
        return smoothstep((t - start) / ramp)
    if ramp > 0.0 and t > stop - ramp:
        return smoothstep((stop - t) / ramp)
    return 1.0


def closed_form(handle: dict, start_points: np.ndarray, t: float) -> tuple[np.ndarray, ...]:
    """Where a handle with the fields of ``handle`` holds ``start_points`` at ``t``: the clock
    by quadrature of its rate, the turn by SciPy's rotation of the offsets, the velocity by
    central differences of the position."""

    def position(time: float) -> np.ndarray:
        start, stop, ramp = handle["start"], handle["stop"], handle["ramp"]
        knots = [k for k in (start, start + ramp, stop - ramp, stop) if 0.0 < k < time]
        s = quad(rate, 0.0, time, args=(start, stop, ramp), points=knots or None,
                 epsabs=1e-14, epsrel=1e-14)[0]  # fmt: skip
        theta = handle["angular_velocity"] * s + handle["amplitude"] * math.sin(
            2 * math.pi * handle["frequency"] * s
        )
        axis = np.array(handle["axis"]) / np.linalg.norm(handle["axis"])
        pivot = np.array(handle["pivot"])
        turned = Rotation.from_rotvec(theta * axis).apply(start_points - pivot)
        return pivot + np.array(handle["velocity"]) * s + turned

    step = 1e-6
    return position(t), (position(t + step) - position(t - step)) / (2 * step)


def test_the_clock_is_the_integral_of_its_smooth_rate():
    motion = HandleMotion(np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]),
                          start=0.5, stop=2.0, ramp=0.4)  # fmt: skip
    for t in np.linspace(0.0, 2.5, 51):
        s, speed = motion.clock(float(t))
        integral = quad(rate, 0.0, t, args=(0.5, 2.0, 0.4), points=[0.5, 0.9, 1.6, 2.0])[0]
        assert s == pytest.approx(integral, abs=1e-14)
        assert speed == pytest.approx(rate(t, 0.5, 2.0, 0.4), abs=1e-15)
    # Speeding up and slowing down each cost half a ramp: it stops at stop − start − ramp.
    assert motion.clock(3.0) == (2.0 - 0.5 - 0.4, 0.0)
    # Without a ramp it runs from start itself, and stops at stop.
    sudden = HandleMotion(np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]), start=1.0, stop=2.0)
    assert sudden.clock(1.0) == (0.0, 1.0)
    assert sudden.clock(2.0) == (1.0, 0.0)


def test_positions_and_velocities_are_the_rigid_motion_and_its_derivative():
    model = rope("symplectic_euler", 0.01, 0.3, EVERYTHING, pinned=(0, 1, 2))
    handles = stage(model)
    start = np.array([[0.1, -0.1 * i, 0.0] for i in range(3)])
    for t in (0.0, 0.03, 0.1, 0.2, 0.26, 0.3):
        x, v = handles.place(t)
        position, velocity = closed_form(EVERYTHING, start, t)
        assert np.abs(x - position).max() < 1e-13
        assert np.abs(v - velocity).max() < 1e-8  # the central difference's own error
    # The handled points start where the rope was built, moving as the handle does.
    assert np.abs(model.particle_position[:3] - start).max() < 1e-16
    assert np.array_equal(model.particle_velocity[:3], handles.place(0.0)[1])
    # A rigid motion keeps the distances between the points it carries.
    x, _ = handles.place(0.2)
    assert np.linalg.norm(x[2] - x[0]) == pytest.approx(0.2, rel=1e-14)


METHODS = [
    ("symplectic_euler", True),  # the fused particle step
    ("symplectic_euler", False),  # the generic pipeline
    ("velocity_verlet", False),
    ("rk4", False),
    ("backward_euler", False),
    ("linearly_implicit_euler", False),
    ("projected_newton", False),
    ("projected_trapezoidal", False),
    ("fast_mass_springs", False),
]


@pytest.mark.parametrize(("method", "fused"), METHODS)
def test_every_integrator_keeps_the_handled_points_on_the_path(method, fused):
    model = rope(method, 0.004, 0.3, EVERYTHING, damping=0.05, pinned=(0, 1))
    simulation = vv.Simulation(model, compiled=fused)
    assert simulation.compiled is fused
    start = np.array([[0.1, 0.0, 0.0], [0.1, -0.1, 0.0]])
    handles = stage(model)
    while simulation.time < 0.3 - 1e-9:
        simulation.step()
        x = simulation.state["particle_position"]
        v = simulation.state["particle_velocity"]
        position, velocity = handles.place(simulation.time)
        assert np.abs(x[:2] - position).max() < 1e-12
        assert np.abs(v[:2] - velocity).max() < 1e-12
    # ... which is the closed form's, and the free points were carried along.
    position, _ = closed_form(EVERYTHING, start, 0.3)
    assert np.abs(x[:2] - position).max() < 1e-12
    assert np.isfinite(x).all()
    assert np.linalg.norm(x[2] - model.particle_position[2]) > 0.05


def test_the_fused_step_is_the_generic_pipeline():
    model = rope("symplectic_euler", 0.002, 0.3, EVERYTHING, damping=0.05)
    fused, generic = vv.Simulation(model, compiled=True), vv.Simulation(model, compiled=False)
    fused.run(until=0.3)
    generic.run(until=0.3)
    difference = fused.state["particle_position"] - generic.state["particle_position"]
    assert np.abs(difference).max() < 1e-12  # the order of the force sum differs


def test_the_springs_see_the_handle_inside_the_step_so_runge_kutta_keeps_its_order():
    """A shaken rope: if the forces saw the handle anywhere but on its path during a step
    (where the step began, or moving on its tangent), RK4's error would fall as h² at best."""
    shaking = {"pivot": (0, 0, 0), "amplitude": 0.8, "frequency": 1.5, "velocity": (0.2, 0.1, 0)}
    shaking |= {"axis": (0, 1, 0), "start": 0.0, "stop": 10.0, "ramp": 0.0}
    finest = vv.Simulation(rope("rk4", 0.0025 / 8, 0.5, shaking))
    finest.run(until=0.5)
    errors = []
    for dt in (0.01, 0.005, 0.0025):
        simulation = vv.Simulation(rope("rk4", dt, 0.5, shaking))
        simulation.run(until=0.5)
        difference = simulation.state["particle_position"] - finest.state["particle_position"]
        errors.append(np.abs(difference).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert (orders > 3.7).all(), orders


@pytest.mark.parametrize("method", ["projected_newton", "backward_euler"])
def test_a_rope_dragged_at_constant_velocity_hangs_as_a_rope_at_rest(method):
    """Galilean invariance: in the frame of a pin moving at constant velocity, a rope whose
    swing has died out hangs straight down, each spring stretched by the weight below it over
    k, every point moving with the pin (the springs' dampers resist only relative motion)."""
    points, spacing, mass, k = 8, 0.1, 0.05, 200.0
    drag = (0.4, 0.0, 0.0)
    builder = vv.SceneBuilder(name="dragged rope")
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method=method, dt=0.05, duration=60.0)
    builder.add_rope([[0.0, -spacing * i, 0.0] for i in range(points)], mass=mass,
                     stiffness=k, damping=0.5, pinned=[0],
                     handle={"velocity": drag, "ramp": 1.0})  # fmt: skip
    simulation = vv.Simulation(builder.build())
    simulation.run(until=60.0)
    x = simulation.state["particle_position"]
    v = simulation.state["particle_velocity"]
    stretch = np.linalg.norm(np.diff(x, axis=0), axis=1) - spacing
    weight_below = mass * GRAVITY * np.arange(points - 1, 0, -1)
    assert stretch == pytest.approx(weight_below / k, rel=1e-6)
    assert np.abs(v - drag).max() < 1e-6
    assert np.abs(x[1:, [0, 2]] - x[0, [0, 2]]).max() < 1e-6  # straight below the pin
    # The pin went where the handle took it: half a second lost to the ramp.
    assert x[0] == pytest.approx([0.4 * (60.0 - 0.5), 0.0, 0.0], abs=1e-12)


def test_a_scene_file_and_the_builder_give_the_same_handles():
    text = """
[integration]
method = "symplectic_euler"
dt = 0.01
duration = 1.0

[[entities]]
type = "hair"
points = [[0, 1.5, 0.1], [0, 1.46, 0.1], [0, 1.42, 0.1]]
mass = 0.0005
stiffness = 200.0
bending = 20.0

[entities.handle]
pivot = [0, 1.5, 0]
angular_velocity = 1.6
start = 0.2
stop = 0.8
ramp = 0.1
"""
    from_file = build_model(parse_scene(text))
    builder = vv.SceneBuilder()
    builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
    builder.add_hair([[0, 1.5, 0.1], [0, 1.46, 0.1], [0, 1.42, 0.1]], mass=0.0005,
                     stiffness=200.0, bending=20.0,
                     handle=vv.entities.Handle(pivot=(0, 1.5, 0), angular_velocity=1.6, start=0.2,
                                            stop=0.8, ramp=0.1))  # fmt: skip
    from_python = builder.build()
    assert from_file.scene.entities == from_python.scene.entities
    for t in (0.0, 0.25, 0.5, 1.0):
        assert np.array_equal(stage(from_file).place(t)[0], stage(from_python).place(t)[0])
    # After the stop, the root has turned by ω (stop − start − ramp) about the vertical.
    root = stage(from_file).place(1.0)[0][0]
    turn = 1.6 * (0.8 - 0.2 - 0.1)
    assert root == pytest.approx([0.1 * math.sin(turn), 1.5, 0.1 * math.cos(turn)], abs=1e-15)
    # A scene written back reads back the same.
    again = parse_scene(vv.io.dump_scene(from_file.scene))
    assert again.entities == from_file.scene.entities


def test_static_pins_have_no_handles_stage_and_stay_bit_identical():
    builder = vv.SceneBuilder()
    builder.set_integration(method="projected_newton", dt=0.02, duration=0.5)
    builder.add_rope([[0, -0.1 * i, 0] for i in range(5)], mass=0.05, stiffness=50.0,
                     damping=0.1, pinned=[0])  # fmt: skip
    model = builder.build()
    assert not model.stages
    simulation = vv.Simulation(model)
    simulation.run(until=0.5)
    assert np.array_equal(simulation.state["particle_position"][0], model.particle_position[0])


BAD_HANDLES = [
    ({"velocity": (math.nan, 0.0, 0.0)}, "handle.velocity[0]", "finite"),
    ({"angular_velocity": math.inf}, "handle.angular_velocity", "finite"),
    ({"ramp": -0.5}, "handle.ramp", "greater than or equal to 0"),
    ({"start": -1.0}, "handle.start", "greater than or equal to 0"),
    ({"stop": -1.0}, "handle.stop", "greater than 0"),
    ({"start": 1.0, "stop": 0.5}, "handle", "`stop` (0.5 s) must be after `start` (1.0 s)"),
    ({"stop": 1.0, "ramp": 0.6}, "handle", "shorten the ramp or move `stop`"),
    ({"angular_speed": 1.0}, "handle.angular_speed", "Did you mean 'angular_velocity'?"),
    ({"amplitude": 0.3}, "handle", "needs a `frequency` > 0"),
    ({"frequency": 2.0}, "handle", "moves nothing without an `amplitude`"),
    ({"axis": (0, 0, 0), "angular_velocity": 1.0}, "handle", "`axis` is the zero vector"),
    ("fast", "handle", "valid dictionary"),
    ({"velocity": (1e300, 0.0, 0.0)}, "handle", "beyond the range of a float"),
    ({"amplitude": 1e300, "frequency": 1e300}, "handle", "beyond the range of a float"),
    ({"amplitude": 1e-10, "frequency": 1e307}, "handle", "beyond the range of a float"),
]


@pytest.mark.parametrize(("handle", "where", "message"), BAD_HANDLES)
def test_bad_handles_are_refused_naming_the_field_and_the_fix(handle, where, message):
    builder = vv.SceneBuilder()
    builder.set_integration(dt=0.01, duration=10.0)
    with pytest.raises(vv.SceneError) as error:
        builder.add_rope([[0, 0, 0], [0, -0.1, 0]], mass=0.1, stiffness=10.0, pinned=[0],
                         handle=handle)  # fmt: skip
        builder.build()
    assert f"entities[0].{where}" in str(error.value)
    assert message in str(error.value)


def test_a_handle_needs_pins_to_move():
    builder = vv.SceneBuilder()
    with pytest.raises(vv.SceneError, match="list the points it should move in `pinned`"):
        builder.add_cloth((3, 3), stiffness=10.0, handle={"velocity": (1, 0, 0)})


def test_a_bad_handle_in_a_scene_file_is_found_at_its_line():
    text = """[[entities]]
type = "rope"
points = [[0, 0, 0], [0, -1, 0]]
stiffness = 10.0
pinned = [0]

[entities.handle]
velocity = [nan, 0, 0]
ramp = -1
spin = 3
"""
    with pytest.raises(vv.SceneError) as error:
        parse_scene(text, source="rope.toml")
    problems = {p.path: p for p in error.value.problems}
    assert set(problems) == {
        "entities[0].handle.velocity[0]",
        "entities[0].handle.ramp",
        "entities[0].handle.spin",
    }
    assert "Allowed: pivot, velocity, axis" in problems["entities[0].handle.spin"].message
    assert [problems[f"entities[0].handle.{key}"].line for key in ("ramp", "spin")] == [9, 10]
