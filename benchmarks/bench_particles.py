#!/usr/bin/env python
"""Particle benchmark: 10⁶ particles under gravity, drag and a plane collider, against peers.

Run ``python benchmarks/bench_particles.py`` (about a minute on 2 cores) or add ``--quick`` for a
smoke run (under a minute) whose figures mean nothing. Warp is never a visviva dependency; to
include the Warp-CPU peer, install it into a directory of its own, without its dependencies
(its only one, NumPy, comes from visviva's environment), and name that directory::

    pip install --no-deps --target /tmp/peers-warp warp-lang
    python benchmarks/bench_particles.py --peers /tmp/peers-warp

(``VISVIVA_PEERS=/tmp/peers-warp`` does the same as ``--peers``.) The directory is put on
``sys.path`` only while ``warp`` is imported, and at the end, so nothing in it can shadow
visviva's own packages. Without Warp the script says so and skips the Warp figures.

The scene, the same for every runner (one step of h = 1/600 s, symplectic Euler, float64):

1. force f = m g − k v, g = (0, −9.81, 0) m/s², k = 0.05 N·s/m, per-particle mass m;
2. v ← v + h f / m, then x ← x + h v;
3. a plane through the origin with normal n = (0, 1, 0); with d = x·n − 0 − r (r: the particle's
   radius), if d < 0 the particle is pushed back to the surface (x ← x − d n) and, if vn = v·n < 0,
   the normal velocity becomes −e_eff vn with e_eff = 0 when −vn < v_rest = 2 |g| h (resting) and
   e = 0.6 otherwise, and the tangential velocity vt = v − vn n is shortened by μ (1 + e_eff) |vn|
   (Coulomb friction, μ = 0.3), down to zero but never reversed.

Particles start uniformly in [−1, 1] × [0, 2] × [−1, 1] m, with velocities of uniformly random
direction and speed up to 3 m/s, masses in [0.5, 1.5] kg and radius 0.01 m (seeded).

Layout: structure of arrays, eight contiguous float64 arrays x, y, z, vx, vy, vz, m, r, updated
in place, for plain Numba and for the Warp-CPU peer alike; Warp's idiomatic layout (``vec3d``
arrays of shape (N,), i.e. NumPy (N, 3)) is timed as well. One step reads x, v, m, r (8 × 8 B)
and writes x, v (6 × 8 B): 112 B per particle and step, which is what "GB/s" counts below.

Parts:

(a) Memory bandwidth, with Numba prange on 1 and 2 threads, over arrays whose total size equals
    the particle state (8 N float64) at each N: a STREAM triad a = b + s·c over three arrays,
    and the in-place a = a + s·b over two (the step's own access pattern: read, modify, write
    back). STREAM counts 24 B per triad element; a cached store first reads its line
    (write-allocate), so 32 B really move, and the triad's limit below counts 32 B. In-place
    updates (a = a + s·b, and the particle step's 112 B) need no such correction.
(b) Particle step at N = 10⁵ and 10⁶: time per step, particles/s, GB/s, the fraction of each
    bandwidth limit (same N and thread count; and of the best figure measured at that N, the
    machine's limit) and the 10⁵ → 10⁶ cost ratio, for
    plain Numba (one step per call; several steps per call, one parallel loop per step; several
    steps per call fused per particle, which keeps a particle in registers and so is not bound
    by the 112 B/step), Warp-CPU (SoA and vec3d, one step per launch; SoA fused steps) and
    visviva (its runner is a slot, ``visviva_runner``, still to be plugged in).
(c) Agreement after 100 steps: plain Numba against a NumPy reference, Warp and visviva.
(d) Fountain: the same forces and plane, starting empty, an emitter adding 10⁵ particles/s until
    10⁶ exist (10 s, 6000 steps): plain Numba, and visviva through ``visviva_fountain_runner``.

Timings are medians of repeated runs after a warm-up (short calls repeated to fill 0.5 s); each
figure comes with the share of the CPU other processes used meanwhile (re-measured when above
5%). Repeated calls keep advancing the same particles, so the scene settles onto the plane
during the runs; the fixed-size step does the same memory traffic whether a particle is in the
air or resting. This is not a test: it prints figures and exits 1 only if a sanity check fails.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import importlib
import math
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numba
import numpy as np
from numba import njit, prange

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

# --------------------------------------------------------------------------------------------
# The scene
# --------------------------------------------------------------------------------------------

STEP = 1.0 / 600.0  # s
GRAVITY = (0.0, -9.81, 0.0)  # m/s²
DRAG = 0.05  # N·s/m, linear: f = −k v
RESTITUTION = 0.6
FRICTION = 0.3  # Coulomb μ
PLANE_NORMAL = (0.0, 1.0, 0.0)
PLANE_OFFSET = 0.0  # m: the plane is {x : x·n = offset}
RADIUS = 0.01  # m
RESTING_SPEED = 2.0 * math.hypot(*GRAVITY) * STEP  # m/s: below it an impact does not bounce
SEED = 20261201

#: The scene's constants in the order the kernels take them.
SCENE = (
    STEP,
    *GRAVITY,
    DRAG,
    *PLANE_NORMAL,
    PLANE_OFFSET,
    RESTITUTION,
    FRICTION,
    RESTING_SPEED,
)

#: Bytes one step moves per particle: reads x, y, z, vx, vy, vz, m, r; writes x, y, z, vx, vy, vz.
BYTES_PER_PARTICLE_STEP = (8 + 6) * 8
#: Bytes a triad element really moves: reads b and c, reads a's line (write-allocate), writes a.
TRIAD_BYTES = 32
TRIAD_BYTES_STREAM = 24  # what STREAM reports
#: Bytes an in-place a = a + s·b element moves: reads a and b, writes a.
IN_PLACE_BYTES = 24

#: The issue's targets for visviva (in the same run as the peers).
TARGET_FRACTION = 0.5
TARGET_VS_WARP = 1.5
TARGET_RATIO = (8.0, 12.0)

#: Fountain emitter: births per second, nozzle position, mean speed along +y, speed spread and
#: cone half-angle. Births per step accumulate fractionally (10⁵/600 = 166.67 per step).
BIRTH_RATE = 1.0e5
NOZZLE = (0.0, 0.05, 0.0)
NOZZLE_SPEED = 5.0  # m/s
NOZZLE_SPEED_SPREAD = 0.5  # m/s, uniform ± this
NOZZLE_HALF_ANGLE = math.radians(15.0)

STEPS_PER_CALL = 10  # for the several-steps-per-call runners


@dataclass
class Particles:
    """Structure of arrays: positions, velocities, masses and radii, float64, contiguous."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    vz: np.ndarray
    m: np.ndarray
    r: np.ndarray

    @property
    def arrays(self) -> tuple[np.ndarray, ...]:
        return (self.x, self.y, self.z, self.vx, self.vy, self.vz, self.m, self.r)

    def copy(self) -> Particles:
        return Particles(*(a.copy() for a in self.arrays))

    def positions(self) -> np.ndarray:
        return np.stack([self.x, self.y, self.z], axis=1)

    def velocities(self) -> np.ndarray:
        return np.stack([self.vx, self.vy, self.vz], axis=1)


