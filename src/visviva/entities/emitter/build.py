"""How an ``emitter`` entity is built: its spec in numbers (:class:`~visviva.particles.emitters.
EmitterSpec`), slots for every particle that can be alive at once (dead at the start), and, for
all the scene's emitters together, the emission stage (:class:`~visviva.particles.emission.
Emission`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...errors import ModelError
from ...particles.emitters import SHAPES, EmitterSpec, unit_vector, value_range
from ..context import BuildContext, Located, ParticleRows
from ..fields import MAX_PARTICLES
from ..kind import KindBuild

__all__ = ["BUILD"]


def _spec(e: Any, where: str, context: BuildContext) -> EmitterSpec:
    """The emitter in numbers; its slots (``first_slot``) are set once the block is laid out,
    and ``index`` is its order among the scene's emitters."""
    triangles = np.zeros((0, 3, 3))
    try:
        if e.shape == "mesh":
            vertices = np.asarray(e.vertices, dtype=np.float64)
            corners = np.asarray(e.triangles, dtype=np.int64)
            if corners.min() < 0 or corners.max() >= len(vertices):
                raise ModelError(
                    f"`triangles` refer to vertices outside 0..{len(vertices) - 1}: each index "
                    "must name one of the `vertices`"
                )
            triangles = vertices[corners]
            sides = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
            if not np.linalg.norm(sides, axis=1).sum() > 0.0:
                raise ModelError("the emitter's mesh has no area: its triangles are degenerate")
        spec = EmitterSpec(
            index=[w for w, _ in context.of_kind("emitter")].index(where),
            name=context.names[context.index(where)],
            first_slot=0,
            capacity=0,
            rate=e.rate,
            start=e.start,
            stop=math.inf if e.stop is None else e.stop,
            burst_times=np.array([b.time for b in e.bursts], dtype=np.float64),
            burst_counts=np.array([b.count for b in e.bursts], dtype=np.int64),
            shape=SHAPES[e.shape],
            position=np.asarray(e.position, dtype=np.float64),
            radius=e.radius,
            extent=np.asarray(e.extent, dtype=np.float64),
            normal=unit_vector("normal", e.normal),
            surface=e.surface,
            triangles=triangles,
            direction=unit_vector("direction", e.direction),
            spread=math.radians(e.spread_deg),
            speed=value_range("speed", e.speed, positive=False),
            lifetime=value_range("lifetime", e.lifetime, positive=True),
            particle_radius=value_range("particle_radius", e.particle_radius, positive=True),
            mass=e.particle_mass,
            color_ramp=np.asarray(e.color_ramp or [(0.0, *e.color)], dtype=np.float64),
            size_ramp=np.asarray(e.size_ramp or [(0.0, 1.0)], dtype=np.float64),
            seed=e.seed,
        )
    except ModelError as error:
        raise Located(where, str(error)) from None
    duration = context.duration
    if e.rate * duration >= 2.0**53:
        raise Located(
            f"{where}.rate",
            f"{e.rate * duration:.3g} births over the duration; the most an emitter may count is "
            "2^53 (9e15): lower the rate",
        )
    needed = spec.most_alive(duration)
    if e.capacity is None and needed > MAX_PARTICLES:
        raise Located(
            where,
            f"this emitter can have {needed:.3g} particles alive at once (rate × lifetime and "
            f"bursts); the limit is {MAX_PARTICLES}: lower its rate or lifetime, or set "
            "`capacity` (births beyond it are dropped and counted)",
        )
    return _with(spec, capacity=e.capacity or max(1, int(needed)))


def _with(spec: EmitterSpec, **changes: Any) -> EmitterSpec:
    return EmitterSpec(**(vars(spec) | changes))


def _count(entity: Any, where: str, context: BuildContext) -> int:
    spec = _spec(entity, where, context)
    context.data[context.index(where)] = spec  # the rows take it up
    return spec.capacity


def _rows(entity: Any, where: str, context: BuildContext) -> ParticleRows:
    spec = context.data[context.index(where)]
    x = np.zeros((spec.capacity, 3))
    color = tuple(spec.color_ramp[0, 1:])
    return ParticleRows(x, x, spec.mass, spec.particle_radius[0], color, emitted=True, data=spec)


def _finish(entries: Sequence[tuple[str, Any]], context: BuildContext) -> None:
    from ...particles.emission import Emission

    context.emitters = [
        _with(context.data[context.index(where)], first_slot=context.group(where).start)
        for where, _ in entries
    ]
    arrays = context.arrays
    context.stages.append(Emission(context.emitters, arrays["alive"], arrays["radius"]))


BUILD = KindBuild(count=_count, rows=_rows, finish=_finish)
