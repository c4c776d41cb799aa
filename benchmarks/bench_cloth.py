#!/usr/bin/env python
"""Cloth benchmark: an explicit mass-spring cloth step (symplectic Euler), against peers.

Run ``python benchmarks/bench_cloth.py`` (about 30 s on 2 cores once compiled) or add
``--quick`` for a smoke run whose figures mean nothing. The peers, Warp-CPU and NVIDIA Newton
(built on Warp), are optional and never visviva dependencies; install them into a directory of
their own and name it, as for ``bench_particles.py``. One directory can hold both (Newton 1.8.0
needs warp-lang ≥ 1.17 and nothing else for what runs here)::

    pip install --no-deps --target /tmp/peers-newton newton warp-lang
    python benchmarks/bench_cloth.py --peers /tmp/peers-newton

``--peers DIR`` is where ``warp`` is found and, unless ``--newton DIR`` names another directory,
``newton`` too (a Warp-only directory, ``pip install --no-deps --target /tmp/peers-warp
warp-lang``, still works: Newton is then reported as not installed). Warp is loaded once per
process: with two directories, Newton runs on the Warp from ``--peers``; the header prints the
versions in use.

The scene, the same for every runner (float64 throughout):

* an N × N grid of points (N = 64, 128, 256, 512; ``--quick``: 16, 32) spaced 1/(N − 1) m in the
  x–z plane at height y = 1 m; point (i, j) (i along x, j along z) has index j·N + i;
* areal density 0.1 kg/m²: each point weighs the density times a quarter of each cell it
  touches (corners ¼ cell, edges ½, inside 1 cell);
* springs, resting at their initial lengths, each with damping c = 0.01 N·s/m along it:
  structural (grid neighbours along x and z, k = 1000 N/m), shear (both diagonals of each cell,
  k = 100 N/m) and bend (points two apart along x and z, k = 1 N/m); with d = x_j − x_i,
  l = |d|, u = d/l, w = v_j − v_i, spring (i, j) pulls i by f = (k (l − L) + c (w·u)) u and j
  by −f;
* the two corners of the first row (points 0 and N − 1) pinned: no force moves them;
* gravity (0, −9.81, 0) m/s²; one symplectic Euler step v ← v + h F/m, x ← x + h v.

The step h is 1e-4 s where that is stable (N ≤ 32, which includes the agreement check). Above,
it is not: the cloth's stiffest mode (structural springs on points of mass ∝ 1/(N − 1)², plus
the damping along them) caps a stable symplectic Euler step at about 9.8e-5 s at N = 64,
4.2e-5 s at N = 128, 1.5e-5 s at N = 256 and 4.6e-6 s at N = 512 (the linearisation at rest:
the largest h with λ_max(M⁻¹(h² K + 2h C)) ≤ 4). The cap falls faster than 1/N (÷2.3, ÷2.8,
÷3.4 per doubling): both terms grow as 1/m ∝ N², and as h shrinks the damping's 2h C, linear
in h, takes over from h² K, so the cap tends to ∝ 1/N². At h = 1e-4 s the cloth blows up
within 2000 steps at N = 64 and visviva's divergence watch stops the run within 20 steps at
N = 128; at N = 512, h = 5e-6 s (above the cap) blows up within 750 steps. So N = 64, 128, 256,
512 use h = 5e-5, 2.5e-5, 1e-5, 2.5e-6 s (``STEP_BY_SIZE``, 0.5–0.65 of the cap); a step does
the same work whatever h is.

Runners (one step per call; time per step is the median of repeats after a first call that
compiles; repeated calls keep advancing the same cloth):

* plain Numba, written by hand to be as fast as we can make it (see the comment above
  ``spring_forces`` for the variants measured): the spring-list step, each spring's force once
  in one pass, then each point's sum through CSR lists fused with the integration; on every
  core and on one (Warp-CPU runs a kernel on one thread: how many cores Warp, Newton and
  visviva keep busy is printed);
* Warp-CPU: what a Warp user writes, a spring kernel scattering with ``wp.atomic_add`` into a
  force array and an integration kernel, ``vec3d`` arrays, one launch pair per step;
* Newton semi-implicit (CPU): ``newton.solvers.SolverSemiImplicit`` on ``device="cpu"``, as
  Newton's cloth examples drive it (``state.clear_forces()``, ``solver.step(state_in,
  state_out, control, None, h)``, the states swapped; the two alternating steps replayed as CPU
  graphs captured with ``wp.ScopedCapture``, as those examples do, or launched directly where
  capture fails). Newton is float32 only (``wp.vec3`` positions and velocities, float32 masses,
  spring constants and forces): the one runner not in float64. Its scene is built from the
  benchmark's lists (``ModelBuilder.add_particles``, and the five spring lists that
  ``add_spring`` appends to, filled in bulk), not with ``add_cloth_grid``, which makes triangle
  FEM elements, dihedral bending and springs along the triangles' edges only, with masses from
  triangle areas. The same points, masses and springs (rest lengths from the float32
  positions, as ``add_spring`` computes them), damping along
  each spring (Newton's ``eval_spring`` is the force above), gravity as a vector with the y axis
  up; pinned points get mass 0, Newton's kinematic particles (1/m = 0, no gravity, so they stay
  put); radius 0, so no particle–particle contact hash grid is built or searched; no shapes, no
  ground, no contacts (``None``), no triangles, edges or tetrahedra, triangle contact off.
  ``particle_max_velocity`` keeps Newton's 1e5 m/s, which the cloth never nears. The step
  integrates exactly v ← v + h (F/m + g), x ← x + h v, in float32: near y = 1 m, where
  float32 numbers are 6e-8 m apart, a move h v under 3e-8 m rounds to nothing, so at N = 256
  (h = 1e-5 s) Newton's cloth stays put for its first ~30 steps (visviva's falls 4e-7 m), and
  at N = 512 (h = 2.5e-6 s) for its first ~490, longer than it is timed; it does the same work
  per step all the same. (c) checks the model it builds;
* visviva through its public API (``visviva_runner``: ``add_cloth``, ``Simulation.step()``),
  which takes the fused particle step on every core. It keeps no spring list for a cloth: since
  its springs are a grid's, it sums them at each point by a stencil
  (``visviva.forces.lattice_springs``), offset by offset along a row of points, reading both
  ends of a spring through contiguous slices, so it reads no spring index, stiffness or
  damping array and the compiler vectorizes it; it computes each spring twice (once from
  each end) and stores one force per point, not per spring, which the integration then reads.

Figures per N: time per step, springs/s (springs × steps / s), GB/s, that GB/s as a fraction
of two STREAM triads measured in the same run (part (a), on every core), and the ratios
visviva ÷ Warp, visviva ÷ Newton and visviva ÷ plain Numba. The triads:

* the DRAM triad, over three arrays each at least 4× the last-level cache (STREAM's own rule
  for a memory bandwidth; 32 MiB of L3 here, so 3 × 128 MiB; the cache size is read from
  sysfs, ``lscpu -B`` or ``sysconf``, else assumed 32 MiB; at least 256 MiB in all): the
  memory-bandwidth limit, against which the target (a third of it) is judged;
* the same-size triad, over arrays totalling the cloth state's size at that N (56 B per point,
  32 B per spring): context. Up to N = 256 the state (≤ 15 MiB) fits in the L3 and this triad
  runs at cache speed, several times the DRAM triad; at N = 512 the state (62 MiB) outgrows
  the L3, so there this triad runs mostly from DRAM too and a spring-list step streams from
  memory (visviva's stencil keeps less, 128 B per point, 32 MiB at N = 512: about the L3).

GB/s counts what a spring-list step must move at least, 104 B per point (reads x, v and 1/m:
7 float64; writes x, v: 6 float64) plus 32 B per spring (reads its two ends as int32, L, k and
c as float64), about 295 B per point in all; every runner gets this one count whatever it
moves. The plain Numba one moves more (it writes and re-reads a force per spring); Newton, in
float32, less (its GB/s is a float64 equivalent); and so does visviva's stencil, which reads no
spring index, L, k or c arrays: per point it reads x, v and 1/m, the rest lengths of its
springs (6 float64 per point for a cloth), writes and rereads one force, and writes x and v,
25 float64 or 200 B per point (``STENCIL_BYTES_PER_POINT``), about 0.7 of the count: its GB/s
is a spring-list equivalent, not what it moves.

Finally the runners' positions after 100 steps at N = 32 from the same start are compared (they
sum forces in different orders, so they agree to round-off, not bit for bit): the float64
runners with plain Numba to 1e-9 m, Newton with visviva to ``NEWTON_TOLERANCE`` (see there);
Newton's model is checked against the scene too. This is not a test: it prints figures and
exits 1 only if a sanity check fails.
"""

