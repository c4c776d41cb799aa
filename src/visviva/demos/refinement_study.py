"""Demo ``refinement-study``: does a mass-spring cloth converge as its grid is refined?

Seed 000 warns that "simple mass-spring systems do not converge": doubling the resolution
need not approach a limit. The same 1 m square of 0.1 kg/m² cloth hangs under gravity at 6,
11 and 21 points per side, each run taken to rest by backward Euler at large steps (its steps
minimize the incremental potential: at rest, the static equilibrium).

How ``k`` scales with resolution: it does not. On a square grid of spacing ``a``, structural
springs ``k`` and two shear diagonals ``k_s`` per cell store ``½ k (ε_xx² + ε_yy²) +
½ k_s (ε_xx + ε_yy)² + 2 k_s ε_xy²`` per unit area under a small uniform strain: the membrane's
moduli ``C₁₁ = k + k_s``, ``C₁₂ = k_s``, ``C₆₆ = k_s`` [N/m] do not depend on ``a``. Keeping
``k`` fixed keeps the material (a rope is different: its springs must stiffen as ``1/a``).

Two ways of holding the cloth:

* **a curtain**, the whole top edge pinned: the cloth stretches as a membrane, its bottom edge
  sinking by ``ρ g H² / (2E)`` if it could contract sideways freely (``E = C₁₁ − C₁₂²/C₁₁``)
  and by ``ρ g H² / (2 C₁₁)`` if it could not: the pinned edge holds the top from
  contracting, so the drop lies between the two. It converges: each doubling changes it
  about half as much as the last.
* **two corners** pinned: the top edge's middle sags more at every refinement, about 2 mm
  per doubling with no sign of a limit. Each corner carries half the weight ``F`` through one
  point: the strain near a point load on a membrane falls as ``1/r``, so the displacement of
  the point grows as the logarithm of the grid spacing, at a rate of order ``(F/E) ln 2`` per
  halving of ``a``. The continuum has no answer here (the pinned point sinks without bound)
  and each grid gives its own.

The summary gives the sags per resolution and their spread. The structure study of seed 001
comes last: a 11 × 11 sheet with structural springs only, with shear or bend springs added, or
both — held along one vertical side, gravity shears it in its plane (only shear springs resist);
held along one horizontal edge by two rows, it must bend to droop (bend springs resist, but
only once it has bent: three points in a line pull along it and not across).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.job import JobOutput
from ..model.builder import SceneBuilder
from ..simulation.simulation import Simulation
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from ._deformables import GRAVITY, one_thread
from .catalogue import BUILTIN_DEMOS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..simulation.recording import Recording

DURATION = 4.0  # [s]: at rest (speeds below 1e-12 m/s) within 2 s
DT = 1.0 / 30.0  # [s]: large steps; only the equilibrium matters
METHOD = "projected_newton"
RESOLUTIONS = (6, 11, 21)  # points per side
SIZE = 1.0  # [m]
HEIGHT = 1.5  # [m]: the top edge
AREAL_DENSITY = 0.1  # [kg/m²]
STIFFNESS = 100.0  # [N/m]: structural and shear alike
AIR = 2.0  # γ [1/s]: still air, so the cloth settles
STRUCTURE_POINTS = 11
#: γ [1/s] of the structure study: its sheets collapse and swing a metre; about critical for
#: their swing's ω ≈ 3/s, so they come to rest soonest.
STRUCTURE_AIR = 5.0
STRUCTURE_STIFFNESS = 1000.0  # [N/m]: every family present
#: The four spring sets of the structure study: (shear, bend) stiffness [N/m] beside the
#: structural springs.
SPRING_SETS = {
    "structural": (0.0, 0.0),
    "structural+shear": (STRUCTURE_STIFFNESS, 0.0),
    "structural+bend": (0.0, STRUCTURE_STIFFNESS),
    "structural+shear+bend": (STRUCTURE_STIFFNESS, STRUCTURE_STIFFNESS),
}
DESCRIPTION = "a 1 m square of 0.1 kg/m² cloth hung at 6, 11 and 21 points per side"


def build_scene(
    points: int,
    pinned: list[int],
    *,
    shear: float = STIFFNESS,
    bending: float = 0.0,
    stiffness: float = STIFFNESS,
    across: tuple[float, float, float] = (0.0, -SIZE, 0.0),
    air: float = AIR,
    duration: float = DURATION,
) -> SceneBuilder:
    """A 1 m square, ``points`` per side, from its top edge ``across`` (default: hanging in
    the x–y plane), held at ``pinned``, in still air slowing it at the rate ``air`` [1/s]."""
    builder = SceneBuilder(name=f"refinement-study {points}", description=DESCRIPTION)
    builder.set_world(gravity=(0.0, -GRAVITY, 0.0))
    builder.set_integration(method=METHOD, dt=DT, duration=duration, record_every=1)
    builder.add_cloth(
        (points, points),
        origin=(-0.5 * SIZE, HEIGHT, 0.0),
        along=(SIZE, 0.0, 0.0),
        across=across,
        areal_density=AREAL_DENSITY,
        stiffness=stiffness,
        shear=shear,
        bending=bending,
        pinned=pinned,
        radius=0.004,
        color=(0.55, 0.3, 0.7),
        name="sheet",
    )
    builder.add_force("damping", rate=air, name="air")
    return builder


def _rest(builder: SceneBuilder, duration: float) -> tuple[Recording, np.ndarray, float]:
    """Run to rest: the recording, the final positions ``(N, 3)`` [m] and the largest speed
    left [m/s]."""
    simulation = Simulation(builder.build())
    recording = simulation.record(until=duration)
    state = simulation.state
    return recording, state["particle_position"], float(np.abs(state["particle_velocity"]).max())


def membrane_moduli(stiffness: float = STIFFNESS, shear: float = STIFFNESS) -> dict[str, float]:
    """``C₁₁`` and the uniaxial modulus ``E = C₁₁ − C₁₂²/C₁₁`` [N/m] of the grid's membrane,
    from its structural ``stiffness`` and ``shear`` stiffness [N/m]."""
    c11, c12 = stiffness + shear, shear
    return {"C11": c11, "E": c11 - c12**2 / c11}


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    runs = output.recordings  # each run kept as it finishes, so that Ctrl-C keeps it
    corners, curtain, speeds = {}, {}, []
    with one_thread():
        for n in RESOLUTIONS:
            recording, x, speed = _rest(build_scene(n, [0, n - 1], duration=duration), duration)
            runs[f"corners_{n}"], corners[n] = recording, x.reshape(n, n, 3)
            speeds.append(speed)
            recording, x, speed = _rest(build_scene(n, list(range(n)), duration=duration), duration)
            runs[f"curtain_{n}"], curtain[n] = recording, x.reshape(n, n, 3)
            speeds.append(speed)
        structure = _structure_study(runs, duration, speeds)
    output.show_first(f"corners_{RESOLUTIONS[-1]}")  # the video shows the finest cloth
    sag = {n: HEIGHT - float(grid[0, n // 2, 1]) for n, grid in corners.items()}
    drop = {n: HEIGHT - SIZE - float(grid[-1, :, 1].mean()) for n, grid in curtain.items()}
    moduli = membrane_moduli()
    load = 0.5 * AREAL_DENSITY * SIZE * SIZE * GRAVITY  # on each corner
    slope = np.polyfit(np.log2(RESOLUTIONS), list(sag.values()), 1)[0]
    output.figures["refinement_study"] = _figure(corners, curtain, sag, structure)
    return {
        "method": METHOD,
        "dt": DT,
        "stiffness_N_per_m": STIFFNESS,
        "membrane_moduli_N_per_m": moduli,
        "largest_speed_at_rest_m_per_s": max(speeds),
        "two_corners_top_middle_sag_m": {
            "per_resolution": {str(n): value for n, value in sag.items()},
            "spread_max_minus_min": max(sag.values()) - min(sag.values()),
            "successive_changes": np.diff(list(sag.values())).tolist(),
            "growth_per_doubling": float(slope),
            "scale_F_over_E_ln2": load / moduli["E"] * np.log(2.0),
        },
        "curtain_bottom_drop_m": {
            "per_resolution": {str(n): value for n, value in drop.items()},
            "spread_max_minus_min": max(drop.values()) - min(drop.values()),
            "successive_changes": np.diff(list(drop.values())).tolist(),
            "free_to_contract_rho_g_H2_over_2E": AREAL_DENSITY
            * GRAVITY
            * SIZE**2
            / (2 * moduli["E"]),
            "held_from_contracting_rho_g_H2_over_2C11": AREAL_DENSITY
            * GRAVITY
            * SIZE**2
            / (2 * moduli["C11"]),
        },
        "structure_study": structure,
    }


def _structure_study(
    runs: dict[str, Recording], duration: float, speeds: list[float]
) -> dict[str, dict[str, float]]:
    """Each spring set's droop [m] under in-plane shear (a vertical sheet held along one
    side: its far bottom corner's drop) and under bending (a horizontal sheet clamped by two
    rows along one edge: its free edge's mean drop)."""
    n = STRUCTURE_POINTS
    out = {}
    for label, (shear, bending) in SPRING_SETS.items():
        side = [j * n for j in range(n)]  # the column i = 0
        sheared = build_scene(n, side, shear=shear, bending=bending, stiffness=STRUCTURE_STIFFNESS,
                              air=STRUCTURE_AIR, duration=duration)  # fmt: skip
        recording, x, speed = _rest(sheared, duration)
        speeds.append(speed)
        runs[f"in_plane_{label}"] = recording
        corner = HEIGHT - SIZE - float(x[n * n - 1, 1])
        clamped = build_scene(n, list(range(2 * n)), shear=shear, bending=bending,
                              stiffness=STRUCTURE_STIFFNESS, across=(0.0, 0.0, SIZE),
                              air=STRUCTURE_AIR, duration=duration)  # fmt: skip
        recording, x, speed = _rest(clamped, duration)
        speeds.append(speed)
        runs[f"clamped_{label}"] = recording
        edge = HEIGHT - float(x[n * (n - 1) :, 1].mean())
        out[label] = {"in_plane_shear_droop_m": corner, "bending_droop_m": edge}
    return out


