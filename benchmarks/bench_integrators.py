#!/usr/bin/env python
"""Time-integration benchmark: visviva against hand-written peers and SciPy's ``solve_ivp``.

Run ``python benchmarks/bench_integrators.py`` (a few minutes) or add ``--quick`` for a short
smoke run whose figures are not representative. This is a benchmark, not a test: it prints
figures; the only things it checks are sanity conditions (the compiled path ran, the visviva
and hand-written Numba kernels agree), and it exits with status 1 if one of those fails.

Parts:

(a) Batch throughput: 10,000 independent double pendulums, RK4 with dt = 1e-3 for 1000 steps,
    through ``vv.solve`` with a one-system Numba ``f`` (compiled time loop) and with a
    NumPy-vectorised ``f``, next to a hand-written Numba kernel, a hand-written NumPy loop and
    ``solve_ivp`` (RK45, one system at a time), all in the same run.
(b) Accuracy-matched single system: one double pendulum over 100 s; visviva's RK4 step and
    dopri5 tolerance are chosen to reach the final-state error of ``solve_ivp`` RK45 and
    DOP853 (rtol 1e-9, atol 1e-12), then wall times and f-evaluations are compared.
(c) CLI start-up: wall time of ``visviva --help`` in a fresh process.

Every timing is the median of at least ``--repeats`` runs after one warm-up run (short calls
are repeated until the runs fill 0.5 s); the warm-up (first) call is reported separately
because it includes Numba compilation. The machine may be shared: each figure comes with the
share of the CPU that other processes used meanwhile, and a contended figure is re-measured.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numba
import numpy as np
import scipy
from scipy.integrate import solve_ivp

import visviva as vv

# --------------------------------------------------------------------------------------------
# The double pendulum: y = [theta1, theta2, omega1, omega2], point masses on massless rods.
# --------------------------------------------------------------------------------------------

M1 = 1.0  # kg
M2 = 1.0  # kg
L1 = 1.0  # m
L2 = 1.0  # m
G = 9.81  # m/s^2


@numba.njit
def pendulum_numba(t, y, out):
    """One double pendulum, written for Numba: fills ``out`` with dy/dt."""
    theta1 = y[0]
    theta2 = y[1]
    omega1 = y[2]
    omega2 = y[3]
    delta = theta1 - theta2
    sin_delta = np.sin(delta)
    cos_delta = np.cos(delta)
    denominator = 2.0 * M1 + M2 - M2 * np.cos(2.0 * delta)
    out[0] = omega1
    out[1] = omega2
    out[2] = (
        -G * (2.0 * M1 + M2) * np.sin(theta1)
        - M2 * G * np.sin(theta1 - 2.0 * theta2)
        - 2.0 * sin_delta * M2 * (omega2 * omega2 * L2 + omega1 * omega1 * L1 * cos_delta)
    ) / (L1 * denominator)
    out[3] = (
        2.0
        * sin_delta
        * (
            omega1 * omega1 * L1 * (M1 + M2)
            + G * (M1 + M2) * np.cos(theta1)
            + omega2 * omega2 * L2 * M2 * cos_delta
        )
    ) / (L2 * denominator)


@numba.njit
def pendulum_numba_returning(t, y):
    """The same function returning the derivative: the form ``solve_ivp`` wants."""
    out = np.empty_like(y)
    pendulum_numba(t, y, out)
    return out


def pendulum_numpy(t, y):
    """The same equations vectorised with NumPy: ``y`` of shape ``(..., 4)``."""
    theta1 = y[..., 0]
    theta2 = y[..., 1]
    omega1 = y[..., 2]
    omega2 = y[..., 3]
    delta = theta1 - theta2
    sin_delta = np.sin(delta)
    cos_delta = np.cos(delta)
    denominator = 2.0 * M1 + M2 - M2 * np.cos(2.0 * delta)
    out = np.empty_like(y)
    out[..., 0] = omega1
    out[..., 1] = omega2
    out[..., 2] = (
        -G * (2.0 * M1 + M2) * np.sin(theta1)
        - M2 * G * np.sin(theta1 - 2.0 * theta2)
        - 2.0 * sin_delta * M2 * (omega2 * omega2 * L2 + omega1 * omega1 * L1 * cos_delta)
    ) / (L1 * denominator)
    out[..., 3] = (
        2.0
        * sin_delta
        * (
            omega1 * omega1 * L1 * (M1 + M2)
            + G * (M1 + M2) * np.cos(theta1)
            + omega2 * omega2 * L2 * M2 * cos_delta
        )
    ) / (L2 * denominator)
    return out


# --------------------------------------------------------------------------------------------
# Hand-written peers
# --------------------------------------------------------------------------------------------


@numba.njit(parallel=True)
def handwritten_numba_rk4(y0, t0, dt, steps):
    """Plain Numba RK4: each thread takes whole systems through all their steps."""
    systems, n = y0.shape
    final = np.empty_like(y0)
    half = 0.5 * dt
    sixth = dt / 6.0
    for i in numba.prange(systems):
        y = y0[i].copy()
        k1 = np.empty(n)
        k2 = np.empty(n)
        k3 = np.empty(n)
        k4 = np.empty(n)
        stage = np.empty(n)
        for s in range(steps):
            t = t0 + s * dt
            pendulum_numba(t, y, k1)
            for j in range(n):
                stage[j] = y[j] + half * k1[j]
            pendulum_numba(t + half, stage, k2)
            for j in range(n):
                stage[j] = y[j] + half * k2[j]
            pendulum_numba(t + half, stage, k3)
            for j in range(n):
                stage[j] = y[j] + dt * k3[j]
            pendulum_numba(t + dt, stage, k4)
            for j in range(n):
                y[j] += sixth * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        final[i, :] = y
    return final


def handwritten_numpy_rk4(y0, t0, dt, steps):
    """Plain NumPy RK4 over the whole batch at once."""
    y = y0.copy()
    half = 0.5 * dt
    sixth = dt / 6.0
    for s in range(steps):
        t = t0 + s * dt
        k1 = pendulum_numpy(t, y)
        k2 = pendulum_numpy(t + half, y + half * k1)
        k3 = pendulum_numpy(t + half, y + half * k2)
        k4 = pendulum_numpy(t + dt, y + dt * k3)
        y = y + sixth * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return y


# --------------------------------------------------------------------------------------------
# Measuring and printing
# --------------------------------------------------------------------------------------------


class Contention:
    """How much of the machine other processes used while we measured (Linux ``/proc/stat``).

    Shared machines are noisy: a timing taken while another process kept a core busy is not
    this code's speed. ``others = (all CPU time used) − (this process's CPU time)``, as a
    fraction of ``wall × cores``; ``None`` where ``/proc/stat`` is unavailable.
    """

    def __init__(self) -> None:
        self.start = self._sample()

    @staticmethod
    def _sample() -> tuple[float, float, float] | None:
        try:
            with open("/proc/stat", encoding="ascii") as handle:
                values = [int(v) for v in handle.readline().split()[1:]]
        except (OSError, ValueError):
            return None
        tick = os.sysconf("SC_CLK_TCK")
        idle = values[3] + (values[4] if len(values) > 4 else 0)  # idle + iowait
        busy = (sum(values[:8]) - idle) / tick  # user..steal, without guest (already in user)
        own = os.times()
        mine = own.user + own.system + own.children_user + own.children_system
        return time.perf_counter(), busy, mine

    def others(self) -> float | None:
        end = self._sample()
        if self.start is None or end is None:
            return None
        wall = end[0] - self.start[0]
        foreign = (end[1] - self.start[1]) - (end[2] - self.start[2])
        cores = os.cpu_count() or 1
        return min(1.0, max(0.0, foreign / (wall * cores))) if wall > 0 else None


@dataclass
class Timing:
    """Wall times of one benchmarked call: the first (warm-up) call and the repeats."""

    first: float
    times: list[float]
    result: Any
    others: float | None = None  # share of the machine used by other processes meanwhile
    attempts: int = 1  # measurements made (re-measured when contended); this is the fastest

    @property
    def median(self) -> float:
        return statistics.median(self.times)

    @property
    def spread(self) -> str:
        return f"{fmt_time(min(self.times))}–{fmt_time(max(self.times))} ({len(self.times)})"

    @property
    def compile_estimate(self) -> float:
        """First call minus the median: compilation and other one-off costs."""
        return max(0.0, self.first - self.median)

    @property
    def busy(self) -> str:
        """Other processes' share of the machine during the timed repeats, for the tables."""
        if self.others is None:
            return "?"
        retried = f" (best of {self.attempts})" if self.attempts > 1 else ""
        return f"{100.0 * self.others:.0f}%{retried}"


