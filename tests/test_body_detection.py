"""The bodies' narrow phase (collision.body_detection.pair_contacts) gives the same contacts,
in the same order, to the bit, serially and on one or two threads."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from thread_counts import assert_same_bits, on_one_and_two_threads
from visviva.collision import Box, Capsule, Cone, Cylinder, Sphere, body_detection
from visviva.collision.body_detection import contact_arrays, pair_contacts, piece_poses
from visviva.collision.body_pieces import BodyPieces
from visviva.collision.broad_phase import overlapping_pairs
from visviva.collision.manifold import MAX_CONTACTS


def _crowded_pieces(count: int, seed: int):
    """``count`` bodies of five shapes packed into a small box, each turned at random: their
    world poses and the broad phase's pairs (well over PARALLEL_MIN_PAIRS)."""
    rng = np.random.default_rng(seed)
    origin = (0.0, 0.0, 0.0)
    kinds = [Sphere(origin, 0.1), Box(origin, (0.2, 0.15, 0.1)), Capsule(origin, 0.05, 0.15),
             Cylinder(origin, 0.08, 0.12), Cone(origin, 0.08, 0.15)]  # fmt: skip
    shapes = [kinds[k] for k in rng.integers(len(kinds), size=count)]
    pieces = BodyPieces.of(shapes, list(range(count)), [0.0] * count, [0.5] * count)
    side = 0.16 * count ** (1 / 3)
    x = rng.uniform(0.0, side, (count, 3))
    rotation = Rotation.random(count, random_state=rng).as_matrix()
    margin = np.full(count, 0.01)
    position = pieces.local_position.copy()
    turn = pieces.local_rotation.copy()
    lo, hi = np.empty((count, 3)), np.empty((count, 3))
    piece_poses(pieces.arrays(), pieces.body, x, rotation, margin, position, turn, lo, hi)
    pairs = overlapping_pairs(lo, hi, np.ones(count, dtype=np.bool_))
    return pieces, position, turn, margin, pairs


def test_the_narrow_phase_is_the_same_on_any_number_of_threads(monkeypatch):
    pieces, position, turn, margin, pairs = _crowded_pieces(1500, 27)
    assert pairs.shape[0] > 2 * body_detection.PARALLEL_MIN_PAIRS

    def run():
        out = contact_arrays(MAX_CONTACTS * pairs.shape[0])
        count = pair_contacts(pieces.arrays(), pieces.body, pairs, position, turn, margin, out)
        return tuple(np.array(a[:count]) for a in out)

    results = on_one_and_two_threads(run)
    monkeypatch.setattr(body_detection, "PARALLEL_MIN_PAIRS", 10**12)  # the serial driver
    results.append(run())
    assert results[0][0].size > 1000  # contacts found
    assert_same_bits(results)