def initial_particles(n: int, seed: int = SEED) -> Particles:
    """The scene's start: uniform in the box, random directions, speeds uniform in [0, 3] m/s."""
    rng = np.random.default_rng(seed)
    low = np.array([-1.0, 0.0, -1.0])
    high = np.array([1.0, 2.0, 1.0])
    position = rng.uniform(low, high, size=(n, 3))
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    velocity = direction * rng.uniform(0.0, 3.0, size=(n, 1))
    mass = rng.uniform(0.5, 1.5, size=n)
    radius = np.full(n, RADIUS)
    columns = [np.ascontiguousarray(position[:, k]) for k in range(3)]
    columns += [np.ascontiguousarray(velocity[:, k]) for k in range(3)]
    return Particles(*columns, mass, radius)


# --------------------------------------------------------------------------------------------
# Plain Numba peer
# --------------------------------------------------------------------------------------------
# `error_model="numpy"`: the one division that can meet zero is guarded, and Python's error
# model (a ZeroDivisionError check) keeps LLVM from vectorising the loop (see NOTES.md).
# `inline="always"`: an ordinary call from the prange loop to another @njit function keeps the
# loop scalar (measured here: 3–4× slower at N = 10⁶); inlined, LLVM if-converts the branches
# and vectorises the particle loop (AVX-512), as if the body had been written in the loop.
# No inlining helps the fused variant: LLVM does not vectorise an outer loop.


@njit(fastmath=False, cache=True, error_model="numpy", inline="always")
def advance(px, py, pz, vx, vy, vz, m, radius, scene):
    """One step of one particle; returns the new position and velocity."""
    h, gx, gy, gz, drag, nx, ny, nz, offset, e, mu, v_rest = scene
    inv_m = 1.0 / m
    vx = vx + h * ((m * gx - drag * vx) * inv_m)
    vy = vy + h * ((m * gy - drag * vy) * inv_m)
    vz = vz + h * ((m * gz - drag * vz) * inv_m)
    px = px + h * vx
    py = py + h * vy
    pz = pz + h * vz
    d = px * nx + py * ny + pz * nz - offset - radius
    if d < 0.0:
        px = px - d * nx
        py = py - d * ny
        pz = pz - d * nz
        vn = vx * nx + vy * ny + vz * nz
        if vn < 0.0:
            e_eff = 0.0 if -vn < v_rest else e
            tx = vx - vn * nx
            ty = vy - vn * ny
            tz = vz - vn * nz
            tangential = math.sqrt(tx * tx + ty * ty + tz * tz)
            reduced = tangential - mu * (1.0 + e_eff) * (-vn)
            scale = reduced / tangential if reduced > 0.0 else 0.0
            bounce = -e_eff * vn
            vx = tx * scale + bounce * nx
            vy = ty * scale + bounce * ny
            vz = tz * scale + bounce * nz
    return px, py, pz, vx, vy, vz


@njit(parallel=True, fastmath=False, cache=True, error_model="numpy")
def numba_step(x, y, z, vx, vy, vz, m, r, scene):
    """One step of every particle."""
    for i in prange(x.shape[0]):
        x[i], y[i], z[i], vx[i], vy[i], vz[i] = advance(
            x[i], y[i], z[i], vx[i], vy[i], vz[i], m[i], r[i], scene
        )


@njit(parallel=True, fastmath=False, cache=True, error_model="numpy")
def numba_steps_rounds(x, y, z, vx, vy, vz, m, r, scene, steps):
    """``steps`` steps in one call, one parallel loop over all particles per step."""
    for _ in range(steps):
        for i in prange(x.shape[0]):
            x[i], y[i], z[i], vx[i], vy[i], vz[i] = advance(
                x[i], y[i], z[i], vx[i], vy[i], vz[i], m[i], r[i], scene
            )


