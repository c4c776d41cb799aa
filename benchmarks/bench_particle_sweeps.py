#!/usr/bin/env python
"""Particle sweep benchmark: runs of a small particle scene in batches and run by run.

Run ``python benchmarks/bench_particle_sweeps.py`` (a few minutes on 2 cores) or add
``--quick`` for a smoke run. Two parts:

1. **A whole sweep** (files included, timed from the call to its return, pre-checks and process
   start included): a ball bouncing on a floor beside a 16-point rope swinging from a pin, in
   light drag, 1 s of symplectic Euler at h = 1 ms (17 particles; the scenes' default method,
   which takes the fused compiled step), ``--runs`` runs varying the floor's restitution and
   the rope's stiffness (so every run copies its own floor into a batch: 64 runs a batch at
   most). visviva's batches on the default process pool (2 workers), against every run alone
   on the pool (``batch=False``, timed on the first ``--alone`` runs and given per run): what
   the batches replace.
2. **Where batches pay**: members of n particles (a cloud of n balls over a floor of its own
   restitution, 0.2 s at h = 1 ms), 64 members as one batch against the same 64 runs one after
   another in this process (no files, no processes: the step alone), for symplectic Euler (the
   fused step) and RK4 (the generic pipeline), n from 1 to 10,000 (runs of more than
   ``MAX_MEMBER_PARTICLES`` = 1,000 particles do not batch: this shows why).

Checks: the runs alone give the batches' figures (energy drift, steps) to round-off; the
in-process members' final positions equal their runs alone to 1e-9 m. This is not a test: it
prints figures and exits 1 only if a check fails.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import visviva as vv
from bench_integrators import Checks, cpu_description, finish, heading, load_average, print_table
from bench_integrators import source_state as visviva_source
from visviva.model.build import build_model
from visviva.model.scene import Scene
from visviva.simulation import Simulation
from visviva.simulation.ensemble import run_ensemble

ROPE = [[0.5 + 0.05 * i, 1.5, 0.0] for i in range(16)]


def sweep_data(runs: int) -> dict:
    """The sweep of part 1 with ``runs`` runs (restitution × stiffness, zipped)."""
    return {
        "sweep": {"name": "ball_and_rope", "design": "zip"},
        "scene": {
            "integration": {"method": "symplectic_euler", "dt": 0.001, "duration": 1.0},
            "entities": [
                {
                    "type": "particles",
                    "name": "ball",
                    "positions": [[0.0, 1.0, 0.0]],
                    "radius": 0.05,
                },
                {
                    "type": "rope",
                    "name": "rope",
                    "points": ROPE,
                    "mass": 0.01,
                    "stiffness": 400.0,
                    "damping": 0.01,
                    "pinned": [0],
                },
                {"type": "force", "kind": "drag", "coefficient": 0.02},
                {"type": "collider", "name": "floor", "shape": "plane", "restitution": 0.5},
            ],
        },
        "parameters": [
            {"path": "entities[floor].restitution", "range": [0.1, 0.95, runs]},
            {"path": "entities[rope].stiffness", "range": [200.0, 800.0, runs]},
        ],
    }


def cloud(count: int, restitution: float, method: str) -> vv.Model:
    """Part 2's member: ``count`` balls over a floor."""
    data = {
        "integration": {"method": method, "dt": 0.001, "duration": 0.2},
        "entities": [
            {
                "type": "particle_cloud",
                "count": count,
                "center": [0.0, 0.5, 0.0],
                "size": [1.0, 0.8, 1.0],
                "velocity_jitter": 0.5,
                "radius": 0.01,
                "seed": 3,
            },
            {"type": "collider", "shape": "plane", "restitution": restitution},
        ],
    }
    return build_model(Scene.model_validate(data))


def timed(call):
    start = time.perf_counter()
    value = call()
    return time.perf_counter() - start, value


