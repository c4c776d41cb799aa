"""Sweep and prune (collision.broad_phase) against all pairs, and its bounds."""

from __future__ import annotations

import numpy as np
import pytest

from visviva.collision import Box, Capsule, distance
from visviva.collision.broad_phase import overlapping_pairs, shape_bounds
from visviva.collision.solids import posed_shape


def test_sweep_and_prune_finds_every_overlapping_pair_in_order():
    rng = np.random.default_rng(2)
    centre = rng.uniform(0.0, 10.0, size=(400, 3)) * [1.0, 0.3, 1.0]
    half = rng.uniform(0.05, 0.6, size=(400, 3))
    lo, hi = centre - half, centre + half
    active = rng.random(400) > 0.1
    pairs = overlapping_pairs(lo, hi, active)
    expected = [
        (i, j)
        for i in range(400)
        for j in range(i + 1, 400)
        if active[i] and active[j] and np.all(lo[i] <= hi[j]) and np.all(lo[j] <= hi[i])
    ]
    assert [tuple(p) for p in pairs] == expected
    assert len(expected) > 100
    # The same pairs whatever order the boxes are sorted in: shuffled input, mapped back.
    order = rng.permutation(400)
    shuffled = overlapping_pairs(lo[order], hi[order], active[order])
    remapped = sorted(tuple(sorted((order[i], order[j]))) for i, j in shuffled)
    assert remapped == expected


def test_bounds_hold_the_shape_and_its_margin():
    capsule = Capsule(center=(1.0, 2.0, 3.0), radius=0.25, height=1.0,
                      orientation=(np.cos(0.3), np.sin(0.3), 0.0, 0.0))  # fmt: skip
    posed = posed_shape(capsule)
    lo, hi = np.zeros((1, 3)), np.zeros((1, 3))
    shape_bounds(posed[0], posed[1], posed[2], posed[6], posed[7], 0.1, lo, hi, 0)
    # Turned by 0.6 rad about x, the axis spans ±0.5 sin/cos 0.6 in z and y.
    reach = np.array([0.0, 0.5 * np.cos(0.6), 0.5 * np.sin(0.6)]) + 0.35
    assert hi[0] == pytest.approx(np.array(capsule.center) + reach)
    assert lo[0] == pytest.approx(np.array(capsule.center) - reach)
    # A box 0.1 beyond the bounds does not touch the shape.
    box = Box(center=(1.0, 2.0 + reach[1] + 0.5, 3.0), size=(1.0, 1.0, 1.0))
    assert distance(capsule, box).distance > 0.0
