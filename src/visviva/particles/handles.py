"""Kinematic handles: particles that follow a prescribed rigid motion of time.

A handle carries some particles (a body's pinned points) on a rigid motion: a translation at
``velocity`` u [m/s] and a turn about the unit ``axis`` n through the ``pivot`` p [m], which
travels with the translation, by the angle

    θ(s) = ω s + A sin(2π f s)        [rad]

(``angular_velocity`` ω [rad/s]; an oscillation of ``amplitude`` A [rad] and ``frequency`` f
[Hz]). Every motion runs on the handle's clock s(t) [s]: it stands at 0 until ``start``, speeds
up over ``ramp`` seconds to run with time (ṡ = 1), slows down over the last ``ramp`` seconds
before ``stop`` and stands still after it. The clock's rate across a ramp is the smoothstep
S(τ) = 3τ² − 2τ³ of the fraction τ of the ramp gone (so s = r τ³ (1 − τ/2) over a ramp of r
seconds, r/2 in all): the rate, and so the handle's velocity, is continuous, and its
acceleration is finite. A point at X at t = 0, with o = X − p, is at

    x(t) = X + u s + sin θ (n × o) − (1 − cos θ) o⊥,      o⊥ = o − n (n·o)
    ẋ(t) = ṡ (u + θ'(s) (cos θ (n × o) − sin θ o⊥)),      θ' = ω + 2π f A cos(2π f s)

(Rodrigues' rotation of o, written so that x(0) = X exactly and a small turn loses no digits).
A head that turns by an angle Θ and stops is ``angular_velocity = Θ / (stop − start − ramp)``.

**How the pipeline holds a handle's particles.** They are pinned: their rows of the force and
of its Jacobians are zero, so no integrator moves them by a force. Whenever the forces are
evaluated at a time t — an explicit step's start, a Runge–Kutta stage, a Newton iterate of an
implicit step — the system puts each of them at x(t) with velocity ẋ(t) first
(:meth:`Handles.hold`, used by :mod:`visviva.model.scene_system`), so the springs pull on the
rest of the body from exactly where the handle is and the dampers see the handle's velocity;
the derivatives with respect to their positions and velocities are then truly zero. After each
step the :class:`Handles` stage sets their positions and velocities to x and ẋ at the step's
end, so they move exactly along the path (to round-off) under every method.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from ..ode.stage import Phase

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["HandleMotion", "Handles"]


@dataclass(frozen=True)
class HandleMotion:
    """A rigid motion of time (see the module docstring); SI units, world frame.

    Attributes:
        pivot: ``(3,)`` the point the turn is about, at t = 0 [m].
        velocity: ``(3,)`` u, the translation's velocity [m/s].
        axis: ``(3,)`` n, the unit axis of the turn.
        angular_velocity: ω [rad/s] (right-handed about ``axis``).
        amplitude: A, the oscillation's amplitude [rad].
        frequency: f, the oscillation's frequency [Hz].
        start: When the clock starts [s].
        stop: When it stops [s] (``inf``: never).
        ramp: How long it takes to speed up and to slow down [s].
    """

    pivot: np.ndarray
    velocity: np.ndarray
    axis: np.ndarray
    angular_velocity: float = 0.0
    amplitude: float = 0.0
    frequency: float = 0.0
    start: float = 0.0
    stop: float = math.inf
    ramp: float = 0.0

    def clock(self, t: float) -> tuple[float, float]:
        """The handle's clock s [s] at time ``t`` [s] and its rate ṡ (from ``start`` on, and
        before ``stop``, the motion runs: without a ramp its rate is 1 at ``start`` itself)."""
        start, stop, r = self.start, self.stop, self.ramp
        if t < start:
            return 0.0, 0.0
        if t >= stop:
            return stop - start - r, 0.0
        up, down = t - start, stop - t
        if up < r:
            tau = up / r
            return r * tau**3 * (1.0 - 0.5 * tau), tau * tau * (3.0 - 2.0 * tau)
        if down < r:
            tau = down / r
            return stop - start - r - r * tau**3 * (1.0 - 0.5 * tau), tau * tau * (3.0 - 2.0 * tau)
        return up - 0.5 * r, 1.0

    def angle(self, s: float) -> tuple[float, float]:
        """θ [rad] at the clock's reading ``s`` [s], and dθ/ds [rad/s]."""
        phase = 2.0 * math.pi * self.frequency * s
        theta = self.angular_velocity * s + self.amplitude * math.sin(phase)
        rate = self.angular_velocity + 2.0 * math.pi * self.frequency * self.amplitude * math.cos(
            phase
        )
        return theta, rate

    def largest_extent(self, until: float) -> tuple[float, float, float]:
        """Bounds on the motion up to time ``until`` [s]: the translation's length [m], the
        angle and the oscillation's phase together [rad], and the angular speed [rad/s] (to
        refuse paths beyond a float's range)."""
        s = self.clock(until)[0]  # the clock never runs back
        travel = float(np.abs(self.velocity).sum()) * s
        turn = (abs(self.angular_velocity) + 2.0 * math.pi * self.frequency) * s + abs(
            self.amplitude
        )
        spin = abs(self.angular_velocity) + 2.0 * math.pi * self.frequency * abs(self.amplitude)
        return travel, turn, spin


