"""How every deformable body is built: its particles and springs from its spring network, its
handle, and what the outputs draw of it.

Each kind gives the function that turns its table into a
:class:`~visviva.deformables.SpringNetwork` (a rope's chain, a cloth's grid, a mesh's edges);
:func:`deformable_build` makes the kind's :class:`~.kind.KindBuild` from it: the body's points
are its particles (pinned ones held by no force), its springs one
:class:`~visviva.forces.Springs` resting at their lengths as built (or as given), its
``handle`` a motion of its pinned points (:mod:`visviva.particles.handles`), and its drawing
its surface's triangles (cloth, soft bodies) or its stretch springs as lines (ropes, hair,
spring graphs; bending and torsion springs skip points and are not drawn).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from ..deformables import DeformableError, SpringNetwork
from ..deformables.topology import STRETCH
from ..errors import ModelError
from ..forces.springs import Springs
from ..particles.emitters import unit_vector
from ..particles.handles import HandleMotion
from .checks import check_lengths
from .context import BuildContext, Located, ParticleRows
from .kind import HOLDS, KindBuild

__all__ = ["body_networks", "deformable_build", "located"]

#: Each deformable kind's network function, by kind (filled as their build modules load).
_NETWORKS: dict[str, Callable[[Any], SpringNetwork]] = {}


def located(where: str, error: ModelError, field: str | None = None) -> Located:
    """``error`` located at the entity ``where``: at the field and item a
    :class:`~visviva.deformables.DeformableError` names, else at ``field`` if given."""
    if isinstance(error, DeformableError):
        where += f".{error.field}" + ("" if error.index is None else f"[{error.index}]")
    elif field is not None:
        where += f".{field}"
    return Located(where, str(error))


def deformable_build(
    kind: str,
    network: Callable[[Any], SpringNetwork],
    placed_by: str,
    points_listed: bool = False,
) -> KindBuild:
    """The build of a kind of deformable body whose table gives its spring ``network``.

    Args:
        kind: The kind's name.
        network: The body's spring network from its table.
        placed_by: The field that places its points, where points too close or too far for
            a spring are refused (``"points"``, ``"resolution"``, ``"vertices"``).
        points_listed: True if its particles are listed one by one (``points``, with
            ``velocities``, ``mass`` and ``radius`` one value or one per point); else they
            move at one ``velocity``.
    """
    _NETWORKS[kind] = network

    def rows(entity: Any, where: str, context: BuildContext) -> ParticleRows:
        try:
            body = network(entity)
        except ModelError as error:
            raise located(where, error) from None
        count = body.points.shape[0]
        if points_listed:
            listed = entity.velocities
            v = np.zeros_like(body.points) if listed is None else np.array(listed, np.float64)
        else:
            v = np.broadcast_to(np.asarray(entity.velocity, dtype=np.float64), (count, 3))
        return ParticleRows(
            body.points, v, body.mass, entity.radius, entity.color, entity.pinned, data=body
        )

    def build(entity: Any, where: str, context: BuildContext) -> None:
        body: SpringNetwork = context.data[context.index(where)]
        first = context.group(where).start
        try:
            rest = body.rest_length()
        except ModelError as error:
            raise located(where, error, placed_by) from None
        lattice = None if body.lattice is None else (body.lattice, first)
        context.springs.append(
            Springs(
                body.pairs + first,
                rest,
                body.stiffness,
                entity.damping,
                context.particle_count,
                lattice,
            )
        )
        if body.faces.shape[0]:
            context.faces.append(body.faces + first)
        else:
            context.edges.append(body.pairs[body.family == STRETCH] + first)
        if entity.handle is not None:
            held = first + np.array(sorted(set(entity.pinned)), dtype=np.int64)
            context.hold(_motion(entity.handle, held, f"{where}.handle", context), held)

    return KindBuild(
        check=(
            (lambda entity, where, scene: check_lengths(entity, where, entity.point_count))
            if points_listed
            else None
        ),
        count=lambda entity, where, context: entity.point_count,
        rows=rows,
        build=build,
        replica=lambda entity: HOLDS,
    )


def body_networks(model: Any) -> Iterator[tuple[SpringNetwork, int]]:
    """Each deformable body of ``model``: its spring network (springs with their families,
    surface) and the index of its first particle (its point ``i`` is particle ``first + i``).
    (Building the model loaded its kinds' build modules, which made their networks known.)"""
    for group in model.particle_groups:
        entity = model.scene.entities[group.entity]
        network = _NETWORKS.get(entity.type)
        if network is not None:
            yield network(entity), group.start


def _motion(handle: Any, held: np.ndarray, where: str, context: BuildContext) -> HandleMotion:
    """A handle's table in numbers (the pivot by default at its points' centroid).

    Raises:
        Located: For a motion that takes the points beyond the range of a float within the
            run.
    """
    points = context.arrays["position"][held]
    pivot = points.mean(axis=0) if handle.pivot is None else np.array(handle.pivot, dtype=float)
    axis = np.array([0.0, 1.0, 0.0])
    if handle.turns:
        try:
            axis = unit_vector("axis", handle.axis)
        except ModelError as error:
            raise Located(f"{where}.axis", str(error)) from None
    motion = HandleMotion(
        pivot=pivot,
        velocity=np.array(handle.velocity, dtype=np.float64),
        axis=axis,
        angular_velocity=handle.angular_velocity,
        amplitude=handle.amplitude,
        frequency=handle.frequency,
        start=handle.start,
        stop=math.inf if handle.stop is None else handle.stop,
        ramp=handle.ramp,
    )
    duration = context.duration
    travel, turn, spin = motion.largest_extent(duration)
    reach = float(np.abs(points - motion.pivot).max()) + travel
    if not all(math.isfinite(v) and v < 1e300 for v in (reach, turn, spin * reach)):
        raise Located(
            where,
            "this motion takes the points beyond the range of a float within the run's "
            f"duration ({duration!r} s): use smaller speeds or other units",
        )
    return motion