from __future__ import annotations

import argparse
import datetime
import glob
import importlib
import math
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

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
from bench_particles import TRIAD_BYTES, TRIAD_BYTES_STREAM, Runner, cpu_share, on_path, triad

# --------------------------------------------------------------------------------------------
# The scene
# --------------------------------------------------------------------------------------------

GRAVITY = (0.0, -9.81, 0.0)  # m/s²
AREAL_DENSITY = 0.1  # kg/m²
STIFFNESS = 1000.0  # N/m, structural springs
SHEAR = 100.0  # N/m, diagonal springs
BENDING = 1.0  # N/m, springs between points two apart
DAMPING = 0.01  # N·s/m, along every spring
HEIGHT = 1.0  # m

#: Symplectic Euler step by grid size: 1e-4 s where it is stable (see the module docstring).
STEP_BY_SIZE = {16: 1e-4, 32: 1e-4, 64: 5e-5, 128: 2.5e-5, 256: 1e-5, 512: 2.5e-6}

#: The agreement check: grid size, steps, largest allowed position difference [m].
CHECK_N = 32
CHECK_STEPS = 100
CHECK_TOLERANCE = 1e-9
#: The same for Newton, in float32, against visviva [m]. Near y = 1 m float32 numbers are
#: 6e-8 m apart, so each x ← x + h v rounds by up to 3e-8 m; over 100 steps these add up like
#: a random walk to ~3e-7 m (2.3e-7 m measured at N = 32 with Newton 1.8.0). 1e-6 m allows
#: that with room and is still 0.2% of the 0.5 mm the cloth sags by then.
NEWTON_TOLERANCE = 1e-6

#: Bytes a step must move at least (see the module docstring for what they are).
BYTES_PER_POINT = (7 + 6) * 8
BYTES_PER_SPRING = 2 * 4 + 3 * 8
#: Bytes of the state a step reads: the same-size triad runs over arrays of this total size.
STATE_BYTES_PER_POINT = 7 * 8
#: What visviva's stencil step moves per point of a cloth (reads x, v, 1/m and 6 rest lengths,
#: writes and rereads a force, writes x and v: 25 float64), for the footnotes: less than the
#: count above, which every runner is given.
STENCIL_BYTES_PER_POINT = (7 + 6 + 3 + 3 + 6) * 8

#: The DRAM triad: each of its three arrays at least this many times the last-level cache
#: (STREAM's rule: smaller, part of them stays cached between repeats and the figure is no
#: longer a memory bandwidth), and the three at least DRAM_TRIAD_BYTES in all.
CACHE_MULTIPLE = 4
DRAM_TRIAD_BYTES = 256 * 2**20
#: The last-level cache assumed where the machine does not say (this machine's L3).
ASSUMED_CACHE = (3, 32 * 2**20)

#: The targets for visviva, printed next to the figures.
TARGET_VS_WARP = 2.0  # × Warp-CPU's springs/s
TARGET_VS_NEWTON = 2.0  # × Newton semi-implicit CPU's springs/s
TARGET_FRACTION = 1.0 / 3.0  # of the DRAM triad's bandwidth (the memory-bandwidth limit)


@dataclass(frozen=True)
class Cloth:
    """The scene at one grid size: points, masses and the spring list.

    ``pairs`` is sorted by first end (each point's springs to higher indices together): the
    plain Numba spring pass then walks the points nearly in order (about 5% faster than the
    springs grouped by family, measured at N = 256).
    """

    n: int
    positions: np.ndarray  # (N², 3) m
    mass: np.ndarray  # (N²,) kg
    pinned: np.ndarray  # indices
    pairs: np.ndarray  # (S, 2) int32
    rest: np.ndarray  # (S,) m
    stiffness: np.ndarray  # (S,) N/m
    damping: np.ndarray  # (S,) N·s/m

    @property
    def springs(self) -> int:
        return self.pairs.shape[0]

    @property
    def inverse_mass(self) -> np.ndarray:
        """1/m, and 0 at the pinned points: every runner multiplies forces by it."""
        inverse = 1.0 / self.mass
        inverse[self.pinned] = 0.0
        return inverse


