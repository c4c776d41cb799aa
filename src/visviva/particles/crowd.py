"""Crowds: pedestrians walking to their goals with the social-force model, through exits.

**The model.** D. Helbing & P. Molnár, "Social force model for pedestrian dynamics", Phys.
Rev. E 51, 4282 (1995), with the body-contact forces and parameters of D. Helbing, I. Farkas &
T. Vicsek, "Simulating dynamical features of escape panic", Nature 407, 487 (2000). Agent ``i``
(mass ``m_i``, radius ``r_i``: a particle of the scene) walks in the horizontal XZ plane under

* the driving term ``m_i (v⁰ e_i − v_i)/τ``: it relaxes to its preferred speed ``v⁰`` along
  its desired direction ``e_i`` in the relaxation time ``τ``;
* from every other agent ``j``, with ``d_ij`` the distance of the centres, ``r_ij = r_i + r_j``,
  ``n_ij`` the unit vector from ``j`` to ``i``, ``t_ij = (−n_ij,z, n_ij,x)`` and
  ``g(s) = max(s, 0)``: ``{A exp((r_ij − d_ij)/B) + k g(r_ij − d_ij)} n_ij
  + κ g(r_ij − d_ij) Δv^t_ji t_ij`` with ``Δv^t_ji = (v_j − v_i)·t_ij`` — a repulsion of
  strength ``A`` and range ``B``, and, when bodies touch, a body force of stiffness ``k`` and a
  sliding friction ``κ`` (for agents of two crowds, ``k`` and ``κ`` are the crowds' means, so
  the contact forces stay equal and opposite);
* the same terms against each wall (distance ``d_iW`` from the centre, ``r_i`` for ``r_ij``,
  ``n_iW`` the wall's outward normal): ``{A exp((r_i − d_iW)/B) + k g(r_i − d_iW)} n_iW
  − κ g(r_i − d_iW) (v_i·t_iW) t_iW``.

The speed is then capped at ``max_speed`` (Helbing & Molnár's ``v_max``, 1.3 v⁰ by default).
The isotropic form of the 2000 paper is used: the 1995 paper's weaker reaction to what is
behind an agent (its field-of-view factor) is not. Forces act in XZ only: an agent keeps the
height it started at (its vertical velocity is set to zero each step), so gravity and walls'
vertical normals do not move it; a wall's outward normal is projected on the plane.

**Goals.** Each crowd has a goal point, or, without one, its agents walk to the centre of the
nearest of its exits. The desired direction is the straight line to it: ``e_i = (goal −
x_i)/|goal − x_i|`` (zero at the goal). There is no path planning: an agent behind a wall
pushes into it and slides along it (the wall's repulsion takes away the normal part of its
drive); a room with one door is the case this suits, a maze is not.

**Walls** are the scene's colliders (:class:`~visviva.collision.ColliderSet`: planes with a
thickness, boxes, spheres, meshes; :func:`~visviva.collision.colliders.collider_distance` gives
the signed distance and outward normal). A crowd's agents meet its walls through the forces
above only: the collision stage leaves them out.

**Exits** are axis-aligned boxes. An agent whose centre is in one of its crowd's exits after a
step leaves: it is dead from then on (``particle_alive`` False, parked at rest at the origin like
a dead emitted particle: every output hides it; it is nobody's neighbour) and the step's end time
is kept in the carried part ``crowd_exit_time`` [s] (NaN while inside), from which the flow
through a door is counted (:func:`visviva.analysis.crowds.exit_flow`).

**Neighbours** come from the shared :class:`~visviva.geometry.neighbour_grid.NeighbourGrid`,
rebuilt each step over the live agents' ``(x, 0, z)``. The repulsion is cut where it falls below
``CUTOFF`` (10⁻³) of ``A``: at ``d_ij − r_ij = B ln(1/CUTOFF) ≈ 6.9 B`` beyond contact (0.55 m
for ``B`` = 0.08 m), so the grid's radius is ``2 r_max + 6.9 B``; the force jumps there by
``CUTOFF · A`` (2 N against a driving force of the order of ``m v⁰/τ`` ≈ 200 N).

**Time stepping.** The crowd is a post-step stage: the integrator moves the particles with the
other forces of the scene; then this stage evaluates the social forces at the new positions and
velocities and kicks the velocities by ``h F/m`` (forward Euler in the velocity, the positions
following in the next step: operator splitting, first order in ``h``). Three limits on ``h``:

* the relaxation time: the drive alone scales the velocity's distance from ``v⁰ e`` by
  ``1 − h/τ`` a step, which oscillates beyond ``h = τ``; ``h`` should be well below ``τ``;
* the body force: two agents pressed together oscillate at ``√(2k/m)``, which symplectic Euler
  follows only for ``h < 2/√(2k/m)`` (37 ms for the papers' ``k`` and 80 kg);
* none from the sliding friction, a damper of rate ``λ = κ g (1/m_i + 1/m_j)`` on the
  relative sliding of a pair overlapping by ``g`` (``κ g / m_i`` against a wall). Explicit, it
  would reverse the sliding once ``h λ > 1``: with the papers' ``κ`` and 80 kg, at overlaps
  beyond 3.3 cm at ``h`` = 5 ms, which agents placed at random or a panicking crowd reach (they
  then circle each other at full speed). So the stage applies it integrated exactly over the
  step for the pair alone: the sliding decays by ``e^(−h λ)``, i.e. the force is scaled by
  ``φ(h λ) = (1 − e^(−h λ))/(h λ)``, which is 1 − O(h λ) for small steps (the model's force) and
  never reverses a pair's sliding.

The scene builder refuses steps beyond the first two. Without noise, an arch of agents across a
narrow door can hold for good (as in granular flow): the flow then stops with agents left
inside.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from ..collision.colliders import ColliderSet
from ..errors import ModelError, SimulationError
from ..geometry.neighbour_grid import PARALLEL_MIN_POINTS, NeighbourGrid
from ..ode.stage import Phase
from .crowd_kernels import exit_agents, social_forces, walk

if TYPE_CHECKING:
    from ..ode.state import State
    from ..ode.workspace import Workspace

__all__ = ["CUTOFF", "Crowd", "CrowdGroup"]

#: The repulsion ``A exp((r − d)/B)`` is cut where it falls below this fraction of ``A``.
CUTOFF = 1e-3
#: How far beyond contact the repulsion reaches, in units of ``B``: ``ln(1/CUTOFF)``.
REACH = math.log(1.0 / CUTOFF)


@dataclass(frozen=True, eq=False)
class CrowdGroup:
    """One crowd in numbers.

    Attributes:
        name: The crowd's entity name.
        agents: The particle indices of its agents, ``(n,)`` int64.
        preferred_speed: ``v⁰`` [m/s].
        relaxation_time: ``τ`` [s].
        max_speed: ``v_max`` [m/s].
        repulsion: ``A`` [N].
        repulsion_range: ``B`` [m].
        body_stiffness: ``k`` [kg/s²].
        friction: ``κ`` [kg/(m·s)].
        goal: The goal point [m] ``(3,)`` (its x and z are used), or ``None``: the nearest exit.
        exits: Exit boxes, ``(E, 2, 3)``: low and high corners [m].
        walls: Which colliders of the stage's :class:`ColliderSet` are its walls (indices).
    """

    name: str
    agents: np.ndarray
    preferred_speed: float = 1.34
    relaxation_time: float = 0.5
    max_speed: float = 1.3 * 1.34
    repulsion: float = 2000.0
    repulsion_range: float = 0.08
    body_stiffness: float = 1.2e5
    friction: float = 2.4e5
    goal: np.ndarray | None = None
    exits: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    walls: tuple[int, ...] = ()


class Crowd:
    """The crowd stage of a scene: every crowd's agents walk, push and leave (see the module
    docstring).

    Args:
        groups: The crowds (their agents disjoint).
        mass: Every particle's mass [kg], ``(N,)``.
        radius: Every particle's radius [m], ``(N,)``.
        walls: The colliders the crowds' ``walls`` index (``None``: none).
    """

    phase: ClassVar[Phase] = Phase.BEHAVIOURS
    #: After the flocks (a scene has both only if it steers other particles).
    order: ClassVar[int] = 1
    compiled: ClassVar[bool] = False
    changes_energy: ClassVar[bool] = True
    #: Agents leave through exits: recordings keep ``alive`` per frame.
    kills_particles: ClassVar[bool] = True

    def __init__(
        self,
        groups: Sequence[CrowdGroup],
        mass: np.ndarray,
        radius: np.ndarray,
        walls: ColliderSet | None = None,
    ) -> None:
        self.groups = tuple(groups)
        self.count = int(mass.shape[0])
        #: Particle index of each agent, crowd after crowd, ``(n,)``.
        self.agents = np.concatenate(
            [np.asarray(g.agents, dtype=np.int64) for g in self.groups]
        ).astype(np.int64)
        #: Each agent's crowd, ``(n,)``.
        self.crowd = np.concatenate(
            [np.full(len(g.agents), c, dtype=np.int64) for c, g in enumerate(self.groups)]
        )
        self.mass = np.ascontiguousarray(mass[self.agents], dtype=np.float64)
        self.radius = np.ascontiguousarray(radius[self.agents], dtype=np.float64)
        self.walls = walls if walls is not None else ColliderSet([])
        self._walls = self.walls.kernel_arrays[1:]
        self.params = np.array(
            [
                (
                    g.repulsion,
                    g.repulsion_range,
                    g.body_stiffness,
                    g.friction,
                    g.preferred_speed,
                    g.relaxation_time,
                    REACH * g.repulsion_range,
                )
                for g in self.groups
            ],
            dtype=np.float64,
        ).reshape(-1, 7)
        self.max_speed = np.array([g.max_speed for g in self.groups], dtype=np.float64)
        self.has_goal = np.array([g.goal is not None for g in self.groups], dtype=np.bool_)
        self.goal = np.array(
            [(0.0, 0.0) if g.goal is None else (g.goal[0], g.goal[2]) for g in self.groups],
            dtype=np.float64,
        ).reshape(-1, 2)
        boxes = [np.asarray(g.exits, dtype=np.float64).reshape(-1, 2, 3) for g in self.groups]
        #: Exit bounds ``(E, 6)``: x low, x high, y low, y high, z low, z high [m].
        self.exits = np.ascontiguousarray(
            np.concatenate(boxes).transpose(0, 2, 1).reshape(-1, 6) if boxes else np.zeros((0, 6))
        )
        self.exit_start = np.cumsum([0] + [b.shape[0] for b in boxes]).astype(np.int64)
        self.wall_mask = np.array(
            [sum(1 << w for w in g.walls) for g in self.groups], dtype=np.uint64
        )
        #: The neighbour grid's radius [m]: the farthest two agents feel each other.
        self.interaction_radius = (
            float(2.0 * self.radius.max(initial=0.0) + self.params[:, 6].max(initial=0.0)) or 1.0
        )
        NeighbourGrid(self.interaction_radius)  # checks the radius as the grid will

    def carried_start(self) -> dict[str, np.ndarray]:
        """The carried parts this stage keeps, at the start: ``crowd_exit_time`` [s], one per
        particle, NaN until the particle (an agent) leaves."""
        return {"crowd_exit_time": np.full(self.count, np.nan)}

    def _scratch(self) -> _Scratch:
        return _Scratch(self.agents.shape[0], self.interaction_radius)

    def apply(self, before: State, after: State, h: float, work: Workspace) -> State:
        """Exits, then the social forces' kick (see the module docstring)."""
        parts = tuple(np.array(part) for part in after.parts)
        result = after.from_parts(after.t, parts)
        x, v = result["particle_position"], result["particle_velocity"]
        alive = np.array(after["particle_alive"])
        exit_time = (
            np.array(after["crowd_exit_time"])
            if "crowd_exit_time" in after.carried
            else self.carried_start()["crowd_exit_time"]
        )
        height = np.ascontiguousarray(before["particle_position"][self.agents, 1])
        x[self.agents, 1] = height  # the exits see the agents at their own height
        exit_agents(
            self.agents, alive, x, v, self.crowd, self.exits, self.exit_start, exit_time, after.t
        )
        scratch = work.get(self, self._scratch)
        try:
            self._evaluate(scratch, x, v, alive, height, h)
        except ModelError as error:  # an agent beyond the grid's reach of the origin
            names = ", ".join(g.name for g in self.groups)
            raise SimulationError(f"crowd {names}: {error}", t=after.t, step=None) from None
        walk(
            self.agents, alive, x, v, height, self.mass, scratch.drive, scratch.social,
            scratch.wall, self.max_speed, self.crowd, h,
        )  # fmt: skip
        return result.with_carried(particle_alive=alive, crowd_exit_time=exit_time)

    def _evaluate(
        self,
        scratch: _Scratch,
        x: np.ndarray,
        v: np.ndarray,
        alive: np.ndarray,
        height: np.ndarray,
        h: float,
    ) -> None:
        """The three forces on the live agents into the scratch's buffers (the sliding
        friction as a step of ``h`` [s] applies it)."""
        agents = self.agents
        live = alive[agents]
        points = scratch.points
        points[:, 0] = x[agents, 0]
        points[:, 2] = x[agents, 2]
        scratch.grid.update(points, live)
        px, pz = np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 2])
        vx, vz = np.ascontiguousarray(v[agents, 0]), np.ascontiguousarray(v[agents, 2])
        social_forces(
            scratch.grid.arrays, px, np.ascontiguousarray(height), pz, vx, vz, self.radius,
            self.mass, self.crowd, self.params, self.goal, self.has_goal, self.exits,
            self.exit_start, self.wall_mask, self._walls, h, scratch.drive, scratch.social,
            scratch.wall, int(live.sum()) >= PARALLEL_MIN_POINTS,
        )  # fmt: skip

    def forces(
        self, x: np.ndarray, v: np.ndarray, alive: np.ndarray | None = None, h: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The social forces [N] at positions ``x`` and velocities ``v`` (``(N, 3)`` each) on
        every live agent: ``(drive, agents, walls)``, each ``(N, 3)`` with zero y component
        and zero rows for other particles and dead agents (``alive`` ``(N,)``, default all).
        ``h`` [s]: the sliding friction as a step of ``h`` applies it (0: the model's force)."""
        x = np.asarray(x, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        alive = np.ones(self.count, dtype=bool) if alive is None else np.asarray(alive, bool)
        scratch = self._scratch()
        self._evaluate(scratch, x, v, alive, np.ascontiguousarray(x[self.agents, 1]), h)
        live = alive[self.agents]
        results = []
        for buffer in (scratch.drive, scratch.social, scratch.wall):
            out = np.zeros((self.count, 3))
            out[self.agents[live], 0] = buffer[live, 0]
            out[self.agents[live], 2] = buffer[live, 1]
            results.append(out)
        return results[0], results[1], results[2]


class _Scratch:
    """A run's storage for a crowd of ``count`` agents: the neighbour grid of ``radius`` [m],
    the agents' ``(x, 0, z)`` ``(count, 3)`` [m], and the driving, social and wall forces on
    each ``(count, 2)`` [N] (x and z)."""

    __slots__ = ("drive", "grid", "points", "social", "wall")

    def __init__(self, count: int, radius: float) -> None:
        self.grid = NeighbourGrid(radius)
        self.points = np.zeros((count, 3))
        self.drive = np.zeros((count, 2))
        self.social = np.zeros((count, 2))
        self.wall = np.zeros((count, 2))
