"""How ``crowd`` entities are built: one crowd stage for all of them
(:class:`~visviva.particles.crowd.Crowd`), each crowd a group of its agents.

Besides the schema's checks of each field, the crowd refuses here what only the placed scene
shows: agents that are not plain particles, an agent in two crowds, walls that are not
colliders, a goal or an exit inside a wall, agents overlapping a wall, agents below or above
every exit, a step too long for the model's relaxation or body force, and values whose forces
overflow.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..._registry import did_you_mean
from ..._validation import describe
from ...collision.colliders import MAX_COLLIDERS, ColliderSet
from ...errors import SceneProblem
from ...geometry.neighbour_cells import CELL_MARGIN, MAX_CELLS, MAX_COORDINATE
from ...particles.crowd import Crowd, CrowdGroup
from ...particles.crowd_kernels import wall_distances
from ..checks import check_names
from ..collider.shapes import collider_shape
from ..context import BuildContext, Located, ParticleGroup
from ..kind import KindBuild
from .schema import Crowd as CrowdEntity
from .schema import wall_indices

__all__ = ["BUILD"]

#: Largest ``(r_i + r_j)/B``: the repulsion at full overlap, ``A exp((r_i + r_j)/B)``, stays
#: a float for any ``A`` up to 10⁴ N (e⁷⁰⁰ ≈ 10³⁰⁴).
MAX_OVERLAP_RANGES = 700.0


def _check(entity: CrowdEntity, where: str, scene: Any) -> list[SceneProblem]:
    return check_names(entity.targets, where, scene)


def _build(entity: CrowdEntity, where: str, context: BuildContext) -> None:
    """A crowd's agents meet its walls through its forces only, not the collision stage."""
    walls = set(wall_indices(entity, context.scene.entities))
    context.exempt.append((context.particles_of(entity.targets), walls))


def _finish(entries: Sequence[tuple[str, CrowdEntity]], context: BuildContext) -> None:
    """The scene's crowd stage."""
    crowds = [(context.index(where), e) for where, e in entries]
    names, arrays, h = context.names, context.arrays, context.h
    groups = list(context.groups.values())
    entities = context.scene.entities
    colliders = {i: e for i, e in enumerate(entities) if e.type == "collider"}
    walls = sorted(
        {w for _, crowd in crowds for w in wall_indices(crowd, entities)},
        key=lambda i: (colliders[i].shape != "plane", i),  # planes first (ColliderSet)
    )
    if len(walls) > MAX_COLLIDERS:
        raise Located(
            f"entities[{walls[MAX_COLLIDERS]}]",
            f"crowds may have at most {MAX_COLLIDERS} walls in all",
        )
    shapes = [collider_shape(colliders[i], f"entities[{i}]") for i in walls]
    collider_set = ColliderSet(shapes)
    wall_names = [names[i] for i in walls]
    owner: dict[int, str] = {}
    specs = []
    for index, crowd in crowds:
        where = f"entities[{index}]"
        _check_walls(crowd, where, names, entities)
        agents = _agents(crowd, where, names, entities, groups, owner, names[index])
        own = tuple(walls.index(i) for i in wall_indices(crowd, entities))
        centre = np.array([e.center for e in crowd.exits], dtype=np.float64).reshape(-1, 3)
        half = 0.5 * np.array([e.size for e in crowd.exits], dtype=np.float64).reshape(-1, 3)
        exits = np.stack([centre - half, centre + half], axis=1)
        spec = CrowdGroup(
            name=names[index],
            agents=agents,
            preferred_speed=crowd.preferred_speed,
            relaxation_time=crowd.relaxation_time,
            max_speed=crowd.top_speed,
            repulsion=crowd.repulsion,
            repulsion_range=crowd.repulsion_range,
            body_stiffness=crowd.body_stiffness,
            friction=crowd.friction,
            goal=None if crowd.goal is None else np.array(crowd.goal, dtype=np.float64),
            exits=exits,
            walls=own,
        )
        _check_numbers(spec, crowd, where, arrays, h)
        _check_places(spec, crowd, where, arrays, groups, collider_set, wall_names)
        specs.append(spec)
    stage = Crowd(specs, arrays["mass"], arrays["radius"], collider_set)
    _check_reach(stage, arrays["position"], groups)
    context.stages.append(stage)