@njit(parallel=True, fastmath=False, cache=True, error_model="numpy")
def numba_steps_fused(x, y, z, vx, vy, vz, m, r, scene, steps):
    """``steps`` steps in one call, each particle taken through all of them in registers.

    Legitimate here because particles do not interact: the state is read and written once per
    call, not once per step, so this runner is not bound by 112 B per step.
    """
    for i in prange(x.shape[0]):
        px, py, pz = x[i], y[i], z[i]
        qx, qy, qz = vx[i], vy[i], vz[i]
        mass = m[i]
        radius = r[i]
        for _ in range(steps):
            px, py, pz, qx, qy, qz = advance(px, py, pz, qx, qy, qz, mass, radius, scene)
        x[i], y[i], z[i], vx[i], vy[i], vz[i] = px, py, pz, qx, qy, qz


def numpy_reference_step(p: Particles) -> None:
    """The same step written independently with whole-array NumPy operations (for checking)."""
    h, gx, gy, gz, drag, nx, ny, nz, offset, e, mu, v_rest = SCENE
    g = np.array([gx, gy, gz])
    normal = np.array([nx, ny, nz])
    x = p.positions()
    v = p.velocities()
    m = p.m[:, None]
    v = v + h * ((m * g - drag * v) * (1.0 / m))
    x = x + h * v
    d = x @ normal - offset - p.r
    contact = d < 0.0
    x[contact] -= d[contact, None] * normal
    vn = v @ normal
    hit = contact & (vn < 0.0)
    e_eff = np.where(-vn < v_rest, 0.0, e)
    vt = v - vn[:, None] * normal
    tangential = np.linalg.norm(vt, axis=1)
    reduced = tangential - mu * (1.0 + e_eff) * np.abs(vn)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(reduced > 0.0, reduced / tangential, 0.0)
    v_hit = vt * scale[:, None] + (-e_eff * vn)[:, None] * normal
    v = np.where(hit[:, None], v_hit, v)
    for k, name in enumerate(("x", "y", "z")):
        getattr(p, name)[:] = x[:, k]
        getattr(p, "v" + name)[:] = v[:, k]


Runner = tuple[Callable[[], None], Callable[[], np.ndarray]]


def numba_runner(n: int, steps_per_call: int, variant: str = "fused") -> Runner:
    """Plain Numba from the scene's start: a callable doing ``steps_per_call`` steps, a getter."""
    p = initial_particles(n)
    arrays = p.arrays
    if steps_per_call == 1:

        def step() -> None:
            numba_step(*arrays, SCENE)

    elif variant == "fused":

        def step() -> None:
            numba_steps_fused(*arrays, SCENE, steps_per_call)

    else:

        def step() -> None:
            numba_steps_rounds(*arrays, SCENE, steps_per_call)

    return step, p.positions


# --------------------------------------------------------------------------------------------
# Memory bandwidth kernels
# --------------------------------------------------------------------------------------------


@njit(parallel=True, fastmath=False, cache=True)
def triad(a, b, c, s):
    """STREAM's triad."""
    for i in prange(a.shape[0]):
        a[i] = b[i] + s * c[i]


@njit(parallel=True, fastmath=False, cache=True)
def scaled_add(a, b, s):
    """In place, like the particle step: each line of ``a`` is read, then written back."""
    for i in prange(a.shape[0]):
        a[i] = a[i] + s * b[i]


# --------------------------------------------------------------------------------------------
# Warp-CPU peer (optional; never a visviva dependency)
# --------------------------------------------------------------------------------------------


@contextlib.contextmanager
def on_path(directory: str | None):
    """Append ``directory`` to ``sys.path`` for the duration (appended: it cannot shadow)."""
    if not directory:
        yield
        return
    sys.path.append(directory)
    try:
        yield
    finally:
        with contextlib.suppress(ValueError):
            sys.path.remove(directory)


#: The ``warp`` module once loaded: a module global because Warp evaluates the kernels'
#: annotations (strings, with ``from __future__ import annotations``) in this module.
wp = None


