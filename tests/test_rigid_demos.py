"""The rigid-body demos: each runs (shortened) and its summary holds the physics it shows."""

from __future__ import annotations

import json
from pathlib import Path

from visviva.demos import run_demo


def summary(directory: Path) -> dict:
    return json.loads((directory / "summary.json").read_text())


def test_dzhanibekov_only_the_intermediate_axis_flips_and_l_is_kept(tmp_path):
    """6 s of the three T-handles: the spin about the intermediate moment changes sign (the
    first flip comes after about 1.3 s at 8 rad/s with a 1 % nudge), the other two never;
    L is kept exactly and the kinetic energy within 1e-6 (O(h²) at h = 1/480 s)."""
    run_demo("dzhanibekov", tmp_path, duration=6.0)
    data = summary(tmp_path)
    flips = data["sign_changes_of_the_spin_axis"]
    assert flips["intermediate moment (y)"] >= 2
    assert flips["smallest moment (x)"] == flips["largest moment (z)"] == 0
    assert data["max_angular_momentum_change"] == 0.0
    assert data["max_relative_energy_change"] < 1e-6
    moments = data["principal_moments_kg_m2"]
    assert moments == sorted(moments)  # the mesh's x, y, z are its principal axes, in order
