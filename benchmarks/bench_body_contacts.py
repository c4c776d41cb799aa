#!/usr/bin/env python
"""Rigid-body contact benchmark: visviva's body contacts against MuJoCo and PyBullet.

Run ``python benchmarks/bench_body_contacts.py`` (about 4 minutes on 2 cores, 7 when other
processes make it measure again) or add ``--quick`` for a smoke run (about 20 s) whose figures
mean nothing. The peers are never visviva dependencies and never imported into visviva's
interpreter: they live in a virtual environment of their own, and this script runs itself there
as a subprocess (``--peer mujoco`` or ``--peer pybullet``, the scene as JSON on its standard
input, the figures as JSON in a file)::

    python3.11 -m venv /tmp/peers-bodies
    /tmp/peers-bodies/bin/pip install mujoco pybullet numpy
    python benchmarks/bench_body_contacts.py --peers /tmp/peers-bodies

``--peers`` takes the environment's directory or its interpreter; ``VISVIVA_BODY_PEERS`` does
the same, and ``/tmp/peers-bodies`` is the default. A peer that is missing or does not import is
named in the header, and its rows are left out.

Every scene is the same for the three engines: steps of h = 1/240 s, gravity 9.81 m/s² down,
restitution 0 and Coulomb friction 0.5 on every pair, density 1000 kg/m³, each engine's own
default solver settings (visviva: symplectic Euler and ``add_body_contacts()``'s 20 sweeps;
MuJoCo: its Euler integrator, Newton solver, pyramidal cones, soft contacts; PyBullet: its
sequential-impulse solver with 50 iterations and whatever else it sets by default). visviva's world
has y up; MuJoCo's and PyBullet's have z up: positions map (x, y, z) → (x, −z, y) and
orientations turn by 90° about x. Friction: MuJoCo takes the larger of a pair's μ and visviva
√(μ_a μ_b), so both are given μ = 0.5; PyBullet multiplies them, so it is given √0.5 each.

1. **Pile of spheres**: 1000 spheres (r = 0.1 m) from a 10 × 10 × 10 lattice 0.4 m apart (the
   lowest layer at 0.5 m, ±2 mm of seeded jitter) dropped into a 4 m × 4 m box (a floor and four
   walls, all planes); 2 s (480 steps) to fall and settle into a pile, then 480 steps timed.
2. **Boxes**: 200 cubes (0.2 m), a 5 × 5 × 8 lattice 0.5 m apart with random orientations,
   dropped onto a plane (no walls); the same 2 s, then 480 steps timed.
3. **Stack**: ten 1 m cubes stacked on a plane, exactly touching, for 10 s (2400 steps): the
   largest displacement of any box from its start over every step [mm].
4. **Scaling** (visviva only): scene 1 with 10³, 2·10³, 5·10³ and 10⁴ spheres, the box's
   side 4 m · √(N/1000) and the lattice's columns grown with it (the same number of spheres per
   square metre of floor, ten layers; 10³ is scene 1's own figure), settled for 2 s, 480 steps
   timed: the ratio time(10⁴)/time(10³) (target 8–12: linear in N).

Timed phases run in chunks of 48 steps (visviva ``sim.step(48)``, MuJoCo
``mj_step(..., nstep=48)``, PyBullet 48 ``stepSimulation()`` calls); steps/s is the phase's
steps over its wall time. The table also gives process CPU time over wall time (about the threads
kept busy: visviva may use every core, the peers one), each engine's own contact count and
deepest overlap at the end, the top of the pile, the fastest body, how many bodies left the box
or fell through the floor, and how many are asleep (velocity exactly zero). A timed phase during
which other processes used more than 5% of the machine (``/proc/stat``, steal time included) is
measured again from the same settled state (a checkpoint, ``mj_copyData``, ``saveState``), up to
``--retries`` times (1 by default, 0 with ``--quick``); the fastest is kept. visviva is also
timed on one thread from the same settled state.

MuJoCo's default Newton solver factorises a matrix over all the degrees of freedom that touch:
on the 1000-sphere pile (one island of 6000 dofs) a step takes 20–50 s, so settling it would
take hours. Scene 1 therefore settles MuJoCo's pile with its CG solver, times CG's 480 steps (a
row marked "not default"), then times Newton, MuJoCo's default, from that settled state, one step
at a time, for ``--newton-budget`` seconds (30 by default; at least one step). "visviva ÷ fastest
peer" compares with the fastest peer at its default settings; the CG row's ratio follows it.

This is not a test: it prints figures and exits 1 only if a sanity check of visviva's motion
fails (no body escaped, no body of a pile faster than 1 m/s at the end, overlaps below a tenth
of a size, the stack within 1 mm).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

try:  # visviva's side; the peers' interpreter (--peer) has none of these
    import numba

    import visviva as vv
    from bench_integrators import (
        CONTENDED,
        CONTENTION_WARNING,
        PATIENCE,
        Checks,
        cpu_description,
        finish,
        fmt_time,
        heading,
        load_average,
        print_table,
        sci,
        source_state,
    )
except ImportError as error:
    vv = None
    VISVIVA_MISSING = f"{type(error).__name__}: {error}"

# --------------------------------------------------------------------------------------------
# The scenes (visviva's axes: y up)
# --------------------------------------------------------------------------------------------

STEP = 1.0 / 240.0  # s
GRAVITY = 9.81  # m/s²
DENSITY = 1000.0  # kg/m³
FRICTION = 0.5  # every pair's Coulomb μ
RESTITUTION = 0.0
SEED = 20261213

RADIUS = 0.1  # m, scene 1 and 4
SPACING = 0.4  # m between lattice sites (scene 1)
LAYERS = 10
FLOOR_SIDE_PER_1000 = 4.0  # m: the box's side for 1000 spheres; the area grows with N
LOWEST = 0.5  # m: the lowest layer's centres
JITTER = 0.002  # m, uniform ± this per coordinate

EDGE = 0.2  # m, scene 2's cubes
BOX_LATTICE = (5, 8, 5)  # x, y, z
BOX_SPACING = 0.5  # m

CUBE = 1.0  # m, scene 3's cubes
STACK_HEIGHT = 10

SETTLE_STEPS = 480  # 2 s
TIMED_STEPS = 480
CHUNK = 48
STACK_STEPS = 2400  # 10 s
SCALE_SIZES = (1000, 2000, 5000, 10_000)
TARGET_SCALING = (8.0, 12.0)

#: The sanity check's "at rest": no body faster than this [m/s] at the end of a pile.
AT_REST = 1.0
#: Above this share of the machine used by other processes a timed phase is measured again.
BUSY_LIMIT = 0.05
DEFAULT_PEERS = "/tmp/peers-bodies"
ENGINES = ("mujoco", "pybullet")
LABELS = {"visviva": "visviva", "mujoco": "MuJoCo", "pybullet": "PyBullet"}


def spheres_scene(n: int, *, settle: int = SETTLE_STEPS, timed: int = TIMED_STEPS) -> dict:
    """N spheres in ten layers over a square floor of (4 m)² · N/1000 with walls around it."""
    rng = np.random.default_rng(SEED + n)
    side = FLOOR_SIDE_PER_1000 * math.sqrt(n / 1000.0)
    columns = math.ceil(math.sqrt(n / LAYERS))
    pitch = side / columns
    layers = math.ceil(n / columns**2)
    i, k, j = np.meshgrid(np.arange(columns), np.arange(columns), np.arange(layers), indexing="ij")
    order = np.argsort(j.ravel(), kind="stable")  # fill from the lowest layer up
    sites = np.stack([i.ravel(), j.ravel(), k.ravel()], axis=1)[order][:n]
    position = np.empty((n, 3))
    position[:, 0] = -0.5 * side + pitch * (sites[:, 0] + 0.5)
    position[:, 1] = LOWEST + SPACING * sites[:, 1]
    position[:, 2] = -0.5 * side + pitch * (sites[:, 2] + 0.5)
    position += rng.uniform(-JITTER, JITTER, position.shape)
    orientation = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    return {
        "name": f"{n} spheres",
        "shape": "sphere",
        "size": RADIUS,
        "position": position.tolist(),
        "orientation": orientation.tolist(),
        "walls": 0.5 * side,
        "settle": settle,
        "timed": timed,
        "chunk": CHUNK,
        "track": False,
    }


def random_quaternions(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) uniform over rotations, w ≥ 0."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q * np.where(q[:, :1] < 0.0, -1.0, 1.0)


def boxes_scene(lattice: Sequence[int], *, settle: int = SETTLE_STEPS, timed: int = TIMED_STEPS):
    """Cubes on a loose lattice over a plane, random orientations."""
    rng = np.random.default_rng(SEED + 7)
    nx, ny, nz = lattice
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    position = np.stack(
        [
            BOX_SPACING * (i.ravel() - 0.5 * (nx - 1)),
            LOWEST + BOX_SPACING * j.ravel(),
            BOX_SPACING * (k.ravel() - 0.5 * (nz - 1)),
        ],
        axis=1,
    )
    n = position.shape[0]
    position += rng.uniform(-JITTER, JITTER, position.shape)
    return {
        "name": f"{n} boxes",
        "shape": "box",
        "size": EDGE,
        "position": position.tolist(),
        "orientation": random_quaternions(rng, n).tolist(),
        "walls": None,
        "settle": settle,
        "timed": timed,
        "chunk": CHUNK,
        "track": False,
    }


def stack_scene(steps: int = STACK_STEPS) -> dict:
    """Ten 1 m cubes, each resting exactly on the one below, the lowest on the floor."""
    position = [[0.0, 0.5 * CUBE + CUBE * i, 0.0] for i in range(STACK_HEIGHT)]
    return {
        "name": f"stack of {STACK_HEIGHT}",
        "shape": "box",
        "size": CUBE,
        "position": position,
        "orientation": [[1.0, 0.0, 0.0, 0.0]] * STACK_HEIGHT,
        "walls": None,
        "settle": 0,
        "timed": steps,
        "chunk": 1,
        "track": True,
    }


def body_mass(spec: dict) -> float:
    size = spec["size"]
    volume = 4.0 / 3.0 * math.pi * size**3 if spec["shape"] == "sphere" else size**3
    return DENSITY * volume


def walls(spec: dict) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
    """The scene's planes as (point, inward normal), y up: the floor, then any walls."""
    planes = [((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))]
    half = spec["walls"]
    if half is not None:
        planes += [
            ((-half, 0.0, 0.0), (1.0, 0.0, 0.0)),
            ((half, 0.0, 0.0), (-1.0, 0.0, 0.0)),
            ((0.0, 0.0, -half), (0.0, 0.0, 1.0)),
            ((0.0, 0.0, half), (0.0, 0.0, -1.0)),
        ]
    return planes