def whole_sweeps(root: Path, runs: int, alone: int, checks: Checks) -> None:
    heading("1. Whole sweeps (files included)")
    path = root / "sweep.json"
    path.write_text(json.dumps(sweep_data(runs)))
    # The first sweep compiles the kernels, once per machine: the fused step for the number of
    # leading planes (up to four) a batch holds, and for one floor alone. Warm them up.
    warm = root / "warm.json"
    warm.write_text(json.dumps(sweep_data(8)))
    vv.sweep(warm, root / "warm", executor="serial")
    vv.sweep(warm, root / "warm-alone", executor="serial", batch=False)
    batch_time, batched = timed(lambda: vv.sweep(path, root / "batch", workers=2))
    cut = sweep_data(runs)
    for parameter in cut["parameters"]:
        del parameter["range"]
        parameter["values"] = [row[parameter["path"]] for row in batched.rows[:alone]]
    subset = root / "alone.json"
    subset.write_text(json.dumps(cut))
    alone_time, by_one = timed(lambda: vv.sweep(subset, root / "alone", workers=2, batch=False))
    per_batch, per_alone = batch_time / runs, alone_time / alone
    print_table(
        ["runner", "runs", "time", "per run", "vs alone"],
        [
            ["batches, process pool", str(runs), f"{batch_time:.2f} s", f"{per_batch * 1e3:.1f} ms",
             f"{per_alone / per_batch:.1f}x"],
            ["alone, process pool", str(alone), f"{alone_time:.2f} s", f"{per_alone * 1e3:.1f} ms",
             "1.0x"],
        ],
    )  # fmt: skip
    sizes = sorted({row.get("batch_size") for row in batched.rows} - {None})
    print(f"batch sizes: {sizes}; failed runs: {batched.failed}")
    gap = max(
        abs(a["energy_drift"] - b["energy_drift"])
        for a, b in zip(batched.rows[:alone], by_one.rows, strict=True)
    )
    steps = all(
        a["steps"] == b["steps"] for a, b in zip(batched.rows[:alone], by_one.rows, strict=True)
    )
    checks.check(
        gap < 1e-9 and steps and batched.failed == 0,
        f"the first {alone} runs alone give the batches' energy drift (largest gap {gap:.1e}) "
        "and steps",
    )


def where_batches_pay(sizes: list[int], members: int, checks: Checks) -> None:
    heading(f"2. Where batches pay: {members} members of n particles, in this process, no files")
    rows = []
    for method in ("symplectic_euler", "rk4"):
        for n in sizes:
            models = [cloud(n, 0.2 + 0.6 * k / members, method) for k in range(members)]
            run_ensemble(models, 0.002)  # compile (for this many leading planes)
            Simulation(models[0]).run(0.002)
            finals: dict[int, np.ndarray] = {}

            def keep(frame, finals=finals):
                for k, member in enumerate(frame.members):
                    finals[member] = frame.state(k).parts[0]

            batch_time, _ = timed(
                lambda models=models, keep=keep: run_ensemble(models, 0.2, on_frame=keep)
            )
            alone_time = 0.0
            worst = 0.0
            for k, model in enumerate(models):
                simulation = Simulation(model)
                seconds, _ = timed(lambda simulation=simulation: simulation.run(0.2))
                alone_time += seconds
                worst = max(worst, float(np.abs(simulation.raw_state.parts[0] - finals[k]).max()))
            checks.check(
                worst < 1e-9, f"{method}, n = {n}: members end where their runs end ({worst:.1e} m)"
            )
            steps = 200 * members
            per_alone, per_batch = alone_time / steps * 1e6, batch_time / steps * 1e6
            speedup = alone_time / batch_time
            rows.append(
                [method, str(n), f"{per_alone:.1f} µs", f"{per_batch:.1f} µs", f"{speedup:.1f}x"]
            )
    print_table(["method", "n", "alone, per member-step", "batched", "speed-up"], rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke run")
    parser.add_argument("--runs", type=int, default=256, help="runs of the sweep (part 1)")
    parser.add_argument("--alone", type=int, default=32, help="runs timed run by run")
    args = parser.parse_args(argv)
    runs, alone = (32, 8) if args.quick else (args.runs, args.alone)
    sizes = [1, 100] if args.quick else [1, 10, 100, 1000, 10_000]
    members = 8 if args.quick else 64
    started = time.perf_counter()
    checks = Checks()
    print("visviva particle sweep benchmark" + ("  [--quick: smoke run]" if args.quick else ""))
    print(f"CPU:          {cpu_description()}")
    print(f"visviva:      {vv.__version__} ({visviva_source()})")
    print(f"load average: {load_average()} at start")
    root = Path(tempfile.mkdtemp(prefix="bench-particle-sweeps-"))
    try:
        whole_sweeps(root, runs, alone, checks)
        where_batches_pay(sizes, members, checks)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