class Handles:
    """The handles stage: each handle's particles put on its path after every step (see the
    module docstring).

    Args:
        motions: Each handle's motion.
        particles: Each handle's particle indices in the scene.
        positions: Each handle's particles' positions at t = 0 [m], ``(k, 3)``.
    """

    phase: ClassVar[Phase] = Phase.CONSTRAINTS
    order: ClassVar[int] = 0
    #: The fused particle step applies it (:mod:`visviva.particles.fused`).
    compiled: ClassVar[bool] = True
    #: A moving handle does work on what it holds.
    changes_energy: ClassVar[bool] = True
    kills_particles: ClassVar[bool] = False

    def __init__(
        self,
        motions: Sequence[HandleMotion],
        particles: Sequence[np.ndarray],
        positions: Sequence[np.ndarray],
    ) -> None:
        self.motions = tuple(motions)
        #: ``(H,)`` every handled particle, handle by handle.
        self.indices = np.concatenate([np.asarray(p, dtype=np.int64) for p in particles])
        self._start = np.concatenate([np.asarray(x, dtype=np.float64) for x in positions])
        across, inward = [], []
        for motion, x in zip(self.motions, positions, strict=True):
            offset = np.asarray(x, dtype=np.float64) - motion.pivot
            across.append(np.cross(motion.axis, offset))  # n × o
            inward.append(offset - np.outer(offset @ motion.axis, motion.axis))  # o⊥
        self._across = np.concatenate(across)
        self._inward = np.concatenate(inward)
        self._slices = np.cumsum([0, *(len(p) for p in particles)])

    def carried_start(self) -> dict[str, np.ndarray]:
        """None: it carries nothing in the state."""
        return {}

    def place(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Where the handles hold their particles at time ``t`` [s]: positions [m] and
        velocities [m/s], ``(H, 3)`` each, in the order of :attr:`indices`."""
        x = np.empty_like(self._start)
        v = np.empty_like(self._start)
        for k, motion in enumerate(self.motions):
            rows = slice(self._slices[k], self._slices[k + 1])
            s, rate = motion.clock(t)
            theta, turning = motion.angle(s)
            sin, cos = math.sin(theta), math.cos(theta)
            slack = 2.0 * math.sin(0.5 * theta) ** 2  # 1 − cos θ without cancellation
            across, inward = self._across[rows], self._inward[rows]
            x[rows] = self._start[rows] + motion.velocity * s + sin * across - slack * inward
            v[rows] = rate * (motion.velocity + turning * (cos * across - sin * inward))
        return x, v

    def hold(
        self, t: float, x: np.ndarray, v: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Copies of the particles' positions ``x`` and velocities ``v`` (``(N, 3)`` each; ``v``
        may be ``None``) with the handled particles where their handles hold them at ``t``."""
        position, velocity = self.place(t)
        x = np.array(x)
        x[self.indices] = position
        if v is not None:
            v = np.array(v)
            v[self.indices] = velocity
        return x, v

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """``after`` with the handled particles on their paths at its time."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        position, velocity = self.place(after.t)
        result["particle_position"][self.indices] = position
        result["particle_velocity"][self.indices] = velocity
        return result
