"""What a recording keeps of a scene's state: its parts, under the state's names, and what
to draw.

Per frame (:func:`frame_fields`), following the recording convention of
:mod:`visviva.simulation.recording` (a field that is a part of the state has the part's name):

    particle_position     (N, 3) [m]   the particles' positions
    particle_velocity     (N, 3) [m/s] their velocities
    particle_alive        (N,) bool    with emitters, or stages that remove particles (a
                                       crowd's exits): which slots hold a live particle
    particle_radius       (N,) [m]     with emitters: radii as they grow and shrink
    particle_color        (N, 3)       with colour ramps: sRGB colours in [0, 1]
    system_points         (S, 3) [m]   each named system's picture (a pendulum's pivot and
                                       bob, gravitating bodies), drawn after the particles
    system_velocity       (S, 3) [m/s] the velocities of those points, when every system
                                       drawn is of gravitating bodies (their coordinates)
    generalized_position  (m,)         the named systems' coordinates (and velocities), unless
                                       every system is of gravitating bodies, whose coordinates
                                       are already their points
    y                     (n,)         a first-order system's state
    body_origin           (B, 3) [m]   each rigid body's own origin (its surface's coordinates
                                       start there), not its centre of mass as in the state
    body_orientation      (B, 4)       unit quaternions (w, x, y, z), body to world

Once (:func:`static_fields`): the particles' masses (``particle_mass``), the radii and colours
that do not change (``particle_radius``, ``particle_color``, and ``system_radius`` and
``system_color`` for the systems' points beside them), and what to draw between the drawn
points (the particles, then the systems' points; point indices, the systems' shifted past the
particles):

    faces   (F, 3) int64  the surfaces of cloth and soft bodies (see
                          :mod:`visviva.deformables.surfaces`)
    edges   (E, 2) int64  the stretch springs of the bodies without a surface (ropes, hair,
                          spring graphs), then the systems' links

the static colliders' surfaces (``scenery_*``, :mod:`visviva.entities.collider.outputs`: what
the kinds record of their own, :attr:`Model.recorded_once`), and the rigid
bodies' surfaces in their own axes (:func:`visviva.rigid.surfaces.body_surface`),
body after body, with their colours and centres of mass (see
:mod:`visviva.simulation.body_geometry`; their names go in the attributes,
:func:`recording_attrs`):

    body_vertices         (V, 3) [m]     body_triangles        (T, 3) int64
    body_vertex_start     (B + 1,) int64 body_triangle_start   (B + 1,) int64
    body_color            (B, 3)         body_center           (B, 3) [m]

Recording the origin rather than the centre of mass lets every output place a body's surface
with its transform alone (``origin + R(q) v``), as USD and glTF transforms do.

A body with a surface is drawn by it alone, not by its springs too. The video draws lines
1.5 px wide whatever the mesh: on a 20 × 20 cloth they made a clear wireframe, but on a 1 m
cloth of 64 × 64 points framed as in the ``cloth-hang`` demo at 960 × 540 (cells of about
3 px) they covered the fabric in a dark mat that hid its shading and folds. The USD and glTF
exports would also repeat every spring beside the mesh, as curves and lines.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..geometry.packing import packed_surfaces
from ..geometry.quaternions import quaternion_rotate
from ..particles.emitters import ramp_values
from ..rigid.surfaces import body_surface

if TYPE_CHECKING:
    from ..model import Model
    from ..ode.state import State
    from ..rigid.bodies import RigidBodies

__all__ = ["UNITS", "frame_fields", "recording_attrs", "static_fields"]

#: The units of the recorded fields and static arrays (those not listed have none).
UNITS = {
    "particle_position": "m",
    "particle_velocity": "m/s",
    "particle_radius": "m",
    "particle_mass": "kg",
    "system_points": "m",
    "system_velocity": "m/s",
    "system_radius": "m",
    "body_origin": "m",
    "body_vertices": "m",
    "body_center": "m",
    "scenery_vertices": "m",
    "body_contact_point": "m",
    "energy": "J",
    "generalized_position": "",
    "generalized_velocity": "",
}


def _system_points(model: Model, state: State) -> list[np.ndarray]:
    """Each drawable system's points for this state, ``(P_s, 3)``."""
    if not model.systems:
        return []
    if "y" in state.names():
        parts: tuple[np.ndarray, ...] = (state["y"][None],)
        return [p[0] for s in model.systems if (p := s.points(model.gravity, parts)) is not None]
    q, v = state["generalized_position"], state["generalized_velocity"]
    pictures = []
    for system in model.systems:
        a, b = system.offset, system.offset + system.size
        points = system.points(model.gravity, (q[None, a:b], v[None, a:b]))
        if points is not None:
            pictures.append(points[0])
    return pictures


