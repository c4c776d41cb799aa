"""Resampling recorded frames to an output rate."""

import numpy as np
import pytest

import visviva as vv
from visviva.errors import ModelError
from visviva.io.timeline import frames_at_rate


def test_uniform_recording_at_a_lower_rate_picks_every_kth_frame():
    # 1000 steps of 1 ms shown at 50 fps: output frame k is recorded frame 20k, exactly.
    time = np.arange(1001) * 1e-3
    np.testing.assert_array_equal(frames_at_rate(time, 50.0), np.arange(51) * 20)


def test_frame_times_come_from_integers_not_accumulation():
    # 3 fps over 1000 s: accumulating 1/3 would drift; k/3 lands on the nearest recorded frame.
    time = np.arange(3_000_001) / 3000.0
    chosen = frames_at_rate(time, 3.0)
    assert chosen.size == 3001
    np.testing.assert_array_equal(chosen, np.arange(3001) * 1000)


def test_uneven_frames_take_the_nearest_and_the_earlier_on_a_tie():
    time = np.array([0.0, 0.05, 0.5, 0.9, 1.0])
    # Wanted times 0, 0.25, 0.5, 0.75, 1.0; nearest recorded: 0, 0.05, 0.5, 0.9, 1.0.
    np.testing.assert_array_equal(frames_at_rate(time, 4.0), [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(frames_at_rate(np.array([0.0, 0.5, 1.0]), 4.0), [0, 0, 1, 1, 2])


def test_single_frame_and_bad_rate():
    np.testing.assert_array_equal(frames_at_rate(np.array([2.0]), 30.0), [0])
    with pytest.raises(vv.ModelError, match="fps"):
        frames_at_rate(np.array([0.0, 1.0]), 0.0)


def test_speed_plays_simulated_time_faster():
    """Output frame k shows t0 + k·speed/fps: a day per second at 2 frames/s over 2 days."""
    day = 86_400.0
    time = np.arange(49) * 3600.0  # hourly frames for two days
    shown = frames_at_rate(time, 2.0, speed=day)
    np.testing.assert_array_equal(time[shown], [0.0, 0.5 * day, day, 1.5 * day, 2 * day])


def test_absurd_frame_counts_are_refused_before_allocating():
    """A year in seconds at 30 frames/s would be ~9.5e8 frames: refused with the fix named."""
    with pytest.raises(ModelError, match=r"more than 1000000.*speed"):
        frames_at_rate(np.array([0.0, 3.15e7]), 30.0)
