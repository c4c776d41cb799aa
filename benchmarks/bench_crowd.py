#!/usr/bin/env python
"""Crowd benchmark: one social-force step of visviva's stage against SciPy ``cKDTree`` + NumPy.

Run ``python benchmarks/bench_crowd.py`` (under a minute on 2 cores) or add ``--quick`` for a
smoke run (fewer repeats). The crowd, the same for both runners (float64): N agents (N = 1,000
and 10,000) on a jittered lattice at 1.5 agents/m² in a square yard walled by four thin boxes,
radii 0.25–0.35 m, 80 kg, velocities drawn with 0.5 m/s per component, walking to a goal far
off, the parameters of Helbing, Farkas & Vicsek (2000). One step of h = 5 ms:

* visviva: ``Crowd.apply(before, after, h, work)``, the stage as the pipeline calls it: copy of the
  state, exits, grid rebuild on the live agents, the forces on every core, the kick;
* SciPy + NumPy: ``cKDTree(x).query_pairs(r, output_type="ndarray")`` (one thread), the pair
  forces both ways by ``np.add.at``, the walls by the colliders' own ``signed_distance``, then
  the same kick and speed cap as array expressions.

Each run checks that both give the same velocities (to 1e-9 m/s: the sums run in different
orders). Figures are medians of ``--repeats`` calls after one warm-up call. This is not a test:
it prints figures and exits 1 only if the check fails.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time

import numpy as np
from scipy.spatial import cKDTree

import visviva as vv
from visviva.ode.workspace import Workspace
from visviva.particles.crowd import Crowd

DENSITY = 1.5  # agents per m²
H = 0.005  # [s]


def crowd_model(n: int) -> vv.model.Model:
    side = int(np.ceil(np.sqrt(n)))
    spacing = 1.0 / np.sqrt(DENSITY)
    rng = np.random.default_rng(n)
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n]
    xz = (cells + 0.5) * spacing + rng.uniform(-0.05, 0.05, (n, 2))
    length = side * spacing
    builder = vv.SceneBuilder(name=f"crowd{n}")
    builder.set_integration(dt=H, duration=1.0)
    builder.add_particles(
        name="people",
        positions=np.column_stack([xz[:, 0], np.ones(n), xz[:, 1]]),
        velocities=np.column_stack([rng.normal(0, 0.5, n), np.zeros(n), rng.normal(0, 0.5, n)]),
        radius=rng.uniform(0.25, 0.35, n).tolist(),
        mass=80.0,
    )
    half = 0.5 * length
    for name, centre, size in (
        ("west", (-0.1, 1.0, half), (0.2, 2.0, length + 0.4)),
        ("east", (length + 0.1, 1.0, half), (0.2, 2.0, length + 0.4)),
        ("south", (half, 1.0, -0.1), (length + 0.4, 2.0, 0.2)),
        ("north", (half, 1.0, length + 0.1), (length + 0.4, 2.0, 0.2)),
    ):
        builder.add_collider("box", center=centre, size=size, name=name)
    builder.add_crowd(["people"], goal=(10 * length, 1.0, half))
    return builder.build()


def numpy_step(stage: Crowd, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The same kick with a k-d tree for the pairs and NumPy for the forces."""
    p, u = x[:, [0, 2]], v[:, [0, 2]]
    A, B, k, kappa, v0, tau, cut = stage.params[0]
    m, r = stage.mass, stage.radius
    to_goal = stage.goal[0] - p
    force = m[:, None] * (v0 * to_goal / np.linalg.norm(to_goal, axis=1)[:, None] - u) / tau
    i, j = cKDTree(p).query_pairs(stage.interaction_radius, output_type="ndarray").T
    d_vec = p[i] - p[j]
    d = np.sqrt((d_vec**2).sum(axis=1))
    rij = r[i] + r[j]
    near = d * d <= (rij + cut) ** 2
    i, j, d_vec, d, rij = i[near], j[near], d_vec[near], d[near], rij[near]
    n = d_vec / d[:, None]
    g = np.maximum(rij - d, 0.0)
    t = np.column_stack([-n[:, 1], n[:, 0]])
    push = A * np.exp((rij - d) / B) + k * g
    slide = kappa * g * ((u[j] - u[i]) * t).sum(axis=1)
    pair = push[:, None] * n + slide[:, None] * t
    np.add.at(force, i, pair)
    np.add.at(force, j, -pair)
    for shape in stage.walls.shapes:
        dist, normal = shape.signed_distance(x)
        nw = normal[:, [0, 2]]
        over = r - dist
        gw = np.maximum(over, 0.0)
        tw = np.column_stack([-nw[:, 1], nw[:, 0]])
        wall = (A * np.exp(over / B) + k * gw)[:, None] * nw
        wall -= (kappa * gw * (u * tw).sum(axis=1))[:, None] * tw
        force += np.where((over >= -cut)[:, None], wall, 0.0)
    w = u + H * force / m[:, None]
    speed = np.linalg.norm(w, axis=1)
    w *= np.minimum(1.0, stage.max_speed[0] / speed)[:, None]
    return np.column_stack([w[:, 0], np.zeros(len(w)), w[:, 1]])


def median_time(call, repeats: int) -> float:
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    parser.add_argument("--repeats", type=int, default=None)
    args = parser.parse_args()
    repeats = args.repeats or (5 if args.quick else 30)
    print(f"crowd step, h = {H} s; {platform.processor() or platform.machine()}, "
          f"{time.strftime('%Y-%m-%d')}; median of {repeats}")  # fmt: skip
    print(f"{'agents':>8} {'visviva [ms]':>13} {'SciPy+NumPy [ms]':>17} {'ratio':>6}")
    failed = False
    for n in (1_000, 10_000):
        model = crowd_model(n)
        stage = next(s for s in model.stages if isinstance(s, Crowd))
        state = vv.Simulation(model).raw_state
        x, v = np.array(state["particle_position"]), np.array(state["particle_velocity"])
        work = Workspace()  # the run's storage, as a simulation keeps it between steps
        ours = median_time(lambda: stage.apply(state, state, H, work), repeats)  # noqa: B023
        peer = median_time(lambda: numpy_step(stage, x, v), repeats)  # noqa: B023
        got = stage.apply(state, state, H, work)["particle_velocity"]
        gap = float(np.abs(got - numpy_step(stage, x, v)).max())
        failed |= not gap <= 1e-9
        print(f"{n:>8} {ours * 1e3:>13.3f} {peer * 1e3:>17.3f} {peer / ours:>6.1f}"
              f"   (velocities agree to {gap:.1e} m/s)")  # fmt: skip
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