class WarpPeer:
    """Warp kernels for the same step, float64 throughout, launched on ``device="cpu"``."""

    def __init__(self, peers: str | None) -> None:
        global wp
        with on_path(peers):
            wp = importlib.import_module("warp")
        self.wp = wp
        wp.config.log_level = wp.LOG_WARNING  # no start-up banner
        wp.init()

        @wp.func
        def advance(
            px: wp.float64,
            py: wp.float64,
            pz: wp.float64,
            vx: wp.float64,
            vy: wp.float64,
            vz: wp.float64,
            m: wp.float64,
            radius: wp.float64,
            h: wp.float64,
            gx: wp.float64,
            gy: wp.float64,
            gz: wp.float64,
            drag: wp.float64,
            nx: wp.float64,
            ny: wp.float64,
            nz: wp.float64,
            offset: wp.float64,
            e: wp.float64,
            mu: wp.float64,
            v_rest: wp.float64,
        ):
            inv_m = wp.float64(1.0) / m
            vx = vx + h * ((m * gx - drag * vx) * inv_m)
            vy = vy + h * ((m * gy - drag * vy) * inv_m)
            vz = vz + h * ((m * gz - drag * vz) * inv_m)
            px = px + h * vx
            py = py + h * vy
            pz = pz + h * vz
            d = px * nx + py * ny + pz * nz - offset - radius
            if d < wp.float64(0.0):
                px = px - d * nx
                py = py - d * ny
                pz = pz - d * nz
                vn = vx * nx + vy * ny + vz * nz
                if vn < wp.float64(0.0):
                    e_eff = e
                    if -vn < v_rest:
                        e_eff = wp.float64(0.0)
                    tx = vx - vn * nx
                    ty = vy - vn * ny
                    tz = vz - vn * nz
                    tangential = wp.sqrt(tx * tx + ty * ty + tz * tz)
                    reduced = tangential - mu * (wp.float64(1.0) + e_eff) * (-vn)
                    scale = wp.float64(0.0)
                    if reduced > wp.float64(0.0):
                        scale = reduced / tangential
                    bounce = -e_eff * vn
                    vx = tx * scale + bounce * nx
                    vy = ty * scale + bounce * ny
                    vz = tz * scale + bounce * nz
            return px, py, pz, vx, vy, vz

        @wp.kernel
        def step_soa(
            x: wp.array(dtype=wp.float64),
            y: wp.array(dtype=wp.float64),
            z: wp.array(dtype=wp.float64),
            vx: wp.array(dtype=wp.float64),
            vy: wp.array(dtype=wp.float64),
            vz: wp.array(dtype=wp.float64),
            m: wp.array(dtype=wp.float64),
            r: wp.array(dtype=wp.float64),
            steps: int,
            h: wp.float64,
            gx: wp.float64,
            gy: wp.float64,
            gz: wp.float64,
            drag: wp.float64,
            nx: wp.float64,
            ny: wp.float64,
            nz: wp.float64,
            offset: wp.float64,
            e: wp.float64,
            mu: wp.float64,
            v_rest: wp.float64,
        ):
            i = wp.tid()
            px = x[i]
            py = y[i]
            pz = z[i]
            qx = vx[i]
            qy = vy[i]
            qz = vz[i]
            mass = m[i]
            radius = r[i]
            for _s in range(steps):
                px, py, pz, qx, qy, qz = advance(
                    px, py, pz, qx, qy, qz, mass, radius, h, gx, gy, gz, drag, nx, ny, nz,
                    offset, e, mu, v_rest,
                )  # fmt: skip
            x[i] = px
            y[i] = py
            z[i] = pz
            vx[i] = qx
            vy[i] = qy
            vz[i] = qz

        @wp.kernel
        def step_aos(
            x: wp.array(dtype=wp.vec3d),
            v: wp.array(dtype=wp.vec3d),
            m: wp.array(dtype=wp.float64),
            r: wp.array(dtype=wp.float64),
            steps: int,
            h: wp.float64,
            gx: wp.float64,
            gy: wp.float64,
            gz: wp.float64,
            drag: wp.float64,
            nx: wp.float64,
            ny: wp.float64,
            nz: wp.float64,
            offset: wp.float64,
            e: wp.float64,
            mu: wp.float64,
            v_rest: wp.float64,
        ):
            i = wp.tid()
            p = x[i]
            q = v[i]
            mass = m[i]
            radius = r[i]
            px = p[0]
            py = p[1]
            pz = p[2]
            qx = q[0]
            qy = q[1]
            qz = q[2]
            for _s in range(steps):
                px, py, pz, qx, qy, qz = advance(
                    px, py, pz, qx, qy, qz, mass, radius, h, gx, gy, gz, drag, nx, ny, nz,
                    offset, e, mu, v_rest,
                )  # fmt: skip
            x[i] = wp.vec3d(px, py, pz)
            v[i] = wp.vec3d(qx, qy, qz)

        self.step_soa = step_soa
        self.step_aos = step_aos
        wp.load_module(device="cpu")

    @property
    def version(self) -> str:
        return self.wp.__version__

    def runner(self, n: int, steps_per_call: int, layout: str = "soa") -> Runner:
        """Warp from the scene's start; the step times ``wp.launch`` + ``wp.synchronize``."""
        wp = self.wp
        p = initial_particles(n)
        if layout == "soa":
            kernel = self.step_soa
            arrays = [wp.array(a, dtype=wp.float64, device="cpu") for a in p.arrays]
        else:
            kernel = self.step_aos
            arrays = [
                wp.array(p.positions(), dtype=wp.vec3d, device="cpu"),
                wp.array(p.velocities(), dtype=wp.vec3d, device="cpu"),
                wp.array(p.m, dtype=wp.float64, device="cpu"),
                wp.array(p.r, dtype=wp.float64, device="cpu"),
            ]
        inputs = [*arrays, steps_per_call, *SCENE]

        def step() -> None:
            wp.launch(kernel, dim=n, inputs=inputs, device="cpu")
            wp.synchronize()

        def positions() -> np.ndarray:
            if layout == "soa":
                return np.stack([a.numpy() for a in arrays[:3]], axis=1)
            return arrays[0].numpy().copy()

        return step, positions


def load_warp(peers: str | None) -> tuple[WarpPeer | None, str]:
    """The Warp peer, or None and the reason it is unavailable."""
    try:
        return WarpPeer(peers), ""
    except ImportError as error:
        return None, f"not installed ({error})"
    except Exception as error:  # a broken install or an unsupported feature: skip, say why
        return None, f"unusable ({type(error).__name__}: {error})"


# --------------------------------------------------------------------------------------------
# visviva slots: the lead plugs visviva's particle step in here
# --------------------------------------------------------------------------------------------


