"""Demo ``rotation-drift``: rotation matrices and quaternions drift off; renormalizing helps.

A free asymmetric body (moments 1, 2, 3 kg·m²) tumbles for 10 s; its orientation is stepped
with h = 0.01 s by the lecture's explicit Euler on a rotation matrix (seed 003), the same with
Gram–Schmidt after each step, explicit Euler on a quaternion, the same renormalized, and the
scenes' default splitting (:mod:`visviva.analysis.rotation_drift`). Without renormalizing,
the matrix and the quaternion stop being rotations within a few hundred steps (the body
shears and grows); renormalizing keeps them rotations but not the energy, which explicit Euler
pumps in; the splitting keeps both — the quaternion by construction, the energy to O(h²).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..analysis.rotation_drift import drift_study
from ..io.job import JobOutput
from ..rigid.motion import BodyMotion
from ..viz.colors import distinct_colors
from ..viz.legends import legend_below
from . import Demo, register_demo
from .catalogue import BUILTIN_DEMOS

MOMENTS = np.array([1.0, 2.0, 3.0])  # [kg·m²]
OMEGA = np.array([0.5, 2.0, 1.0])  # body angular velocity at the start [rad/s]
DT = 0.01  # [s]


def splitting(q: np.ndarray, angular_momentum: np.ndarray, h: float) -> np.ndarray:
    """One drift of the scenes' default method (:meth:`BodyMotion.drift`) for this body."""
    motion = BodyMotion(0, np.ones(1), MOMENTS[None])
    positions = np.concatenate([np.zeros(3), q])
    return motion.drift(positions, np.concatenate([np.zeros(3), angular_momentum]), h)[3:]


def run(output: JobOutput, duration: float) -> dict[str, Any]:
    from matplotlib.figure import Figure

    study = drift_study(MOMENTS, OMEGA, DT, round(duration / DT), {"splitting": splitting})
    figure = Figure(figsize=(13, 4.5), layout="constrained")
    shape, energy, error = figure.subplots(1, 3)
    for name, color in zip(study.error, distinct_colors(len(study.error)), strict=True):
        shape.semilogy(
            study.t[1:], np.maximum(study.not_a_rotation[name][1:], 1e-17), color=color, label=name
        )
        energy.plot(study.t, study.energy_error[name], color=color, label=name)
        error.semilogy(
            study.t[1:], np.maximum(study.error[name][1:], 1e-17), color=color, label=name
        )
    shape.set_title("How far from a rotation: ‖RᵀR − E‖")
    energy.set_title("Kinetic energy / start − 1")
    energy.set_ylim(-0.3, 1.0)
    error.set_title("Distance from the reference: ‖R − R_ref‖")
    for axes in (shape, energy, error):
        axes.set_xlabel("t [s]")
    legend_below(shape)
    output.figures["rotation_drift"] = figure
    return {
        "dt_s": DT,
        "final_not_a_rotation": {k: float(v[-1]) for k, v in study.not_a_rotation.items()},
        "final_energy_error": {k: float(v[-1]) for k, v in study.energy_error.items()},
        "final_orientation_error": {k: float(v[-1]) for k, v in study.error.items()},
    }


register_demo(
    Demo(
        "rotation-drift",
        BUILTIN_DEMOS["rotation-drift"].summary,
        10.0,
        run,
    )
)