def _check_walls(crowd: CrowdEntity, where: str, names: list[str], entities: Sequence[Any]) -> None:
    if crowd.walls is None:
        return
    colliders = [names[i] for i, e in enumerate(entities) if e.type == "collider"]
    for k, wall in enumerate(crowd.walls):
        if wall not in colliders:
            raise Located(
                f"{where}.walls[{k}]",
                f"no collider is called {wall!r}.{did_you_mean(wall, colliders)} Colliders: "
                f"{', '.join(colliders) or 'none'}",
            )


def _agents(
    crowd: CrowdEntity,
    where: str,
    names: list[str],
    entities: Sequence[Any],
    groups: Sequence[ParticleGroup],
    owner: dict[int, str],
    name: str,
) -> np.ndarray:
    """The particle indices of a crowd's agents (each entity in one crowd at most)."""
    chosen = []
    for k, target in enumerate(crowd.targets):
        index = names.index(target)  # build's target check found it
        entity = entities[index]
        if entity.type not in ("particles", "particle_cloud"):
            raise Located(
                f"{where}.targets[{k}]",
                f"a crowd's agents are the particles of a particles or particle_cloud entity; "
                f"{target!r} is of type {entity.type}",
            )
        if index in owner:
            raise Located(
                f"{where}.targets[{k}]",
                f"the particles of {target!r} already walk in crowd {owner[index]!r}: an agent "
                "belongs to one crowd",
            )
        owner[index] = name
        group = next(g for g in groups if g.entity == index)
        chosen.append(np.arange(group.start, group.start + group.count, dtype=np.int64))
    return np.unique(np.concatenate(chosen))


def _check_numbers(
    spec: CrowdGroup, crowd: CrowdEntity, where: str, arrays: dict[str, np.ndarray], h: float
) -> None:
    """The step against the relaxation time and the body force, and forces that overflow."""
    mass = arrays["mass"][spec.agents]
    radius = arrays["radius"][spec.agents]
    if not h < spec.relaxation_time:
        raise Located(
            f"{where}.relaxation_time",
            f"the step h = {h!r} s must be shorter than the relaxation time tau "
            f"({spec.relaxation_time!r} s), better by ten times: the drive relaxes the velocity "
            "by 1 - h/tau per step; use a smaller dt or more substeps",
        )
    if spec.body_stiffness > 0.0:
        limit = 2.0 / math.sqrt(2.0 * spec.body_stiffness / float(mass.min()))
        if not h < limit:
            raise Located(
                f"{where}.body_stiffness",
                f"the step h = {h!r} s must be below 2/sqrt(2k/m) = {limit:.3g} s for two "
                f"agents pressed together (k = {spec.body_stiffness!r} kg/s^2, lightest agent "
                f"{float(mass.min())!r} kg): use a smaller dt or more substeps",
            )
    widest = 2.0 * float(radius.max())
    if widest / spec.repulsion_range > MAX_OVERLAP_RANGES:
        raise Located(
            f"{where}.repulsion_range",
            f"the repulsion at full overlap, A exp(2r/B), overflows a float: 2r/B = "
            f"{widest / spec.repulsion_range:.3g} for the widest agents (r = "
            f"{widest / 2!r} m); use B of at least {widest / MAX_OVERLAP_RANGES:.3g} m",
        )
    with np.errstate(over="ignore"):
        kick = (
            h
            / float(mass.min())
            * (
                spec.repulsion * math.exp(widest / spec.repulsion_range)
                + spec.body_stiffness * widest
            )
        )
    if not math.isfinite(kick):
        raise Located(
            f"{where}.repulsion",
            "the forces at full overlap overflow a float (A exp(2r/B) + 2kr, times h/m): use "
            "smaller `repulsion` or `body_stiffness`",
        )


