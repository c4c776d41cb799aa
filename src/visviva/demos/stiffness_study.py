"""Demo ``stiffness-study``: one cloth at growing stiffness, explicit against implicit steps.

A 1 m square of heavy canvas (1 kg/m², 8 × 8 points) held at two corners falls from
horizontal under undamped structural and shear springs of stiffness ``k`` from 3 to 10⁴ N/m,
always at h = 1/60 s, stepped by symplectic Euler, by backward Euler as a minimization
(``projected_newton``; Gast et al. 2015) and by Baraff & Witkin's linearized backward Euler
(``linearly_implicit_euler``; Baraff & Witkin 1998).

Why the explicit method blows up: linearized about a state, the cloth is a set of undamped
oscillators ``q'' = −ω² q`` whose fastest ``ω_max`` grows as ``√(k/m)``. Symplectic Euler
multiplies each by a matrix whose eigenvalues stay on the unit circle while ``ωh ≤ 2`` and
leave it beyond, one growing by more than ``(ωh)² − 1`` per step: it is stable only for
``h < h_max = 2/ω_max ∝ √(m/k)``. The stability advisor computes ``h_max`` before the first
step from the spectrum of ``M⁻¹ ∂F/∂x`` (:func:`visviva.analysis.advisor.largest_stable_step`),
and the check is that it predicts each run: symplectic Euler survives exactly where
``h < h_max``. Backward Euler's factor on an oscillation, ``1/(1 − iωh)``, has modulus
``1/√(1 + (ωh)²) < 1`` at every step: it never blows up, at any stiffness, and pays with
numerical damping — the stiff modes vanish within a step, and even the slow swing loses
energy; projected Newton's minimization keeps the energy from ever rising. Baraff & Witkin's
step shares that factor on linear problems and solves one linear system a step instead of
Newton's several.

Why it matters: the cloths symplectic Euler survives at h = 1/60 s are rubber. With
``ω_max² ≈ c k/m`` (``c`` ≈ 11 here, from the advisor: a point pulled by eight springs)
stability needs ``k/m < 4/(c h²)``, while a column of ``n`` points of mass ``m`` hanging from
springs of length ``a`` stretches its top spring by ``n m g/(k a)``: at least
``c n g h²/(4a)``, about 40 % for this canvas (n = 7, a = 14 cm). The summary gives each implicit
run's stretch: tens of percent or more at the stiffnesses the explicit method survives, a
fraction of a percent at 10⁴ N/m.

References:
    D. Baraff, A. Witkin, "Large steps in cloth simulation", SIGGRAPH 1998.
    T. F. Gast, C. Schroeder, A. Stomakhin, C. Jiang, J. M. Teran, "Optimization integrator
    for large time steps", IEEE TVCG 21 (2015).
    E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, Springer 1996, §IV.2.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..analysis.advisor import largest_stable_step
from ..errors import SimulationError
from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..simulation.simulation import Simulation
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._deformables import GRAVITY, largest_rise, one_thread, strain, stretch_pairs
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulation.recording import Recording

DURATION = 2.0  # [s]
DT = 1.0 / 60.0  # [s]
STIFFNESS = (3.0, 10.0, 100.0, 1000.0, 10000.0)  # k [N/m], structural and shear
EXPLICIT = "symplectic_euler"
IMPLICIT = ("projected_newton", "linearly_implicit_euler")
POINTS = 8  # per side: the advisor takes the eigenvalues of a 384 × 384 matrix
SIZE = 1.0  # [m]
HEIGHT = 1.5  # [m]
AREAL_DENSITY = 1.0  # [kg/m²]: heavy canvas
DESCRIPTION = "a 1 m square of 1 kg/m² canvas, 8 × 8 points, held at two corners"


def build_scene(stiffness: float, method: str, duration: float = DURATION) -> SceneBuilder:
    """The canvas with springs of ``stiffness`` [N/m], stepped by ``method``."""
    builder = SceneBuilder(name=f"stiffness-study k={stiffness:g}", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method=method, dt=DT, duration=duration, record_every=1)
    builder.add_cloth(
        (POINTS, POINTS),
        origin=(-0.5 * SIZE, HEIGHT, 0.0),
        along=(SIZE, 0.0, 0.0),
        across=(0.0, 0.0, SIZE),
        areal_density=AREAL_DENSITY,
        stiffness=stiffness,
        shear=stiffness,
        pinned=[0, POINTS - 1],
        radius=0.01,
        color=(0.75, 0.6, 0.35),
        name="canvas",
    )
    return builder


def _run(stiffness: float, method: str, duration: float) -> tuple[Simulation, Recording, float]:
    """One run: the simulation, its recording (cut short by a blow-up or a failed implicit
    step, then marked failed) and the time [s] it failed (``inf`` if it did not)."""
    simulation = Simulation(build_scene(stiffness, method, duration).build())
    try:
        recording = simulation.record(until=duration)
    except SimulationError as failure:
        recording = failure.recording
        recording.attrs |= {"success": False, "message": str(failure).splitlines()[0]}
        return simulation, recording, failure.t
    return simulation, recording, float("inf")


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    runs = output.recordings  # each run kept as it finishes, so that Ctrl-C keeps it
    table = []
    with one_thread():
        for k in STIFFNESS:
            simulation, recording, blown = _run(k, EXPLICIT, duration)
            advised = largest_stable_step(
                simulation.system, simulation.integrator, simulation.model.initial_state()
            )
            runs[f"{EXPLICIT}_k{k:g}"] = recording
            row: dict[str, Any] = {
                "k_N_per_m": k,
                "advisor_h_max_s": advised,
                "h_over_h_max": DT / advised,
                "predicted": "stable" if advised > DT else "unstable",
                EXPLICIT: "survived" if np.isinf(blown) else f"blew up at t = {blown:.3g} s",
            }
            row["prediction_holds"] = (advised > DT) == bool(np.isinf(blown))
            for method in IMPLICIT:
                implicit, recording, failed = _run(k, method, duration)
                runs[f"{method}_k{k:g}"] = recording
                energy = recording["energy"]
                edges = stretch_pairs(implicit.model)
                row[method] = {
                    "survived": bool(np.isinf(failed)),
                    "energy_lost_fraction": float((energy[0] - energy[-1]) / energy[0]),
                    "largest_energy_rise_per_step_J": largest_rise(energy),
                    "largest_stretch_at_end": float(
                        strain(implicit.model, recording["particle_position"][-1], edges).max()
                    ),
                    "newton_iterations": int(implicit.system.counters.newton_iterations),
                    "krylov_iterations": int(implicit.system.counters.krylov_iterations),
                }
            table.append(row)
    # The first run is the one the video shows: the stiffest cloth, at 1/60 s, implicit.
    output.show_first(f"{IMPLICIT[0]}_k{STIFFNESS[-1]:g}")
    output.figures["stiffness_study"] = _figure(table, output.recordings)
    return {
        "dt": DT,
        "stiffness": table,
        "all_predictions_hold": all(row["prediction_holds"] for row in table),
    }


def _figure(table: list[dict[str, Any]], recordings: dict[str, Recording]) -> Figure:
    """Where symplectic Euler is stable (the advisor's h_max against h), and every run's
    energy over time."""
    from matplotlib.figure import Figure

    methods = (EXPLICIT, *IMPLICIT)
    figure = Figure(figsize=(15, 8.5), layout="constrained")
    # L: the limit, B: the board; one panel of energies per method (E, P, I).
    axes = figure.subplot_mosaic("LLLBBB;EEPPII")
    limit, board = axes["L"], axes["B"]
    panels = dict(zip(methods, (axes["E"], axes["P"], axes["I"]), strict=True))
    k = np.array([row["k_N_per_m"] for row in table])
    advised = np.array([row["advisor_h_max_s"] for row in table])
    survived = np.array([row[EXPLICIT] == "survived" for row in table])
    limit.loglog(k, 1e3 * advised, "k-", lw=0.8, label="advisor's h_max (symplectic Euler)")
    limit.loglog(k[survived], 1e3 * advised[survived], "o", color="C2", label="survived")
    limit.loglog(k[~survived], 1e3 * advised[~survived], "x", color="C3", ms=9, label="blew up")
    limit.axhline(1e3 * DT, color="C0", linestyle="--", label="h = 1/60 s")
    limit.set_xlabel("spring stiffness k [N/m]")
    limit.set_ylabel("step [ms]")
    limit.set_title("Stable where h < h_max ∝ 1/√k")
    legend_below(limit)
    for row_index, method in enumerate(methods):
        for column, entry in enumerate(table):
            result = entry[method]
            ok = result == "survived" if method == EXPLICIT else result["survived"]
            board.plot(column, row_index, "o" if ok else "x", ms=12, color="C2" if ok else "C3")
    board.set_xticks(range(len(table)), [f"{row['k_N_per_m']:g}" for row in table])
    board.set_yticks(range(len(methods)), methods)
    board.set_xlabel("spring stiffness k [N/m]")
    board.set_ylim(-0.5, len(methods) - 0.5)
    board.set_title("At h = 1/60 s: o survived, x blew up")
    for method in methods:
        panel = panels[method]
        for entry, color in zip(table, distinct_colors(len(table)), strict=True):
            recording = recordings[f"{method}_k{entry['k_N_per_m']:g}"]
            energy = recording["energy"]
            change = np.abs(energy - energy[0]) / abs(energy[0])
            panel.semilogy(recording.time[1:], np.maximum(change[1:], 1e-12), color=color,
                           label=f"k = {entry['k_N_per_m']:g}")  # fmt: skip
        panel.set_xlabel("t [s]")
        panel.set_ylabel("|E − E₀| / E₀")
        panel.set_ylim(1e-6, 1e6)
        panel.set_title(method)
    legend_below(panels[methods[-1]])
    return figure


register_demo(
    Demo(
        "stiffness-study",
        BUILTIN_DEMOS["stiffness-study"].summary,
        DURATION,
        run,
        picture=True,
    )
)