def _scene_builder() -> vv.SceneBuilder:
    """The benchmark's world, integration and plane, as a visviva scene."""
    builder = vv.SceneBuilder(name="benchmark particles")
    builder.set_world(gravity=GRAVITY)
    builder.set_integration(method="symplectic_euler", dt=STEP, duration=1.0)
    # Same work as the peers: a contact test and response each step, no time of impact.
    builder.add_collider(
        "plane",
        point=(0.0, PLANE_OFFSET, 0.0),
        normal=PLANE_NORMAL,
        restitution=RESTITUTION,
        friction=FRICTION,
        resting_speed=RESTING_SPEED,
        time_of_impact=False,
    )
    return builder


def visviva_runner(n: int, steps_per_call: int) -> Runner:
    """visviva's particle step on this scene (``initial_particles(n)``, ``SCENE``).

    Returns ``(step, positions)``: ``step()`` advances the particles by ``steps_per_call``
    steps of ``STEP`` and returns when the work is done; ``positions()`` returns the current
    positions as an (N, 3) float64 array (for the agreement check against plain Numba).
    """
    particles = initial_particles(n)
    builder = _scene_builder()
    builder.add_particles(
        particles.positions(),
        velocities=particles.velocities(),
        mass=particles.m,
        radius=RADIUS,
        name="particles",
    )
    builder.add_force("drag", coefficient=DRAG)
    simulation = vv.Simulation(builder.build(), compiled=True)

    def step() -> None:
        simulation.step(steps_per_call)

    def positions() -> np.ndarray:
        return np.array(simulation.raw_state["particle_position"])

    return step, positions


def visviva_fountain_runner(
    births_per_second: float, capacity: int, steps_per_call: int
) -> tuple[Callable[[], None], Callable[[], int]]:
    """visviva on the fountain scene: the same forces and plane, an emitter at ``NOZZLE``.

    Starts with no particles; ``step()`` advances by ``steps_per_call`` steps, each emitting
    ``births_per_second × STEP`` particles (births on the clock) and stepping every living
    particle; ``count()`` returns the number alive. Particles live longer than the run, and
    emission stops at ``capacity``.
    """
    builder = _scene_builder()
    builder.add_emitter(
        rate=births_per_second,
        stop=capacity / births_per_second,
        position=NOZZLE,
        direction=(0.0, 1.0, 0.0),
        spread_deg=math.degrees(NOZZLE_HALF_ANGLE),
        speed=[NOZZLE_SPEED - NOZZLE_SPEED_SPREAD, NOZZLE_SPEED + NOZZLE_SPEED_SPREAD],
        lifetime=1e6,
        particle_radius=RADIUS,
        particle_mass=1.0,
        capacity=capacity,
        name="fountain",
    )
    builder.add_force("drag", coefficient=DRAG)
    simulation = vv.Simulation(builder.build(), compiled=True)

    def step() -> None:
        simulation.step(steps_per_call)

    def count() -> int:
        return int(simulation.raw_state["particle_alive"].sum())

    return step, count


def visviva_or_none(factory: Callable[[], object], what: str) -> object | None:
    try:
        return factory()
    except NotImplementedError:
        print(f"  {what}: not available yet")
        return None


# --------------------------------------------------------------------------------------------
# (a) Memory bandwidth
# --------------------------------------------------------------------------------------------


def bench_bandwidth(args: argparse.Namespace) -> dict[tuple[str, int, int], float]:
    """Bytes really moved per second, by (kernel, N, threads); kernel "triad" or "in-place"."""
    heading("(a) Memory bandwidth over arrays of the particle state's total size (8 N float64)")
    bandwidth = {}
    rows = []
    for n in args.sizes:
        rng = np.random.default_rng(1)
        length = (8 * n + 2) // 3  # three arrays holding 8 N float64 between them
        a, b, c = np.zeros(length), rng.random(length), rng.random(length)
        half = 4 * n  # two arrays holding 8 N float64 between them
        p, q = rng.random(half), rng.random(half)
        for threads in (1, 2):
            numba.set_num_threads(threads)
            timing = measure(
                lambda a=a, b=b, c=c: triad(a, b, c, 3.0), args.repeats, f"(a) triad N={n}"
            )
            real = TRIAD_BYTES * length / timing.median
            bandwidth[("triad", n, threads)] = real
            stream = TRIAD_BYTES_STREAM * length / timing.median
            rows.append(["triad a = b + s·c", f"{n:,}", f"{24 * length / 2**20:.1f} MiB"])
            rows[-1] += [str(threads), fmt_time(timing.median), f"{stream / 1e9:.1f}"]
            rows[-1] += [f"{real / 1e9:.1f}", timing.spread, timing.busy]
            timing = measure(
                lambda p=p, q=q: scaled_add(p, q, 1e-9), args.repeats, f"(a) in-place N={n}"
            )
            real = IN_PLACE_BYTES * half / timing.median
            bandwidth[("in-place", n, threads)] = real
            rows.append(["in place a = a + s·b", f"{n:,}", f"{16 * half / 2**20:.1f} MiB"])
            rows[-1] += [str(threads), fmt_time(timing.median), "", f"{real / 1e9:.1f}"]
            rows[-1] += [timing.spread, timing.busy]
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    print()
    headers = ["kernel", "particles N", "arrays", "threads", "median", "GB/s (STREAM)"]
    headers += ["GB/s (real)", "spread", "others' CPU"]
    print_table(headers, rows)
    print(
        "  STREAM counts 24 B per triad element; 'real' counts 32 B (with the write-allocate"
        " read of a) for the triad and 24 B in place."
    )
    print(
        f"  one particle step moves {BYTES_PER_PARTICLE_STEP} B per particle (8 float64 read,"
        " 6 written back, in place)"
    )
    return bandwidth


