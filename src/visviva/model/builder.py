"""The Python way to write a scene: ``vv.SceneBuilder`` → ``build()`` → frozen Model.

The builder holds the same validated scene description a file would
(:mod:`visviva.model.scene`), so a scene built in Python and the same scene read from TOML give
the same Model, and ``vv.io.dump_scene(builder.scene)`` writes the file that reproduces it. Each
``add_*`` validates its entity at once (typed keywords; an argument left at ``None`` takes the
scene file's default) and returns the entity's index in the scene.

Every deformable body's ``pinned`` points stay where they are, unless its ``handle`` — a
:class:`~visviva.model.Handle` or a dict of its fields, as in a scene file's
``[entities.handle]`` table — moves them (:mod:`visviva.particles.handles`)::

    builder.add_hair(points, mass=5e-4, stiffness=200.0, bending=20.0,
                     handle={"pivot": (0, 1.5, 0), "angular_velocity": 1.6,
                             "start": 1.0, "stop": 2.0, "ramp": 0.25})
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Concatenate, ParamSpec

import numpy as np
from pydantic import BaseModel, ValidationError

from ..errors import SceneError, SceneProblem
from .build import build_model
from .model import Model
from .scene import (
    Collider,
    Emitter,
    ForceField,
    Integration,
    Output,
    ParticleCloud,
    Particles,
    Scene,
    System,
    World,
)
from .scene_bodies import Cloth, ClothMesh, Hair, Rope, SoftLattice, SoftMesh, SpringGraph
from .scene_boids import Boids
from .scene_contacts import ParticleCollisionSettings
from .scene_crowd import Crowd
from .scene_errors import scene_problems
from .scene_handles import Handle
from .scene_meshes import with_mesh_file
from .scene_renames import RENAMED_FIELDS, entity_owner, renamed_message
from .scene_rigid import RigidBody

__all__ = ["SceneBuilder"]

Vector = Sequence[float]
Arguments = ParamSpec("Arguments")
AddMethod = Callable[Concatenate["SceneBuilder", Arguments], int]


def _refusing_old_names(tag: str) -> Callable[[AddMethod[Arguments]], AddMethod[Arguments]]:
    """The ``add_*`` method of entity type ``tag``, refusing the field names the scene
    vocabulary gave up (:data:`~visviva.model.scene_renames.RENAMED_FIELDS`) with a
    :class:`~visviva.errors.SceneError` that names the new one, where Python would only say
    "unexpected keyword argument". The method keeps its signature (``inspect.signature``,
    ``help`` and type checkers see the typed keywords)."""
    renamed = RENAMED_FIELDS[tag]

    def decorate(method: AddMethod[Arguments]) -> AddMethod[Arguments]:
        @functools.wraps(method)
        def checked(
            self: SceneBuilder, /, *args: Arguments.args, **kwargs: Arguments.kwargs
        ) -> int:
            old = [key for key in kwargs if key in renamed]
            if old:
                where = f"entities[{len(self._scene.entities)}]"
                name = kwargs.get("name")
                raise SceneError(
                    [
                        SceneProblem(
                            f"{where}.{key}",
                            renamed_message(key, renamed[key], entity_owner(tag, name)),
                        )
                        for key in old
                    ]
                )
            return method(self, *args, **kwargs)

        return checked

    return decorate


class SceneBuilder:
    """Builds a scene step by step.

    Args:
        name: Scene name.
        description: What the scene shows.

    Example:
        >>> import visviva as vv
        >>> builder = vv.SceneBuilder(name="drop")
        >>> builder.set_integration(method="symplectic_euler", dt=0.01, duration=1.0)
        >>> builder.add_particles([[0.0, 2.0, 0.0]], mass=0.5, name="ball")
        0
        >>> builder.add_force("drag", coefficient=0.1, targets=["ball"])
        1
        >>> builder.add_collider("plane", point=(0, 0, 0), normal=(0, 1, 0), restitution=0.8)
        2
        >>> model = builder.build()
        >>> model.particle_count, float(model.particle_mass[0]), len(model.forces)
        (1, 0.5, 2)
    """

    def __init__(self, *, name: str = "untitled", description: str = "") -> None:
        self._scene = _validated(Scene, "scene", scene={"name": name, "description": description})

    @classmethod
    def from_scene(cls, scene: Scene) -> SceneBuilder:
        """A builder holding an already validated scene (for example one read from a file)."""
        builder = cls()
        builder._scene = scene
        return builder

    @property
    def scene(self) -> Scene:
        """The validated scene description so far."""
        return self._scene

    def set_world(self, *, gravity: Vector = (0.0, -9.81, 0.0)) -> None:
        """Set the gravitational acceleration [m/s²] (Y up) acting on every particle."""
        self._replace(world=_validated(World, "world", gravity=gravity))

    def set_integration(
        self,
        *,
        method: str | None = None,
        dt: float | None = None,
        duration: float | None = None,
        substeps: int | None = None,
        record_every: int | None = None,
        energy_tolerance: float | None = None,
    ) -> None:
        """Set the integrator ``method``, the step ``dt`` [s], the ``duration`` [s], the
        ``substeps`` per step, ``record_every`` k-th step, and the ``energy_tolerance``."""
        self._replace(integration=_validated(Integration, "integration", **_given(locals())))

    def set_output(
        self,
        *,
        formats: Sequence[str] | None = None,
        fps: float | None = None,
        speed: float | None = None,
        trail: float | None = None,
        color_by: str | None = None,
    ) -> None:
        """Set the extra output ``formats`` of ``visviva run``, their ``fps``, ``speed``
        (simulated seconds per second of playback), ``trail`` [s] and ``color_by``
        (``"scene"`` or ``"speed"``)."""
        self._replace(output=_validated(Output, "output", **_given(locals())))

    def add_particles(
        self,
        positions: Any,
        *,
        velocities: Any = None,
        mass: float | Sequence[float] | None = None,
        radius: float | Sequence[float] | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add particles at ``positions`` [m] ``(n, 3)`` with ``velocities`` [m/s], ``mass`` [kg]
        and ``radius`` [m] (one value or one per particle) and an sRGB ``color``."""
        return self._add(Particles, "particles", _given(locals()))

    def add_particle_cloud(
        self,
        count: int,
        *,
        center: Vector | None = None,
        size: Vector | None = None,
        velocity: Vector | None = None,
        velocity_jitter: float | None = None,
        mass: float | None = None,
        radius: float | None = None,
        color: Vector | None = None,
        seed: int | None = None,
        name: str | None = None,
    ) -> int:
        """Add ``count`` particles at random in a box (``center``, edge lengths ``size`` [m]),
        with a mean ``velocity`` and a ``velocity_jitter`` [m/s], ``mass``, ``radius``, ``seed``."""
        return self._add(ParticleCloud, "particle_cloud", _given(locals()))

    def add_rope(
        self,
        points: Any,
        *,
        stiffness: float,
        mass: float | Sequence[float] | None = None,
        damping: float | None = None,
        bending: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocities: Any = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add a rope: particles at ``points`` [m] ``(n, 3)`` (in this order in the state) of
        ``mass`` [kg] (one value or one per point), joined in order by springs of
        ``stiffness`` [N/m] and ``damping`` [N·s/m] at rest at the points' distances;
        ``bending`` [N/m] > 0 adds springs between points two apart; the points ``pinned``
        (indices) stay where they are, or follow the ``handle``'s motion."""
        return self._add(Rope, "rope", _given(locals()))

    def add_hair(
        self,
        points: Any,
        *,
        mass: float | Sequence[float],
        stiffness: float,
        bending: float,
        torsion: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocities: Any = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add a hair strand (Selle, Lentine & Fedkiw 2008): particles at ``points`` [m]
        ``(n, 3)``, root first (in this order in the state), of ``mass`` [kg] (one value or
        one per point), joined by edge springs of ``stiffness`` [N/m] between consecutive
        points, bending springs of ``bending`` [N/m] between points two apart and torsion
        springs of ``torsion`` [N/m] (default none) between points three apart, each with
        ``damping`` [N·s/m]; the points ``pinned`` (default: the root, ``[0]``; ``[]`` for a
        free strand) stay where they are, or follow the ``handle``'s motion (a moving head).
        Selle et al.'s altitude springs are left out (see
        :mod:`visviva.deformables.topology`)."""
        return self._add(Hair, "hair", _given(locals()))

    def add_springs(
        self,
        points: Any,
        pairs: Any,
        *,
        mass: float | Sequence[float],
        stiffness: float | Sequence[float],
        rest_length: float | Sequence[float] | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocities: Any = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add particles at ``points`` [m] ``(n, 3)`` (in this order in the state) of ``mass``
        [kg] (one value or one per point) joined by a spring on each of ``pairs`` ``(S, 2)``
        (indices into ``points``, each unordered pair once), of ``stiffness`` [N/m] and
        ``rest_length`` [m] (each one value or one per spring; rest lengths by default the
        springs' lengths as built) and ``damping`` [N·s/m]; the points ``pinned`` stay where
        they are, or follow the ``handle``'s motion."""
        return self._add(SpringGraph, "springs", _given(locals()))

    @_refusing_old_names("cloth")
    def add_cloth(
        self,
        resolution: Sequence[int],
        *,
        stiffness: float,
        origin: Vector | None = None,
        along: Vector | None = None,
        across: Vector | None = None,
        areal_density: float | None = None,
        shear: float | None = None,
        bending: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Vector | None = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add a cloth: ``resolution`` = (nu, nv) points on a grid spanning ``origin + s·along
        + t·across`` [m], of ``areal_density`` [kg/m²], with structural springs of
        ``stiffness`` [N/m], shear springs of ``shear`` (default ``stiffness``) and bending
        springs of ``bending`` [N/m] (default none), each with ``damping`` [N·s/m]; point
        (i, j) has index j·nu + i, and the points ``pinned`` stay where they are, or follow the
        ``handle``'s motion."""
        given = _given(locals())
        given["resolution"] = tuple(given["resolution"])
        return self._add(Cloth, "cloth", given)

    @_refusing_old_names("soft_lattice")
    def add_soft_lattice(
        self,
        resolution: Sequence[int],
        *,
        stiffness: float,
        origin: Vector | None = None,
        size: Vector | None = None,
        density: float | None = None,
        shear: float | None = None,
        diagonal: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Vector | None = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add a soft body: ``resolution`` = (nx, ny, nz) points on a lattice filling the box
        from the corner ``origin`` with edge lengths ``size`` [m], of ``density`` [kg/m³],
        with structural springs of ``stiffness`` [N/m] and face- and body-diagonal springs of
        ``shear`` and ``diagonal`` (default ``stiffness``), each with ``damping`` [N·s/m];
        point (i, j, k) has index (k·ny + j)·nx + i; the points ``pinned`` stay where they
        are, or follow the ``handle``'s motion."""
        given = _given(locals())
        given["resolution"] = tuple(given["resolution"])
        return self._add(SoftLattice, "soft_lattice", given)

    @_refusing_old_names("cloth_mesh")
    def add_cloth_mesh(
        self,
        vertices: Any = None,
        triangles: Any = None,
        *,
        path: str | os.PathLike[str] | None = None,
        areal_density: float,
        stiffness: float,
        bending: float | None = None,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Vector | None = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add cloth on a triangle mesh: a particle at each of the ``vertices`` [m] ``(n, 3)``
        (in this order in the state) weighing the ``areal_density`` [kg/m²] times a third of
        the area of each of its ``triangles`` ``(T, 3)`` (vertex indices); stretch springs of
        ``stiffness`` [N/m] on every edge and bending springs of ``bending`` [N/m] (default
        none) between the vertices facing each other across every edge two triangles share,
        each with ``damping`` [N·s/m]. A triangle resists shear by itself: there is no shear
        family. The vertices ``pinned`` stay where they are, or follow the ``handle``'s
        motion.

        Instead of ``vertices`` and ``triangles``, ``path`` names a mesh file (OBJ, STL, PLY,
        OFF, glTF; relative to the working directory), read at once: its vertices are those
        of :func:`visviva.deformables.mesh_files.read_triangle_mesh`, which ``pinned`` indexes.
        """
        given = _given(locals())
        if "path" in given:
            given["path"] = os.fspath(given["path"])
        index = len(self._scene.entities)
        where = f"entities[{index}]"
        entity = _validated(ClothMesh, where, **(given | {"type": "cloth_mesh"}))
        self._replace(entities=[*self._scene.entities, with_mesh_file(entity, where)])
        return index

    @_refusing_old_names("body")
    def add_body(
        self,
        shape: str,
        *,
        density: float | None = None,
        mass: float | None = None,
        position: Vector | None = None,
        orientation: Sequence[float] | None = None,
        velocity: Vector | None = None,
        angular_velocity: Vector | None = None,
        size: Vector | None = None,
        radius: float | None = None,
        height: float | None = None,
        vertices: Any = None,
        triangles: Any = None,
        path: str | os.PathLike[str] | None = None,
        linear_damping_rate: float | None = None,
        angular_damping_rate: float | None = None,
        push: Sequence[Mapping[str, Any]] | None = None,
        anchor: Mapping[str, Any] | None = None,
        motion: str | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add a rigid body: a ``shape`` (``"box"`` with ``size`` [m] its full edge lengths,
        ``"sphere"`` with ``radius``, ``"ellipsoid"`` with ``size`` its semi-axes,
        ``"cylinder"``, ``"capsule"``, ``"cone"`` with ``radius`` and ``height`` along its y
        axis, ``"mesh"`` with ``vertices`` ``(V, 3)`` and ``triangles`` ``(T, 3)`` or a mesh
        file at ``path``) of uniform ``density`` [kg/m³] or total ``mass`` [kg], its own
        origin at ``position`` [m], turned by ``orientation`` (a unit quaternion (w, x, y, z),
        body to world), its centre of mass moving at ``velocity`` [m/s] and spinning at
        ``angular_velocity`` [rad/s] (world frame); ``linear_damping_rate`` and
        ``angular_damping_rate`` [1/s] damp its momenta; ``push`` is a list of forces at its
        points (``{"force": ..., "point": ..., "start": ..., "duration": ...}``) and
        ``anchor`` holds one of its points at a world point by a spring (``{"point": ...,
        "at": ..., "stiffness": ..., "damping": ...}``). ``motion``: ``"dynamic"`` (the
        default), ``"kinematic"`` (moves at its velocities whatever acts on it) or
        ``"static"`` (see :mod:`visviva.model.scene_rigid`).
        Its state is ``body_position`` (the centre of mass), ``body_orientation``,
        ``body_momentum`` and ``body_angular_momentum``."""
        given = _given(locals())
        if "path" in given:
            given["path"] = os.fspath(given["path"])
        index = len(self._scene.entities)
        where = f"entities[{index}]"
        entity = _validated(RigidBody, where, **(given | {"type": "body"}))
        self._replace(entities=[*self._scene.entities, with_mesh_file(entity, where)])
        return index

    def add_soft_mesh(
        self,
        vertices: Any,
        tetrahedra: Any,
        *,
        density: float,
        stiffness: float,
        damping: float | None = None,
        pinned: Sequence[int] | None = None,
        handle: Handle | Mapping[str, Any] | None = None,
        velocity: Vector | None = None,
        radius: float | None = None,
        color: Vector | None = None,
        name: str | None = None,
    ) -> int:
        """Add a soft body on a tetrahedral mesh: a particle at each of the ``vertices`` [m]
        ``(n, 3)`` (in this order in the state) weighing the ``density`` [kg/m³] times a
        quarter of the volume of each of its ``tetrahedra`` ``(T, 4)`` (vertex indices
        [a, b, c, d] with (b − a)·((c − a) × (d − a)) > 0), and a spring of ``stiffness``
        [N/m] and ``damping`` [N·s/m] on every edge; the vertices ``pinned`` stay where they
        are, or follow the ``handle``'s motion."""
        return self._add(SoftMesh, "soft_mesh", _given(locals()))

    def add_system(
        self, system: str, parameters: Mapping[str, float] | None = None, *, name: str | None = None
    ) -> int:
        """Add a named system (``visviva schema`` lists them: ``pendulum``, ``kepler``, ...)
        with parameter values (omitted ones take their defaults)."""
        return self._add(System, "system", _given(locals()))

    @_refusing_old_names("emitter")
    def add_emitter(
        self,
        *,
        rate: float | None = None,
        start: float | None = None,
        stop: float | None = None,
        bursts: Sequence[Mapping[str, float]] | None = None,
        shape: str | None = None,
        position: Vector | None = None,
        radius: float | None = None,
        extent: Vector | None = None,
        normal: Vector | None = None,
        surface: bool | None = None,
        vertices: Any = None,
        triangles: Any = None,
        direction: Vector | None = None,
        spread_deg: float | None = None,
        speed: float | Sequence[float] | None = None,
        lifetime: float | Sequence[float] | None = None,
        particle_radius: float | Sequence[float] | None = None,
        particle_mass: float | None = None,
        color: Vector | None = None,
        color_ramp: Sequence[Sequence[float]] | None = None,
        size_ramp: Sequence[Sequence[float]] | None = None,
        capacity: int | None = None,
        seed: int | None = None,
        name: str | None = None,
    ) -> int:
        """Add an emitter (see :class:`visviva.model.scene.Emitter` for every field): particles
        born at ``rate`` [1/s] and in ``bursts`` (``{"time": s, "count": n}``) from a ``shape``
        (point, disc, sphere, box, mesh), flying out along ``direction`` within ``spread_deg``
        [degrees] at ``speed`` [m/s], living ``lifetime`` [s]; ranges are ``[low, high]``."""
        return self._add(Emitter, "emitter", _given(locals()))

    def add_force(
        self,
        kind: str,
        *,
        targets: Sequence[str] | None = None,
        coefficient: float | None = None,
        velocity: Vector | None = None,
        rate: float | None = None,
        point: Vector | None = None,
        strength: float | None = None,
        softening: float | None = None,
        axis: Vector | None = None,
        circulation: float | None = None,
        core_radius: float | None = None,
        G: float | None = None,
        method: str | None = None,
        theta: float | None = None,
        name: str | None = None,
    ) -> int:
        """Add a force on particles (all, or the entities named in ``targets``): ``"drag"``
        (``coefficient`` k [N·s/m]: F = −k v), ``"wind"`` (``velocity``, ``coefficient``),
        ``"quadratic_drag"`` (``coefficient`` [kg/m]), ``"damping"`` (``rate`` [1/s]),
        ``"attractor"`` (``point``, ``strength`` [m³/s²], ``softening``), ``"vortex"``
        (``point``, ``axis``, ``circulation`` [m²/s], ``coefficient``, ``core_radius``) or
        ``"gravitation"`` among them (``G``, ``softening``, ``method``, ``theta``)."""
        return self._add(ForceField, "force", _given(locals()))

    def add_collider(
        self,
        shape: str,
        *,
        point: Vector | None = None,
        normal: Vector | None = None,
        thickness: float | None = None,
        center: Vector | None = None,
        radius: float | None = None,
        size: Vector | None = None,
        orientation: Sequence[float] | None = None,
        vertices: Any = None,
        triangles: Any = None,
        restitution: float | None = None,
        friction: float | None = None,
        response: str | None = None,
        stiffness: float | None = None,
        damping: float | None = None,
        time_of_impact: bool | None = None,
        resting_speed: float | None = None,
        targets: Sequence[str] | None = None,
        color: Sequence[float] | None = None,
        name: str | None = None,
    ) -> int:
        """Add a static collider: ``"plane"`` (``point``, ``normal``, optional ``thickness``),
        ``"sphere"`` (``center``, ``radius``), ``"box"`` (``center``, ``size``,
        ``orientation``) or ``"mesh"`` (``vertices``, ``triangles``), with ``restitution`` e,
        ``friction`` μ, and ``response`` ``"impulse"`` or ``"penalty"`` (``stiffness``,
        ``damping``). The outputs draw a sphere, box or mesh in its sRGB ``color`` (default
        grey); planes are not drawn."""
        return self._add(Collider, "collider", _given(locals()))

    def add_particle_collisions(
        self,
        *,
        targets: Sequence[str] | None = None,
        restitution: float | None = None,
        friction: float | None = None,
        iterations: int | None = None,
        resting_speed: float | None = None,
        name: str | None = None,
    ) -> int:
        """Make the particles of ``targets`` (default: every particle) collide with each other
        as spheres of their radii, with restitution ``e`` in [0, 1] and Coulomb ``friction``
        μ, in ``iterations`` sweeps per step; approaches slower than ``resting_speed`` [m/s]
        rest (:mod:`visviva.collision.particle_contacts`)."""
        return self._add(ParticleCollisionSettings, "particle_collisions", _given(locals()))

    @_refusing_old_names("boids")
    def add_boids(
        self,
        targets: Sequence[str],
        *,
        radius: float,
        separation: float,
        max_speed: float,
        max_acceleration: float,
        fov_deg: float | None = None,
        min_speed: float | None = None,
        separation_weight: float | None = None,
        alignment_weight: float | None = None,
        cohesion_weight: float | None = None,
        goal: Vector | None = None,
        goal_weight: float | None = None,
        leader: str | None = None,
        leader_weight: float | None = None,
        look_ahead: float | None = None,
        min_distance: float | None = None,
        plane: str | None = None,
        name: str | None = None,
    ) -> int:
        """Add a flock: Reynolds' boids steering the particles of the entities named in
        ``targets`` (:mod:`visviva.particles.boids`). Boids see flockmates within ``radius``
        [m] and the field of view ``fov_deg`` [degrees]; separation from those closer than
        ``separation`` [m], alignment and cohesion with weights [1/s]; desired speed
        ``max_speed`` [m/s], steering bounded by ``max_acceleration`` [m/s²]; an optional ``goal``
        point and ``leader`` entity (weights default to 1/s); colliders avoided from
        ``look_ahead`` [m]; no two boids left closer than ``min_distance`` [m] if given;
        ``plane="xz"`` for a 2-D flock."""
        return self._add(Boids, "boids", _given(locals()))

    def add_crowd(
        self,
        targets: Sequence[str],
        *,
        goal: Vector | None = None,
        exits: Sequence[Mapping[str, Vector]] | None = None,
        walls: Sequence[str] | None = None,
        preferred_speed: float | None = None,
        relaxation_time: float | None = None,
        max_speed: float | None = None,
        repulsion: float | None = None,
        repulsion_range: float | None = None,
        body_stiffness: float | None = None,
        friction: float | None = None,
        name: str | None = None,
    ) -> int:
        """Add a crowd: the particles of ``targets`` walk in the XZ plane to ``goal`` [m] or
        the nearest of ``exits`` (``{"center": [x, y, z], "size": [sx, sy, sz]}`` boxes that
        remove who enters), avoiding each other and the colliders named in ``walls`` (default:
        all) with the social-force model (:mod:`visviva.particles.crowd`): ``preferred_speed``
        v0 [m/s], ``relaxation_time`` tau [s], ``max_speed`` [m/s], ``repulsion`` A [N] of
        range ``repulsion_range`` B [m], ``body_stiffness`` k [kg/s²], ``friction`` kappa
        [kg/(m·s)]; defaults from Helbing, Farkas & Vicsek (2000)."""
        return self._add(Crowd, "crowd", _given(locals()))

    def build(self) -> Model:
        """Check the scene as a whole and return the frozen :class:`Model`."""
        return build_model(self._scene)

    def _add(self, schema: type[BaseModel], tag: str, fields: dict[str, Any]) -> int:
        index = len(self._scene.entities)
        entity = _validated(schema, f"entities[{index}]", **(fields | {"type": tag}))
        self._replace(entities=[*self._scene.entities, entity])
        return index

    def _replace(self, **parts: Any) -> None:
        self._scene = self._scene.model_copy(update=parts)


def _given(arguments: dict[str, Any]) -> dict[str, Any]:
    """The arguments the caller gave (not ``None``), as plain Python values (NumPy arrays and
    scalars become lists and floats, which the strict schema accepts)."""
    return {
        key: _plain(value)
        for key, value in arguments.items()
        if key != "self" and value is not None
    }


def _plain(value: Any) -> Any:
    if isinstance(value, BaseModel):  # a table given as its schema (a Handle): validated again
        return _plain(value.model_dump(exclude_none=True))
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _validated(schema: type[Any], where: str, /, **fields: Any) -> Any:
    """``schema(**fields)`` validated, with problems reported at ``where`` like a file's."""
    try:
        return schema.model_validate(fields)
    except ValidationError as exc:
        problems = scene_problems(exc, fields, lambda path: None, schema)
        for i, problem in enumerate(problems):
            path = f"{where}.{problem.path}" if problem.path else where
            problems[i] = type(problem)(path, problem.message, problem.got)
        raise SceneError(problems) from None