#: Above this share of the machine used by others, a measurement counts as contended: it is
#: repeated (after waiting for a quiet moment) up to ``--retries`` times, and reported with a
#: warning if every attempt was contended.
CONTENTION_WARNING = 0.05
CONTENDED: list[str] = []
PATIENCE = {"quiet_wait": 30.0, "retries": 2}


def wait_for_quiet(max_wait: float) -> None:
    """Sleep until other processes have left the machine idle for 2 s, or ``max_wait`` passes."""
    deadline = time.perf_counter() + max_wait
    quiet = 0
    while quiet < 4 and time.perf_counter() < deadline:
        meter = Contention()
        time.sleep(0.5)
        others = meter.others()
        if others is None:
            return
        quiet = quiet + 1 if others < CONTENTION_WARNING else 0


#: Short calls are repeated beyond ``repeats`` until the timed runs fill this many seconds, so
#: that the median is stable and the contention meter (10 ms clock ticks) is meaningful.
MIN_WINDOW = 0.5
MAX_RUNS = 2000


def measure_once(call: Callable[[], Any], repeats: int) -> Timing:
    start = time.perf_counter()
    result = call()
    first = time.perf_counter() - start
    times: list[float] = []
    meter = Contention()
    while len(times) < repeats or (sum(times) < MIN_WINDOW and len(times) < MAX_RUNS):
        start = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - start)
    return Timing(first, times, result, meter.others())