def spring_count(n: int) -> int:
    """Structural 2 N (N − 1), shear 2 (N − 1)², bend 2 N (N − 2)."""
    return 2 * n * (n - 1) + 2 * (n - 1) ** 2 + 2 * n * (n - 2)


def cloth_scene(n: int) -> Cloth:
    """The scene on an n × n grid, built directly (not through visviva)."""
    spacing = 1.0 / (n - 1)
    j, i = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")  # (row j, column i)
    positions = np.stack([i * spacing, np.full(i.shape, HEIGHT), j * spacing], axis=-1)
    # A point's share of the cells around it is the product of its shares along x and z.
    edge = np.ones(n)
    edge[[0, -1]] = 0.5
    mass = AREAL_DENSITY * spacing**2 * np.outer(edge, edge)
    index = j * n + i
    pairs, stiffness = [], []
    # (Δi, Δj) from the first end to the second, and the family's stiffness.
    families = [
        (1, 0, STIFFNESS),
        (0, 1, STIFFNESS),
        (1, 1, SHEAR),
        (-1, 1, SHEAR),
        (2, 0, BENDING),
        (0, 2, BENDING),
    ]
    for di, dj, k in families:
        inside = (i + di >= 0) & (i + di < n) & (j + dj < n)
        first = index[inside]
        second = (j[inside] + dj) * n + i[inside] + di
        pairs.append(np.stack([first, second], axis=1))
        stiffness.append(np.full(first.size, k))
    pairs = np.concatenate(pairs)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    pairs = pairs[order].astype(np.int32)
    positions = positions.reshape(-1, 3)
    rest = np.linalg.norm(positions[pairs[:, 1]] - positions[pairs[:, 0]], axis=1)
    return Cloth(
        n,
        positions,
        mass.reshape(-1),
        np.array([0, n - 1]),
        pairs,
        rest,
        np.concatenate(stiffness)[order],
        np.full(len(pairs), DAMPING),
    )


def numpy_reference(cloth: Cloth, h: float, steps: int) -> np.ndarray:
    """The step written plainly with NumPy (``np.add.at`` scatters): positions after ``steps``."""
    x = cloth.positions.copy()
    v = np.zeros_like(x)
    inverse_mass = cloth.inverse_mass[:, None]
    gravity = np.where(inverse_mass > 0.0, np.array(GRAVITY), 0.0)
    i, j = cloth.pairs[:, 0], cloth.pairs[:, 1]
    for _ in range(steps):
        d = x[j] - x[i]
        length = np.linalg.norm(d, axis=1)
        u = d / length[:, None]
        rate = np.einsum("sk,sk->s", v[j] - v[i], u)
        f = (cloth.stiffness * (length - cloth.rest) + cloth.damping * rate)[:, None] * u
        force = np.zeros_like(x)
        np.add.at(force, i, f)
        np.add.at(force, j, -f)
        v += h * (force * inverse_mass + gravity)
        x += h * v
    return x


# --------------------------------------------------------------------------------------------
# Plain Numba peer
# --------------------------------------------------------------------------------------------
# Race-free parallel force kernels measured here (N = 256, 2 threads, per step, force and
# integration together):
#   per-point gather over a CSR list of incident springs, each spring evaluated by both ends,
#     fused with the integration (new x, v into a second buffer)                     1.9 ms
#   12 graph-coloured spring sets (no two springs of a set share a point), each a
#     prange over its springs scattering into a force array, then the integration   2.7 ms
#   two passes: a prange over springs writing each spring's force (no scatter, so LLVM
#     vectorises it: AVX-512 gathers, vsqrtpd), then a prange over points summing their
#     springs' forces through CSR lists and integrating                             1.2 ms
# The last is the fastest and is the one below. Each spring's force is computed once, as in
# the peers (the gather variant computes it twice and is compute bound on sqrt and division;
# visviva's stencil computes it twice too, but vectorized along a grid row, with no index
# list to read: see src/visviva/forces/lattice_springs.py).
# Two CSR lists per point (springs where it is the first end, where it is the second) instead
# of one list with a ±1 per entry: no sign to read, about 5% faster.


@njit(parallel=True, cache=True, error_model="numpy")
def spring_forces(x, y, z, vx, vy, vz, first, second, rest, k, c, fx, fy, fz):
    """Each spring's force on its first end (its second end gets the opposite)."""
    for s in prange(first.shape[0]):
        i, j = first[s], second[s]
        dx, dy, dz = x[j] - x[i], y[j] - y[i], z[j] - z[i]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        inverse = 1.0 / length  # one division, three multiplications
        ux, uy, uz = dx * inverse, dy * inverse, dz * inverse
        rate = (vx[j] - vx[i]) * ux + (vy[j] - vy[i]) * uy + (vz[j] - vz[i]) * uz
        magnitude = k[s] * (length - rest[s]) + c[s] * rate
        fx[s], fy[s], fz[s] = magnitude * ux, magnitude * uy, magnitude * uz


@njit(parallel=True, cache=True, error_model="numpy")
def gather_and_advance(
    x, y, z, vx, vy, vz, fx, fy, fz, as_first, first_of, as_second, second_of, inverse_mass, h, g
):
    """Sum each point's spring forces, then one symplectic Euler step of it, in place.

    ``first_of[as_first[i]:as_first[i + 1]]`` are the springs whose first end is point i (they
    pull it by +f), ``second_of[...]`` likewise for the second end (−f). ``g``: gravity.
    """
    gx, gy, gz = g
    for i in prange(x.shape[0]):
        sx = sy = sz = 0.0
        for e in range(as_first[i], as_first[i + 1]):
            s = first_of[e]
            sx, sy, sz = sx + fx[s], sy + fy[s], sz + fz[s]
        for e in range(as_second[i], as_second[i + 1]):
            s = second_of[e]
            sx, sy, sz = sx - fx[s], sy - fy[s], sz - fz[s]
        a = inverse_mass[i]
        free = 1.0 if a > 0.0 else 0.0  # pinned points have 1/m = 0: no force moves them
        px = vx[i] + h * (sx * a + free * gx)
        py = vy[i] + h * (sy * a + free * gy)
        pz = vz[i] + h * (sz * a + free * gz)
        vx[i], vy[i], vz[i] = px, py, pz
        x[i] += h * px
        y[i] += h * py
        z[i] += h * pz


