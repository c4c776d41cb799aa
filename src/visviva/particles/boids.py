"""Flocking: Reynolds' boids as a post-step stage on the shared neighbour grid.

Each boid i (a particle at ``x_i`` [m] with velocity ``v_i`` [m/s]) sees its *flockmates*:
the other live boids j within the ``radius`` r, ``|x_j − x_i|² ≤ r²`` (the grid's test), and
inside its field of view, a cone of full angle ``fov_deg`` φ around its heading
``u_i = v_i / |v_i|``: ``d · u_i ≥ cos(φ/2) |d|`` with ``d = x_j − x_i`` (a boid at rest, or
``fov_deg = 360``, sees all around). Three rules (C. W. Reynolds, "Flocks, herds and schools: a
distributed behavioral model", SIGGRAPH 1987) give each a *desired direction*:

* separation: the *crowding* ``S = Σ (s/|d| − 1) (x_i − x_j)/|d|`` over the flockmates closer
  than ``separation`` s: each pushes away from itself, from nothing at s to without bound (as
  1/|d|) as they approach (capped at :data:`MAX_CROWDING` a flockmate; coincident ones, closer
  than about 1e-154 m, have no direction and do not push);
* alignment: ``Σ v_j``, the direction of the flockmates' mean velocity;
* cohesion: ``Σ (x_j − x_i)``, towards the flockmates' centre;

and two more steer the flock as a whole: a ``goal`` point (direction ``goal − x_i``) and the
nearest live *leader* (a particle of another entity; direction ``x_leader − x_i``).

**Steering** (C. W. Reynolds, "Steering behaviors for autonomous characters", GDC 1999): each
rule asks for the desired velocity ``V u`` at the ``max_speed`` V along its direction ``u``;
its steering is ``V u − v_i`` (nothing if it has no direction), times its weight w [1/s]: alone,
a rule relaxes the velocity towards its desired one at the rate w. Separation's weight is
``w_s |S|``: it grows as flockmates close in, so a crowded boid is pushed out against the pull
of cohesion, which a constant weight could not do (every rule's steering is at most 2V long,
so a lone nearest flockmate settles near ``s / (1 + 2 Σw / w_s)``, Σw the other weights; a
boid squeezed between flockmates feels the difference of their pushes and may settle nearer).
The weighted sum is an acceleration [m/s²], truncated to the length ``max_acceleration`` A.

**Obstacles** come first (Reynolds 1987's prioritised allocation): a boid within the
``look_ahead`` distance L of a collider's surface (signed distance ``d < L`` from
:func:`~visviva.collision.colliders.collider_distance`, outward normal n) and heading into it
(``v · n < 0``) steers towards ``V (n + t)/|n + t|``, half-way between leaving along the
normal and sliding along its tangential heading ``t`` (the unit part of v across n; n alone
head-on), as fast as A allows without overshooting in the step: ``a_o = (V û − v)/h``
truncated to A. The other rules share what is left, ``A − |a_o|``. (The nearest such
collider counts.) Turning at A, a boid at V runs a circle of radius V²/A, so the default
look-ahead, 2 V²/A, lets it turn away from a wall it flies at head-on.

**Update** — Reynolds' own, first order in h whatever the integrator: after the integrator's
step of h (which moved the boids with their velocities and any forces), this stage computes
the steering a from the state at the step's end and sets ``v ← v + a h``, then truncates
``|v|`` to V (and raises it to ``min_speed`` if given: birds do not hover; a boid at rest
stays at rest). Velocities above V entering the step (a start, other forces) are first
truncated to V, so every velocity the rules see is bounded. The next step's integrator moves
the boids with the new velocities. World gravity acts on boids like on any particle: set it to
zero for birds (their lift is not modelled).

**Spacing** (``min_distance`` d, optional, ``≤ s``): separation is a steering, so a flock held
together by cohesion settles with its nearest flockmates inside s. Where boids must never come
closer than d (birds that keep a body length, a swarm of drones), the stage then moves every
pair of live boids closer than d apart along the line between them, each by half the
intrusion — the projection of position-based dynamics (M. Müller, B. Heidelberger, M. Hennix &
J. Ratcliff, "Position based dynamics", VRIPHYS 2006): Gauss–Seidel sweeps over the pairs
within :data:`SPACING_REACH` d in a fixed order until no pair is closer than d by more than
:data:`SPACING_TOLERANCE` d (at most :data:`SPACING_SWEEPS` sweeps), the pairs searched again
if it took more than one sweep (at most :data:`SPACING_ROUNDS` searches). As in position-based
dynamics each boid's velocity then gains its move over h (truncated to V): a boid that pressed
into a flockmate stops pressing, instead of being pushed back every step by the projection.

**2-D** (``plane = "xz"``): every desired direction and the steering lose their vertical (y)
component, the velocity's y is set to zero and each boid is put back at the height it had
before the step, so a flock stays in its horizontal planes exactly (distances are still 3-D).

**Data**: the stage's targets are rows of the scene's particle arrays; per step it gathers
their positions, rebuilds a :class:`~visviva.geometry.neighbour_grid.NeighbourGrid` of radius r
on the live ones (dead slots are never flockmates), and runs one parallel pass over the sorted
boids (chunks of 256 sorted positions, a serial function per chunk, the safe pattern of
:mod:`~visviva.geometry.neighbour_search`). Cost O(N k) for k boids in a neighbourhood's 27
cells, plus O(N L) for L leaders and O(N K) for K colliders.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numba import njit, prange

from .._validation import describe, real_number
from ..collision.colliders import ColliderSet, collider_distance
from ..errors import ModelError, SimulationError
from ..geometry.neighbour_cells import MAX_COORDINATE, cell_of, neighbour_runs
from ..geometry.neighbour_grid import PARALLEL_MIN_POINTS, NeighbourGrid
from ..ode.stage import Phase

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["MAX_LEADERS", "Boids", "polarisation"]

#: Largest crowding one flockmate adds, ``s/|d| − 1``: flockmates closer than ``s/MAX_CROWDING``
#: push as if they were that far (so that the sum stays finite however close they come).
MAX_CROWDING = 1e8
#: Sorted boids per parallel task.
CHUNK = 256
#: The spacing projection: pairs searched within this many d (so that moves of a quarter of d
#: meet no pair unseen), at most this many Gauss–Seidel sweeps per search and searches per
#: step, until no pair is closer than d by more than this fraction of d.
SPACING_REACH = 1.5
SPACING_SWEEPS = 64
SPACING_ROUNDS = 4
SPACING_TOLERANCE = 1e-9
#: Most leader particles: every boid looks for the nearest one by brute force (O(N L)).
MAX_LEADERS = 1024
#: Largest speed, acceleration bound, weight and look-ahead accepted: sums of a neighbourhood's
#: velocities and steerings then stay far inside the range of a float.
LIMIT = MAX_COORDINATE

#: Sums of squares between these are computed directly in :func:`_norm` (no overflow, no
#: digits lost to subnormals); outside, by ``hypot``.
_TINY, _HUGE = 1e-290, 1e290

# Slots of the kernel's parameter vector.
_R2, _SEP, _COS, _VMAX, _VMIN, _AMAX, _WSEP, _WALI, _WCOH = 0, 1, 2, 3, 4, 5, 6, 7, 8
_WGOAL, _GX, _GY, _GZ, _WLEAD, _LOOK, _H, _PLANAR = 9, 10, 11, 12, 13, 14, 15, 16
_PARAMETERS = 17


def polarisation(velocities: Any, alive: Any = None) -> float:
    """The flock's polarisation ``Φ = |Σ v_i/|v_i|| / N`` over the moving live boids.

    1 when every boid heads the same way; about ``1/√N`` for random headings. ``velocities``
    is ``(N, 3)`` [m/s]; ``alive`` an optional ``(N,)`` bool mask. Boids at rest are left out;
    0.0 if none moves.
    """
    v = np.asarray(velocities, dtype=np.float64)
    if alive is not None:
        v = v[np.asarray(alive, dtype=bool)]
    speed = np.hypot(v[:, 0], np.hypot(v[:, 1], v[:, 2]))
    moving = speed > 0.0
    if not moving.any():
        return 0.0
    headings = v[moving] / speed[moving, None]
    return float(np.linalg.norm(headings.sum(axis=0)) / moving.sum())


class Boids:
    """The flocking stage of one flock (see the module docstring for the model).

    Args:
        targets: The flock's rows in the scene's particle arrays, ``(T,)``.
        radius: r, how far a boid sees its flockmates [m].
        separation: s, how close flockmates push it away [m], ``0 < s ≤ r``.
        max_speed: V, the speed every desired velocity has and no boid exceeds [m/s].
        max_acceleration: A, the bound of the steering acceleration [m/s²].
        fov_deg: φ, the field of view, full angle around the heading [degrees], ``(0, 360]``.
        min_speed: The least speed of a moving boid [m/s], ``≤ V``.
        separation_weight, alignment_weight, cohesion_weight: The rules' weights [1/s], ≥ 0.
        goal: A point the flock seeks [m], ``(3,)``, or ``None``.
        goal_weight: Its weight [1/s] (needs ``goal``).
        leaders: Rows of the particles the flock follows (not steered by it), or ``None``.
        leader_weight: Their weight [1/s] (needs ``leaders``).
        colliders: The colliders the boids avoid, or ``None``.
        look_ahead: L, the distance from a collider at which a boid turns away [m] (default
            2 V²/A).
        min_distance: d, the distance [m] no two boids are left closer than after a step
            (``0 < d ≤ s``), or ``None`` (separation steers only).
        plane: ``"xz"`` for a flock in horizontal planes, ``None`` for 3-D.
        name: The flock's name, for messages.

    Raises:
        ModelError: A value out of its range, naming the argument (backquoted) and the fix.
    """

    phase: ClassVar[Phase] = Phase.BEHAVIOURS
    order: ClassVar[int] = 0
    #: Not a part of the fused particle step (which knows only its own stages).
    compiled: ClassVar[bool] = False
    changes_energy: ClassVar[bool] = True
    kills_particles: ClassVar[bool] = False

    def __init__(
        self,
        targets: Any,
        *,
        radius: float,
        separation: float,
        max_speed: float,
        max_acceleration: float,
        fov_deg: float = 360.0,
        min_speed: float = 0.0,
        separation_weight: float = 1.5,
        alignment_weight: float = 1.0,
        cohesion_weight: float = 1.0,
        goal: Any = None,
        goal_weight: float = 0.0,
        leaders: Any = None,
        leader_weight: float = 0.0,
        colliders: ColliderSet | None = None,
        look_ahead: float | None = None,
        min_distance: float | None = None,
        plane: str | None = None,
        name: str = "boids",
    ) -> None:
        self.name = name
        self.targets = _rows("targets", targets)
        self.radius = NeighbourGrid(radius).radius  # checked as the grid checks it
        self.separation = _bounded("separation", separation, positive=True, unit=" m")
        if self.separation > self.radius:
            raise ModelError(
                f"`separation` ({self.separation!r} m) must not exceed `radius` "
                f"({self.radius!r} m): a boid pushes away only flockmates it sees"
            )
        self.max_speed = _bounded("max_speed", max_speed, positive=True, unit=" m/s")
        self.max_acceleration = _bounded(
            "max_acceleration", max_acceleration, positive=True, unit=" m/s^2"
        )
        self.fov_deg = real_number("fov_deg", fov_deg, unit=" degrees")
        if not 0.0 < self.fov_deg <= 360.0:
            raise ModelError(
                f"`fov_deg` must lie in (0, 360] degrees, the full angle of the cone a boid sees "
                f"around its heading (got {self.fov_deg!r})"
            )
        self.min_speed = real_number("min_speed", min_speed, nonnegative=True, unit=" m/s")
        if self.min_speed > self.max_speed:
            raise ModelError(
                f"`min_speed` ({self.min_speed!r} m/s) must not exceed `max_speed` "
                f"({self.max_speed!r} m/s)"
            )
        weights = {
            "separation_weight": separation_weight,
            "alignment_weight": alignment_weight,
            "cohesion_weight": cohesion_weight,
            "goal_weight": goal_weight,
            "leader_weight": leader_weight,
        }
        self.weights = {
            k: _bounded(k, w, nonnegative=True, unit=" 1/s") for k, w in weights.items()
        }
        self.goal = None if goal is None else _point("goal", goal)
        if self.goal is None and self.weights["goal_weight"] > 0.0:
            raise ModelError("`goal_weight` is given without a `goal`: give the point to seek")
        self.leaders = _rows("leaders", np.zeros(0) if leaders is None else leaders)
        if self.leaders.shape[0] > MAX_LEADERS:
            raise ModelError(
                f"`leaders`: {self.leaders.shape[0]} leader particles; every boid looks for the "
                f"nearest by brute force, so at most {MAX_LEADERS} are accepted"
            )
        if np.isin(self.leaders, self.targets).any():
            raise ModelError(
                "`leaders` must not be boids of the flock they lead: the flock does not steer "
                "its leaders"
            )
        if not self.leaders.shape[0] and self.weights["leader_weight"] > 0.0:
            raise ModelError("`leader_weight` is given without `leaders`: name whom to follow")
        self.colliders = colliders if colliders is not None else ColliderSet([])
        default = 2.0 * self.max_speed**2 / self.max_acceleration
        self.look_ahead = (
            min(default, LIMIT)
            if look_ahead is None
            else _bounded("look_ahead", look_ahead, positive=True, unit=" m")
        )
        self.min_distance = None
        if min_distance is not None:
            self.min_distance = _bounded("min_distance", min_distance, positive=True, unit=" m")
            if self.min_distance > self.separation:
                raise ModelError(
                    f"`min_distance` ({self.min_distance!r} m) must not exceed `separation` "
                    f"({self.separation!r} m): separation steers boids apart before they are "
                    "held apart"
                )
        if plane not in (None, "xz"):
            raise ModelError(f'`plane` must be "xz" (a 2-D flock) or None (3-D), not {plane!r}')
        self.plane = plane

    def parameters(self, h: float) -> np.ndarray:
        """The kernel's parameter vector for a step of ``h`` [s]."""
        p = np.zeros(_PARAMETERS)
        p[_R2] = self.radius * self.radius
        p[_SEP] = self.separation
        p[_COS] = -2.0 if self.fov_deg == 360.0 else math.cos(math.radians(0.5 * self.fov_deg))
        p[_VMAX], p[_VMIN], p[_AMAX] = self.max_speed, self.min_speed, self.max_acceleration
        p[_WSEP] = self.weights["separation_weight"]
        p[_WALI] = self.weights["alignment_weight"]
        p[_WCOH] = self.weights["cohesion_weight"]
        p[_WGOAL] = self.weights["goal_weight"]
        if self.goal is not None:
            p[_GX], p[_GY], p[_GZ] = self.goal
        p[_WLEAD] = self.weights["leader_weight"]
        p[_LOOK], p[_H], p[_PLANAR] = self.look_ahead, h, self.plane == "xz"
        return p

    def carried_start(self) -> dict[str, np.ndarray]:
        """None: it carries nothing in the state."""
        return {}

    def _scratch(self) -> _Scratch:
        spacing = None if self.min_distance is None else SPACING_REACH * self.min_distance
        return _Scratch(self.targets.shape[0], self.radius, spacing)

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """The state after the boids steered for the step of ``h`` [s] (module docstring)."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        x, v = result["particle_position"], result["particle_velocity"]
        alive = after["particle_alive"]
        if not np.isfinite(x[self.targets]).all():
            return result  # a blown-up state: the divergence watch reports it
        scratch = work.get(self, self._scratch)
        try:
            self._run(scratch, x, v, alive, before["particle_position"], x, v, h)
            if scratch.spacing is not None:
                self._space(scratch.spacing, x, v, alive, h)
        except ModelError as error:  # a boid beyond the grid's reach of the origin
            raise SimulationError(f"{self.name}: {error}", t=after.t, step=None) from None
        return result

    def _space(
        self, grid: NeighbourGrid, x: np.ndarray, v: np.ndarray, alive: np.ndarray, h: float
    ) -> None:
        """Move the live boids at ``x`` (in place) so that no two are closer than
        ``min_distance``, and add each move over ``h`` to its velocity ``v`` (see the module
        docstring)."""
        rows = self.targets
        start = np.ascontiguousarray(x[rows])
        points = start.copy()
        live = np.ascontiguousarray(alive[rows])
        for _ in range(SPACING_ROUNDS):
            grid.update(points, live)
            first, second = grid.pairs()
            sweeps = _separate(points, first, second, self.min_distance, self.plane == "xz")
            if sweeps <= 1:  # nothing moved, or one sweep did it: no pair is new
                break
        moved = points - start
        if not moved.any():
            return
        x[rows] = points
        u = v[rows] + moved / h
        speed = np.sqrt(np.einsum("ij,ij->i", u, u))
        fast = speed > self.max_speed
        u[fast] *= (self.max_speed / speed[fast])[:, None]
        v[rows] = u

    def steering(
        self,
        positions: Any,
        velocities: Any,
        alive: Any = None,
        h: float = 1e-3,
        work: Workspace | None = None,
    ) -> np.ndarray:
        """Each boid's steering acceleration [m/s²], ``(T,)`` rows in the order of
        ``targets`` (zero for dead ones), for particles at ``positions`` ``(N, 3)`` [m] with
        ``velocities`` ``(N, 3)`` [m/s] (``h`` [s] enters only the obstacle avoidance);
        ``work``: a run's storage to keep the neighbour grid in (``None``: a fresh one)."""
        x = np.ascontiguousarray(positions, dtype=np.float64)
        v = np.ascontiguousarray(velocities, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != 3 or v.shape != x.shape:
            raise ModelError(
                f"`positions` and `velocities` must both have shape (N, 3) (got {x.shape} and "
                f"{v.shape})"
            )
        if self.targets.shape[0] and self.targets.max() >= x.shape[0]:
            raise ModelError(
                f"`targets` name row {int(self.targets.max())} of {x.shape[0]} particles"
            )
        mask = np.ones(x.shape[0], dtype=bool) if alive is None else np.asarray(alive)
        if mask.dtype != np.bool_ or mask.shape != (x.shape[0],):
            raise ModelError(
                f"`alive` must be a boolean mask of shape ({x.shape[0]},), one flag per particle "
                f"(got dtype {mask.dtype}, shape {mask.shape})"
            )
        scratch = self._scratch() if work is None else work.get(self, self._scratch)
        self._run(scratch, x, v, mask, x, x.copy(), v.copy(), real_number("h", h, positive=True))
        return scratch.acceleration.copy()

    def _run(
        self,
        scratch: _Scratch,
        x: np.ndarray,
        v: np.ndarray,
        alive: np.ndarray,
        x_before: np.ndarray,
        x_out: np.ndarray,
        v_out: np.ndarray,
        h: float,
    ) -> None:
        """Steer the flock at ``x``, ``v``: new velocities into ``v_out``, 2-D heights into
        ``x_out``, accelerations into the scratch's."""
        rows = self.targets
        live = np.ascontiguousarray(alive[rows])
        scratch.grid.update(x[rows], live)
        acc = scratch.acceleration
        acc[:] = 0.0
        leaders = self.leaders[alive[self.leaders]]
        lead = np.ascontiguousarray(x[leaders])
        p = self.parameters(h)
        g = scratch.grid.arrays
        n = g.order.shape[0]
        vs = scratch.velocity[:n]
        _, kinds, crows, offsets, nb, nl, tp, tn = self.colliders.kernel_arrays
        args = (g, rows, v, vs, p, lead, kinds, crows, offsets, nb, nl, tp, tn, x_before)
        if n >= PARALLEL_MIN_POINTS:
            _steer_parallel(*args, acc, x_out, v_out)
        else:
            _gather_velocities(g.order, rows, v, vs, p[_VMAX], 0, n)
            _steer_chunk(*args, acc, x_out, v_out, 0, n)


class _Scratch:
    """A run's storage for a flock of ``count`` boids: the neighbour grid of radius r, the grid
    of the spacing projection (``None`` without ``min_distance``), the sorted boids'
    velocities and each boid's steering acceleration, ``(count, 3)`` each."""

    __slots__ = ("acceleration", "grid", "spacing", "velocity")

    def __init__(self, count: int, radius: float, spacing: float | None) -> None:
        self.grid = NeighbourGrid(radius)
        self.spacing = None if spacing is None else NeighbourGrid(spacing)
        self.velocity = np.empty((count, 3))
        self.acceleration = np.empty((count, 3))


def _bounded(name: str, value: Any, *, positive: bool = False, nonnegative: bool = False,
             unit: str = "") -> float:  # fmt: skip
    number = real_number(name, value, positive=positive, nonnegative=nonnegative, unit=unit)
    if number > LIMIT:
        raise ModelError(f"`{name}` must be at most {LIMIT:g}{unit} (got {number!r})")
    return number


def _rows(name: str, value: Any) -> np.ndarray:
    rows = np.asarray(value)
    if rows.ndim != 1 or (rows.size and rows.dtype.kind not in "iu"):
        raise ModelError(f"`{name}` must be a 1-D array of particle rows (got {describe(value)})")
    rows = rows.astype(np.int64)
    if rows.size and rows.min() < 0:
        raise ModelError(f"`{name}` must be particle rows, not negative (got {int(rows.min())})")
    if np.unique(rows).shape[0] != rows.shape[0]:
        raise ModelError(f"`{name}` names a particle twice: each row at most once")
    return np.ascontiguousarray(rows)


def _point(name: str, value: Any) -> np.ndarray:
    point = np.asarray(value, dtype=np.float64) if _numeric(value) else None
    if point is None or point.shape != (3,) or not np.isfinite(point).all():
        raise ModelError(f"`{name}` must be a finite point [x, y, z] in m (got {describe(value)})")
    return point


def _numeric(value: Any) -> bool:
    try:
        return np.asarray(value).dtype.kind in "iuf"
    except (TypeError, ValueError):
        return False


# ---------------------------------------------------------------------------------------------
# Kernels
# ---------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _norm(x, y, z):  # pragma: no cover - compiled
    """|(x, y, z)|: the square root of the sum of squares while it is a normal float far from
    overflow (within about an ulp of ``hypot``, which cost 3 of the 8 ms of a step of 10⁴ boids
    on one core, measured), else ``hypot``."""
    s = x * x + y * y + z * z
    if _TINY < s < _HUGE:
        return math.sqrt(s)
    return math.hypot(x, math.hypot(y, z))


@njit(cache=True, inline="always")
def _steer(dx, dy, dz, vx, vy, vz, vmax, planar):  # pragma: no cover - compiled
    """Reynolds' steering ``V d/|d| − v`` towards the direction d (zero if d has none)."""
    if planar:
        dy = 0.0
    length = _norm(dx, dy, dz)
    if length == 0.0:
        return 0.0, 0.0, 0.0
    sx, sy, sz = vmax * (dx / length) - vx, vmax * (dy / length) - vy, vmax * (dz / length) - vz
    if planar:
        sy = 0.0
    return sx, sy, sz


@njit(cache=True, inline="always")
def _truncate(x, y, z, limit):  # pragma: no cover - compiled
    length = _norm(x, y, z)
    if length > limit:
        f = limit / length
        return x * f, y * f, z * f
    return x, y, z


@njit(cache=True, error_model="numpy")
def _separate(points, first, second, distance, planar):  # pragma: no cover - compiled
    """Gauss–Seidel projection of the pairs ``(first[k], second[k])`` of rows of ``points``
    ``(T, 3)`` [m] to at least ``distance`` [m] apart, each moved by half the intrusion along
    the line between them (horizontally in a 2-D flock); coincident boids part along x.
    Sweeps until no pair is closer than ``distance`` by more than :data:`SPACING_TOLERANCE` of
    it, at most :data:`SPACING_SWEEPS`; returns how many moved a pair (0: none was too close).
    """
    slack = SPACING_TOLERANCE * distance
    for sweep in range(SPACING_SWEEPS):
        intruded = False
        for k in range(first.shape[0]):
            i, j = first[k], second[k]
            dx = points[i, 0] - points[j, 0]
            dy = 0.0 if planar else points[i, 1] - points[j, 1]
            dz = points[i, 2] - points[j, 2]
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if d >= distance - slack:
                continue
            intruded = True
            if d > 0.0:
                f = 0.5 * (distance - d) / d
                dx, dy, dz = f * dx, f * dy, f * dz
            else:
                dx, dy, dz = 0.5 * distance, 0.0, 0.0
            points[i, 0] += dx
            points[i, 1] += dy
            points[i, 2] += dz
            points[j, 0] -= dx
            points[j, 1] -= dy
            points[j, 2] -= dz
        if not intruded:
            return sweep
    return SPACING_SWEEPS


@njit(cache=True)
def _gather_velocities(order, rows, v, vs, vmax, begin, end):  # pragma: no cover - compiled
    """The boids' velocities in sorted order, truncated to ``vmax``."""
    for s in range(begin, end):
        r = rows[order[s]]
        vx, vy, vz = _truncate(v[r, 0], v[r, 1], v[r, 2], vmax)
        vs[s, 0], vs[s, 1], vs[s, 2] = vx, vy, vz


@njit(cache=True)
def _avoid(px, py, pz, vx, vy, vz, p, kinds, crows, offsets, nb, nl, tp, tn):  # pragma: no cover
    """The obstacle's acceleration: from the nearest collider within the look-ahead that the
    boid heads into (zero if none)."""
    planar = p[_PLANAR] != 0.0
    best = p[_LOOK]
    found = False
    mx = my = mz = 0.0
    for k in range(kinds.shape[0]):
        d, nx, ny, nz = collider_distance(k, px, py, pz, kinds, crows, offsets, nb, nl, tp, tn)
        if planar:
            ny = 0.0
            length = _norm(nx, ny, nz)
            if length == 0.0:
                continue
            nx, nz = nx / length, nz / length
        if d < best and vx * nx + vy * ny + vz * nz < 0.0:
            best, found = d, True
            mx, my, mz = nx, ny, nz
    if not found:
        return 0.0, 0.0, 0.0
    along = vx * mx + vy * my + vz * mz
    tx, ty, tz = vx - along * mx, vy - along * my, vz - along * mz
    if planar:
        ty = 0.0
    slide = _norm(tx, ty, tz)
    if slide > 0.0:
        mx, my, mz = mx + tx / slide, my + ty / slide, mz + tz / slide
    sx, sy, sz = _steer(mx, my, mz, vx, vy, vz, p[_VMAX], planar)
    h = p[_H]
    return _truncate(sx / h, sy / h, sz / h, p[_AMAX])


@njit(cache=True)
def _steer_chunk(
    g, rows, v, vs, p, lead, kinds, crows, offsets, nb, nl, tp, tn, x_before, acc, x_out, v_out,
    begin, end,
):  # fmt: skip  # pragma: no cover - compiled
    """Steer the boids at sorted positions ``begin .. end − 1`` (``vs`` gathered for all)."""
    x, y, z, order = g.x, g.y, g.z, g.order
    r2, sep, sep2, cos_half = p[_R2], p[_SEP], p[_SEP] * p[_SEP], p[_COS]
    vmax, vmin, amax, h = p[_VMAX], p[_VMIN], p[_AMAX], p[_H]
    planar = p[_PLANAR] != 0.0
    runs = np.empty((27, 2), dtype=np.int64)
    m = 0
    qx = qy = qz = np.int64(0)
    for s in range(begin, end):
        xi, yi, zi = x[s], y[s], z[s]
        vx, vy, vz = vs[s, 0], vs[s, 1], vs[s, 2]
        speed = _norm(vx, vy, vz)
        see_all = cos_half < -1.0 or speed == 0.0
        ux = uy = uz = 0.0
        if not see_all:
            ux, uy, uz = vx / speed, vy / speed, vz / speed
        cx, cy, cz = cell_of(xi, yi, zi, g.inv_cell)
        if s == begin or cx != qx or cy != qy or cz != qz:
            m = neighbour_runs(g, cx, cy, cz, runs)
            qx, qy, qz = cx, cy, cz
        mates = 0
        ax = ay = az = 0.0  # Σ v_j
        bx = by = bz = 0.0  # Σ (x_j − x_i)
        sx = sy = sz = 0.0  # the crowding vector S
        for k in range(m):
            for t in range(runs[k, 0], runs[k, 1]):
                if t == s:
                    continue
                dx, dy, dz = x[t] - xi, y[t] - yi, z[t] - zi
                d2 = dx * dx + dy * dy + dz * dz
                if d2 > r2:
                    continue
                if not see_all and dx * ux + dy * uy + dz * uz < cos_half * math.sqrt(d2):
                    continue
                mates += 1
                ax += vs[t, 0]
                ay += vs[t, 1]
                az += vs[t, 2]
                bx += dx
                by += dy
                bz += dz
                if d2 < sep2 and d2 > 0.0:
                    dist = math.sqrt(d2)
                    push = (min(sep / dist, MAX_CROWDING) - 1.0) / dist
                    sx -= dx * push
                    sy -= dy * push
                    sz -= dz * push
        fx = fy = fz = 0.0
        if mates:
            ex, ey, ez = _steer(sx, sy, sz, vx, vy, vz, vmax, planar)
            w = p[_WSEP] * (_norm(sx, 0.0, sz) if planar else _norm(sx, sy, sz))
            fx, fy, fz = fx + w * ex, fy + w * ey, fz + w * ez
            ex, ey, ez = _steer(ax, ay, az, vx, vy, vz, vmax, planar)
            w = p[_WALI]
            fx, fy, fz = fx + w * ex, fy + w * ey, fz + w * ez
            ex, ey, ez = _steer(bx, by, bz, vx, vy, vz, vmax, planar)
            w = p[_WCOH]
            fx, fy, fz = fx + w * ex, fy + w * ey, fz + w * ez
        w = p[_WGOAL]
        if w > 0.0:
            ex, ey, ez = _steer(p[_GX] - xi, p[_GY] - yi, p[_GZ] - zi, vx, vy, vz, vmax, planar)
            fx, fy, fz = fx + w * ex, fy + w * ey, fz + w * ez
        w = p[_WLEAD]
        if w > 0.0 and lead.shape[0]:
            nearest, best = 0, math.inf
            for j in range(lead.shape[0]):
                dist = _norm(lead[j, 0] - xi, lead[j, 1] - yi, lead[j, 2] - zi)
                if dist < best:
                    nearest, best = j, dist
            ex, ey, ez = _steer(
                lead[nearest, 0] - xi, lead[nearest, 1] - yi, lead[nearest, 2] - zi,
                vx, vy, vz, vmax, planar,
            )  # fmt: skip
            fx, fy, fz = fx + w * ex, fy + w * ey, fz + w * ez
        ox, oy, oz = _avoid(xi, yi, zi, vx, vy, vz, p, kinds, crows, offsets, nb, nl, tp, tn)
        fx, fy, fz = _truncate(fx, fy, fz, amax - _norm(ox, oy, oz))
        fx, fy, fz = fx + ox, fy + oy, fz + oz
        i = order[s]
        acc[i, 0], acc[i, 1], acc[i, 2] = fx, fy, fz
        wx, wy, wz = vx + h * fx, vy + h * fy, vz + h * fz
        row = rows[i]
        if planar:
            wy = 0.0
            x_out[row, 1] = x_before[row, 1]
        speed = _norm(wx, wy, wz)
        if speed > vmax:
            wx, wy, wz = wx * (vmax / speed), wy * (vmax / speed), wz * (vmax / speed)
        elif 0.0 < speed < vmin:
            wx, wy, wz = wx * (vmin / speed), wy * (vmin / speed), wz * (vmin / speed)
        v_out[row, 0], v_out[row, 1], v_out[row, 2] = wx, wy, wz


@njit(cache=True, parallel=True)
def _steer_parallel(
    g, rows, v, vs, p, lead, kinds, crows, offsets, nb, nl, tp, tn, x_before, acc, x_out, v_out
):  # pragma: no cover - compiled
    """:func:`_steer_chunk` over chunks of :data:`CHUNK` sorted boids on every core, after
    the velocities are gathered (the chunks read each other's)."""
    n = g.order.shape[0]
    tasks = (n + CHUNK - 1) // CHUNK
    for task in prange(tasks):
        _gather_velocities(
            g.order, rows, v, vs, p[_VMAX], task * CHUNK, min(n, task * CHUNK + CHUNK)
        )
    for task in prange(tasks):
        begin, end = task * CHUNK, min(n, task * CHUNK + CHUNK)
        _steer_chunk(
            g, rows, v, vs, p, lead, kinds, crows, offsets, nb, nl, tp, tn, x_before, acc,
            x_out, v_out, begin, end,
        )  # fmt: skip