def _check_places(
    spec: CrowdGroup,
    crowd: CrowdEntity,
    where: str,
    arrays: dict[str, np.ndarray],
    groups: Sequence[ParticleGroup],
    walls: ColliderSet,
    wall_names: list[str],
) -> None:
    """Goal and exits outside the walls, agents clear of them and within the exits' heights."""
    kernel = walls.kernel_arrays[1:]
    own = list(spec.walls)
    position = arrays["position"][spec.agents]
    heights = np.unique(position[:, 1])
    if spec.goal is not None and own:
        at_heights = np.repeat(spec.goal[None], heights.shape[0], axis=0)
        at_heights[:, 1] = heights
        inside = wall_distances(at_heights, kernel)[:, own] < 0.0
        if inside.any():
            wall = wall_names[own[int(np.argwhere(inside)[0][1])]]
            raise Located(
                f"{where}.goal",
                f"the goal {describe(spec.goal.tolist())} lies inside the wall {wall!r}: put the "
                "goal outside the walls",
            )
    if own and spec.exits.shape[0]:
        centres = 0.5 * spec.exits[:, 0] + 0.5 * spec.exits[:, 1]  # no overflow near 1.8e308
        inside = wall_distances(np.ascontiguousarray(centres), kernel)[:, own] < 0.0
        if inside.any():
            e, w = (int(v) for v in np.argwhere(inside)[0])
            raise Located(
                f"{where}.exits[{e}]",
                f"the exit's centre {describe(centres[e].tolist())} lies inside the wall "
                f"{wall_names[own[w]]!r}: put the exits outside the walls",
            )
    radius = arrays["radius"][spec.agents]
    if own:
        clearance = wall_distances(np.ascontiguousarray(position), kernel)[:, own]
        clearance -= radius[:, None]
        if (clearance < 0.0).any():
            a, w = (int(v) for v in np.argwhere(clearance < 0.0)[0])
            _refuse_agent(
                spec.agents[a], groups,
                f"overlaps the wall {wall_names[own[w]]!r}: its centre is "
                f"{clearance[a, w] + radius[a]:.4g} m from it, less than its radius "
                f"{float(radius[a])!r} m; place the agents at least a radius away from the "
                "walls (or leave that collider out of the crowd's `walls`)",
            )  # fmt: skip
    if spec.exits.shape[0]:
        y = position[:, 1]
        within = (spec.exits[None, :, 0, 1] <= y[:, None]) & (
            y[:, None] <= spec.exits[None, :, 1, 1]
        )
        stranded = ~within.any(axis=1)
        if stranded.any():
            a = int(np.argmax(stranded))
            _refuse_agent(
                spec.agents[a], groups,
                f"stands at height y = {float(y[a])!r} m, outside the height range of every exit "
                f"of crowd {spec.name!r}: it could never leave; make the "
                "exits' `size` span the agents' heights",
            )  # fmt: skip


def _refuse_agent(particle: int, groups: Sequence[ParticleGroup], what: str) -> None:
    group = next(g for g in groups if g.start <= particle < g.start + g.count)
    raise Located(
        f"entities[{group.entity}]",
        f"agent {particle - group.start} of {group.name!r} {what}",
    )


def _check_reach(
    stage: Crowd,
    position: np.ndarray,
    groups: Sequence[ParticleGroup],
) -> None:
    """Agents within the neighbour grid's reach (2⁴⁰ cells of the interaction radius)."""
    reach = min(MAX_CELLS * stage.interaction_radius * CELL_MARGIN, MAX_COORDINATE) / 2.0
    far = np.abs(position[stage.agents][:, [0, 2]]).max(axis=1) > reach
    if far.any():
        _refuse_agent(
            int(stage.agents[int(np.argmax(far))]), groups,
            f"lies beyond {reach:.3g} m from the origin, out of the reach of the crowd's "
            "neighbour grid: move the crowd nearer the origin",
        )  # fmt: skip


BUILD = KindBuild(check=_check, build=_build, finish=_finish)