def measure(call: Callable[[], Any], repeats: int, label: str = "") -> Timing:
    """Run ``call`` once as warm-up, then ``repeats`` times; keep the last result.

    If other processes were busy meanwhile, wait for a quiet moment and measure again (at most
    ``PATIENCE["retries"]`` times); the fastest attempt is kept (contention only ever adds
    time). ``first`` is always the very first call (the one that compiles).
    """
    attempts = [measure_once(call, repeats)]
    while (attempts[-1].others or 0.0) > CONTENTION_WARNING and (
        len(attempts) <= PATIENCE["retries"]
    ):
        wait_for_quiet(PATIENCE["quiet_wait"])
        attempts.append(measure_once(call, repeats))
    timing = min(attempts, key=lambda t: t.median)
    timing.first = attempts[0].first
    timing.attempts = len(attempts)
    if label and all((a.others or 0.0) > CONTENTION_WARNING for a in attempts):
        CONTENDED.append(
            f"{label}: other processes used {100.0 * timing.others:.0f}% of the "
            f"machine (fastest of {len(attempts)} attempts)"
        )
    return timing


def sci(x: float, digits: int = 3) -> str:
    """Compact scientific notation: 1.52e7, 3.1e-9."""
    if x == 0.0 or not math.isfinite(x):
        return str(x)
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def fmt_time(seconds: float) -> str:
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e6:.0f} µs"


def print_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> None:
    """A plain-text table with aligned columns (first column left, others right)."""
    widths = [max(len(str(r[c])) for r in [headers, *rows]) for c in range(len(headers))]

    def line(cells: Sequence[str]) -> str:
        parts = [
            str(cell).ljust(w) if c == 0 else str(cell).rjust(w)
            for c, (cell, w) in enumerate(zip(cells, widths, strict=True))
        ]
        return "  ".join(parts).rstrip()

    print(line(headers))
    print("  ".join("-" * w for w in widths))
    for row in rows:
        print(line(row))


def heading(text: str) -> None:
    print()
    print(text)
    print("=" * len(text))


def finish(started: float, checks: Checks) -> int:
    """Print the run's total time, load and contention warnings and failed checks; return the
    exit status (1 if a sanity check failed). Every benchmark script ends with this."""
    print()
    print(
        f"total benchmark time: {time.perf_counter() - started:.0f} s; load average at the end: "
        f"{load_average()}"
    )
    if CONTENDED:
        print(
            f"WARNING: other processes were busy during {len(CONTENDED)} measurement(s); "
            "those figures understate this machine:"
        )
        for line in CONTENDED:
            print(f"  - {line}")
    else:
        print(
            f"no measurement saw other processes use more than {CONTENTION_WARNING:.0%} of "
            "the machine"
        )
    if checks.failures:
        print(f"{len(checks.failures)} sanity check(s) FAILED:")
        for failure in checks.failures:
            print(f"  - {failure}")
        return 1
    return 0


class Checks:
    """Sanity checks: printed as they happen, summarised at the end (exit status 1 if any fail)."""

    def __init__(self) -> None:
        self.failures: list[str] = []

    def check(self, condition: bool, description: str) -> None:
        print(f"  [{'ok' if condition else 'FAILED'}] {description}")
        if not condition:
            self.failures.append(description)


# --------------------------------------------------------------------------------------------
# Machine description
# --------------------------------------------------------------------------------------------


def cpu_description() -> str:
    """CPU model, family/model numbers and whether AVX-512 is available."""
    fields: dict[str, str] = {}
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            for raw in handle:
                if not raw.strip():
                    break  # the first processor is enough
                key, _, value = raw.partition(":")
                fields[key.strip()] = value.strip()
    except OSError:
        pass
    model = fields.get("model name")
    if model is None and shutil.which("lscpu"):
        output = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        for raw in output.splitlines():
            if raw.startswith("Model name:"):
                model = raw.split(":", 1)[1].strip()
    model = model or platform.processor() or "unknown"
    details = []
    if "cpu family" in fields and "model" in fields:
        details.append(f"family {fields['cpu family']} model {fields['model']}")
    if "flags" in fields:
        flags = fields["flags"].split()
        details.append("AVX-512" if "avx512f" in flags else "no AVX-512")
        if "avx2" in flags:
            details.append("AVX2")
    return model + (f" ({', '.join(details)})" if details else "")