# --------------------------------------------------------------------------------------------
# (b) The particle step
# --------------------------------------------------------------------------------------------


@dataclass
class Entry:
    label: str
    threads: int
    steps: int  # per call
    n: int
    timing: Timing

    @property
    def per_step(self) -> float:
        return self.timing.median / self.steps


def cpu_share(call: Callable[[], None], seconds: float = 0.3) -> float:
    """Process CPU time over wall time while repeating ``call``: about the threads it uses."""
    call()
    start_cpu = time.process_time()
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        call()
    return (time.process_time() - start_cpu) / (time.perf_counter() - start)


def bench_step(
    args: argparse.Namespace,
    warp: WarpPeer | None,
    bandwidth: dict[tuple[str, int, int], float],
) -> list[Entry]:
    heading(
        f"(b) Particle step, h = 1/600 s, f64 SoA: N = {', '.join(f'{n:,}' for n in args.sizes)}"
    )
    k = STEPS_PER_CALL
    # (label, threads, steps per call, factory(n) -> runner or None)
    plan: list[tuple[str, int, int, Callable[[int], Runner]]] = []
    for threads in (1, 2):
        plan.append(("plain Numba, 1 step/call", threads, 1, lambda n: numba_runner(n, 1)))
        plan.append(
            (
                f"plain Numba, {k} steps/call, loop per step",
                threads,
                k,
                lambda n: numba_runner(n, k, "rounds"),
            )
        )
        plan.append(
            (
                f"plain Numba, {k} steps/call, fused",
                threads,
                k,
                lambda n: numba_runner(n, k, "fused"),
            )
        )
    if warp is not None:
        plan.append(("Warp-CPU SoA, 1 step/launch", 1, 1, lambda n: warp.runner(n, 1, "soa")))
        plan.append(("Warp-CPU vec3d, 1 step/launch", 1, 1, lambda n: warp.runner(n, 1, "aos")))
        plan.append(
            (f"Warp-CPU SoA, {k} steps/launch, fused", 1, k, lambda n: warp.runner(n, k, "soa"))
        )
    for threads in (1, 2):
        for steps in (1, k):
            plan.append(
                (
                    f"visviva, {steps} step{'s' if steps > 1 else ''}/call",
                    threads,
                    steps,
                    lambda n, steps=steps: visviva_runner(n, steps),
                )
            )
    entries: list[Entry] = []
    missing: set[str] = set()
    for n in args.sizes:
        for label, threads, steps, factory in plan:
            if label in missing:
                continue
            try:
                step, _ = factory(n)
            except NotImplementedError:
                missing.add(label)
                continue
            numba.set_num_threads(threads)
            timing = measure(step, args.repeats, f"(b) {label}, {threads} thread(s), N={n}")
            entries.append(Entry(label, threads, steps, n, timing))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    if any(label.startswith("visviva") for label in missing):
        print("  visviva: not available yet (visviva_runner raises NotImplementedError)")
    if warp is None:
        print("  Warp: not installed: see the module docstring for how to add it.")

    rows = []
    for entry in entries:
        moved = BYTES_PER_PARTICLE_STEP * entry.n / entry.per_step
        threads = min(entry.threads, 2)
        best = max(v for (_, n, _), v in bandwidth.items() if n == entry.n)
        rows.append(
            [
                entry.label,
                str(entry.threads),
                f"{entry.n:,}",
                fmt_time(entry.per_step),
                sci(entry.n / entry.per_step),
                f"{moved / 1e9:.1f}",
                f"{100 * moved / bandwidth[('triad', entry.n, threads)]:.0f}%",
                f"{100 * moved / bandwidth[('in-place', entry.n, threads)]:.0f}%",
                f"{100 * moved / best:.0f}%",
                fmt_time(entry.timing.first),
                entry.timing.busy,
            ]
        )
    print()
    print_table(
        [
            "runner",
            "threads",
            "N",
            "per step",
            "particles/s",
            "GB/s",
            "of triad",
            "of in-place",
            "of best",
            "first call",
            "others' CPU",
        ],
        rows,
    )
    print(
        f"  GB/s = {BYTES_PER_PARTICLE_STEP} B × N / time per step, as a share of (a)'s real GB/s"
        " at the same N and thread count; 'of best': of the highest figure in (a) at that N"
    )
    print(
        f"  fused runners read and write each particle once per {k} steps: their GB/s is what"
        " one step at a time would have had to move, and may exceed 100%."
    )
    if warp is not None:
        step, _ = warp.runner(args.sizes[-1], 1, "soa")
        share = cpu_share(step)
        print(
            f"  Warp-CPU threads: process CPU time / wall time while launching = {share:.2f}"
            f" ({'one thread' if share < 1.3 else 'several threads'})"
        )
    return entries