def _figure(
    corners: dict[int, np.ndarray],
    curtain: dict[int, np.ndarray],
    sag: dict[int, float],
    structure: dict[str, dict[str, float]],
) -> Figure:
    """The top edge between two pins and the curtain's bottom edge at each resolution; the
    sag against the resolution; the structure study."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(16, 4.4), layout="constrained")
    top, bottom, trend, sets = figure.subplots(1, 4)
    resolutions = sorted(corners.keys() | curtain.keys())  # one colour per resolution
    color = dict(zip(resolutions, distinct_colors(len(resolutions)), strict=True))
    for n, grid in corners.items():
        top.plot(grid[0, :, 0], 1e3 * (grid[0, :, 1] - HEIGHT), "o-", ms=3, color=color[n],
                 label=f"{n} × {n}")  # fmt: skip
    top.set_xlabel("x [m]")
    top.set_ylabel("height of the top edge [mm]")
    top.set_title("Held at two corners: the top edge")
    legend_below(top)
    for n, grid in curtain.items():
        bottom.plot(grid[-1, :, 0], 1e3 * (grid[-1, :, 1] - HEIGHT + SIZE), "o-", ms=3,
                    color=color[n], label=f"{n} × {n}")  # fmt: skip
    moduli = membrane_moduli()
    for key, style in (("E", ":"), ("C11", "--")):
        level = AREAL_DENSITY * GRAVITY * SIZE**2 / (2 * moduli[key])
        bottom.axhline(-1e3 * level, color="k", linestyle=style, lw=0.8,
                       label=f"ρgH²/(2·{key})")  # fmt: skip
    bottom.set_xlabel("x [m]")
    bottom.set_ylabel("drop of the bottom edge [mm]")
    bottom.set_title("A curtain (top edge pinned): converges")
    legend_below(bottom)
    resolution = np.array(list(sag))
    trend.semilogx(resolution, 1e3 * np.array(list(sag.values())), "o-", base=2)
    trend.set_xlabel("points per side")
    trend.set_ylabel("sag of the top edge's middle [mm]")
    trend.set_title("Two corners: grows ∝ log(resolution)")
    labels = list(structure)
    place = np.arange(len(labels))
    sets.barh(place - 0.2, [structure[s]["in_plane_shear_droop_m"] for s in labels], 0.4,
              left=1e-4, label="held by one side: shear")  # fmt: skip
    sets.barh(place + 0.2, [structure[s]["bending_droop_m"] for s in labels], 0.4,
              left=1e-4, label="clamped along an edge: bending")  # fmt: skip
    sets.set_xscale("log")
    sets.set_xlim(1e-4, 1e3)
    sets.set_yticks(place, labels)
    sets.set_xlabel("droop [m]")
    sets.set_title("Which springs resist what (seed 001)")
    legend_below(sets)
    return figure


register_demo(
    Demo(
        "refinement-study",
        BUILTIN_DEMOS["refinement-study"].summary,
        DURATION,
        run,
        picture=True,
    )
)