def source_state() -> str:
    """The git commit of the visviva being measured, and whether its sources differ from it."""
    package = Path(vv.__file__).resolve().parent

    def git(*arguments: str) -> str | None:
        try:
            completed = subprocess.run(
                ["git", "-C", str(package), *arguments],
                capture_output=True,
                text=True,
                check=False,
                timeout=10,
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return completed.stdout.strip() if completed.returncode == 0 else None

    commit = git("rev-parse", "--short", "HEAD")
    if commit is None:
        return f"installed at {package} (not a git checkout)"
    changed = git("status", "--porcelain", "--", str(package))
    count = len(changed.splitlines()) if changed else 0
    return f"git {commit}" + (
        f", {count} changed/untracked path(s) under src/visviva" if count else ", clean"
    )


def load_average() -> str:
    try:
        return " / ".join(f"{x:.2f}" for x in os.getloadavg()) + " (1 / 5 / 15 min)"
    except OSError:
        return "unknown"


def print_header(args: argparse.Namespace) -> None:
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count() or 0
    env_threads = os.environ.get("NUMBA_NUM_THREADS")
    print(
        "visviva time-integration benchmark"
        + ("  [--quick: smoke run, figures not representative]" if args.quick else "")
    )
    now = datetime.datetime.now().astimezone()
    print(f"date:              {now.isoformat(timespec='seconds')}")
    print(f"CPU:               {cpu_description()}")
    print(f"cores:             {os.cpu_count()} logical, {usable} usable by this process")
    print(f"Python:            {platform.python_version()} ({platform.python_implementation()})")
    print(f"numpy / scipy:     {np.__version__} / {scipy.__version__}")
    print(f"numba:             {numba.__version__}")
    print(f"visviva:           {vv.__version__} ({source_state()})")
    print(
        f"NUMBA_NUM_THREADS: {numba.config.NUMBA_NUM_THREADS} "
        f"({'set in the environment' if env_threads else 'default'})"
    )
    print(
        f"timing:            median of {args.repeats} runs after one warm-up run (more runs "
        f"for calls under {MIN_WINDOW / args.repeats:.2g} s, to fill {MIN_WINDOW:g} s); up to "
        f"{args.retries} re-measurements if other processes were busy"
    )
    print(f"load average:      {load_average()} at start")


# --------------------------------------------------------------------------------------------
# (a) Batch throughput
# --------------------------------------------------------------------------------------------

TARGET_NUMBA_F = 1.5e7  # system-steps/s, the target on the reference machine
TARGET_NUMPY_F = 5e6


def random_pendulums(systems: int, seed: int) -> np.ndarray:
    """Angles and rates uniform in [-1, 1] (rad, rad/s)."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.0, 1.0, size=(systems, 4))


def bench_batch(args: argparse.Namespace, checks: Checks) -> None:
    systems = 1000 if args.quick else 10_000
    scipy_systems = 10 if args.quick else 100
    steps = 1000
    dt = 1e-3
    until = steps * dt
    system_steps = systems * steps
    y0 = random_pendulums(systems, seed=20261122)

    heading(
        f"(a) Batch throughput: {systems:,} double pendulums, RK4, dt = {dt:g} s, {steps} steps"
    )
    print(
        "  timed: building vv.ode.FirstOrderProblem + vv.solve(..., record_every=1000), or the "
        "peer's whole call"
    )

    def visviva_run(f: Callable[..., Any]) -> Any:
        problem = vv.ode.FirstOrderProblem(f, y0)
        return vv.solve(problem, "rk4", dt=dt, until=until, record_every=steps)

    vv_numba = measure(lambda: visviva_run(pendulum_numba), args.repeats, "(a) visviva Numba f")
    peer_numba = measure(
        lambda: handwritten_numba_rk4(y0, 0.0, dt, steps), args.repeats, "(a) hand-written Numba"
    )
    vv_numpy = measure(lambda: visviva_run(pendulum_numpy), args.repeats, "(a) visviva NumPy f")
    peer_numpy = measure(
        lambda: handwritten_numpy_rk4(y0, 0.0, dt, steps), args.repeats, "(a) hand-written NumPy"
    )

    def scipy_batch() -> tuple[np.ndarray, int]:
        final = np.empty((scipy_systems, 4))
        evaluations = 0
        for i in range(scipy_systems):
            solution = solve_ivp(
                pendulum_numba_returning, (0.0, until), y0[i], method="RK45", rtol=1e-6, atol=1e-9
            )
            if not solution.success:
                raise RuntimeError(f"solve_ivp failed on system {i}: {solution.message}")
            final[i] = solution.y[:, -1]
            evaluations += solution.nfev
        return final, evaluations

    peer_scipy = measure(scipy_batch, args.repeats, "(a) solve_ivp batch")

    rate = {
        "vv_numba": system_steps / vv_numba.median,
        "vv_numpy": system_steps / vv_numpy.median,
        "peer_numba": system_steps / peer_numba.median,
        "peer_numpy": system_steps / peer_numpy.median,
    }
    system_seconds_per_s = scipy_systems * until / peer_scipy.median
    scipy_equivalent = system_seconds_per_s / dt
    scipy_f_per_system = peer_scipy.result[1] / scipy_systems

    def meets(value: float, target: float) -> str:
        return "yes" if value >= target else f"no ({value / target:.2f}×)"

    rows = [
        [
            "visviva, Numba f (compiled loop)",
            sci(rate["vv_numba"]),
            sci(TARGET_NUMBA_F),
            meets(rate["vv_numba"], TARGET_NUMBA_F),
            f"{rate['vv_numba'] / rate['peer_numba']:.2f}× hand Numba",
            fmt_time(vv_numba.median),
            vv_numba.spread,
            fmt_time(vv_numba.first),
            vv_numba.busy,
        ],
        [
            "visviva, NumPy f",
            sci(rate["vv_numpy"]),
            sci(TARGET_NUMPY_F),
            meets(rate["vv_numpy"], TARGET_NUMPY_F),
            f"{rate['vv_numpy'] / rate['peer_numpy']:.2f}× hand NumPy",
            fmt_time(vv_numpy.median),
            vv_numpy.spread,
            fmt_time(vv_numpy.first),
            vv_numpy.busy,
        ],
        [
            "hand-written Numba RK4 (prange)",
            sci(rate["peer_numba"]),
            "",
            "",
            "1.00 (peer)",
            fmt_time(peer_numba.median),
            peer_numba.spread,
            fmt_time(peer_numba.first),
            peer_numba.busy,
        ],
        [
            "hand-written NumPy RK4",
            sci(rate["peer_numpy"]),
            "",
            "",
            "1.00 (peer)",
            fmt_time(peer_numpy.median),
            peer_numpy.spread,
            fmt_time(peer_numpy.first),
            peer_numpy.busy,
        ],
        [
            f"solve_ivp RK45, {scipy_systems} systems one by one *",
            sci(scipy_equivalent),
            "",
            "",
            f"{scipy_equivalent / rate['peer_numba']:.4f}× hand Numba",
            fmt_time(peer_scipy.median),
            peer_scipy.spread,
            fmt_time(peer_scipy.first),
            peer_scipy.busy,
        ],
    ]
    print()
    print_table(
        [
            "path",
            "system-steps/s",
            "target",
            "meets target",
            "vs same-kind peer",
            "median wall",
            "min–max (runs)",
            "first call",
            "others' CPU",
        ],
        rows,
    )
    print()
    print(
        f"  * solve_ivp: RK45, rtol=1e-6, atol=1e-9, over {until:g} s per system, f = the same "
        "equations as a Numba function returning the derivative."
    )
    print(
        f"    It simulates {sci(system_seconds_per_s)} system-seconds per wall-second; the "
        f"system-steps/s shown is that × {1 / dt:g} (the RK4 steps per simulated second at "
        f"dt = {dt:g}),"
    )
    print(
        f"    an equivalent for comparison only, not the same work or accuracy "
        f"({scipy_f_per_system:.0f} f-evaluations per system-second vs {4 / dt:.0f} for RK4)."
    )
    print(
        "  others' CPU: share of the machine's CPU time used by other processes during the "
        "timed repeats (0% = quiet machine)."
    )
    print(
        "  targets are the issue's, for the reference machine (Zen-5-class, AVX-512); "
        "'vs same-kind peer' is the throughput ratio, below 1 = visviva slower."
    )
    print(
        f"  compile/one-off cost of the first call (first − median): visviva Numba f "
        f"{fmt_time(vv_numba.compile_estimate)} (includes compiling the user's f), "
        f"hand-written Numba kernel {fmt_time(peer_numba.compile_estimate)}"
    )
    try:
        layer = numba.threading_layer()
    except ValueError:
        layer = "unknown"
    print(f"  Numba threads: {numba.get_num_threads()}, threading layer: {layer}")

    print()
    print("  sanity checks:")
    final = {
        "vv_numba": vv_numba.result.y[-1],
        "vv_numpy": vv_numpy.result.y[-1],
        "peer_numba": peer_numba.result,
        "peer_numpy": peer_numpy.result,
    }
    for name, timing in (("Numba f", vv_numba), ("NumPy f", vv_numpy)):
        sol = timing.result
        checks.check(bool(sol.success), f"visviva {name}: success ({sol.message})")
        checks.check(
            sol.y.shape == (2, systems, 4),
            f"visviva {name}: record_every={steps} kept first and last frame only "
            f"(y shape {sol.y.shape})",
        )
        checks.check(
            abs(float(sol.t[-1]) - until) < 1e-12,
            f"visviva {name}: last frame at t = {float(sol.t[-1])!r}",
        )
        print(f"       visviva {name}: counters {sol.counters}")
    checks.check(
        vv_numba.result.recording.attrs["compiled"] is True,
        "visviva Numba f: recording.attrs['compiled'] is True",
    )
    checks.check(
        vv_numpy.result.recording.attrs["compiled"] is False,
        "visviva NumPy f: recording.attrs['compiled'] is False (NumPy path)",
    )
    difference = float(np.max(np.abs(final["vv_numba"] - final["peer_numba"])))
    checks.check(
        difference <= 1e-12,
        f"final states, visviva Numba path vs hand-written Numba kernel: max |Δ| = "
        f"{sci(difference)} (≤ 1e-12)",
    )
    for a, b, label in (
        ("vv_numpy", "peer_numpy", "visviva NumPy path vs hand-written NumPy"),
        ("vv_numba", "vv_numpy", "visviva Numba path vs visviva NumPy path"),
    ):
        d = float(np.max(np.abs(final[a] - final[b])))
        print(f"       (info) final states, {label}: max |Δ| = {sci(d)}")
    d = float(np.max(np.abs(final["peer_numba"][:scipy_systems] - peer_scipy.result[0])))
    print(
        f"       (info) final states, hand-written RK4 vs solve_ivp RK45 (rtol 1e-6): max |Δ| "
        f"= {sci(d)}"
    )


# --------------------------------------------------------------------------------------------
# (b) Accuracy-matched single system
# --------------------------------------------------------------------------------------------

#: Steps per run on an E24-like ladder (two significant digits), from 100 to 91 million.
E24 = (
    10,
    11,
    12,
    13,
    15,
    16,
    18,
    20,
    22,
    24,
    27,
    30,
    33,
    36,
    39,
    43,
    47,
    51,
    56,
    62,
    68,
    75,
    82,
    91,
)
STEP_LADDER = tuple(m * 10**k for k in range(1, 7) for m in E24)
#: Tolerances rtol = 10^(-k/4) from 1e-5 to 1e-13 (atol = 1e-3 rtol, the ratio of the SciPy runs).
RTOL_LADDER = tuple(10.0 ** (-k / 4.0) for k in range(20, 53))


def ladder_search(
    values: Sequence[Any], start: int, error_of: Callable[[Any], float], target: float
) -> tuple[int, dict[int, float]]:
    """The cheapest rung (lowest index) near ``start`` whose error is at most ``target``.

    ``values`` go from cheapest (least accurate) to most expensive. From ``start`` the search
    walks toward cheaper rungs while they still meet the target, or toward dearer ones until
    one does. Returns the index and the errors of every rung tried.
    """
    tried: dict[int, float] = {}

    def error(i: int) -> float:
        if i not in tried:
            tried[i] = error_of(values[i])
        return tried[i]

    i = start
    if error(i) <= target:
        while i > 0 and error(i - 1) <= target:
            i -= 1
    else:
        while error(i) > target:
            i += 1
            if i >= len(values):
                raise RuntimeError(f"no rung of the ladder reaches the error {target:.3g}")
    return i, tried


def bench_accuracy(args: argparse.Namespace, checks: Checks) -> None:
    theta = 0.5
    until = 10.0 if args.quick else 100.0
    y0 = np.array([theta, theta, 0.0, 0.0])
    span = (0.0, until)

    heading(
        f"(b) Accuracy-matched single system: double pendulum, θ1 = θ2 = {theta} rad, "
        f"rates 0, until = {until:g} s"
    )
    print(
        "  error = max over the 4 components of |y(until) − reference|; reference = solve_ivp "
        "DOP853, rtol = atol = 1e-13"
    )
    print(
        "  solve_ivp gets the same equations as a Numba function returning dy/dt; visviva "
        "gets the in-place Numba f(t, y, out)"
    )

    def scipy_run(method: str, rtol: float, atol: float, y_start: np.ndarray = y0) -> Any:
        solution = solve_ivp(
            pendulum_numba_returning, span, y_start, method=method, rtol=rtol, atol=atol
        )
        if not solution.success:
            raise RuntimeError(f"solve_ivp {method} failed: {solution.message}")
        return solution

    reference = scipy_run("DOP853", 1e-13, 1e-13).y[:, -1]
    tighter = scipy_run("DOP853", 3e-14, 3e-14).y[:, -1]
    nudged = scipy_run("DOP853", 1e-13, 1e-13, y0 + np.array([1e-10, 0.0, 0.0, 0.0])).y[:, -1]
    reference_uncertainty = float(np.max(np.abs(reference - tighter)))
    growth = float(np.max(np.abs(nudged - reference))) / 1e-10

    def error_of(final: np.ndarray) -> float:
        return float(np.max(np.abs(np.asarray(final) - reference)))

    print(
        f"  reference check: |DOP853(1e-13) − DOP853(3e-14)| = {sci(reference_uncertainty)}; a "
        f"1e-10 change of θ1(0) changes y(until) by {growth:.3g}× as much (regular, not "
        "chaotic, motion)"
    )

    rk45 = measure(lambda: scipy_run("RK45", 1e-9, 1e-12), args.repeats, "(b) solve_ivp RK45")
    dop853 = measure(lambda: scipy_run("DOP853", 1e-9, 1e-12), args.repeats, "(b) solve_ivp DOP853")
    targets = {"RK45": error_of(rk45.result.y[:, -1]), "DOP853": error_of(dop853.result.y[:, -1])}
    for name, value in targets.items():
        checks.check(
            value > 100.0 * reference_uncertainty,
            f"solve_ivp {name} error {sci(value)} is ≥ 100× the reference's uncertainty",
        )

    def visviva_rk4(steps: int) -> Any:
        problem = vv.ode.FirstOrderProblem(pendulum_numba, y0)
        return vv.solve(problem, "rk4", dt=until / steps, until=until, record_every=steps)

    def visviva_dopri5(rtol: float) -> Any:
        problem = vv.ode.FirstOrderProblem(pendulum_numba, y0)
        return vv.solve(problem, "dopri5", until=until, rtol=rtol, atol=1e-3 * rtol)

    def solution_error(solution: Any) -> float:
        if not solution.success:
            raise RuntimeError(f"visviva run failed: {solution.message}")
        return error_of(solution.y[-1])

    # RK4: the error goes as dt^4, so one probe run predicts where on the ladder to start.
    probe_steps = STEP_LADDER.index(1000 if args.quick else 10_000)
    probe = visviva_rk4(STEP_LADDER[probe_steps])
    checks.check(
        probe.recording.attrs["compiled"] is True,
        "visviva rk4 single system: recording.attrs['compiled'] is True",
    )
    probe_error = solution_error(probe)
    rk4_choice: dict[str, int] = {}
    dopri5_choice: dict[str, int] = {}
    same_tolerance = RTOL_LADDER.index(min(RTOL_LADDER, key=lambda r: abs(math.log10(r) + 9)))
    print()
    print("  step / tolerance search (cheapest ladder rung reaching each target):")
    for name, target in targets.items():
        wanted = STEP_LADDER[probe_steps] * (probe_error / target) ** 0.25
        start = next(i for i, s in enumerate(STEP_LADDER) if s >= wanted)
        index, tried = ladder_search(
            STEP_LADDER, start, lambda s: solution_error(visviva_rk4(s)), target
        )
        rk4_choice[name] = index
        trail = ", ".join(
            f"dt={sci(until / STEP_LADDER[i])}→{sci(e, 2)}" for i, e in sorted(tried.items())
        )
        print(f"    rk4    to {name:6s} ({sci(target)}): {trail}")
        index, tried = ladder_search(
            RTOL_LADDER, same_tolerance, lambda r: solution_error(visviva_dopri5(r)), target
        )
        dopri5_choice[name] = index
        trail = ", ".join(
            f"rtol={sci(RTOL_LADDER[i], 2)}→{sci(e, 2)}" for i, e in sorted(tried.items())
        )
        print(f"    dopri5 to {name:6s} ({sci(target)}): {trail}")

    rows: list[list[str]] = []

    def add_row(
        label: str, setting: str, timing: Timing, final: np.ndarray, evaluations: int, steps: str
    ) -> None:
        rows.append(
            [
                label,
                setting,
                sci(error_of(final)),
                f"{evaluations:,}",
                steps,
                fmt_time(timing.median),
                timing.spread,
                f"{timing.median / rk45.median:.2f}",
                f"{timing.median / dop853.median:.2f}",
                timing.busy,
            ]
        )

    for name, timing in (("RK45", rk45), ("DOP853", dop853)):
        result = timing.result
        add_row(
            f"solve_ivp {name}",
            "rtol 1e-9, atol 1e-12",
            timing,
            result.y[:, -1],
            result.nfev,
            f"{result.t.size - 1:,} (–)",
        )

    def add_visviva(label: str, timing: Timing, setting: str) -> None:
        solution = timing.result
        counters = solution.counters
        add_row(
            label,
            setting,
            timing,
            solution.y[-1],
            counters["f_evaluations"],
            f"{counters['accepted_steps']:,} ({counters['rejected_steps']:,})",
        )

    same = measure(
        lambda: visviva_dopri5(RTOL_LADDER[same_tolerance]),
        args.repeats,
        "(b) visviva dopri5, same tolerances",
    )
    add_visviva("visviva dopri5, same tolerances", same, "rtol 1e-9, atol 1e-12")
    for name in targets:
        steps = STEP_LADDER[rk4_choice[name]]
        timing = measure(
            lambda steps=steps: visviva_rk4(steps),
            args.repeats,
            f"(b) visviva rk4 matched to {name}",
        )
        add_visviva(
            f"visviva rk4, matched to {name}", timing, f"dt {sci(until / steps)} ({steps:,} steps)"
        )
        rtol = RTOL_LADDER[dopri5_choice[name]]
        timing = measure(
            lambda rtol=rtol: visviva_dopri5(rtol),
            args.repeats,
            f"(b) visviva dopri5 matched to {name}",
        )
        add_visviva(
            f"visviva dopri5, matched to {name}",
            timing,
            f"rtol {sci(rtol, 2)}, atol {sci(1e-3 * rtol, 2)}",
        )
    print()
    print_table(
        [
            "run",
            "setting",
            "final error",
            "f-evals",
            "steps (rejected)",
            "median wall",
            "min–max (runs)",
            "÷ RK45",
            "÷ DOP853",
            "others' CPU",
        ],
        rows,
    )
    print()
    print(
        "  f-evals: solve_ivp nfev; visviva solution.counters['f_evaluations']. steps: "
        "accepted (rejected; solve_ivp does not report them). '÷ RK45', '÷ DOP853': wall-time "
        "ratio to that solve_ivp run "
        "(below 1 = visviva faster);"
    )
    print("  others' CPU: share of the machine used by other processes during the timed repeats.")
    print(
        "  visviva rk4 runs the compiled Numba loop (record_every = all steps: first and last "
        "frame); dopri5 runs the Python adaptive driver recording every step, as solve_ivp does."
    )


# --------------------------------------------------------------------------------------------
# (c) CLI start-up
# --------------------------------------------------------------------------------------------

TARGET_CLI = 0.3  # s


def cli_commands() -> list[tuple[str, list[str]]]:
    """How to start the CLI: the console script next to this interpreter, and the one on PATH.

    The script next to ``sys.executable`` is what pip installed; the one found on PATH may be a
    wrapper (pyenv shim, ...) that adds its own start-up time, so it is timed separately.
    """
    commands = []
    beside = Path(sys.executable).with_name("visviva")
    if beside.is_file():
        commands.append((str(beside), [str(beside), "--help"]))
    on_path = shutil.which("visviva")
    if on_path and (not beside.is_file() or Path(on_path).resolve() != beside.resolve()):
        commands.append((f"{on_path} (on PATH)", [on_path, "--help"]))
    if not commands:
        # No console script installed: call the entry point the way the script would.
        code = (
            "import sys; from visviva.cli.main import main; sys.argv = ['visviva', '--help']; "
            "sys.exit(main())"
        )
        commands.append(("python -c 'visviva.cli.main:main()'", [sys.executable, "-c", code]))
    return commands


def bench_cli(args: argparse.Namespace) -> None:
    repeats = 5
    heading("(c) CLI start-up: `visviva --help` in a fresh process")

    def run(command: list[str]) -> tuple[float, subprocess.CompletedProcess[str]]:
        start = time.perf_counter()
        completed = subprocess.run(
            command,
            capture_output=True,
            text=True,
            check=False,
            stdin=subprocess.DEVNULL,
            timeout=120,
        )
        return time.perf_counter() - start, completed

    rows = []
    available = False
    for label, command in cli_commands():
        first, completed = run(command)
        if completed.returncode != 0:
            reason = (completed.stderr.strip().splitlines() or ["no output"])[-1]
            print(
                f"  CLI not available: {label} exited with status {completed.returncode} ({reason})"
            )
            continue
        available = True
        timing = measure(lambda command=command: run(command)[0], repeats, f"(c) {label}")
        median = timing.median
        rows.append(
            [
                label,
                fmt_time(median),
                timing.spread,
                fmt_time(first),
                f"≤ {TARGET_CLI:g} s",
                "yes" if median <= TARGET_CLI else f"no ({median / TARGET_CLI:.1f}×)",
                timing.busy,
            ]
        )
    baselines = [
        ("python -c pass", [sys.executable, "-c", "pass"]),
        ("python -c 'import visviva'", [sys.executable, "-c", "import visviva"]),
    ]
    for label, command in baselines:
        first, completed = run(command)
        if completed.returncode != 0:
            continue
        timing = measure(lambda command=command: run(command)[0], repeats)
        rows.append(
            [
                f"(context) {label}",
                fmt_time(timing.median),
                timing.spread,
                fmt_time(first),
                "",
                "",
                timing.busy,
            ]
        )
    print()
    print_table(
        ["command", "median", "min–max (runs)", "first", "target", "meets", "others' CPU"], rows
    )
    if not available:
        print("  (the entry point visviva.cli.main:main does not exist yet; rerun once it does)")


# --------------------------------------------------------------------------------------------


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="short smoke run (1,000 systems, 10 s single-system run)",
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=None,
        help="timed runs per figure after the warm-up (default 5, --quick 3)",
    )
    parser.add_argument(
        "--retries",
        type=int,
        default=None,
        help="re-measure a figure taken while other processes were busy up to "
        "this many times (default 2, --quick 0)",
    )
    parser.add_argument(
        "--quiet-wait",
        type=float,
        default=30.0,
        help="before a retry, wait up to this many seconds for the machine to be idle (default 30)",
    )
    args = parser.parse_args(argv)
    if args.repeats is None:
        args.repeats = 3 if args.quick else 5
    if args.retries is None:
        args.retries = 0 if args.quick else 2
    PATIENCE["retries"] = max(0, args.retries)
    PATIENCE["quiet_wait"] = max(0.0, args.quiet_wait)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")

    started = time.perf_counter()
    print_header(args)
    checks = Checks()
    bench_batch(args, checks)
    bench_accuracy(args, checks)
    bench_cli(args)
    return finish(started, checks)


if __name__ == "__main__":
    sys.exit(main())