def incidence(points: int, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CSR lists: the springs having point i at ``ends`` are ``springs[start[i]:start[i + 1]]``."""
    start = np.zeros(points + 1, dtype=np.int64)
    np.cumsum(np.bincount(ends, minlength=points), out=start[1:])
    return start, np.argsort(ends, kind="stable").astype(np.int32)


def numba_runner(n: int) -> Runner:
    """Plain Numba from the scene's start: one step per call, and a positions getter."""
    cloth = cloth_scene(n)
    h = STEP_BY_SIZE[n]
    state = [np.ascontiguousarray(cloth.positions[:, k]) for k in range(3)]
    state += [np.zeros(n * n) for _ in range(3)]
    first, second = (np.ascontiguousarray(cloth.pairs[:, e]) for e in range(2))
    springs = (first, second, cloth.rest, cloth.stiffness, cloth.damping)
    forces = [np.empty(cloth.springs) for _ in range(3)]
    lists = (*incidence(n * n, first), *incidence(n * n, second))
    inverse_mass = cloth.inverse_mass

    def step() -> None:
        spring_forces(*state, *springs, *forces)
        gather_and_advance(*state, *forces, *lists, inverse_mass, h, GRAVITY)

    return step, lambda: np.stack(state[:3], axis=1)


# --------------------------------------------------------------------------------------------
# Warp-CPU peer (optional; never a visviva dependency)
# --------------------------------------------------------------------------------------------

#: The ``warp`` module once loaded: a module global because Warp evaluates the kernels'
#: annotations (strings, with ``from __future__ import annotations``) in this module.
wp = None


class WarpCloth:
    """Warp kernels for the same step, float64, launched on ``device="cpu"``."""

    def __init__(self, peers: str | None) -> None:
        global wp
        with on_path(peers):
            wp = importlib.import_module("warp")
        self.wp = wp
        wp.config.log_level = wp.LOG_WARNING  # no start-up banner
        wp.init()

        @wp.kernel
        def spring_forces(
            x: wp.array(dtype=wp.vec3d),
            v: wp.array(dtype=wp.vec3d),
            first: wp.array(dtype=wp.int32),
            second: wp.array(dtype=wp.int32),
            rest: wp.array(dtype=wp.float64),
            k: wp.array(dtype=wp.float64),
            c: wp.array(dtype=wp.float64),
            force: wp.array(dtype=wp.vec3d),
        ):
            s = wp.tid()
            i = first[s]
            j = second[s]
            d = x[j] - x[i]
            length = wp.length(d)
            u = d / length
            rate = wp.dot(v[j] - v[i], u)
            f = (k[s] * (length - rest[s]) + c[s] * rate) * u
            wp.atomic_add(force, i, f)
            wp.atomic_sub(force, j, f)

        @wp.kernel
        def advance(
            x: wp.array(dtype=wp.vec3d),
            v: wp.array(dtype=wp.vec3d),
            force: wp.array(dtype=wp.vec3d),
            inverse_mass: wp.array(dtype=wp.float64),
            gravity: wp.vec3d,
            h: wp.float64,
        ):
            i = wp.tid()
            a = inverse_mass[i]
            if a > wp.float64(0.0):  # pinned points (1/m = 0) stay
                q = v[i] + h * (force[i] * a + gravity)
                v[i] = q
                x[i] = x[i] + h * q
            # Cleared here for the next step's atomics (saves a separate force.zero_() pass).
            force[i] = wp.vec3d(wp.float64(0.0), wp.float64(0.0), wp.float64(0.0))

        self.spring_forces = spring_forces
        self.advance = advance
        wp.load_module(device="cpu")

    @property
    def version(self) -> str:
        return self.wp.__version__

    def runner(self, n: int) -> Runner:
        """Warp from the scene's start; a step is two launches and ``wp.synchronize``."""
        wp = self.wp
        cloth = cloth_scene(n)
        points, springs = n * n, cloth.springs

        def array(values: np.ndarray, dtype: object) -> object:
            return wp.array(np.ascontiguousarray(values), dtype=dtype, device="cpu")

        x = array(cloth.positions, wp.vec3d)
        v = wp.zeros(points, dtype=wp.vec3d, device="cpu")
        force = wp.zeros(points, dtype=wp.vec3d, device="cpu")
        spring_inputs = [
            x,
            v,
            array(cloth.pairs[:, 0], wp.int32),
            array(cloth.pairs[:, 1], wp.int32),
            array(cloth.rest, wp.float64),
            array(cloth.stiffness, wp.float64),
            array(cloth.damping, wp.float64),
            force,
        ]
        advance_inputs = [
            x,
            v,
            force,
            array(cloth.inverse_mass, wp.float64),
            wp.vec3d(*GRAVITY),
            wp.float64(STEP_BY_SIZE[n]),
        ]

        def step() -> None:
            wp.launch(self.spring_forces, dim=springs, inputs=spring_inputs, device="cpu")
            wp.launch(self.advance, dim=points, inputs=advance_inputs, device="cpu")
            wp.synchronize()

        return step, lambda: x.numpy().copy()


def load_warp(peers: str | None) -> tuple[WarpCloth | None, str]:
    """The Warp peer, or None and the reason it is unavailable."""
    try:
        return WarpCloth(peers), ""
    except ImportError as error:
        return None, f"not installed ({error})"
    except Exception as error:  # a broken install or an unsupported feature: skip, say why
        return None, f"unusable ({type(error).__name__}: {error})"


# --------------------------------------------------------------------------------------------
# Newton peer (optional; never a visviva dependency)
# --------------------------------------------------------------------------------------------


class NewtonCloth:
    """NVIDIA Newton's semi-implicit solver on the same scene, ``device="cpu"``, float32.

    How the scene maps onto Newton's model: see the module docstring (and ``scene_problems``).
    """

    def __init__(self, directory: str | None) -> None:
        with on_path(directory):
            self.newton = importlib.import_module("newton")
            importlib.import_module("newton.solvers")
            self.wp = importlib.import_module("warp")
        self.wp.config.log_level = self.wp.LOG_WARNING  # no start-up banner
        self.wp.init()
        self.captured: bool | None = None  # CPU graph replay: None until a runner has tried

    @property
    def version(self) -> str:
        return f"{self.newton.__version__} on Warp {self.wp.__version__}"

    def build(self, n: int) -> tuple[Cloth, object]:
        """The scene at ``n`` and Newton's model of it (on the CPU)."""
        newton = self.newton
        cloth = cloth_scene(n)
        builder = newton.ModelBuilder(up_axis=newton.Axis.Y, gravity=GRAVITY)
        mass = cloth.mass.copy()
        mass[cloth.pinned] = 0.0  # Newton's kinematic particles: 1/m = 0 and no gravity
        positions = cloth.positions.astype(np.float32)
        builder.add_particles(
            pos=positions.tolist(),
            vel=np.zeros_like(positions).tolist(),
            mass=mass.tolist(),
            radius=[0.0] * (n * n),  # no particle-particle contact (and no hash grid)
        )
        # What add_spring(i, j, k, c, control=0.0) appends to the builder's five spring lists,
        # rest length from the float32 positions included, but for all springs at once: one
        # Python call per spring (2 to 6 µs each) took seconds at N = 256 (391k springs).
        ends = positions[cloth.pairs[:, 1]] - positions[cloth.pairs[:, 0]]
        builder.spring_indices.extend(cloth.pairs.reshape(-1).tolist())
        builder.spring_rest_length.extend(np.sqrt((ends * ends).sum(axis=1)).tolist())
        builder.spring_stiffness.extend(cloth.stiffness.tolist())
        builder.spring_damping.extend(cloth.damping.tolist())
        builder.spring_control.extend([0.0] * cloth.springs)
        return cloth, builder.finalize(device="cpu")

    def scene_problems(self, n: int) -> list[str]:
        """Where Newton's model at ``n`` differs from the scene (empty: nowhere)."""
        cloth, model = self.build(n)
        f32 = np.float32
        problems = []

        def compare(what: str, got: np.ndarray, want: np.ndarray, rtol: float = 0.0) -> None:
            if got.shape != want.shape or not np.allclose(got, want, rtol=rtol, atol=0.0):
                problems.append(what)

        compare("spring ends", model.spring_indices.numpy().reshape(-1, 2), cloth.pairs)
        compare("stiffness", model.spring_stiffness.numpy(), cloth.stiffness.astype(f32))
        compare("damping", model.spring_damping.numpy(), cloth.damping.astype(f32))
        # add_spring takes rest lengths from the float32 positions: a relative 2e-6 from the
        # float64 ones at N = 32 (0.03 m between coordinates rounded to 6e-8 m near 1 m).
        start = cloth.positions.astype(f32).astype(np.float64)
        ends = start[cloth.pairs[:, 1]] - start[cloth.pairs[:, 0]]
        compare(
            "rest lengths", model.spring_rest_length.numpy(), np.linalg.norm(ends, axis=1), 1e-6
        )
        compare("1/m", model.particle_inv_mass.numpy(), cloth.inverse_mass, 1e-6)
        compare("gravity", model.gravity.numpy().reshape(-1), np.array(GRAVITY, f32))
        compare("start", model.particle_q.numpy(), cloth.positions.astype(f32))
        others = {
            "triangles": model.tri_count,
            "edges": model.edge_count,
            "tetrahedra": model.tet_count,
            "shapes": model.shape_count,
            "bodies": model.body_count,
            "particle hash grid": int(model.particle_grid is not None),
        }
        problems += [f"{count} {what}" for what, count in others.items() if count]
        return problems

    def runner(self, n: int) -> Runner:
        """Newton from the scene's start: one ``solver.step`` per call (see the docstring)."""
        wp = self.wp
        _, model = self.build(n)
        solver = self.newton.solvers.SolverSemiImplicit(model, enable_tri_contact=False)
        states = (model.state(), model.state())
        control = model.control()
        h = STEP_BY_SIZE[n]
        graphs: list[object] = []
        done = [0]  # steps so far: the newest state is states[done % 2]

        def advance(a: int) -> None:
            states[a].clear_forces()
            solver.step(states[a], states[1 - a], control, None, h)

        def step() -> None:
            a = done[0] % 2
            if done[0] == 0:  # compiles Newton's kernels, then records both steps
                advance(a)
                try:
                    for b in (0, 1):
                        with wp.ScopedCapture(device="cpu") as capture:  # records, runs nothing
                            advance(b)
                        graphs.append(capture.graph)
                except Exception:  # no CPU graphs in this Warp: launch directly
                    graphs.clear()
                self.captured = bool(graphs)
            elif graphs:
                wp.capture_launch(graphs[a])
            else:
                advance(a)
            wp.synchronize()
            done[0] += 1

        def positions() -> np.ndarray:
            return states[done[0] % 2].particle_q.numpy().astype(np.float64)

        return step, positions


def load_newton(directory: str | None) -> tuple[NewtonCloth | None, str]:
    """The Newton peer, or None and the reason it is unavailable."""
    try:
        return NewtonCloth(directory), ""
    except ImportError as error:
        return None, f"not installed ({error})"
    except Exception as error:  # a broken install or an unsupported feature: skip, say why
        return None, f"unusable ({type(error).__name__}: {error})"


# --------------------------------------------------------------------------------------------
# visviva
# --------------------------------------------------------------------------------------------


def visviva_runner(n: int) -> Runner:
    """visviva's cloth through the public API: one ``sim.step()`` per call.

    ``positions()`` returns the (n², 3) positions; point (i, j) has index j·n + i, as here.
    """
    builder = vv.SceneBuilder(name=f"benchmark cloth {n}x{n}")
    builder.set_world(gravity=GRAVITY)
    builder.set_integration(method="symplectic_euler", dt=STEP_BY_SIZE[n], duration=1.0)
    builder.add_cloth(
        (n, n),
        stiffness=STIFFNESS,
        shear=SHEAR,
        bending=BENDING,
        damping=DAMPING,
        areal_density=AREAL_DENSITY,
        origin=(0.0, HEIGHT, 0.0),
        along=(1.0, 0.0, 0.0),
        across=(0.0, 0.0, 1.0),
        pinned=[0, n - 1],
    )
    simulation = vv.Simulation(builder.build())

    def step() -> None:
        simulation.step()

    def positions() -> np.ndarray:
        return np.array(simulation.state["particle_position"])

    return step, positions


# --------------------------------------------------------------------------------------------
# (a) Memory bandwidth
# --------------------------------------------------------------------------------------------


def state_bytes(n: int) -> int:
    """Bytes of the state a step reads (the triad's arrays total this)."""
    return STATE_BYTES_PER_POINT * n * n + BYTES_PER_SPRING * spring_count(n)


def step_bytes(n: int) -> int:
    """Bytes a step must move at least (GB/s below counts these)."""
    return BYTES_PER_POINT * n * n + BYTES_PER_SPRING * spring_count(n)


def cache_bytes(text: str) -> int:
    """A size as sysfs writes it (``32768K``, ``1M``) or as ``lscpu -B`` does (bytes)."""
    text = text.strip().upper()
    scale = {"K": 2**10, "M": 2**20, "G": 2**30}.get(text[-1:], 1)
    return int(text.rstrip("KMGB")) * scale


def last_level_cache() -> tuple[int, int, str]:
    """The last-level cache: its level, its bytes (all its instances together: STREAM's rule
    is about all the cache a run can use) and where that was read."""
    # Linux's sysfs: every CPU's caches; an instance shared by several CPUs is counted once.
    instances: dict[tuple[int, str, str], int] = {}
    for index in glob.glob("/sys/devices/system/cpu/cpu[0-9]*/cache/index[0-9]*"):
        try:
            level, kind, shared, size = (
                Path(index, name).read_text().strip()
                for name in ("level", "type", "shared_cpu_list", "size")
            )
            instances[int(level), kind, shared] = cache_bytes(size)
        except (OSError, ValueError):
            continue
    if instances:
        top = max(level for level, *_ in instances)
        total = sum(size for (level, *_), size in instances.items() if level == top)
        return top, total, "sysfs"
    # lscpu -B prints each level's total over its instances, in bytes.
    try:
        lines = subprocess.run(
            ["lscpu", "-B"], capture_output=True, text=True, timeout=10, check=True
        ).stdout.splitlines()
        sizes = {}
        for line in lines:
            name, _, value = line.partition(":")
            if name.startswith("L") and name.endswith(" cache") and name[1].isdigit():
                sizes[int(name[1])] = cache_bytes(value.split()[0])
        if sizes:
            return max(sizes), sizes[max(sizes)], "lscpu -B"
    except (OSError, subprocess.SubprocessError, ValueError, IndexError):
        pass
    # glibc's sysconf: one instance's size (0 or absent where unknown).
    for level in (3, 2):
        name = f"SC_LEVEL{level}_CACHE_SIZE"
        if name in os.sysconf_names and os.sysconf(name) > 0:
            return level, os.sysconf(name), "sysconf"
    return *ASSUMED_CACHE, "assumed"


@dataclass(frozen=True)
class Bandwidth:
    """(a)'s triads, in real bytes per second (every core)."""

    same_size: dict[int, float]  # by N, over arrays totalling the state's size: context
    dram: float  # over arrays beyond the caches by STREAM's rule: the memory-bandwidth limit
    cache: int  # bytes of the last-level cache


def bench_bandwidth(args: argparse.Namespace) -> Bandwidth:
    """The triad over arrays of the state's size at each N, and over arrays past the caches.

    ``bench_particles.bench_bandwidth`` sizes its arrays by particle count (8 float64 each);
    the cloth's state also holds its springs, so the triad kernel is reused, not that table.
    """
    heading(
        "(a) Memory bandwidth: STREAM triad a = b + s·c over the cloth state's size, and over"
        " arrays beyond the caches"
    )
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    level, cache, source = last_level_cache()
    # Each array 4× the cache (STREAM's rule), the three at least DRAM_TRIAD_BYTES in all.
    dram_length = max(CACHE_MULTIPLE * cache, DRAM_TRIAD_BYTES // 3) // 8
    runs = [(f"N = {n}: the state's size", state_bytes(n) // (3 * 8)) for n in args.sizes]
    runs.append((f"DRAM (STREAM rule: arrays ≥ {CACHE_MULTIPLE}× L{level})", dram_length))
    figures = []
    rows = []
    for label, length in runs:
        rng = np.random.default_rng(1)
        a, b, c = np.zeros(length), rng.random(length), rng.random(length)
        timing = measure(lambda a=a, b=b, c=c: triad(a, b, c, 3.0), args.repeats, f"triad, {label}")
        figures.append(TRIAD_BYTES * length / timing.median)
        del a, b, c  # the DRAM triad's arrays are hundreds of MiB: not kept while the rest runs
        rows.append(
            [
                label,
                f"{3 * 8 * length / 2**20:.1f} MiB",
                fmt_time(timing.median),
                f"{TRIAD_BYTES_STREAM * length / timing.median / 1e9:.1f}",
                f"{figures[-1] / 1e9:.1f}",
                timing.busy,
            ]
        )
    print()
    print_table(
        ["triad over", "arrays", "median", "GB/s (STREAM)", "GB/s (real)", "others' CPU"],
        rows,
    )
    print(
        f"  {numba.get_num_threads()} threads; the state's size: {STATE_BYTES_PER_POINT} B per"
        f" point + {BYTES_PER_SPRING} B per spring; last-level cache: L{level},"
        f" {cache / 2**20:.1f} MiB ({source}); 'real' counts 32 B per element (with the"
        " write-allocate read of a), STREAM 24 B"
    )
    return Bandwidth(dict(zip(args.sizes, figures[:-1], strict=True)), figures[-1], cache)


# --------------------------------------------------------------------------------------------
# (b) The cloth step
# --------------------------------------------------------------------------------------------


@dataclass
class Figure:
    label: str
    n: int
    timing: Timing

    @property
    def springs_per_second(self) -> float:
        return spring_count(self.n) / self.timing.median


#: The runners' labels (plain Numba twice: on every core, and on one like the peers here).
PLAIN = f"plain Numba, {numba.config.NUMBA_NUM_THREADS} threads"
PLAIN_ONE = "plain Numba, 1 thread"
WARP = "Warp-CPU"
NEWTON = "Newton semi-implicit (CPU)"
VISVIVA = "visviva"


@dataclass(frozen=True)
class Peers:
    """The optional peers (None where unavailable) and why each is missing."""

    warp: WarpCloth | None
    warp_why: str
    newton: NewtonCloth | None
    newton_why: str


@dataclass(frozen=True)
class Contender:
    label: str
    factory: Callable[[int], Runner]
    threads: int  # Numba threads while it runs (Warp and visviva: left at the default)


def contenders(peers: Peers) -> list[Contender]:
    every = numba.config.NUMBA_NUM_THREADS
    plan = [Contender(PLAIN, numba_runner, every), Contender(PLAIN_ONE, numba_runner, 1)]
    if peers.warp is not None:
        plan.append(Contender(WARP, peers.warp.runner, every))
    if peers.newton is not None:
        plan.append(Contender(NEWTON, peers.newton.runner, every))
    plan.append(Contender(VISVIVA, visviva_runner, every))
    return plan


def bench_step(
    args: argparse.Namespace,
    peers: Peers,
    bandwidth: Bandwidth,
    checks: Checks,
) -> list[Figure]:
    heading("(b) Cloth step, one step per call: N = " + ", ".join(map(str, args.sizes)))
    figures = []
    rows = []
    lowest: dict[int, dict[str, float]] = {}  # the lowest point after the timed steps, by N
    # The runners at the largest N, kept for the CPU shares below: building them again would
    # cost seconds (visviva's 512² scene takes ~7 s to build, Newton's ~2 s).
    largest: dict[str, Callable[[], None]] = {}
    for n in args.sizes:
        lowest[n] = {}
        for contender in contenders(peers):
            label = contender.label
            numba.set_num_threads(contender.threads)
            step, positions = contender.factory(n)
            try:
                timing = measure(step, args.repeats, f"(b) {label}, N={n}")
            except vv.SimulationError as error:  # the divergence watch: report, go on
                checks.check(False, f"{label}, N={n}: {error}")
                continue
            final = positions()
            lowest[n][label] = float(final[:, 1].min()) if np.isfinite(final).all() else math.nan
            if n == args.sizes[-1]:
                largest[label] = step
            figure = Figure(label, n, timing)
            figures.append(figure)
            moved = step_bytes(n) / timing.median
            rows.append(
                [
                    label,
                    str(n),
                    f"{spring_count(n):,}",
                    fmt_time(timing.median),
                    sci(figure.springs_per_second),
                    f"{moved / 1e9:.1f}",
                    f"{100 * moved / bandwidth.dram:.0f}%",
                    f"{100 * moved / bandwidth.same_size[n]:.0f}%",
                    fmt_time(timing.first),
                    timing.busy,
                ]
            )
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    print()
    print_table(
        ["runner", "N", "springs", "per step", "springs/s", "GB/s", "of DRAM triad"]
        + ["of same-size triad", "first call", "others' CPU"],
        rows,
    )
    print(
        f"  GB/s = ({BYTES_PER_POINT} B × points + {BYTES_PER_SPRING} B × springs) / time per"
        " step, what a spring-list step moves at least, the same count for every runner; as a"
        " share of (a)'s real GB/s of the DRAM triad (the memory-bandwidth limit) and of the"
        " triad over the state's size at the same N (at cache speed where that fits in the"
        " cache)"
    )
    print(
        f"  {VISVIVA}'s stencil moves less than that count: it reads no spring index, L, k or c"
        " arrays; per point it reads x, v, 1/m and its springs' rest lengths, writes and"
        f" rereads one force and writes x, v ({STENCIL_BYTES_PER_POINT} B per point against"
        f" the count's {step_bytes(args.sizes[-1]) / args.sizes[-1] ** 2:.0f} B per point at"
        f" N = {args.sizes[-1]}): its GB/s is a spring-list equivalent"
    )
    print("  h by N: " + ", ".join(f"{n}: {STEP_BY_SIZE[n]:g} s" for n in args.sizes))
    n = args.sizes[-1]
    for label, step in largest.items():
        if label in (WARP, NEWTON, VISVIVA):
            share = cpu_share(step)
            print(
                f"  {label}: process CPU time / wall time while stepping at N = {n}:"
                f" {share:.2f} ({'one thread' if share < 1.3 else 'several threads'})"
            )
    if peers.newton is not None and peers.newton.captured is not None:
        how = "replayed as CPU graphs" if peers.newton.captured else "launched directly"
        print(f"  {NEWTON}: its steps {how} (see the module docstring)")
    for n, heights in lowest.items():
        # Newton's float32 cloth may not have moved yet: at N = 512 a step's move rounds to
        # nothing for ~490 steps (see the module docstring), so it need only not be above.
        checks.check(
            all(
                HEIGHT - 1.0 < y < HEIGHT or (label == NEWTON and y == HEIGHT)
                for label, y in heights.items()
            ),
            f"N={n}: every cloth finite and below its start after its timed steps ({NEWTON}: not"
            " above it); how far its lowest point fell: "
            + ", ".join(f"{label} {sci(HEIGHT - y)} m" for label, y in heights.items()),
        )
    return figures


def summarise(args: argparse.Namespace, figures: list[Figure], bandwidth: Bandwidth) -> None:
    heading("Comparisons (springs/s)")
    rate = {(f.label, f.n): f.springs_per_second for f in figures}

    def ratio(a: str, b: str, n: int) -> float:
        return rate.get((a, n), math.nan) / rate.get((b, n), math.nan)

    def of_triad(label: str, n: int, triad: float) -> float:
        steps_per_second = rate.get((label, n), math.nan) / spring_count(n)
        return steps_per_second * step_bytes(n) / triad

    def verdict(value: float, target: float) -> str:
        return "n/a" if math.isnan(value) else ("yes" if value >= target else "no")

    def times(value: float) -> str:
        return "n/a" if math.isnan(value) else f"{value:.2f}×"

    def share(value: float) -> str:
        return "n/a" if math.isnan(value) else f"{value:.1%}"

    rows = []
    for n in args.sizes:
        versus_warp = ratio(VISVIVA, WARP, n)
        versus_newton = ratio(VISVIVA, NEWTON, n)
        fraction = of_triad(VISVIVA, n, bandwidth.dram)
        rows.append(
            [
                str(n),
                times(versus_warp),
                verdict(versus_warp, TARGET_VS_WARP),
                times(versus_newton),
                verdict(versus_newton, TARGET_VS_NEWTON),
                times(ratio(VISVIVA, PLAIN, n)),
                times(ratio(VISVIVA, PLAIN_ONE, n)),
                times(ratio(PLAIN, WARP, n)),
                share(fraction),
                verdict(fraction, TARGET_FRACTION),
                share(of_triad(VISVIVA, n, bandwidth.same_size[n])),
                share(of_triad(PLAIN, n, bandwidth.dram)),
            ]
        )
    print()
    print_table(
        [
            "N",
            "visviva ÷ Warp",
            f"≥ {TARGET_VS_WARP:g}×",
            "visviva ÷ Newton",
            f"≥ {TARGET_VS_NEWTON:g}×",
            "visviva ÷ Numba(2)",
            "visviva ÷ Numba(1)",
            "Numba(2) ÷ Warp",
            "visviva of DRAM",
            f"≥ {TARGET_FRACTION:.0%}",
            "visviva of same-size",
            "Numba(2) of DRAM",
        ],
        rows,
    )
    print(
        f"  Numba(2), Numba(1): {PLAIN}, {PLAIN_ONE}; Newton: {NEWTON}, float32; targets for"
        f" visviva: ≥ {TARGET_VS_WARP:g}× Warp-CPU's springs/s, ≥ {TARGET_VS_NEWTON:g}× Newton's,"
        f" ≥ {TARGET_FRACTION:.0%} of the DRAM triad's bandwidth (the memory-bandwidth limit;"
        " GB/s as counted in (b)); 'of same-size': of the triad over arrays of the state's size"
        " at that N"
    )
    fits = [n for n in args.sizes if state_bytes(n) <= bandwidth.cache]
    print(
        "  the state is "
        + ", ".join(f"{state_bytes(n) / 2**20:.1f} MiB at N = {n}" for n in args.sizes)
        + f", the last-level cache {bandwidth.cache / 2**20:.0f} MiB: "
        + (
            f"up to N = {fits[-1]} the state fits and the same-size triad runs at cache speed;"
            if fits
            else "none fits;"
        )
        + f" {VISVIVA}'s stencil does a square root and a division for each end of each spring"
        " and reads no index arrays, moving less than (b)'s count (its share is a spring-list"
        " equivalent); the hand-written spring-list kernel's share shows what such a step"
        " reaches"
    )


# --------------------------------------------------------------------------------------------
# (c) Agreement
# --------------------------------------------------------------------------------------------


def bench_agreement(peers: Peers, checks: Checks) -> None:
    n, steps = CHECK_N, CHECK_STEPS
    heading(f"(c) Agreement after {steps} steps of {STEP_BY_SIZE[n]:g} s, N = {n} (max |Δx|)")
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    results = {"NumPy reference": numpy_reference(cloth_scene(n), STEP_BY_SIZE[n], steps)}
    for contender in contenders(peers):
        if contender.label == PLAIN_ONE:
            continue  # the same kernels as PLAIN
        step, positions = contender.factory(n)
        for _ in range(steps):
            step()
        results[contender.label] = positions()
    plain = results.pop(PLAIN)
    sag = HEIGHT - plain[:, 1].min()
    print(f"  the cloth's lowest point fell {sag * 1e3:.3f} mm ({PLAIN})")
    newton = results.pop(NEWTON, None)
    for label, positions in results.items():
        difference = float(np.abs(positions - plain).max())
        checks.check(
            difference <= CHECK_TOLERANCE,
            f"{PLAIN} vs {label}: {difference:.1e} m (≤ {CHECK_TOLERANCE:g} m)",
        )
    if peers.newton is None or newton is None:
        return
    problems = peers.newton.scene_problems(n)
    checks.check(
        not problems,
        f"{NEWTON}'s model holds the scene (spring ends, k, c, rest lengths, 1/m, gravity, start;"
        " no triangles, edges, tetrahedra, shapes, bodies or contact grid)"
        + (f": differs in {', '.join(problems)}" if problems else ""),
    )
    visviva = results[VISVIVA]
    difference = float(np.abs(newton - visviva).max())
    newton_sag = HEIGHT - newton[:, 1].min()
    checks.check(
        difference <= NEWTON_TOLERANCE,
        f"{VISVIVA} vs {NEWTON}: {difference:.1e} m (≤ {NEWTON_TOLERANCE:g} m: float32, see"
        f" NEWTON_TOLERANCE); its lowest point fell {newton_sag * 1e3:.3f} mm",
    )


# --------------------------------------------------------------------------------------------


def print_header(args: argparse.Namespace, peers: Peers) -> None:
    print("visviva cloth benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / numba:     {np.__version__} / {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    if peers.warp is None:
        print(f"Warp:              {peers.warp_why}; see the module docstring")
    else:
        print(f"Warp:              {peers.warp.version} (device cpu, float64)")
    if peers.newton is None:
        print(f"Newton:            {peers.newton_why}; see the module docstring")
    else:
        print(
            f"Newton:            {peers.newton.version} (device cpu, float32, SolverSemiImplicit)"
        )
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
        default=10.0,
        help="before a retry, wait up to this many seconds for the machine to be idle (default 10)",
    )
    parser.add_argument(
        "--peers",
        default=os.environ.get("VISVIVA_PEERS"),
        help="directory holding warp, and newton unless --newton says otherwise (pip install"
        " --no-deps --target DIR newton warp-lang)",
    )
    parser.add_argument(
        "--newton",
        default=os.environ.get("VISVIVA_NEWTON"),
        help="directory holding newton (default: the --peers directory)",
    )
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (3 if args.quick else 7)
    if args.retries is None:
        args.retries = 0 if args.quick else 2
    args.sizes = (16, 32) if args.quick else (64, 128, 256, 512)
    PATIENCE["retries"] = max(0, args.retries)
    PATIENCE["quiet_wait"] = max(0.0, args.quiet_wait)
    # Warp first: if Newton's directory holds another Warp, Newton runs on this one.
    peers = Peers(*load_warp(args.peers), *load_newton(args.newton or args.peers))
    # Compile (or load from the cache) the Numba kernels before the header and the timings.
    numba_runner(min(STEP_BY_SIZE))[0]()
    tiny = np.zeros(3)
    triad(tiny, tiny, tiny, 1.0)
    started = time.perf_counter()
    print_header(args, peers)
    checks = Checks()
    bandwidth = bench_bandwidth(args)
    figures = bench_step(args, peers, bandwidth, checks)
    summarise(args, figures, bandwidth)
    bench_agreement(peers, checks)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
