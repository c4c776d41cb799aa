#!/usr/bin/env python
"""Mass-properties benchmark: visviva's Mirtich integrals on a 100k-triangle mesh, against trimesh.

Run ``python benchmarks/bench_mass_properties.py`` (under a minute on 2 cores once compiled) or
add ``--quick`` for a smoke run whose figures mean nothing.

The mesh, generated here so that nothing downloads: a cube sphere (each face of a cube cut in
91 × 91 squares, two triangles each, 99,372 triangles and 49,688 vertices) pushed out to the
radius r(u) = 1 + 0.15 sin(3 uₓ) cos(2 u_y) + 0.1 u_z² m along each direction u, stretched by
(1, 0.8, 1.2) and moved by (0.1, 0.2, −0.3) m: a closed, outward, star-shaped and lumpy solid of
density 1250 kg/m³, with no symmetry that would make a figure exact.

(a) One mass-properties computation (mass, centre of mass, inertia about it):

* trimesh (a visviva dependency, so the same run always has it): ``Trimesh(vertices, faces,
  process=False)`` with ``density`` set, then ``mesh.mass_properties``, the cache emptied before
  each repeat so that every call computes (its ``triangles`` gather included);
* visviva's ``mesh_mass_properties`` three ways: the integrals alone (``check_topology=False,
  check_intersections=False``: array checks, then the Numba kernel), with the closed-mesh check
  (closed, manifold, oriented, outward, no degenerate triangle), and with that and the
  self-intersection check (the default);
* the two checks alone, and the kernel on one thread.

The target is visviva ≥ 3× trimesh's speed with agreement to 1e-12: relative for the mass,
over the mesh's extent for the centre of mass, over the largest entry for the inertia.

(b) The self-intersection check's cost against the number of triangles T (cube spheres of
6k to 400k triangles): time per triangle stays flat if the check is O(T).

Every timing is the median of repeats after a warm-up call (which compiles), with the share of
the CPU other processes used meanwhile (re-measured when above 5%); timing helpers are shared
with ``bench_integrators.py``. Figures, not tests: the script exits 1 only if visviva and trimesh
disagree beyond 1e-12 or a check refuses the (valid) mesh.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numba
import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
import visviva as vv
from bench_integrators import (
    PATIENCE,
    Checks,
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
from mesh_shapes import cube_sphere
from visviva.geometry.mesh_topology import check_closed_mesh, mesh_arrays
from visviva.geometry.self_intersection import find_self_intersection
from visviva.rigid.mesh_integrals import polyhedral_integrals

DENSITY = 1250.0  # kg/m³
TARGET_SPEEDUP = 3.0
TARGET_AGREEMENT = 1e-12


def lumpy_sphere(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The benchmark's solid (see the module docstring): 12 n² triangles."""
    vertices, triangles = cube_sphere(n)
    u = vertices  # unit directions
    radius = 1.0 + 0.15 * np.sin(3.0 * u[:, 0]) * np.cos(2.0 * u[:, 1]) + 0.1 * u[:, 2] ** 2
    vertices = u * radius[:, None] * [1.0, 0.8, 1.2] + [0.1, 0.2, -0.3]
    return vertices, triangles


def agreement(ours: vv.rigid.MassProperties, theirs, extent: float) -> tuple[float, float, float]:
    mass = abs(ours.mass - theirs.mass) / theirs.mass
    center = float(np.max(np.abs(ours.center_of_mass - theirs.center_mass))) / extent
    inertia = float(np.max(np.abs(ours.inertia - theirs.inertia)) / np.max(np.abs(theirs.inertia)))
    return mass, center, inertia