def _kills(model: Model) -> bool:
    """True if a stage may remove particles (a crowd's exits): ``particle_alive`` is then
    recorded."""
    return any(stage.kills_particles for stage in model.stages)


def _varying_color(model: Model) -> bool:
    return any(e.color_ramp.shape[0] > 1 for e in model.emitters)


def frame_fields(model: Model, state: State) -> dict[str, np.ndarray]:
    """One frame of ``state`` as recorded fields (see the module docstring)."""
    fields: dict[str, np.ndarray] = {}
    if model.particle_count:
        fields["particle_position"] = state["particle_position"]
        fields["particle_velocity"] = state["particle_velocity"]
        if model.emitters or _kills(model):
            fields["particle_alive"] = state["particle_alive"]
        if model.emitters:
            fields["particle_radius"] = state["particle_radius"]
            if _varying_color(model):
                fields["particle_color"] = _colors(model, state).astype(np.float32)
    pictures = _system_points(model, state)
    if pictures:
        fields["system_points"] = np.concatenate(pictures) if len(pictures) > 1 else pictures[0]
    if model.systems and "y" not in state.names():
        v = state["generalized_velocity"]
        drawn = [s for s in model.systems if s.drawn]
        if drawn and all(s.gravitating for s in drawn):
            fields["system_velocity"] = np.concatenate(
                [v[s.offset : s.offset + s.size].reshape(-1, 3) for s in drawn]
            )
        if not all(s.gravitating for s in model.systems):
            fields["generalized_position"] = state["generalized_position"]
            fields["generalized_velocity"] = v
    if "y" in state.names():
        fields["y"] = state["y"]
    if model.bodies is not None:
        orientation = state["body_orientation"]
        center = quaternion_rotate(orientation, model.bodies.center)
        fields["body_origin"] = state["body_position"] - center
        fields["body_orientation"] = np.array(orientation)
    return fields


def _colors(model: Model, state: State) -> np.ndarray:
    """Particle colours: each emitter's ramp at its particles' age fractions."""
    colors = np.array(model.particle_color)
    if not model.emitters:
        return colors
    age, lifetime = state["particle_age"], state["particle_lifetime"]
    for spec in model.emitters:
        slots = slice(spec.first_slot, spec.first_slot + spec.capacity)
        with np.errstate(invalid="ignore", divide="ignore"):
            fraction = np.nan_to_num(age[slots] / lifetime[slots])
        colors[slots] = ramp_values(spec.color_ramp, fraction)
    return colors


def _system_radius(model: Model) -> float:
    """The radius drawn for systems' points beside particles: the particles' median."""
    return float(np.median(model.particle_radius)) if model.particle_count else 0.05


def static_fields(model: Model) -> dict[str, np.ndarray]:
    """Arrays recorded once (see the module docstring)."""
    static: dict[str, np.ndarray] = {}
    start = model.initial_state()
    extra = sum(p.shape[0] for p in _system_points(model, start))
    count = model.particle_count
    if count:
        static["particle_mass"] = np.array(model.particle_mass)
        if not model.emitters:
            static["particle_radius"] = np.array(model.particle_radius)
        if extra:  # the systems' points beside particles are drawn at their median radius
            static["system_radius"] = np.full(extra, _system_radius(model))
        if not _varying_color(model) and (model.emitters or np.any(model.particle_color != 1.0)):
            static["particle_color"] = _colors(model, start)
        if extra and (_varying_color(model) or "particle_color" in static):
            static["system_color"] = np.ones((extra, 3))
    edges, faces = list(model.edges), list(model.faces)
    first = count
    for system, points in zip(
        [s for s in model.systems if s.drawn],
        _system_points(model, start),
        strict=True,
    ):
        own = system.edges
        if own is not None:
            edges.append(np.array(own, dtype=np.int64) + first)
        first += points.shape[0]
    if edges:
        static["edges"] = np.concatenate(edges)
    if faces:
        static["faces"] = np.concatenate(faces)
    if model.bodies is not None:
        static |= _body_surfaces(model.bodies)
    return static | dict(model.recorded_once)


def _body_surfaces(bodies: RigidBodies) -> dict[str, np.ndarray]:
    """The rigid bodies' drawing surfaces, body after body, and their colours and centres."""
    surfaces = [body_surface(shape) for shape in bodies.shapes]
    return packed_surfaces(surfaces, "body") | {
        "body_color": np.array(bodies.color, dtype=np.float64),
        "body_center": np.array(bodies.center, dtype=np.float64),
    }


def recording_attrs(model: Model) -> dict[str, Any]:
    """Attributes a recording keeps of the scene besides its arrays: whether it is
    conservative (its energy change is then the integrator's error), the bodies' names, the
    drawn colliders' names."""
    bodies = {} if model.bodies is None else {"body_names": list(model.bodies.names)}
    return {"conservative": model.conservative} | bodies | dict(model.recorded_attrs)