def summarise(args: argparse.Namespace, entries: list[Entry]) -> None:
    small, large = args.sizes[0], args.sizes[-1]
    heading(f"Cost ratio N = {small:,} → {large:,} and comparisons at N = {large:,}")
    times = {(e.label, e.threads, e.n): e.per_step for e in entries}
    rows = []
    low, high = TARGET_RATIO
    for label, threads in dict.fromkeys((e.label, e.threads) for e in entries):
        if (label, threads, small) in times and (label, threads, large) in times:
            ratio = times[(label, threads, large)] / times[(label, threads, small)]
            rows.append(
                [label, str(threads), f"{ratio:.1f}", "yes" if low <= ratio <= high else "no"]
            )
    print()
    print_table(["runner", "threads", "cost ratio", f"in [{low:g}, {high:g}]"], rows)
    if large // small != 10:
        print(f"  (sizes differ by {large / small:g}×, not 10×: --quick)")

    def speedup(a: tuple[str, int], b: tuple[str, int]) -> str:
        if (*a, large) not in times or (*b, large) not in times:
            return "n/a"
        return f"{times[(*b, large)] / times[(*a, large)]:.2f}×"

    k = STEPS_PER_CALL
    warp_one = ("Warp-CPU SoA, 1 step/launch", 1)
    warp_fused = (f"Warp-CPU SoA, {k} steps/launch, fused", 1)
    print()
    print_table(
        ["runner (2 threads)", "vs Warp, 1 step/launch", f"vs Warp, {k} steps/launch"],
        [
            [
                "plain Numba, 1 step/call",
                speedup(("plain Numba, 1 step/call", 2), warp_one),
                speedup(("plain Numba, 1 step/call", 2), warp_fused),
            ],
            [
                f"plain Numba, {k} steps/call, fused",
                speedup((f"plain Numba, {k} steps/call, fused", 2), warp_one),
                speedup((f"plain Numba, {k} steps/call, fused", 2), warp_fused),
            ],
            [
                "visviva, 1 step/call",
                speedup(("visviva, 1 step/call", 2), warp_one),
                speedup(("visviva, 1 step/call", 2), warp_fused),
            ],
            [
                f"visviva, {k} steps/call",
                speedup((f"visviva, {k} steps/call", 2), warp_one),
                speedup((f"visviva, {k} steps/call", 2), warp_fused),
            ],
        ],
    )
    print(
        f"  targets for visviva: ≥ {TARGET_VS_WARP:g}× Warp-CPU doing the same work (same steps"
        f" per call), ≥ {TARGET_FRACTION:.0%} of the bandwidth limit, cost ratio in"
        f" [{low:g}, {high:g}]"
    )


# --------------------------------------------------------------------------------------------
# (c) Agreement
# --------------------------------------------------------------------------------------------


def bench_agreement(args: argparse.Namespace, warp: WarpPeer | None, checks: Checks) -> None:
    n = args.check_n
    steps = 100
    heading(f"(c) Agreement after {steps} steps, N = {n:,} (max |Δx| in m)")
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    step, positions = numba_runner(n, 1)
    for _ in range(steps):
        step()
    plain = positions()
    start = initial_particles(n)
    print(f"  particles on the plane after {steps} steps (plain Numba): ", end="")
    print(f"{np.count_nonzero(plain[:, 1] <= RADIUS * (1 + 1e-12)):,} of {n:,}")
    others: list[tuple[str, Callable[[], Runner]]] = [
        ("plain Numba, 100 steps fused", lambda: numba_runner(n, steps, "fused")),
        ("plain Numba, 10 × 10 steps, loop per step", lambda: numba_runner(n, 10, "rounds")),
    ]
    if warp is not None:
        others += [
            ("Warp-CPU SoA", lambda: warp.runner(n, 1, "soa")),
            ("Warp-CPU vec3d", lambda: warp.runner(n, 1, "aos")),
            ("Warp-CPU SoA, 100 steps fused", lambda: warp.runner(n, steps, "soa")),
        ]
    reference = start.copy()
    for _ in range(steps):
        numpy_reference_step(reference)
    difference = np.abs(reference.positions() - plain).max()
    checks.check(difference < 1e-9, f"plain Numba vs NumPy reference: {difference:.1e}")
    for label, factory in others:
        runner_step, runner_positions = factory()
        calls = steps // (10 if "10 × 10" in label else (steps if "100 steps" in label else 1))
        for _ in range(calls):
            runner_step()
        difference = np.abs(runner_positions() - plain).max()
        checks.check(difference < 1e-9, f"plain Numba vs {label}: {difference:.1e}")
    try:
        runner_step, runner_positions = visviva_runner(n, 1)
    except NotImplementedError:
        print("  visviva: not available yet")
        return
    for _ in range(steps):
        runner_step()
    difference = np.abs(runner_positions() - plain).max(axis=1)
    # visviva holds a resting particle by static friction where it is; the peers let it slide
    # by the step's displacement before friction stops it (at most a step's slide, h·|v|).
    held = plain[:, 1] <= RADIUS * (1 + 1e-12)
    free = float(difference[~held].max(initial=0.0))
    resting = float(difference[held].max(initial=0.0))
    checks.check(free < 1e-9, f"plain Numba vs visviva, particles off the plane: {free:.1e}")
    slide = STEP * 3.0  # a step at the starting speeds (≤ 3 m/s)
    checks.check(
        resting < slide,
        f"plain Numba vs visviva, particles resting on the plane: {resting:.1e} (visviva's static "
        f"friction holds them; below one step's slide, {slide:.1e} m)",
    )


# --------------------------------------------------------------------------------------------
# (d) Fountain
# --------------------------------------------------------------------------------------------