# --------------------------------------------------------------------------------------------
# Measuring (the same code in both interpreters: the standard library and NumPy only)
# --------------------------------------------------------------------------------------------


def machine_sample() -> tuple[float, float, float] | None:
    """(wall, CPU time of every process, this process's CPU time) from ``/proc/stat``."""
    try:
        with open("/proc/stat", encoding="ascii") as handle:
            values = [int(v) for v in handle.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    tick = os.sysconf("SC_CLK_TCK")
    idle = values[3] + (values[4] if len(values) > 4 else 0)
    own = os.times()
    return time.perf_counter(), (sum(values[:8]) - idle) / tick, own.user + own.system


def others_share(start: tuple[float, float, float] | None) -> float | None:
    """Other processes' share of the machine since ``start``."""
    end = machine_sample()
    if start is None or end is None or end[0] <= start[0]:
        return None
    foreign = (end[1] - start[1]) - (end[2] - start[2])
    return min(1.0, max(0.0, foreign / ((end[0] - start[0]) * (os.cpu_count() or 1))))


def wait_until_quiet(max_wait: float = 10.0) -> None:
    """Sleep until other processes have left the machine idle for 2 s, or ``max_wait`` passes."""
    deadline = time.perf_counter() + max_wait
    quiet = 0
    while quiet < 4 and time.perf_counter() < deadline:
        start = machine_sample()
        time.sleep(0.5)
        share = others_share(start)
        if share is None:
            return
        quiet = quiet + 1 if share < BUSY_LIMIT else 0


class World:
    """One engine's copy of a scene: what :func:`measured` needs of it (y-up figures)."""

    label = "?"

    def step(self, count: int) -> None:
        raise NotImplementedError

    def positions(self) -> np.ndarray:  # (N, 3) centres of mass
        raise NotImplementedError

    def velocities(self) -> np.ndarray:  # (N, 3)
        raise NotImplementedError

    def contacts(self) -> tuple[int, float]:  # the engine's contact count, deepest overlap [m]
        raise NotImplementedError

    def save(self) -> Any:
        raise NotImplementedError

    def restore(self, saved: Any) -> None:
        raise NotImplementedError


def timed_phase(
    world: World,
    spec: dict,
    retries: int,
    start: np.ndarray | None = None,
    budget: float | None = None,
) -> dict:
    """Time ``spec["timed"]`` steps in chunks; again from the same state while contended.

    ``start``: track the largest displacement from these positions after every chunk.
    ``budget`` [s]: step one at a time and stop once this much wall time has passed (at least
    one step): for an engine too slow to take the whole phase in the run's time.
    """
    steps, chunk = spec["timed"], 1 if budget is not None else spec["chunk"]
    saved = world.save() if retries > 0 else None
    attempts = []
    for attempt in range(retries + 1):
        if attempt:
            wait_until_quiet()
            world.restore(saved)
        worst = worst_across = 0.0
        chunks = []
        meter = machine_sample()
        cpu = time.process_time()
        began = time.perf_counter()
        done = 0
        while done < steps:
            k = min(chunk, steps - done)
            t = time.perf_counter()
            world.step(k)
            chunks.append((time.perf_counter() - t) / k)
            done += k
            if start is not None:
                moved = world.positions() - start
                worst = max(worst, float(np.linalg.norm(moved, axis=1).max()))
                across = float(np.linalg.norm(moved[:, [0, 2]], axis=1).max())
                worst_across = max(worst_across, across)
            if budget is not None and time.perf_counter() - began >= budget:
                break
        wall = time.perf_counter() - began
        share = others_share(meter)
        attempts.append(
            {
                "wall": wall,
                "steps": done,
                "capped": done < steps,
                "cpu_over_wall": (time.process_time() - cpu) / wall,
                "chunk_median": statistics.median(chunks),
                "others": share,
                "worst_displacement": worst if start is not None else None,
                "worst_across": worst_across if start is not None else None,
            }
        )
        if share is None or share <= BUSY_LIMIT:
            break
    best = min(attempts, key=lambda a: a["wall"] / a["steps"])
    best["attempts"] = len(attempts)
    return best


def settle(world: World, spec: dict) -> float:
    """Step the scene's settling steps; their wall time [s]."""
    began = time.perf_counter()
    for _ in range(spec["settle"] // CHUNK):
        world.step(CHUNK)
    if spec["settle"] % CHUNK:
        world.step(spec["settle"] % CHUNK)
    return time.perf_counter() - began


def measured(
    world: World,
    spec: dict,
    retries: int,
    start: np.ndarray | None = None,
    budget: float | None = None,
) -> dict:
    """The timed phase, then the state's figures at its end: one table row."""
    figures = timed_phase(world, spec, retries, start, budget)
    count, deepest = world.contacts()
    x, v = world.positions(), world.velocities()
    figures |= {
        "engine": world.label,
        "contacts": count,
        "deepest": deepest,
        "top": float(x[:, 1].max()),
        "lowest": float(x[:, 1].min()),
        "widest": float(np.abs(x[:, [0, 2]]).max()),
        "fastest": float(np.linalg.norm(v, axis=1).max()),
        "escaped": escaped(spec, x),
        "at_rest_exactly": int(np.count_nonzero(np.all(v == 0.0, axis=1))),
    }
    return figures


def escaped(spec: dict, x: np.ndarray) -> int:
    """Bodies whose centre is below the floor or beyond a wall (tunnelled through)."""
    out = x[:, 1] < 0.0
    if spec["walls"] is not None:
        out |= np.abs(x[:, [0, 2]]).max(axis=1) > spec["walls"]
    return int(np.count_nonzero(out))


# --------------------------------------------------------------------------------------------
# The peers (run only in the peers' interpreter, ``--peer ENGINE``)
# --------------------------------------------------------------------------------------------

#: visviva's y-up world into the peers' z-up one: a quarter turn about x, y → z, z → −y.
TURN = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
TURN_Q = np.array([math.cos(math.pi / 4.0), math.sin(math.pi / 4.0), 0.0, 0.0])


def z_up(y_up: np.ndarray) -> np.ndarray:
    return np.asarray(y_up) @ TURN.T


def y_up(z_up_: np.ndarray) -> np.ndarray:
    return np.asarray(z_up_) @ TURN


def turned(q: np.ndarray) -> np.ndarray:
    """(N, 4) TURN_Q ⊗ q, quaternions (w, x, y, z)."""
    w0, x0, y0, z0 = TURN_Q
    w, x, y, z = np.asarray(q).T
    return np.stack(
        [
            w0 * w - x0 * x - y0 * y - z0 * z,
            w0 * x + x0 * w + y0 * z - z0 * y,
            w0 * y - x0 * z + y0 * w + z0 * x,
            w0 * z + x0 * y - y0 * x + z0 * w,
        ],
        axis=1,
    )


def numbers(values: Sequence[float]) -> str:
    return " ".join(f"{float(v):.17g}" for v in values)


class MuJoCoWorld(World):
    label = "MuJoCo"

    def __init__(self, spec: dict) -> None:
        import mujoco  # the peers' interpreter only

        self.mujoco = mujoco
        x = z_up(np.array(spec["position"]))
        q = turned(np.array(spec["orientation"]))
        n = x.shape[0]
        friction = f'friction="{FRICTION!r} 0.005 0.0001"'
        if spec["shape"] == "sphere":
            geom = f'<geom type="sphere" size="{spec["size"]!r}" density="{DENSITY!r}" {friction}/>'
        else:
            half = 0.5 * spec["size"]
            geom = (
                f'<geom type="box" size="{numbers([half] * 3)}" density="{DENSITY!r}" {friction}/>'
            )
        planes = "".join(
            f'<geom type="plane" size="100 100 1" pos="{numbers(z_up(p))}"'
            f' zaxis="{numbers(z_up(normal))}" {friction}/>'
            for p, normal in walls(spec)
        )
        bodies = "".join(
            f'<body pos="{numbers(xi)}" quat="{numbers(qi)}"><freejoint/>{geom}</body>'
            for xi, qi in zip(x, q, strict=True)
        )
        memory = max(64, n // 4)  # MiB: its automatic arena is too small for big piles
        text = (
            f'<mujoco model="visviva body contacts"><size memory="{memory}M"/>'
            f'<option timestep="{STEP!r}" gravity="0 0 {-GRAVITY!r}"/>'
            f"<worldbody>{planes}{bodies}</worldbody></mujoco>"
        )
        self.model = mujoco.MjModel.from_xml_string(text)
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.n = n
        try:
            mujoco.mj_step(self.model, mujoco.MjData(self.model), nstep=1)
            self.nstep = True
        except TypeError:
            self.nstep = False

    def use_solver(self, name: str) -> None:
        """``"Newton"`` (MuJoCo's default), ``"CG"`` or ``"PGS"``."""
        self.model.opt.solver = getattr(self.mujoco.mjtSolver, f"mjSOL_{name.upper()}")

    def step(self, count: int) -> None:
        if self.nstep:
            self.mujoco.mj_step(self.model, self.data, nstep=count)
        else:
            for _ in range(count):
                self.mujoco.mj_step(self.model, self.data)

    def positions(self) -> np.ndarray:
        return y_up(self.data.qpos.reshape(self.n, 7)[:, :3])

    def velocities(self) -> np.ndarray:
        return y_up(self.data.qvel.reshape(self.n, 6)[:, :3])

    def contacts(self) -> tuple[int, float]:
        self.mujoco.mj_forward(self.model, self.data)  # the contacts of the current positions
        count = int(self.data.ncon)
        dist = self.data.contact.dist[:count]
        return count, float(max(0.0, -dist.min())) if count else 0.0

    def save(self) -> Any:
        saved = self.mujoco.MjData(self.model)
        self.mujoco.mj_copyData(saved, self.model, self.data)
        return saved

    def restore(self, saved: Any) -> None:
        self.mujoco.mj_copyData(self.data, self.model, saved)

    @staticmethod
    def version() -> str:
        import mujoco

        return f"{mujoco.__version__} (engine {mujoco.mj_versionString()})"


class BulletWorld(World):
    label = "PyBullet"

    def __init__(self, spec: dict) -> None:
        import pybullet  # the peers' interpreter only

        self.p = p = pybullet
        self.client = p.connect(p.DIRECT)
        p.setGravity(0.0, 0.0, -GRAVITY, physicsClientId=self.client)
        p.setTimeStep(STEP, physicsClientId=self.client)
        # Bullet multiplies a pair's frictions: √μ each gives the pair μ.
        mu = math.sqrt(FRICTION)
        c = {"physicsClientId": self.client}
        for point, normal in walls(spec):
            shape = p.createCollisionShape(p.GEOM_PLANE, planeNormal=z_up(normal).tolist(), **c)
            plane = p.createMultiBody(0.0, shape, basePosition=z_up(point).tolist(), **c)
            p.changeDynamics(plane, -1, lateralFriction=mu, restitution=RESTITUTION, **c)
        if spec["shape"] == "sphere":
            shape = p.createCollisionShape(p.GEOM_SPHERE, radius=spec["size"], **c)
        else:
            half = 0.5 * spec["size"]
            shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[half] * 3, **c)
        mass = body_mass(spec)
        x = z_up(np.array(spec["position"]))
        q = turned(np.array(spec["orientation"]))[:, [1, 2, 3, 0]]  # Bullet's (x, y, z, w)
        self.bodies = []
        for xi, qi in zip(x.tolist(), q.tolist(), strict=True):
            body = p.createMultiBody(mass, shape, basePosition=xi, baseOrientation=qi, **c)
            p.changeDynamics(body, -1, lateralFriction=mu, restitution=RESTITUTION, **c)
            self.bodies.append(body)

    def step(self, count: int) -> None:
        step, client = self.p.stepSimulation, self.client
        for _ in range(count):
            step(physicsClientId=client)

    def positions(self) -> np.ndarray:
        get, c = self.p.getBasePositionAndOrientation, self.client
        return y_up(np.array([get(b, physicsClientId=c)[0] for b in self.bodies]))

    def velocities(self) -> np.ndarray:
        get, c = self.p.getBaseVelocity, self.client
        return y_up(np.array([get(b, physicsClientId=c)[0] for b in self.bodies]))

    def contacts(self) -> tuple[int, float]:
        points = self.p.getContactPoints(physicsClientId=self.client)
        deepest = max((-point[8] for point in points), default=0.0)
        return len(points), max(0.0, float(deepest))

    def save(self) -> Any:
        return self.p.saveState(physicsClientId=self.client)

    def restore(self, saved: Any) -> None:
        self.p.restoreState(stateId=saved, physicsClientId=self.client)

    @staticmethod
    def version() -> str:
        from importlib.metadata import version

        import pybullet

        return f"{version('pybullet')} (API {pybullet.getAPIVersion()})"


PEER_WORLDS: dict[str, type[World]] = {"mujoco": MuJoCoWorld, "pybullet": BulletWorld}


def peer_main(engine: str, out: str) -> int:
    """``--peer ENGINE --out FILE``: the request (JSON) from standard input, the figures of
    each row (a list) to FILE."""
    request = json.load(sys.stdin)
    if request.get("probe"):
        result: Any = {}
        for name, world_type in PEER_WORLDS.items():
            try:
                result[name] = {"version": world_type.version()}
            except Exception as error:  # missing or broken: say why
                result[name] = {"error": f"{type(error).__name__}: {error}"}
        Path(out).write_text(json.dumps(result), encoding="utf-8")
        return 0
    spec, retries = request["scene"], request["retries"]
    began = time.perf_counter()
    world = PEER_WORLDS[engine](spec)
    build = time.perf_counter() - began
    start = world.positions().copy() if spec["track"] else None
    helper = request.get("settle_solver") if engine == "mujoco" else None
    if helper:
        # MuJoCo's default Newton solver takes seconds a step on a big pile: settle it with
        # another of its solvers, time that one, then time Newton on the same settled state.
        world.use_solver(helper)
        settling = settle(world, spec)
        saved = world.save()
        other = measured(world, spec, retries, start)
        other |= {"engine": f"MuJoCo ({helper}, not default)", "default": False}
        world.restore(saved)
        world.use_solver("Newton")
        main = measured(world, spec, 0, start, budget=request.get("budget"))
        main |= {"engine": f"MuJoCo (Newton, default; settled by {helper})", "default": True}
        rows = [main, other]
    else:
        settling = settle(world, spec)
        rows = [measured(world, spec, retries, start) | {"default": True}]
    for row in rows:
        row |= {"build": build, "settle": settling}
    Path(out).write_text(json.dumps(rows), encoding="utf-8")
    return 0


# --------------------------------------------------------------------------------------------
# visviva's side
# --------------------------------------------------------------------------------------------


class VisvivaWorld(World):
    label = "visviva"

    def __init__(self, spec: dict) -> None:
        builder = vv.SceneBuilder(name=f"bench {spec['name']}")
        builder.set_integration(method="symplectic_euler", dt=STEP, duration=10.0)
        for point, normal in walls(spec):
            builder.add_collider(
                "plane", point=point, normal=normal, restitution=RESTITUTION, friction=FRICTION
            )
        size = spec["size"]
        shape = {"radius": size} if spec["shape"] == "sphere" else {"size": (size, size, size)}
        for x, q in zip(spec["position"], spec["orientation"], strict=True):
            builder.add_body(
                spec["shape"],
                density=DENSITY,
                position=tuple(x),
                orientation=tuple(q),
                restitution=RESTITUTION,
                friction=FRICTION,
                **shape,
            )
        builder.add_body_contacts()
        self.model = builder.build()
        self.simulation = vv.Simulation(self.model)
        self.mass = body_mass(spec)

    def step(self, count: int) -> None:
        self.simulation.step(count)

    def positions(self) -> np.ndarray:
        return np.array(self.simulation.state["body_position"])

    def velocities(self) -> np.ndarray:
        return np.array(self.simulation.state["body_momentum"]) / self.mass

    def contacts(self) -> tuple[int, float]:
        found = self.simulation.body_contacts()
        return len(found), float(max(0.0, found.depth.max(initial=0.0)))

    def save(self) -> Any:
        return self.simulation.checkpoint()

    def restore(self, saved: Any) -> None:
        self.simulation = vv.Simulation.restore(self.model, saved)


@dataclass
class Peers:
    python: str | None
    versions: dict[str, str] = field(default_factory=dict)
    missing: dict[str, str] = field(default_factory=dict)

    @property
    def available(self) -> list[str]:
        return [engine for engine in ENGINES if engine in self.versions]


def call_peer(python: str, engine: str, request: dict, timeout: float = 900.0) -> dict:
    """Run this script as ``--peer ENGINE`` in the peers' interpreter."""
    with tempfile.TemporaryDirectory(prefix="bench-body-contacts-") as folder:
        out = Path(folder) / "result.json"
        completed = subprocess.run(
            [python, str(Path(__file__).resolve()), "--peer", engine, "--out", str(out)],
            input=json.dumps(request),
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
            env=os.environ | {"PYTHONPATH": ""},
        )
        if completed.returncode != 0 or not out.exists():
            tail = (completed.stderr or completed.stdout).strip().splitlines()[-3:]
            raise RuntimeError(f"exit {completed.returncode}: {' | '.join(tail)}")
        return json.loads(out.read_text(encoding="utf-8"))


def find_peers(where: str | None) -> Peers:
    if not where:
        return Peers(None, missing={e: "no peers' environment given" for e in ENGINES})
    path = Path(where)
    python = path / "bin" / "python" if path.is_dir() else path
    if not python.exists():
        reason = f"no interpreter at {python}"
        return Peers(None, missing={e: reason for e in ENGINES})
    peers = Peers(str(python))
    try:
        probe = call_peer(str(python), "probe", {"probe": True}, timeout=120.0)
    except (OSError, subprocess.SubprocessError, RuntimeError, ValueError) as error:
        peers.missing = {e: f"{python} failed: {error}" for e in ENGINES}
        return peers
    for engine in ENGINES:
        answer = probe.get(engine, {})
        if "version" in answer:
            peers.versions[engine] = answer["version"]
        else:
            peers.missing[engine] = f"not usable in {python} ({answer.get('error', '?')})"
    return peers


def run_peer(
    peers: Peers, engine: str, spec: dict, args: argparse.Namespace, retries: int
) -> list[dict]:
    """The peer's rows for a scene (none, with the reason printed, if it failed)."""
    request = {"scene": spec, "retries": retries}
    if engine == "mujoco" and spec["shape"] == "sphere" and spec["walls"] is not None:
        request |= {"settle_solver": "CG", "budget": args.newton_budget}
    try:
        rows = call_peer(peers.python, engine, request)
    except (OSError, subprocess.SubprocessError, RuntimeError, ValueError) as error:
        print(f"  {LABELS[engine]} failed on {spec['name']}, left out: {error}")
        return []
    for row in rows:
        note_contention(row, f"{spec['name']}: {row['engine']}")
    return rows


def visviva_scene(spec: dict, retries: int, one_thread: bool) -> tuple[dict, dict | None]:
    """Build and settle; time on every core and (optionally) again on one thread from the
    same settled state."""
    began = time.perf_counter()
    world = VisvivaWorld(spec)
    build = time.perf_counter() - began
    start = world.positions().copy() if spec["track"] else None
    settling = settle(world, spec)
    saved = world.save() if one_thread else None
    figures = measured(world, spec, 0 if spec["track"] else retries, start)
    figures |= {"engine": "visviva", "build": build, "settle": settling, "default": True}
    note_contention(figures, f"{spec['name']}: visviva")
    single = None
    if one_thread:
        every = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            world.restore(saved)
            single = timed_phase(world, spec, retries)
        finally:
            numba.set_num_threads(every)
        note_contention(single, f"{spec['name']}: visviva, 1 thread")
    return figures, single


def note_contention(figures: dict, label: str) -> None:
    share = figures.get("others")
    if share is not None and share > CONTENTION_WARNING:
        CONTENDED.append(
            f"{label}: other processes used {100.0 * share:.0f}% of the machine"
            f" (fastest of {figures.get('attempts', 1)} attempts)"
        )


def busy(figures: dict) -> str:
    share = figures.get("others")
    if share is None:
        return "?"
    retried = f" ({figures['attempts']} tries)" if figures.get("attempts", 1) > 1 else ""
    return f"{100.0 * share:.0f}%{retried}"


def rate(figures: dict) -> float:
    return figures["steps"] / figures["wall"]


def mm(metres: float) -> str:
    return f"{1e3 * metres:.2f}"


# --------------------------------------------------------------------------------------------
# Scenes 1 and 2: piles
# --------------------------------------------------------------------------------------------


def bench_pile(
    title: str, spec: dict, args: argparse.Namespace, peers: Peers, checks: Checks
) -> dict:
    """Scenes 1 and 2; visviva's figures (on every core)."""
    n = len(spec["position"])
    heading(title)
    ours, single = visviva_scene(spec, args.retries, one_thread=True)
    ours["engine"] = f"visviva ({numba.get_num_threads()} threads)"
    rows = [pile_row(ours)]
    if single is not None:
        cells = [f"{single['steps']}", sci(rate(single)), fmt_time(1.0 / rate(single))]
        rows.append(
            ["visviva (1 thread)", *cells, f"{single['cpu_over_wall']:.2f}"]
            + [""] * 7
            + [busy(single)]
        )
    theirs = [
        row
        for engine in peers.available
        for row in run_peer(peers, engine, spec, args, args.retries)
    ]
    rows += [pile_row(row) for row in theirs]
    print_table(
        [
            "engine",
            "steps timed",
            "steps/s",
            "per step",
            "CPU/wall",
            "contacts",
            "deepest mm",
            "top m",
            "max |v| m/s",
            "escaped",
            "v = 0",
            "build s",
            "others' CPU",
        ],
        rows,
    )
    defaults = [row for row in theirs if row["default"]]
    fastest = max(defaults, key=rate, default=None)
    if fastest is not None:
        line = (
            f"  visviva ÷ fastest peer at its default settings ({fastest['engine']}), steps/s:"
            f" {rate(ours) / rate(fastest):.2f}×"
        )
        if single is not None:
            line += f"; visviva on 1 thread ÷ the same: {rate(single) / rate(fastest):.2f}×"
        print(line)
        for other in theirs:
            if not other["default"]:
                print(f"  visviva ÷ {other['engine']}: {rate(ours) / rate(other):.2f}×")
    else:
        print("  no peer figures (see the header): no ratio")
    print(
        f"  {n} bodies, {spec['settle']} steps to settle, then {spec['timed']} steps timed in"
        f" chunks of {spec['chunk']}; at the end: contacts as each engine counts them (visviva:"
        " pieces within 1 µm; MuJoCo: ncon; PyBullet: getContactPoints, its manifolds' points"
        " within its contact threshold), the deepest overlap, the highest centre, the fastest"
        " body, bodies escaped (centre below the floor or beyond a wall) and bodies whose"
        " velocity is exactly zero (asleep)"
    )
    if any(row["capped"] for row in theirs):
        print(
            f"  MuJoCo's Newton solver is timed for {args.newton_budget:g} s of steps, one at a"
            " time, from the pile its CG solver settled (Newton would take an hour to settle it)"
        )
    size = spec["size"]
    checks.check(
        ours["escaped"] == 0,
        f"{spec['name']}: no visviva body escaped the box or fell through the floor"
        f" ({ours['escaped']})",
    )
    checks.check(
        ours["fastest"] < AT_REST,
        f"{spec['name']}: visviva's pile is at rest after"
        f" {(spec['settle'] + spec['timed']) * STEP:g} s"
        f" (fastest body {ours['fastest']:.3f} m/s < {AT_REST:g}: nothing thrown about)",
    )
    checks.check(
        ours["deepest"] < 0.1 * size,
        f"{spec['name']}: visviva's deepest overlap {mm(ours['deepest'])} mm < a tenth of"
        f" {'the radius' if spec['shape'] == 'sphere' else 'the edge'}",
    )
    return ours


def pile_row(figures: dict) -> list[str]:
    return [
        figures["engine"],
        f"{figures['steps']}",
        sci(rate(figures)),
        fmt_time(1.0 / rate(figures)),
        f"{figures['cpu_over_wall']:.2f}",
        f"{figures['contacts']:,}",
        mm(figures["deepest"]),
        f"{figures['top']:.3f}",
        f"{figures['fastest']:.3f}",
        str(figures["escaped"]),
        str(figures["at_rest_exactly"]),
        f"{figures['build']:.1f}",
        busy(figures),
    ]


# --------------------------------------------------------------------------------------------
# Scene 3: the stack
# --------------------------------------------------------------------------------------------


def bench_stack(spec: dict, args: argparse.Namespace, peers: Peers, checks: Checks) -> None:
    heading(
        f"3. A stack of {STACK_HEIGHT} cubes ({CUBE:g} m, {DENSITY:g} kg/m³) on a plane,"
        f" {spec['timed'] * STEP:g} s ({spec['timed']} steps)"
    )
    ours = visviva_scene(spec, 0, one_thread=False)[0]
    theirs = [row for engine in peers.available for row in run_peer(peers, engine, spec, args, 0)]
    rows = [
        [
            f["engine"],
            mm(f["worst_displacement"]),
            mm(f["worst_across"]),
            mm(f["top"] - (STACK_HEIGHT - 0.5) * CUBE),
            f"{f['fastest']:.2e}",
            f"{f['contacts']}",
            mm(f["deepest"]),
            sci(rate(f)),
        ]
        for f in [ours, *theirs]
    ]
    print_table(
        [
            "engine",
            "largest displacement mm",
            "of it sideways mm",
            "top box's height change mm",
            "max |v| m/s",
            "contacts",
            "deepest mm",
            "steps/s",
        ],
        rows,
    )
    best = min(theirs, key=lambda row: row["worst_displacement"], default=None)
    if best is not None:
        worst = best["worst_displacement"]
        ratio = ours["worst_displacement"] / worst if worst > 0 else math.inf
        print(
            f"  visviva ÷ best peer ({best['engine']}), largest displacement: {ratio:.3g}×"
            " (below 1: visviva's stack moved less)"
        )
    print(
        "  largest displacement: of any box's centre from its start, read after every step"
        " (sideways: its largest horizontal part); top box's height change and max |v| at the"
        " end; steps/s: one step per call with the positions read after each (not a speed"
        " figure)"
    )
    worst = ours["worst_displacement"]
    checks.check(
        worst < 1e-3, f"stack: visviva's boxes within 1 mm of their start ({mm(worst)} mm)"
    )


# --------------------------------------------------------------------------------------------
# Scene 4: scaling
# --------------------------------------------------------------------------------------------


def bench_scaling(args: argparse.Namespace, known: dict[int, dict], checks: Checks) -> None:
    sizes = args.scale_sizes
    heading(
        f"4. visviva's contacts from {sizes[0]:,} to {sizes[-1]:,} spheres"
        f" ({numba.get_num_threads()} threads), the same spheres per m² of floor"
    )
    rows = []
    later: list[tuple[bool, str]] = []
    per_step: dict[int, float] = {}
    for n in sizes:
        spec = spheres_scene(n, settle=args.settle, timed=args.timed)
        if n in known:
            figures = known[n]
        else:
            figures, _ = visviva_scene(spec, args.retries, one_thread=False)
            later.append(
                (
                    figures["escaped"] == 0 and figures["fastest"] < AT_REST,
                    f"{n:,} spheres: none escaped ({figures['escaped']}), at rest (fastest body"
                    f" {figures['fastest']:.3f} m/s < {AT_REST:g})",
                )
            )
        seconds = 1.0 / rate(figures)
        per_step[n] = seconds
        rows.append(
            [
                f"{n:,}",
                f"{2.0 * spec['walls']:.2f}",
                f"{figures['contacts']:,}",
                f"{figures['contacts'] / n:.2f}",
                fmt_time(seconds),
                sci(rate(figures)),
                f"{1e9 * seconds / n:.0f}",
                f"{1e9 * seconds / max(1, figures['contacts']):.0f}",
                f"{seconds / per_step[sizes[0]]:.2f}",
                f"{figures['top']:.3f}",
                mm(figures["deepest"]),
                f"{figures['build']:.1f}",
                busy(figures),
            ]
        )
    print_table(
        [
            "N",
            "box side m",
            "contacts",
            "per body",
            "per step",
            "steps/s",
            "ns/body",
            "ns/contact",
            f"÷ N={sizes[0]:,}",
            "top m",
            "deepest mm",
            "build s",
            "others' CPU",
        ],
        rows,
    )
    ratio = round(per_step[sizes[-1]] / per_step[sizes[0]], 2)  # judged as printed
    growth = sizes[-1] / sizes[0]
    low, high = (t * growth / 10.0 for t in TARGET_SCALING)
    if ratio < low:
        verdict = "below the range: better than linear (fixed costs weigh on the smallest N)"
    else:
        verdict = "met" if ratio <= high else "not met: worse than linear"
    print(
        f"  time({sizes[-1]:,}) / time({sizes[0]:,}) = {ratio:.2f} for {growth:g}× the bodies"
        f" (target {low:g}–{high:g}: linear): {verdict}"
    )
    if args.quick:
        print("  (--quick: sizes too small for the figure to mean anything)")
    for condition, description in later:
        checks.check(condition, description)


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace, peers: Peers) -> None:
    print("visviva body-contact benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count() or 0
    print(f"cores:             {os.cpu_count()} logical, {usable} usable by this process")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / numba:     {np.__version__} / {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    print(f"Numba threads:     {numba.get_num_threads()}, layer {numba.threading_layer()}")
    for engine in ENGINES:
        what = peers.versions.get(engine) or f"{peers.missing.get(engine)}; see the docstring"
        print(f"{LABELS[engine] + ':':<19}{what}")
    if peers.python:
        print(f"peers' Python:     {peers.python} (a subprocess)")
    print(
        f"scenes:            h = 1/{1.0 / STEP:.0f} s, g = {GRAVITY} m/s², μ = {FRICTION},"
        f" e = {RESTITUTION:g}, {DENSITY:g} kg/m³; settle {args.settle} steps, time"
        f" {args.timed}"
    )
    print(f"load average:      {load_average()} at start")


def warm_up() -> None:
    """Compile (or load from the cache) visviva's contact kernels: spheres and boxes, walls."""
    spec = spheres_scene(8, settle=0, timed=1)
    spec["position"][1] = [0.05, 0.3, 0.0]
    VisvivaWorld(spec).step(30)
    VisvivaWorld(boxes_scene((2, 2, 1), settle=0, timed=1)).step(150)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small scenes; figures mean nothing")
    parser.add_argument(
        "--peers",
        default=os.environ.get("VISVIVA_BODY_PEERS", DEFAULT_PEERS),
        help="the peers' virtual environment (or its python) with mujoco and pybullet"
        f" (default {DEFAULT_PEERS})",
    )
    parser.add_argument("--no-peers", action="store_true", help="visviva's figures alone")
    parser.add_argument("--retries", type=int, default=None, help="re-timings when contended")
    parser.add_argument(
        "--newton-budget",
        type=float,
        default=30.0,
        help="seconds of MuJoCo Newton steps timed on the sphere pile (default 30)",
    )
    parser.add_argument("--peer", choices=[*ENGINES, "probe"], help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.peer:
        return peer_main(args.peer, args.out)
    if vv is None:
        parser.exit(2, f"visviva is not importable here ({VISVIVA_MISSING})\n")
    if args.retries is None:
        args.retries = 0 if args.quick else 1
    args.retries = max(0, args.retries)
    PATIENCE["retries"] = args.retries
    if args.quick:
        args.spheres, args.lattice = 125, (3, 3, 3)
        args.settle, args.timed, args.stack_steps = SETTLE_STEPS, 96, 480
        args.scale_sizes = (125, 1250)
    else:
        args.spheres, args.lattice = 1000, BOX_LATTICE
        args.settle, args.timed, args.stack_steps = SETTLE_STEPS, TIMED_STEPS, STACK_STEPS
        args.scale_sizes = SCALE_SIZES
    peers = find_peers(None if args.no_peers else args.peers)
    warm_up()
    started = time.perf_counter()
    print_header(args, peers)
    checks = Checks()
    spheres = spheres_scene(args.spheres, settle=args.settle, timed=args.timed)
    side = 2.0 * spheres["walls"]
    piles = bench_pile(
        f"1. {args.spheres:,} spheres (r = {RADIUS:g} m) into a {side:g} m × {side:g} m box",
        spheres,
        args,
        peers,
        checks,
    )
    boxes = boxes_scene(args.lattice, settle=args.settle, timed=args.timed)
    bench_pile(
        f"2. {len(boxes['position']):,} cubes ({EDGE:g} m), random orientations, onto a plane",
        boxes,
        args,
        peers,
        checks,
    )
    bench_stack(stack_scene(args.stack_steps), args, peers, checks)
    bench_scaling(args, {args.spheres: piles}, checks)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
