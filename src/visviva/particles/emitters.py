"""Emitters: particles born from a shape at a rate and in bursts, living for their lifetimes.

An :class:`EmitterSpec` is one emitter in numbers: when it emits, from where, with which
speeds, lifetimes, radii and colours (constants, uniform ranges ``[low, high]`` and ramps over
each particle's life). :mod:`visviva.particles.emission` is the stage that makes them live.

Births follow the clock, not the steps: continuous birth ``k`` (``k = 0, 1, ...``) happens at
``start + k/rate`` exactly, so the fractional remainder of every step carries over and a run
with another step size makes the same particles at the same times (seed 002: "particles are
generated according to a stochastic process"; here the process is deterministic in time and
random in everything else).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._validation import real_number
from ..errors import ModelError

__all__ = ["SHAPES", "EmitterSpec", "ramp_values", "unit_vector", "value_range"]

#: Shape codes of the sampling kernels.
SHAPES = {"point": 0, "disc": 1, "sphere": 2, "box": 3, "mesh": 4}


def value_range(
    name: str, value: float | Sequence[float], *, positive: bool
) -> tuple[float, float]:
    low, high = (value, value) if isinstance(value, (int, float)) else tuple(value)
    for bound in (low, high):
        real_number(name, bound, positive=positive, nonnegative=not positive)
    if low > high:
        raise ModelError(f"`{name}` is a range [low, high] with low > high (got {[low, high]})")
    return float(low), float(high)


def unit_vector(name: str, value: Sequence[float]) -> np.ndarray:
    """``value`` scaled to unit length (any finite non-zero 3-vector, however large or small)."""
    vector = np.asarray(value, dtype=np.float64)
    largest = float(np.abs(vector).max()) if vector.shape == (3,) else 0.0
    if not (0.0 < largest < math.inf):
        raise ModelError(f"`{name}` must be a finite non-zero 3-vector (got {list(value)!r})")
    vector = vector / largest  # first to order one, so the length cannot overflow
    return vector / float(np.linalg.norm(vector))


def ramp_values(stops: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """A ramp's value at each age ``fraction`` (linear between stops, constant beyond).

    Args:
        stops: ``(S, 1 + C)``: age fraction in [0, 1], then ``C`` values.
        fraction: Age over lifetime, any shape.

    Returns:
        ``fraction.shape + (C,)``.
    """
    columns = [np.interp(fraction, stops[:, 0], stops[:, 1 + c]) for c in range(stops.shape[1] - 1)]
    return np.stack(columns, axis=-1)


@dataclass(frozen=True, eq=False)
class EmitterSpec:
    """One emitter in numbers (SI units; see :class:`visviva.model.scene.Emitter`).

    Attributes:
        index: The emitter's index in the scene (its random stream).
        name: The emitter's name, for messages.
        first_slot: First particle slot it owns.
        capacity: Number of slots it owns.
        rate: Continuous births per second [1/s].
        start: When continuous births start [s].
        stop: When they stop [s] (``inf``: never).
        burst_times: ``(B,)`` burst times [s], sorted.
        burst_counts: ``(B,)`` particles per burst.
        shape: Shape code (:data:`SHAPES`).
        position: Centre of the shape [m].
        radius: Disc or sphere radius [m].
        extent: Box edge lengths [m].
        normal: Unit normal of a disc.
        surface: Born on the surface of a sphere or box.
        triangles: ``(T, 3, 3)`` corners of a mesh's triangles [m] (empty otherwise).
        direction: Unit axis of the emission cone.
        spread: Cone half-angle [rad].
        speed, lifetime, particle_radius: ``(low, high)`` uniform ranges [m/s], [s], [m].
        mass: Mass of each particle [kg].
        color_ramp: ``(S, 4)`` stops ``[age fraction, r, g, b]`` (one stop: constant).
        size_ramp: ``(S, 2)`` stops ``[age fraction, radius factor]``.
        seed: Random seed.
    """

    index: int
    name: str
    first_slot: int
    capacity: int
    rate: float
    start: float
    stop: float
    burst_times: np.ndarray
    burst_counts: np.ndarray
    shape: int
    position: np.ndarray
    radius: float
    extent: np.ndarray
    normal: np.ndarray
    surface: bool
    triangles: np.ndarray
    direction: np.ndarray
    spread: float
    speed: tuple[float, float]
    lifetime: tuple[float, float]
    particle_radius: tuple[float, float]
    mass: float
    color_ramp: np.ndarray
    size_ramp: np.ndarray
    seed: int

    def births_before(self, t: float) -> int:
        """Continuous births at times ``< t``: ``k`` with ``start + k/rate < min(t, stop)``."""
        if self.rate == 0.0:
            return 0
        end = min(t, self.stop) - self.start
        return max(0, math.ceil(end * self.rate)) if end > 0.0 else 0

    def most_alive(self, duration: float) -> float:
        """An upper bound on how many of its particles are alive at once within ``duration``
        [s] (a float: it may be too large to allocate, which the caller refuses)."""
        longest = self.lifetime[1]
        continuous = 0.0
        if self.rate > 0.0 and self.start < duration:
            # Births happen within [start, min(stop, duration)); at most a lifetime of them live.
            window = min(longest, min(self.stop, duration) - self.start) + 1e-9
            continuous = (
                math.ceil(window * self.rate) + 1.0 if window * self.rate < 1e300 else math.inf
            )
        # At each burst, the bursts whose particles may still be alive.
        bursts = max(
            (
                float(
                    self.burst_counts[
                        (self.burst_times <= t) & (self.burst_times > t - longest)
                    ].sum()
                )
                for t in self.burst_times
                if t < duration
            ),
            default=0.0,
        )
        return continuous + bursts

    def __post_init__(self) -> None:
        for value in vars(self).values():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