@njit(fastmath=False, cache=True)
def emit(x, y, z, vx, vy, vz, m, r, count, uniforms):
    """Add one particle per row of ``uniforms`` (4 numbers in [0, 1)) after index ``count``.

    Serial (a step emits ~167 particles); returns the new count, at most the capacity.
    """
    nx, ny, nz = NOZZLE
    end = min(count + uniforms.shape[0], x.shape[0])
    cos_max = math.cos(NOZZLE_HALF_ANGLE)
    for i in range(count, end):
        u = uniforms[i - count]
        cos_theta = 1.0 - u[0] * (1.0 - cos_max)  # uniform over the cone's spherical cap
        sin_theta = math.sqrt(1.0 - cos_theta * cos_theta)
        phi = 2.0 * math.pi * u[1]
        speed = NOZZLE_SPEED + NOZZLE_SPEED_SPREAD * (2.0 * u[2] - 1.0)
        x[i], y[i], z[i] = nx, ny, nz
        vx[i] = speed * sin_theta * math.cos(phi)
        vy[i] = speed * cos_theta
        vz[i] = speed * sin_theta * math.sin(phi)
        m[i] = 0.5 + u[3]
        r[i] = RADIUS
    return end


def numba_fountain(capacity: int, steps: int) -> int:
    """Plain Numba fountain from empty for ``steps`` steps; returns the particles alive."""
    rng = np.random.default_rng(SEED)
    arrays = tuple(np.empty(capacity) for _ in range(8))
    count = 0
    owed = 0.0
    for _ in range(steps):
        owed += BIRTH_RATE * STEP
        births = int(owed)
        owed -= births
        count = emit(*arrays, count, rng.random((births, 4)))
        numba_step(*(a[:count] for a in arrays), SCENE)
    return count


def bench_fountain(args: argparse.Namespace, checks: Checks) -> None:
    capacity = args.fountain_capacity
    steps = math.ceil(capacity / (BIRTH_RATE * STEP))
    heading(
        f"(d) Fountain: {BIRTH_RATE:.0e} births/s from empty to {capacity:,} particles"
        f" ({steps} steps, {steps * STEP:.2f} s), 2 threads"
    )
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    timing = measure(
        lambda: numba_fountain(capacity, steps), max(1, args.repeats // 2), "(d) Numba fountain"
    )
    alive = timing.result
    checks.check(alive == capacity, f"plain Numba fountain reached {alive:,} particles")
    particle_steps = sum(
        min(capacity, math.floor((s + 1) * BIRTH_RATE * STEP + 1e-9)) for s in range(steps)
    )
    rows = [
        [
            "plain Numba, 1 step/call",
            fmt_time(timing.median),
            fmt_time(timing.median / steps),
            sci(particle_steps / timing.median),
            timing.spread,
            timing.busy,
        ]
    ]

    def visviva_fountain() -> Callable[[], int]:
        step, count = visviva_fountain_runner(BIRTH_RATE, capacity, 1)

        def run() -> int:
            for _ in range(steps):
                step()
            return count()

        return run

    run = visviva_or_none(visviva_fountain, "visviva fountain")
    if run is not None:
        timing = measure(run, max(1, args.repeats // 2), "(d) visviva fountain")
        rows.append(
            [
                "visviva",
                fmt_time(timing.median),
                fmt_time(timing.median / steps),
                sci(particle_steps / timing.median),
                timing.spread,
                timing.busy,
            ]
        )
    print()
    print_table(
        ["runner", "whole run", "per step", "particle-steps/s", "spread", "others' CPU"], rows
    )
    print(
        f"  nozzle at {NOZZLE} m, {NOZZLE_SPEED:g} ± {NOZZLE_SPEED_SPREAD:g} m/s within"
        f" {math.degrees(NOZZLE_HALF_ANGLE):g}° of +y; each step emits, then steps the living"
    )


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace, warp: WarpPeer | None, why: str) -> None:
    print("visviva particle benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / numba:     {np.__version__} / {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    if warp is None:
        print(f"Warp:              {why}; see the module docstring")
    else:
        print(f"Warp:              {warp.version} (device cpu, float64)")
    print(f"Numba threads:     {numba.config.NUMBA_NUM_THREADS}, layer {numba.threading_layer()}")
    print(f"load average:      {load_average()} at start")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes; figures mean nothing")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per figure")
    parser.add_argument("--retries", type=int, default=None, help="re-measurements when contended")
    parser.add_argument(
        "--quiet-wait",
        type=float,
        default=30.0,
        help="before a retry, wait up to this many seconds for the machine to be idle (default 30)",
    )
    parser.add_argument(
        "--peers",
        default=os.environ.get("VISVIVA_PEERS"),
        help="directory holding warp (pip install --no-deps --target DIR warp-lang)",
    )
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (2 if args.quick else 5)
    if args.retries is None:
        args.retries = 0 if args.quick else 2
    args.sizes = (20_000, 200_000) if args.quick else (100_000, 1_000_000)
    args.check_n = 10_000 if args.quick else 100_000
    args.fountain_capacity = 100_000 if args.quick else 1_000_000
    PATIENCE["retries"] = max(0, args.retries)
    PATIENCE["quiet_wait"] = max(0.0, args.quiet_wait)
    warp, why = load_warp(args.peers)
    # Compile (or load from the cache) every kernel before the header and the first timing.
    tiny = initial_particles(64)
    numba_step(*tiny.arrays, SCENE)
    numba_steps_rounds(*tiny.arrays, SCENE, 2)
    numba_steps_fused(*tiny.arrays, SCENE, 2)
    triad(tiny.x, tiny.y, tiny.z, 3.0)
    scaled_add(tiny.x, tiny.y, 0.0)
    emit(*tiny.arrays, 0, np.full((1, 4), 0.5))
    started = time.perf_counter()
    print_header(args, warp, why)
    checks = Checks()
    bandwidth = bench_bandwidth(args)
    entries = bench_step(args, warp, bandwidth)
    summarise(args, entries)
    bench_agreement(args, warp, checks)
    bench_fountain(args, checks)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