def bench_one_mesh(args: argparse.Namespace, checks: Checks) -> None:
    vertices, triangles = lumpy_sphere(args.n)
    heading(
        f"(a) mass properties of a {len(triangles):,}-triangle mesh ({len(vertices):,} vertices)"
    )
    extent = float(np.max(np.ptp(vertices, axis=0)))
    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    mesh.density = DENSITY

    def with_trimesh():
        mesh._cache.clear()  # every repeat computes, as a first call would
        return mesh.mass_properties

    runs = {
        "trimesh mesh.mass_properties": with_trimesh,
        "visviva, integrals only (checks off)": lambda: vv.rigid.mesh_mass_properties(
            vertices, triangles, DENSITY, check_topology=False, check_intersections=False
        ),
        "visviva, + closed-mesh check": lambda: vv.rigid.mesh_mass_properties(
            vertices, triangles, DENSITY, check_intersections=False
        ),
        "visviva, + self-intersection check (default)": lambda: vv.rigid.mesh_mass_properties(
            vertices, triangles, DENSITY
        ),
    }
    timings = {label: measure(call, args.repeats, label) for label, call in runs.items()}
    reference = timings["trimesh mesh.mass_properties"]
    rows = []
    for label, timing in timings.items():
        speedup = reference.median / timing.median
        verdict = ""
        if label.startswith("visviva"):
            verdict = "met" if speedup >= TARGET_SPEEDUP else "not met"
        rows.append(
            [
                label,
                fmt_time(timing.median),
                timing.spread,
                f"{speedup:.2f}×",
                verdict,
                fmt_time(timing.first),
                timing.busy,
            ]
        )
    print_table(
        [
            "run",
            "median",
            "min–max (runs)",
            "vs trimesh",
            f"≥ {TARGET_SPEEDUP:g}×",
            "first",
            "others",
        ],
        rows,
    )

    # The parts on their own.
    checked_vertices, checked_triangles = mesh_arrays(vertices, triangles)
    origin = 0.5 * (checked_vertices.min(axis=0) + checked_vertices.max(axis=0))
    edges = check_closed_mesh(vertices, triangles)[2]
    parts = {
        "closed-mesh check (check_closed_mesh)": lambda: check_closed_mesh(vertices, triangles),
        "self-intersection check": lambda: find_self_intersection(
            checked_vertices, checked_triangles, edges
        ),
        "integration kernel, all threads": lambda: polyhedral_integrals(
            checked_vertices, checked_triangles, origin
        ),
    }
    part_rows = []
    for label, call in parts.items():
        timing = measure(call, args.repeats, label)
        part_rows.append([label, fmt_time(timing.median), timing.busy])
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        timing = measure(
            lambda: polyhedral_integrals(checked_vertices, checked_triangles, origin),
            args.repeats,
            "kernel, 1 thread",
        )
    finally:
        numba.set_num_threads(threads)
    part_rows.append(["integration kernel, 1 thread", fmt_time(timing.median), timing.busy])
    print()
    print_table(["part", "median", "others"], part_rows)

    theirs = with_trimesh()
    print()
    for label in list(runs)[1:]:
        ours = timings[label].result
        mass, center, inertia = agreement(ours, theirs, extent)
        worst = max(mass, center, inertia)
        print(
            f"  {label}: mass {sci(mass)}, centre of mass {sci(center)} (of the extent), "
            f"inertia {sci(inertia)} (of the largest entry)"
        )
        checks.check(
            worst <= TARGET_AGREEMENT,
            f"{label} agrees with trimesh to {sci(worst)} (≤ {TARGET_AGREEMENT:g})",
        )
    print(
        f"  mass {theirs.mass:.12g} kg, volume {theirs.volume:.12g} m³, centre of mass "
        f"{np.array2string(theirs.center_mass, precision=6)} m"
    )


def bench_scaling(args: argparse.Namespace, checks: Checks) -> None:
    heading("(b) self-intersection check against the number of triangles")
    rows = []
    for n in args.scaling:
        vertices, triangles = mesh_arrays(*lumpy_sphere(n))
        timing = measure(
            lambda v=vertices, t=triangles: find_self_intersection(v, t),
            args.repeats,
            f"self-intersection n={n}",
        )
        checks.check(
            timing.result is None,
            f"no crossing found in the valid {len(triangles):,}-triangle mesh",
        )
        per = timing.median / len(triangles)
        rows.append(
            [f"{len(triangles):,}", fmt_time(timing.median), f"{per * 1e9:.0f} ns", timing.busy]
        )
    print_table(["triangles", "median", "per triangle", "others"], rows)


def print_header(args: argparse.Namespace) -> None:
    print(
        "visviva mass-properties benchmark"
        + ("  [--quick: smoke run, figures mean nothing]" if args.quick else "")
    )
    print(
        f"date:              {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}"
    )
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical")
    print(f"Python:            {platform.python_version()}")
    print(f"numpy / numba:     {np.__version__} / {numba.__version__}")
    print(f"trimesh:           {trimesh.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    print(f"Numba threads:     {numba.config.NUMBA_NUM_THREADS}, layer {numba.threading_layer()}")
    print(f"timing:            median of at least {args.repeats} runs after a warm-up run")
    print(f"load average:      {load_average()} at start")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small meshes; figures mean nothing")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per figure")
    parser.add_argument("--retries", type=int, default=2, help="re-measurements when contended")
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (2 if args.quick else 7)
    args.n = 30 if args.quick else 91
    args.scaling = (12, 24) if args.quick else (23, 46, 91, 182)
    PATIENCE["retries"] = max(0, args.retries)
    # Compile every kernel before the header's load average and the first timing.
    vv.rigid.mesh_mass_properties(*lumpy_sphere(4), DENSITY)
    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    bench_one_mesh(args, checks)
    bench_scaling(args, checks)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
