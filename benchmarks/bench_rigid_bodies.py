#!/usr/bin/env python
"""Rigid-body benchmark: 10,000 free boxes under gravity and damping, visviva against MuJoCo.

Run ``python benchmarks/bench_rigid_bodies.py`` (under a minute on 2 cores, about 12 s of it
MuJoCo compiling its model, a time that grows about as N²: 0.5 s at 2,000 bodies) or add
``--quick`` (500 bodies) for a smoke run whose figures mean nothing. MuJoCo is optional and
never a visviva dependency; install it into a directory of its own and name that directory::

    pip install --target /tmp/peers-mujoco mujoco
    python benchmarks/bench_rigid_bodies.py --peers /tmp/peers-mujoco

(``VISVIVA_PEERS=/tmp/peers-mujoco`` does the same as ``--peers``.) MuJoCo 4.0.0 needs its
``mujoco-core`` and ``mujoco-studio`` wheels, so it is installed with its dependencies and the
directory holds a NumPy too: the directory is appended to ``sys.path`` while ``mujoco`` is
imported, never put first, so visviva's NumPy is the one that loads. Without MuJoCo the script
says so and prints visviva's figures alone.

The scene, the same for both runners (float64 throughout):

* N boxes (N = 10,000; ``--bodies N``; ``--quick``: 500); each edge of each box drawn uniformly
  in [0.1, 0.3] m (seeded), density 500 kg/m³: mass m = 500 abc and, about the centre and along
  the edges, the moments m (b² + c²)/12, m (a² + c²)/12, m (a² + b²)/12, three different ones
  (asymmetric bodies that tumble);
* centres on a cubic grid 1 m apart (a box is at most 0.52 m across: none touch), orientations
  random unit quaternions, velocities of random direction and speed up to 2 m/s, angular
  velocities (world frame) of random direction and up to 5 rad/s (all seeded);
* gravity (0, −9.81, 0) m/s², linear damping P' = F − γ P with γ = 0.5 1/s and angular damping
  L' = τ − γ' L with γ' = 0.2 1/s (P, L the world-frame momenta); no contacts;
* steps of h = 1/240 s.

visviva: one ``SceneBuilder.add_body("box", ...)`` per box (``linear_damping_rate`` γ,
``angular_damping_rate`` γ'), then ``vv.Simulation(model)`` with the scene's symplectic Euler: a
kick P += h (F − γ P), L += h (τ − γ' L), then a drift, x += h P/m and the free rotation by the
splitting of Dullweber, Leimkuhler and McLachlan, which keeps L exactly.

MuJoCo: an MJCF string generated here, per box a ``<body>`` with a ``<freejoint/>`` and a
``<geom type="box">`` of its half-edges and the density; ``<option>`` with the step, the gravity
and ``<flag contact="disable"/>``; its default integrator, Euler (semi-implicit: velocities
first, positions from the new velocities, joint damping taken implicitly). ``<size memory>``
gives it 4 KiB of arena per body: at 10,000 free bodies its automatic size fails ("Could not
allocate memory"). The damping is MuJoCo's joint damping, a force −d · qvel per dof, set in
``model.dof_damping`` after compiling: d = γ m on a free joint's three translational dofs, which
is P' = F − γ P exactly, and d_k = γ' I_kk on its three rotational dofs, which is L' = τ − γ' L
exactly as well: those dofs are the angular velocity ω in the body's frame, where a box's
inertia I is diagonal, so −γ' I_kk ω_k = −γ' (I ω)_k, the body-frame angular momentum (part (a)
checks that MuJoCo's inertia is diagonal in the body's axes). The start is written to ``qpos``
and ``qvel`` (the angular velocity turned into the body's frame).

(a) Building each scene (one measurement each, not in the step figures) and the scene check:
both runners' masses and inertias against the closed forms (1e-12, relative), MuJoCo's centres
of mass at its bodies' origins, and both starts equal to the scene's (x, q, P, L).

(b) Stepping, ten steps per timed call (time per step: the call's median over its steps),
repeated calls advancing the same bodies (they fall on; the work per step does not change):

* MuJoCo ``mj_step(model, data)`` once per step in a Python loop, as its users write it, and
  ``mj_step(model, data, nstep=10)``, the loop in C (where the installed version has ``nstep``);
* visviva ``sim.step()`` once per step in a Python loop, and ``sim.step(10)``, on every core,
  and ``sim.step(10)`` on one thread (MuJoCo steps on one thread).

Figures: time per step, steps/s, body-steps/s (N × steps/s), process CPU time / wall time while
stepping (about the threads each keeps busy), the first call (visviva's compiles), and the ratios
visviva ÷ MuJoCo; the target is ≥ 3× MuJoCo's steps/s in the same run, judged on each runner's
fastest way to step.

(c) Agreement after 1 s (240 steps) from the same start, fresh simulations of the same models:

* translation: each runner follows its own recurrence to round-off (1e-9 m), visviva the
  explicit v ← (1 − hγ) v + h g, MuJoCo the implicit v ← (v + h g)/(1 + hγ), both then
  x ← x + h v. Applied to the same v they differ by h² γ (γ v − g)/(1 + hγ); |γ v − g| only
  shrinks (by 1 − hγ or 1/(1 + hγ) a step) and both maps contract, so after n steps, t = n h,
  |Δx| ≤ h γ |γ v₀ − g| t (t + h)/2 for each body (about 1.1 cm at t = 1 s): checked. Each is
  about g h t/2 ≈ 2 cm from the exact solution (both add h v_{n+1}, not the exact area): printed.
* rotation: visviva's L after n steps is (1 − hγ')ⁿ L₀ (the drift keeps L): checked to 1e-10,
  relative. MuJoCo's L has the factor (1 + hγ')⁻ⁿ of its implicit damping; its Euler step takes
  the gyroscopic torque ω × I ω explicitly, so its free rotation keeps neither |L| nor the
  rotational energy E. Printed, not checked: each runner's |L| and E with its own damping factor
  divided out (squared for E) as changes relative to the start, median and largest over the
  bodies; and the angles between the two runners' orientations.

Timings are medians of repeats after a warm-up call, each with the share of the CPU other
processes used meanwhile (re-measured when above 5%). This is not a test: it prints figures and
exits 1 only if a sanity check fails.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import math
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np

import visviva as vv
from bench_integrators import (
    PATIENCE,
    Checks,
    Timing,
    cpu_description,
    finish,
    fmt_time,
    heading,
    load_average,
    measure,
    print_table,
    sci,
    source_state,
)
from bench_particles import cpu_share, on_path

# --------------------------------------------------------------------------------------------
# The scene
# --------------------------------------------------------------------------------------------

GRAVITY = (0.0, -9.81, 0.0)  # m/s²
DENSITY = 500.0  # kg/m³
EDGES = (0.1, 0.3)  # m: each edge of each box uniform in this range
SPACING = 1.0  # m between neighbouring centres
MAX_SPEED = 2.0  # m/s
MAX_SPIN = 5.0  # rad/s
LINEAR_DAMPING = 0.5  # γ [1/s]
ANGULAR_DAMPING = 0.2  # γ' [1/s]
STEP = 1.0 / 240.0  # s
SEED = 20261212
BODIES = 10_000
QUICK_BODIES = 500

#: Steps per timed call (the Python-loop runners loop this many times in a call).
STEPS_PER_CALL = 10
#: MuJoCo's arena per body [B] (it uses about 100 B a body here; its automatic size fails).
MUJOCO_ARENA_PER_BODY = 4096

#: The agreement check: simulated time [s] and the round-off allowed on a runner's own
#: recurrence [m] (the centres are within ~20 m of the origin and fall ~4 m in 240 steps).
CHECK_TIME = 1.0
ROUND_OFF = 1e-9
#: Mass and inertia against the closed forms, and the starts against the scene (relative).
PROPERTY_TOLERANCE = 1e-12
#: visviva's L against (1 − hγ')ⁿ L₀ (relative to |L₀|; 240 roundings of ~1e-16 each).
ANGULAR_TOLERANCE = 1e-10

TARGET_VS_MUJOCO = 3.0  # × MuJoCo's steps/s, each runner's fastest way


@dataclass(frozen=True)
class Boxes:
    """The scene's boxes (see the module docstring); every array's first axis is the box."""

    edges: np.ndarray  # (N, 3) full edge lengths [m]
    position: np.ndarray  # (N, 3) centres [m], the centres of mass
    orientation: np.ndarray  # (N, 4) unit quaternions (w, x, y, z), body to world
    velocity: np.ndarray  # (N, 3) [m/s]
    angular_velocity: np.ndarray  # (N, 3) world frame [rad/s]

    @property
    def count(self) -> int:
        return int(self.edges.shape[0])

    @property
    def mass(self) -> np.ndarray:
        """(N,) [kg]."""
        return DENSITY * self.edges.prod(axis=1)

    @property
    def moments(self) -> np.ndarray:
        """(N, 3) moments of inertia about the centre along the edges [kg·m²]."""
        square = self.edges**2
        return self.mass[:, None] / 12.0 * (square.sum(axis=1, keepdims=True) - square)

    @property
    def angular_momentum(self) -> np.ndarray:
        """(N, 3) L = R I Rᵀ ω [kg·m²/s], world frame."""
        rotation = rotation_matrices(self.orientation)
        spin = np.einsum("bji,bj->bi", rotation, self.angular_velocity)  # Rᵀ ω
        return np.einsum("bij,bj->bi", rotation, self.moments * spin)

    @property
    def rotational_energy(self) -> np.ndarray:
        """(N,) ½ ω · I ω [J]."""
        return 0.5 * np.einsum("bi,bi->b", self.angular_velocity, self.angular_momentum)


def directions(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3) unit vectors, uniform on the sphere."""
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def box_scene(n: int, seed: int = SEED) -> Boxes:
    """The scene with ``n`` boxes, from a seeded generator."""
    rng = np.random.default_rng(seed)
    side = 1
    while side**3 < n:
        side += 1
    index = np.arange(n)
    grid = np.stack([index % side, index // side % side, index // side**2], axis=1)
    q = rng.normal(size=(n, 4))
    q *= np.where(q[:, :1] < 0.0, -1.0, 1.0) / np.linalg.norm(q, axis=1, keepdims=True)
    return Boxes(
        edges=rng.uniform(*EDGES, size=(n, 3)),
        position=SPACING * (grid - 0.5 * (side - 1)),
        orientation=q,
        velocity=MAX_SPEED * rng.uniform(size=(n, 1)) * directions(rng, n),
        angular_velocity=MAX_SPIN * rng.uniform(size=(n, 1)) * directions(rng, n),
    )


def rotation_matrices(q: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) unit quaternions (w, x, y, z)."""
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def discrete_positions(boxes: Boxes, steps: int, *, implicit: bool) -> np.ndarray:
    """The centres after ``steps`` under gravity and linear damping, the damping taken
    explicitly (visviva) or implicitly (MuJoCo's Euler), then x ← x + h v."""
    x, v = boxes.position.copy(), boxes.velocity.copy()
    g, decay = STEP * np.array(GRAVITY), STEP * LINEAR_DAMPING
    for _ in range(steps):
        v = (v + g) / (1.0 + decay) if implicit else (1.0 - decay) * v + g
        x += STEP * v
    return x


def exact_positions(boxes: Boxes, t: float) -> np.ndarray:
    """The centres at ``t`` [s] solving x'' = g − γ x' exactly."""
    g, rate = np.array(GRAVITY), LINEAR_DAMPING
    terminal = g / rate
    return (
        boxes.position + terminal * t + (boxes.velocity - terminal) * -math.expm1(-rate * t) / rate
    )


@dataclass(frozen=True)
class Snapshot:
    """What the agreement check reads from a runner."""

    position: np.ndarray  # (N, 3) centres of mass [m]
    orientation: np.ndarray  # (N, 4)
    angular_momentum: np.ndarray  # (N, 3) world frame [kg·m²/s]
    rotational_energy: np.ndarray  # (N,) [J]


# --------------------------------------------------------------------------------------------
# visviva
# --------------------------------------------------------------------------------------------


def visviva_model(boxes: Boxes) -> tuple[vv.Model, dict[str, float]]:
    """The scene built through visviva's public builder, and how long each part took [s]."""
    started = time.perf_counter()
    builder = vv.SceneBuilder(name="benchmark rigid bodies")
    builder.set_world(gravity=GRAVITY)
    builder.set_integration(method="symplectic_euler", dt=STEP, duration=CHECK_TIME)
    columns = zip(
        boxes.edges.tolist(),
        boxes.position.tolist(),
        boxes.orientation.tolist(),
        boxes.velocity.tolist(),
        boxes.angular_velocity.tolist(),
        strict=True,
    )
    for i, (edges, position, orientation, velocity, spin) in enumerate(columns):
        builder.add_body(
            "box",
            size=edges,
            density=DENSITY,
            position=position,
            orientation=orientation,
            velocity=velocity,
            angular_velocity=spin,
            linear_damping_rate=LINEAR_DAMPING,
            angular_damping_rate=ANGULAR_DAMPING,
            name=f"box {i}",
        )
    added = time.perf_counter()
    model = builder.build()
    built = time.perf_counter()
    vv.Simulation(model)
    times = {"add_body × N": added - started, "build()": built - added}
    times["Simulation(model)"] = time.perf_counter() - built
    return model, times


def visviva_snapshot(simulation: vv.Simulation, model: vv.Model) -> Snapshot:
    state = simulation.state
    orientation = np.array(state["body_orientation"])
    momentum = np.array(state["body_angular_momentum"])
    spin = np.einsum("bji,bj->bi", rotation_matrices(orientation), momentum)  # Rᵀ L
    omega = np.linalg.solve(model.bodies.inertia, spin[..., None])[..., 0]  # body frame
    return Snapshot(
        np.array(state["body_position"]),
        orientation,
        momentum,
        0.5 * np.einsum("bi,bi->b", spin, omega),
    )


# --------------------------------------------------------------------------------------------
# MuJoCo peer (optional; never a visviva dependency)
# --------------------------------------------------------------------------------------------


def numbers(values: Sequence[float]) -> str:
    """Floats as MJCF writes them, each to the last bit."""
    return " ".join(f"{value:.17g}" for value in values)


class MuJoCoPeer:
    """MuJoCo's Python bindings, loaded from a directory of their own."""

    def __init__(self, directory: str | None) -> None:
        with on_path(directory):
            self.mujoco = importlib.import_module("mujoco")
        mujoco = self.mujoco
        tiny = mujoco.MjModel.from_xml_string(
            "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>"
        )
        try:
            mujoco.mj_step(tiny, mujoco.MjData(tiny), nstep=2)
            self.has_nstep = True
        except TypeError:  # older bindings: mj_step(model, data) only
            self.has_nstep = False

    @property
    def version(self) -> str:
        where = Path(self.mujoco.__file__).parent.parent
        return f"{self.mujoco.__version__} (engine {self.mujoco.mj_versionString()}) from {where}"

    @staticmethod
    def mjcf(boxes: Boxes) -> str:
        """The scene as MJCF: a free body and a box geom per box, contacts off."""
        arena = max(2**20, MUJOCO_ARENA_PER_BODY * boxes.count)
        bodies = "".join(
            f'<body pos="{numbers(x)}" quat="{numbers(q)}"><freejoint/>'
            f'<geom type="box" size="{numbers(0.5 * e)}" density="{DENSITY!r}"/></body>'
            for x, q, e in zip(boxes.position, boxes.orientation, boxes.edges, strict=True)
        )
        return (
            f'<mujoco model="visviva rigid bodies"><size memory="{arena // 1024}K"/>'
            f'<option timestep="{STEP!r}" gravity="{numbers(GRAVITY)}" integrator="Euler">'
            f'<flag contact="disable"/></option><worldbody>{bodies}</worldbody></mujoco>'
        )

    def build(self, boxes: Boxes) -> tuple[Any, dict[str, float]]:
        """The compiled model with the damping set, and how long each part took [s]."""
        started = time.perf_counter()
        text = self.mjcf(boxes)
        written = time.perf_counter()
        model = self.mujoco.MjModel.from_xml_string(text)
        compiled = time.perf_counter()
        dof = model.body_dofadr[1:, None] + np.arange(3)
        model.dof_damping[dof] = LINEAR_DAMPING * model.body_mass[1:, None]
        model.dof_damping[dof + 3] = ANGULAR_DAMPING * np.diagonal(
            self.body_inertia(model), axis1=1, axis2=2
        )
        times = {"MJCF string": written - started, "MjModel.from_xml_string": compiled - written}
        self.start(model, boxes)
        times["MjData, damping, start"] = time.perf_counter() - compiled
        return model, times

    @staticmethod
    def body_inertia(model: Any) -> np.ndarray:
        """(N, 3, 3) each body's inertia about its centre of mass in the body's axes."""
        turn = rotation_matrices(model.body_iquat[1:])
        return np.einsum("bij,bj,bkj->bik", turn, model.body_inertia[1:], turn)

    def start(self, model: Any, boxes: Boxes) -> Any:
        """Fresh data at the scene's start."""
        data = self.mujoco.MjData(model)
        qpos = model.jnt_qposadr[model.body_jntadr[1:]][:, None]
        dof = model.body_dofadr[1:, None] + np.arange(3)
        data.qpos[qpos + np.arange(3)] = boxes.position
        data.qpos[qpos + 3 + np.arange(4)] = boxes.orientation
        data.qvel[dof] = boxes.velocity
        turn = rotation_matrices(boxes.orientation)
        data.qvel[dof + 3] = np.einsum("bji,bj->bi", turn, boxes.angular_velocity)
        self.mujoco.mj_forward(model, data)
        return data

    def snapshot(self, model: Any, data: Any) -> Snapshot:
        # mj_step computes the kinematics (xipos, xquat) before it integrates: bring them up
        # to date with the state it leaves.
        self.mujoco.mj_kinematics(model, data)
        orientation = data.xquat[1:].copy()
        omega = data.qvel[model.body_dofadr[1:, None] + 3 + np.arange(3)]
        spin = np.einsum("bij,bj->bi", self.body_inertia(model), omega)
        return Snapshot(
            data.xipos[1:].copy(),
            orientation,
            np.einsum("bij,bj->bi", rotation_matrices(orientation), spin),
            0.5 * np.einsum("bi,bi->b", omega, spin),
        )


def load_mujoco(directory: str | None) -> tuple[MuJoCoPeer | None, str]:
    """The MuJoCo peer, or None and the reason it is unavailable."""
    try:
        return MuJoCoPeer(directory), ""
    except ImportError as error:
        return None, f"not installed ({error})"
    except Exception as error:  # a broken install: skip it, say why
        return None, f"unusable ({type(error).__name__}: {error})"


# --------------------------------------------------------------------------------------------
# (a) Building, and the scene check
# --------------------------------------------------------------------------------------------


def relative(a: np.ndarray, b: np.ndarray, scale: np.ndarray | float) -> float:
    """The largest |a − b| over ``scale`` (broadcast), 0 for empty arrays."""
    return float(np.max(np.abs(a - b) / scale, initial=0.0))


def bench_build(
    boxes: Boxes, peer: MuJoCoPeer | None, checks: Checks
) -> tuple[vv.Model, Any | None]:
    heading(f"(a) Building the scene: {boxes.count:,} boxes (one measurement each)")
    model, times = visviva_model(boxes)
    rows = [["visviva", part, fmt_time(seconds)] for part, seconds in times.items()]
    mujoco_model = None
    if peer is not None:
        mujoco_model, times = peer.build(boxes)
        rows += [["MuJoCo", part, fmt_time(seconds)] for part, seconds in times.items()]
    print_table(["runner", "part", "time"], rows)
    print()
    mass, moments = boxes.mass, boxes.moments
    inertia = np.einsum("bi,ij->bij", moments, np.eye(3))
    largest = moments.max(axis=1)[:, None, None]
    bodies = model.bodies
    checks.check(
        relative(bodies.mass, mass, mass) <= PROPERTY_TOLERANCE
        and relative(bodies.inertia, inertia, largest) <= PROPERTY_TOLERANCE,
        f"visviva's masses and inertias (body axes) are the closed forms: mass"
        f" {relative(bodies.mass, mass, mass):.1e}, inertia"
        f" {relative(bodies.inertia, inertia, largest):.1e} (≤ {PROPERTY_TOLERANCE:g}, relative)",
    )
    simulation = vv.Simulation(model)
    start = visviva_snapshot(simulation, model)
    momentum = np.array(simulation.state["body_momentum"])
    spin = np.linalg.norm(boxes.angular_momentum, axis=1, keepdims=True)
    differences = {
        "x": relative(start.position, boxes.position, 1.0),
        "q": relative(start.orientation, boxes.orientation, 1.0),
        "P": relative(momentum, mass[:, None] * boxes.velocity, mass[:, None] * MAX_SPEED),
        "L": relative(start.angular_momentum, boxes.angular_momentum, spin),
    }
    checks.check(
        max(differences.values()) <= PROPERTY_TOLERANCE,
        "visviva starts from the scene's state: "
        + ", ".join(f"{key} {value:.1e}" for key, value in differences.items()),
    )
    if peer is None or mujoco_model is None:
        return model, None
    theirs = peer.body_inertia(mujoco_model)
    their_mass = mujoco_model.body_mass[1:]
    centres = float(np.abs(mujoco_model.body_ipos[1:]).max())
    checks.check(
        relative(their_mass, mass, mass) <= PROPERTY_TOLERANCE
        and relative(theirs, inertia, largest) <= PROPERTY_TOLERANCE
        and centres <= PROPERTY_TOLERANCE,
        f"MuJoCo's masses and inertias (body axes, so diagonal there: the rotational damping's"
        f" premise) are the closed forms: mass {relative(their_mass, mass, mass):.1e}, inertia"
        f" {relative(theirs, inertia, largest):.1e}; centres of mass {centres:.1e} m from the"
        " bodies' origins",
    )
    data = peer.start(mujoco_model, boxes)
    first = peer.snapshot(mujoco_model, data)
    velocity = data.qvel[mujoco_model.body_dofadr[1:, None] + np.arange(3)]
    differences = {
        "x": relative(first.position, boxes.position, 1.0),
        "q": relative(first.orientation, boxes.orientation, 1.0),
        "v": relative(velocity, boxes.velocity, MAX_SPEED),
        "L": relative(first.angular_momentum, boxes.angular_momentum, spin),
    }
    checks.check(
        max(differences.values()) <= PROPERTY_TOLERANCE,
        "MuJoCo starts from the scene's state: "
        + ", ".join(f"{key} {value:.1e}" for key, value in differences.items()),
    )
    return model, mujoco_model


# --------------------------------------------------------------------------------------------
# (b) Stepping
# --------------------------------------------------------------------------------------------

MUJOCO_LOOP = "MuJoCo mj_step, Python loop"
MUJOCO_NSTEP = f"MuJoCo mj_step(nstep={STEPS_PER_CALL})"
VISVIVA_LOOP = "visviva sim.step(), Python loop"
VISVIVA_BATCH = f"visviva sim.step({STEPS_PER_CALL})"
VISVIVA_ONE = f"visviva sim.step({STEPS_PER_CALL}), 1 thread"


@dataclass(frozen=True)
class Runner:
    label: str
    call: Callable[[], None]  # advances STEPS_PER_CALL steps
    threads: int  # Numba threads while it runs (MuJoCo ignores them)


def runners(
    boxes: Boxes, model: vv.Model, peer: MuJoCoPeer | None, mujoco_model: Any | None
) -> list[Runner]:
    every = numba.config.NUMBA_NUM_THREADS
    plan = []
    if peer is not None and mujoco_model is not None:
        mujoco = peer.mujoco
        looped = peer.start(mujoco_model, boxes)

        def mujoco_loop() -> None:
            for _ in range(STEPS_PER_CALL):
                mujoco.mj_step(mujoco_model, looped)

        plan.append(Runner(MUJOCO_LOOP, mujoco_loop, every))
        if peer.has_nstep:
            batched = peer.start(mujoco_model, boxes)

            def mujoco_nstep() -> None:
                mujoco.mj_step(mujoco_model, batched, nstep=STEPS_PER_CALL)

            plan.append(Runner(MUJOCO_NSTEP, mujoco_nstep, every))
    one_by_one = vv.Simulation(model)

    def visviva_loop() -> None:
        for _ in range(STEPS_PER_CALL):
            one_by_one.step()

    plan.append(Runner(VISVIVA_LOOP, visviva_loop, every))
    together = vv.Simulation(model)
    plan.append(Runner(VISVIVA_BATCH, lambda: together.step(STEPS_PER_CALL), every))
    alone = vv.Simulation(model)
    plan.append(Runner(VISVIVA_ONE, lambda: alone.step(STEPS_PER_CALL), 1))
    return plan


def bench_step(
    args: argparse.Namespace,
    boxes: Boxes,
    model: vv.Model,
    peer: MuJoCoPeer | None,
    mujoco_model: Any | None,
    checks: Checks,
) -> dict[str, float]:
    """Time every runner; return steps/s by label."""
    heading(f"(b) Stepping {boxes.count:,} boxes, {STEPS_PER_CALL} steps of {STEP:.4g} s a call")
    rates: dict[str, float] = {}
    rows = []
    for runner in runners(boxes, model, peer, mujoco_model):
        numba.set_num_threads(runner.threads)
        try:
            timing: Timing = measure(runner.call, args.repeats, f"(b) {runner.label}")
            share = cpu_share(runner.call)
        except vv.SimulationError as error:  # the divergence watch: report, go on
            checks.check(False, f"{runner.label}: {error}")
            continue
        finally:
            numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        per_step = timing.median / STEPS_PER_CALL
        rates[runner.label] = 1.0 / per_step
        rows.append(
            [
                runner.label,
                fmt_time(per_step),
                sci(1.0 / per_step),
                sci(boxes.count / per_step),
                f"{share:.2f}",
                fmt_time(timing.first),
                timing.busy,
            ]
        )
    print_table(
        ["runner", "per step", "steps/s", "body-steps/s", "CPU/wall", "first call", "others' CPU"],
        rows,
    )
    print(
        "  CPU/wall: process CPU time over wall time while stepping, about the threads a runner"
        f" keeps busy; first call: {STEPS_PER_CALL} steps, visviva's compiling its kernels (or"
        " loading them from the cache)"
    )
    if peer is not None and not peer.has_nstep:
        print("  MuJoCo's mj_step has no nstep argument in this version: its loop runs alone")
    return rates


def summarise(rates: dict[str, float]) -> None:
    heading("Comparisons (steps/s)")

    def fastest(prefix: str) -> str | None:
        labels = [label for label in rates if label.startswith(prefix)]
        return max(labels, key=rates.__getitem__, default=None)

    if fastest("MuJoCo") is None:
        print("  no MuJoCo figures (see the header): no comparisons")
        return
    pairs = [
        ("each runner's fastest (the target)", fastest("visviva"), fastest("MuJoCo")),
        ("k steps a call", VISVIVA_BATCH, MUJOCO_NSTEP),
        ("Python loop of single steps", VISVIVA_LOOP, MUJOCO_LOOP),
        ("both on one thread", VISVIVA_ONE, fastest("MuJoCo")),
    ]
    rows = []
    for what, ours, theirs in pairs:
        if ours in rates and theirs in rates:
            ratio = rates[ours] / rates[theirs]
            verdict = "met" if ratio >= TARGET_VS_MUJOCO else "not met"
            rows.append([what, f"{ours} ÷ {theirs}", f"{ratio:.2f}×", verdict])
        else:
            rows.append([what, f"{ours} ÷ {theirs}", "n/a", "n/a"])
    print_table(["comparison", "runners", "visviva ÷ MuJoCo", f"≥ {TARGET_VS_MUJOCO:g}×"], rows)
    print(
        f"  target: visviva ≥ {TARGET_VS_MUJOCO:g}× MuJoCo's steps/s on the same bodies in the"
        " same run, each runner stepping its fastest way (first row); the others for context"
    )


# --------------------------------------------------------------------------------------------
# (c) Agreement
# --------------------------------------------------------------------------------------------


def free_rotation(snapshot: Snapshot, boxes: Boxes, factor: float) -> tuple[np.ndarray, ...]:
    """Relative changes of |L| and E over the run with the damping's ``factor`` (on L) out."""
    start = np.linalg.norm(boxes.angular_momentum, axis=1)
    kept = np.linalg.norm(snapshot.angular_momentum, axis=1) / factor / start - 1.0
    energy = snapshot.rotational_energy / factor**2 / boxes.rotational_energy - 1.0
    return kept, energy


def bench_agreement(
    boxes: Boxes,
    model: vv.Model,
    peer: MuJoCoPeer | None,
    mujoco_model: Any | None,
    checks: Checks,
) -> None:
    steps = round(CHECK_TIME / STEP)
    t = steps * STEP
    heading(f"(c) Agreement after {t:g} s ({steps} steps) from the same start")
    simulation = vv.Simulation(model)
    simulation.step(steps)
    ours = visviva_snapshot(simulation, model)
    exact = exact_positions(boxes, t)
    fall = float(np.median(boxes.position[:, 1] - exact[:, 1]))
    print(f"  the centres fell {fall:.2f} m (median) in {t:g} s")
    own = relative(ours.position, discrete_positions(boxes, steps, implicit=False), 1.0)
    checks.check(
        own <= ROUND_OFF,
        f"visviva's centres follow v ← (1 − hγ) v + h g, x ← x + h v: {own:.1e} m"
        f" (≤ {ROUND_OFF:g})",
    )
    factor = (1.0 - STEP * ANGULAR_DAMPING) ** steps
    start = np.linalg.norm(boxes.angular_momentum, axis=1, keepdims=True)
    spin = relative(ours.angular_momentum, factor * boxes.angular_momentum, start)
    checks.check(
        spin <= ANGULAR_TOLERANCE,
        f"visviva's L is (1 − hγ')ⁿ L₀: {spin:.1e} of |L₀| (≤ {ANGULAR_TOLERANCE:g})",
    )
    rows = [["visviva", *figures(ours, boxes, factor, exact)]]
    if peer is not None and mujoco_model is not None:
        data = peer.start(mujoco_model, boxes)
        for _ in range(steps):
            peer.mujoco.mj_step(mujoco_model, data)
        theirs = peer.snapshot(mujoco_model, data)
        own = relative(theirs.position, discrete_positions(boxes, steps, implicit=True), 1.0)
        checks.check(
            own <= ROUND_OFF,
            f"MuJoCo's centres follow v ← (v + h g)/(1 + hγ), x ← x + h v: {own:.1e} m"
            f" (≤ {ROUND_OFF:g})",
        )
        gap = np.abs(ours.position - theirs.position).max(axis=1)
        speeds = np.linalg.norm(LINEAR_DAMPING * boxes.velocity - np.array(GRAVITY), axis=1)
        bound = STEP * LINEAR_DAMPING * speeds * t * (t + STEP) / 2.0
        checks.check(
            bool(np.all(gap <= bound + ROUND_OFF)),
            f"visviva vs MuJoCo, centres: largest {gap.max():.2e} m, at most"
            f" {(gap / bound).max():.2f} of each body's bound h γ |γ v₀ − g| t (t + h)/2"
            f" (largest {bound.max():.2e} m)",
        )
        factor = (1.0 + STEP * ANGULAR_DAMPING) ** -steps
        rows.append(["MuJoCo", *figures(theirs, boxes, factor, exact)])
        cosine = np.abs(np.einsum("bi,bi->b", ours.orientation, theirs.orientation))
        angle = np.degrees(2.0 * np.arccos(np.minimum(cosine, 1.0)))
        difference = np.linalg.norm(ours.angular_momentum - theirs.angular_momentum, axis=1)
        print(
            f"  visviva vs MuJoCo, orientations: {np.median(angle):.3f}° apart (median),"
            f" {angle.max():.2f}° at most; angular momenta"
            f" {np.median(difference / start[:, 0]):.1e} of |L₀| apart (median),"
            f" {(difference / start[:, 0]).max():.1e} at most"
        )
    print()
    print_table(
        ["runner", "|x − exact| max", "|L| change, median", "max", "E change, median", "max"],
        rows,
    )
    print(
        "  |x − exact|: the centres against the exact solution of x'' = g − γ x' (first order:"
        f" about g h t/2 = {9.81 * STEP * t / 2:.1e} m); |L|, E: each runner's angular momentum"
        " and rotational energy with its own damping factor taken out ((1 − hγ')ⁿ for visviva,"
        " (1 + hγ')⁻ⁿ for MuJoCo, squared for E), relative to the start: what its free rotation"
        " did to quantities the exact motion keeps"
    )


def figures(snapshot: Snapshot, boxes: Boxes, factor: float, exact: np.ndarray) -> list[str]:
    kept, energy = free_rotation(snapshot, boxes, factor)
    return [
        f"{np.abs(snapshot.position - exact).max():.2e} m",
        f"{np.median(np.abs(kept)):.1e}",
        f"{np.abs(kept).max():.1e}",
        f"{np.median(np.abs(energy)):.1e}",
        f"{np.abs(energy).max():.1e}",
    ]


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace, peer: MuJoCoPeer | None, why: str) -> None:
    print("visviva rigid-body benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / numba:     {np.__version__} / {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()}), symplectic Euler")
    if peer is None:
        print(f"MuJoCo:            {why}; see the module docstring")
    else:
        print(f"MuJoCo:            {peer.version}")
        print("                   Euler integrator (semi-implicit, implicit joint damping)")
    print(f"scene:             {args.bodies:,} boxes, h = 1/{1.0 / STEP:.0f} s, float64")
    print(f"Numba threads:     {numba.config.NUMBA_NUM_THREADS}, layer {numba.threading_layer()}")
    print(f"load average:      {load_average()} at start")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="500 bodies; figures mean nothing")
    parser.add_argument("--bodies", type=int, default=None, help="number of boxes (10,000)")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per figure")
    parser.add_argument("--retries", type=int, default=None, help="re-measurements when contended")
    parser.add_argument(
        "--quiet-wait",
        type=float,
        default=10.0,
        help="before a retry, wait up to this many seconds for the machine to be idle (default 10)",
    )
    parser.add_argument(
        "--peers",
        default=os.environ.get("VISVIVA_PEERS"),
        help="directory holding mujoco (pip install --target DIR mujoco)",
    )
    args = parser.parse_args(argv)
    args.bodies = args.bodies or (QUICK_BODIES if args.quick else BODIES)
    if args.bodies < 1:
        parser.error(f"--bodies must be at least 1, not {args.bodies}")
    args.repeats = args.repeats or (3 if args.quick else 7)
    if args.retries is None:
        args.retries = 0 if args.quick else 2
    PATIENCE["retries"] = max(0, args.retries)
    PATIENCE["quiet_wait"] = max(0.0, args.quiet_wait)
    peer, why = load_mujoco(args.peers)
    # Compile (or load from the cache) visviva's rigid-body kernels before the header.
    vv.Simulation(visviva_model(box_scene(1))[0]).step()
    started = time.perf_counter()
    print_header(args, peer, why)
    checks = Checks()
    boxes = box_scene(args.bodies)
    model, mujoco_model = bench_build(boxes, peer, checks)
    rates = bench_step(args, boxes, model, peer, mujoco_model, checks)
    summarise(rates)
    bench_agreement(boxes, model, peer, mujoco_model, checks)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
