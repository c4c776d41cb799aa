"""The scene description: what a scene (a ``.toml`` / ``.json`` file, or a
:class:`~visviva.model.SceneBuilder`) may hold, as plain data validated by pydantic 2.

Unknown keys are errors (``extra="forbid"``), every number must be finite, a value of the wrong
type is refused rather than converted (``dt = "0.005"`` and ``duration = true`` are errors; an
integer is accepted where a real number belongs), and each entity
carries a ``type`` tag that selects its fields. ``visviva schema`` prints the JSON Schema built
from these classes for editor completion. Cross-entity rules (unique names, targets that exist,
total sizes) live in :mod:`visviva.model.build`, which turns a validated :class:`Scene` into the
frozen :class:`~visviva.model.Model`. Files are read and written by :mod:`visviva.io.scene_files`;
nothing here knows about files.

Entities (``[[entities]]``, each with a ``type``): ``particles`` and ``particle_cloud`` (particles
placed once), ``emitter`` (particles born and dying over time), the deformable bodies of
:mod:`.scene_bodies` (``rope``, ``hair``, ``springs``, ``cloth``, ``cloth_mesh``,
``soft_lattice``, ``soft_mesh``: particles joined by springs), ``body`` (a rigid body,
:mod:`.scene_rigid`), ``system`` (a named mechanical
system: pendulums, Kepler orbits, star clusters...), ``force`` (a force field on particles, or
gravitation among them), ``collider`` (a static shape particles bounce off), ``boids``
(a flock: Reynolds' steering of the particles it names, :mod:`.scene_boids`) and
``particle_collisions`` (particles colliding with each other as spheres,
:mod:`.scene_contacts`); ``crowd`` makes particles pedestrians (the social-force model,
:mod:`.scene_crowd`). The value types
the tables share are in :mod:`.scene_fields`.
"""

from __future__ import annotations

from typing import Annotated, Literal, get_args

from pydantic import BaseModel, Field, field_validator, model_validator
from pydantic_core import PydanticCustomError

from .._registry import did_you_mean
from .scene_bodies import Cloth, ClothMesh, Hair, Rope, SoftLattice, SoftMesh, SpringGraph
from .scene_boids import Boids
from .scene_contacts import ParticleCollisionSettings
from .scene_crowd import Crowd
from .scene_fields import (
    MAX_PARTICLES,
    Color,
    Finite,
    Fraction,
    Name,
    NonNegative,
    Positive,
    Strict,
    Vector,
)
from .scene_rigid import RigidBody

__all__ = [
    "COLLIDER_SHAPES",
    "EMITTER_SHAPES",
    "ENTITY_TYPES",
    "FORCE_KINDS",
    "MAX_PARTICLES",
    "OUTPUT_FORMATS",
    "Boids",
    "Burst",
    "Cloth",
    "ClothMesh",
    "Collider",
    "Crowd",
    "Emitter",
    "Entity",
    "ForceField",
    "Hair",
    "Integration",
    "Output",
    "ParticleCloud",
    "ParticleCollisionSettings",
    "Particles",
    "Rope",
    "Scene",
    "SceneInfo",
    "SoftLattice",
    "SoftMesh",
    "SpringGraph",
    "System",
    "World",
]

#: Output formats ``visviva run`` can write besides ``recording.h5`` and ``summary.json``.
OutputFormat = Literal["mp4", "gif", "html", "usd", "glb", "obj", "pc2"]
OUTPUT_FORMATS: tuple[str, ...] = get_args(OutputFormat)

#: Most steps between recorded frames: a run takes at most 1e9 steps (simulation.loop).
MAX_RECORD_EVERY = 10**9


class SceneInfo(Strict):
    """``[scene]``: what the scene is."""

    name: Name = "untitled"
    description: Annotated[str, Field(strict=True, max_length=10_000)] = ""


class World(Strict):
    """``[world]``: gravity and conventions (SI units, Y up)."""

    gravity: Vector = Field((0.0, -9.81, 0.0), description="gravitational acceleration [m/s^2]")
    up: Literal["y"] = Field("y", description="up axis; visviva is Y-up throughout")
    units: Literal["SI"] = Field("SI", description="unit system: metres, kilograms, seconds")


class Integration(Strict):
    """``[integration]``: how time advances."""

    method: Name = Field("symplectic_euler", description="integrator (visviva integrators)")
    dt: Positive = Field(1e-3, description="time step [s]")
    duration: Positive = Field(2.0, description="simulated time [s]")
    substeps: Annotated[int, Field(strict=True, ge=1, le=10_000)] = Field(
        1, description="steps per dt"
    )
    record_every: Annotated[int, Field(strict=True, ge=1, le=MAX_RECORD_EVERY)] | None = Field(
        None, description="record every k-th step (default: about 60 frames per second)"
    )
    energy_tolerance: NonNegative = Field(
        0.01,
        description="warn when the energy of a conservative scene changes by more than this "
        "fraction of its initial value",
    )

    @field_validator("method")
    @classmethod
    def _known_fixed_step_method(cls, method: str) -> str:
        from ..integrators import get, names

        if method not in names():
            raise PydanticCustomError(
                "unknown_method",
                "unknown integrator.{hint} Valid: {valid}",
                {"hint": did_you_mean(method, names()), "valid": ", ".join(names())},
            )
        if get(method).adaptive:
            raise PydanticCustomError(
                "adaptive_method",
                "scenes run with fixed steps; choose a fixed-step method such as rk4 or "
                "symplectic_euler (adaptive methods run from Python via vv.solve)",
            )
        return method


class Output(Strict):
    """``[output]``: files ``visviva run`` writes besides the recording and the summary."""

    formats: list[OutputFormat] = Field(default_factory=list, description="extra outputs")
    fps: Annotated[float, Field(strict=True, gt=0, le=1000, allow_inf_nan=False)] = Field(
        30.0, description="frames per second of videos, viewer and exports [1/s]"
    )
    speed: Positive = Field(
        1.0,
        description="simulated seconds per second of playback (1: real time; 86400: a day "
        "per second)",
    )
    trail: NonNegative = Field(
        0.0,
        description="simulated seconds of each point's path drawn behind it in the video and "
        "the viewer [s] (0: none; at most 1000 points)",
    )
    color_by: Literal["scene", "speed"] = Field(
        "scene",
        description="what colours the points of videos and the viewer: scene (the entities' "
        "colours) or speed (purple at rest to yellow at the fastest)",
    )


class Particles(Strict):
    """``type = "particles"``: particles at given positions, moving freely under the forces."""

    type: Literal["particles"]
    name: Name | None = None
    positions: Annotated[list[Vector], Field(min_length=1)] = Field(
        description="initial positions [m], one [x, y, z] per particle"
    )
    velocities: list[Vector] | None = Field(None, description="initial velocities [m/s]")
    mass: Positive | Annotated[list[Positive], Field(min_length=1)] = Field(
        1.0, description="mass [kg]: one value or one per particle"
    )
    radius: Positive | Annotated[list[Positive], Field(min_length=1)] = Field(
        0.05, description="radius [m] (drawing and collisions)"
    )
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")


class ParticleCloud(Strict):
    """``type = "particle_cloud"``: ``count`` particles placed at random in a box."""

    type: Literal["particle_cloud"]
    name: Name | None = None
    count: Annotated[int, Field(strict=True, ge=1, le=MAX_PARTICLES)] = Field(
        description="number of particles"
    )
    center: Vector = Field((0.0, 1.0, 0.0), description="centre of the box [m]")
    size: tuple[Positive, Positive, Positive] = Field(
        (1.0, 1.0, 1.0), description="edge lengths of the box [m]"
    )
    velocity: Vector = Field((0.0, 0.0, 0.0), description="mean initial velocity [m/s]")
    velocity_jitter: NonNegative = Field(
        0.0, description="standard deviation of each velocity component [m/s]"
    )
    mass: Positive = Field(1.0, description="mass of each particle [kg]")
    radius: Positive = Field(0.02, description="radius of each particle [m]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")
    seed: Annotated[int, Field(strict=True, ge=0, lt=2**63)] = Field(0, description="random seed")


class System(Strict):
    """``type = "system"``: a named mechanical system (see ``visviva run --list-systems``)."""

    type: Literal["system"]
    name: Name | None = None
    system: Name = Field(description="oscillator, pendulum, circular or test-equation")
    parameters: dict[str, Finite] = Field(
        default_factory=dict, description="parameter values; omitted ones take their defaults"
    )

    @field_validator("system")
    @classmethod
    def _known_system(cls, system: str) -> str:
        from ..model.systems import SYSTEMS

        if system not in SYSTEMS:
            raise PydanticCustomError(
                "unknown_system",
                "unknown system.{hint} Valid: {valid}",
                {"hint": did_you_mean(system, SYSTEMS), "valid": ", ".join(SYSTEMS)},
            )
        return system


Count = Annotated[int, Field(strict=True, ge=1, le=MAX_PARTICLES)]
Seed = Annotated[int, Field(strict=True, ge=0, lt=2**63)]
#: A value drawn for each particle: one number, or ``[low, high]`` for a uniform draw.
NonNegativeRange = NonNegative | tuple[NonNegative, NonNegative]
PositiveRange = Positive | tuple[Positive, Positive]
Names = Annotated[list[Name], Field(min_length=1)]

EmitterShape = Literal["point", "disc", "sphere", "box", "mesh"]
EMITTER_SHAPES: tuple[str, ...] = get_args(EmitterShape)
ForceKind = Literal[
    "drag", "wind", "quadratic_drag", "damping", "attractor", "vortex", "gravitation"
]
FORCE_KINDS: tuple[str, ...] = get_args(ForceKind)
ColliderShape = Literal["plane", "sphere", "box", "mesh"]
COLLIDER_SHAPES: tuple[str, ...] = get_args(ColliderShape)


def _ordered_range(value: float | tuple[float, float], name: str) -> None:
    if isinstance(value, tuple) and value[0] > value[1]:
        raise PydanticCustomError(
            "range_order",
            "`{name}` is a range [low, high] with low > high (got {value})",
            {"name": name, "value": list(value)},
        )


def _ramp_order(stops: list[tuple[float, ...]] | None, name: str) -> None:
    if stops is None:
        return
    ages = [stop[0] for stop in stops]
    if ages != sorted(ages):
        raise PydanticCustomError(
            "ramp_order",
            "the stops of `{name}` must be in increasing order of age fraction (got {ages})",
            {"name": name, "ages": ages},
        )


class Burst(Strict):
    """A burst: ``count`` particles born at once at ``time``."""

    time: NonNegative = Field(description="when [s]")
    count: Count = Field(description="how many particles")


class Emitter(Strict):
    """``type = "emitter"``: particles born over time from a shape, each living for its lifetime.

    Particles are born at ``rate`` per second between ``start`` and ``stop`` (the fractional
    remainder carried from step to step, so a rate of 0.5 per step gives one particle every
    other step) and in ``bursts``; each gets a speed along a direction in a cone, a lifetime, a
    radius and a colour, drawn from seeded random numbers, and ramps of colour and size over its
    life. The model keeps ``capacity`` slots for them (by default enough for every particle that
    can be alive at once).
    """

    type: Literal["emitter"]
    name: Name | None = None
    rate: NonNegative = Field(0.0, description="particles born per second [1/s]")
    start: NonNegative = Field(0.0, description="when continuous emission starts [s]")
    stop: Positive | None = Field(None, description="when it stops [s] (default: never)")
    bursts: list[Burst] = Field(default_factory=list, description="particles born at once")
    shape: EmitterShape = Field("point", description="where particles are born")
    position: Vector = Field((0.0, 0.0, 0.0), description="centre of the shape [m]")
    radius: NonNegative = Field(0.0, description="radius of a disc or sphere [m]")
    extent: tuple[Positive, Positive, Positive] = Field(
        (1.0, 1.0, 1.0), description="edge lengths of a box [m]"
    )
    normal: Vector = Field((0.0, 1.0, 0.0), description="normal of a disc")
    surface: bool = Field(False, description="born on the surface of a sphere or box")
    vertices: list[Vector] | None = Field(None, description="mesh vertices [m]")
    triangles: list[tuple[int, int, int]] | None = Field(None, description="mesh triangles")
    direction: Vector = Field((0.0, 1.0, 0.0), description="axis of the emission cone")
    spread_deg: Annotated[float, Field(strict=True, ge=0, le=180, allow_inf_nan=False)] = Field(
        0.0, description="half-angle of the emission cone [degrees]"
    )
    speed: NonNegativeRange = Field(1.0, description="initial speed [m/s] or [low, high]")
    lifetime: PositiveRange = Field(1.0, description="lifetime [s] or [low, high]")
    particle_radius: PositiveRange = Field(0.02, description="radius [m] or [low, high]")
    particle_mass: Positive = Field(0.001, description="mass of each particle [kg]")
    color: Color = Field((1.0, 1.0, 1.0), description="sRGB colour in [0, 1]")
    color_ramp: (
        Annotated[list[tuple[Fraction, Fraction, Fraction, Fraction]], Field(min_length=1)] | None
    ) = Field(None, description="[[age fraction, r, g, b], ...]: colour over each particle's life")
    size_ramp: Annotated[list[tuple[Fraction, NonNegative]], Field(min_length=1)] | None = Field(
        None, description="[[age fraction, scale], ...]: radius factor over each particle's life"
    )
    capacity: Count | None = Field(None, description="particle slots (default: enough)")
    seed: Seed = Field(0, description="random seed")

    @model_validator(mode="after")
    def _consistent(self) -> Emitter:
        for name in ("speed", "lifetime", "particle_radius"):
            _ordered_range(getattr(self, name), name)
        _ramp_order(self.color_ramp, "color_ramp")
        _ramp_order(self.size_ramp, "size_ramp")
        if self.rate == 0.0 and not self.bursts:
            raise PydanticCustomError(
                "emits_nothing", "this emitter emits nothing: give `rate` > 0 or `bursts`"
            )
        if self.stop is not None and self.stop <= self.start:
            raise PydanticCustomError(
                "stop_before_start",
                "`stop` ({stop} s) must be after `start` ({start} s)",
                {"stop": self.stop, "start": self.start},
            )
        for name in ("direction", "normal"):
            if not any(getattr(self, name)):
                raise PydanticCustomError(
                    "zero_vector", "`{name}` must not be the zero vector", {"name": name}
                )
        if (self.shape == "mesh") != (self.vertices is not None or self.triangles is not None):
            raise PydanticCustomError(
                "mesh_fields",
                '`vertices` and `triangles` belong to (and are needed by) shape = "mesh"',
            )
        if self.shape == "mesh" and (self.vertices is None or self.triangles is None):
            raise PydanticCustomError(
                "mesh_fields", 'shape = "mesh" needs both `vertices` and `triangles`'
            )
        return self


#: The parameters of each force kind: name → required (True) or optional (False).
FORCE_PARAMETERS: dict[str, dict[str, bool]] = {
    "drag": {"coefficient": True},
    "wind": {"velocity": True, "coefficient": True},
    "quadratic_drag": {"coefficient": True, "velocity": False},
    "damping": {"rate": True},
    "attractor": {"point": True, "strength": True, "softening": False},
    "vortex": {
        "point": False,
        "axis": False,
        "circulation": True,
        "coefficient": True,
        "core_radius": False,
    },
    "gravitation": {"G": False, "softening": False, "method": False, "theta": False},
}


class ForceField(Strict):
    """``type = "force"``: a force on particles (all of them, or the entities in ``targets``).

    Kinds and their parameters: ``drag`` (``coefficient`` k [N·s/m]: F = −k v), ``wind``
    (``velocity`` w [m/s], ``coefficient`` k: F = −k (v − w)), ``quadratic_drag``
    (``coefficient`` c [kg/m], optional air ``velocity``: F = −c |v − w| (v − w)), ``damping``
    (``rate`` γ [1/s]: F = −γ m v), ``attractor`` (``point`` [m], ``strength`` s [m³/s²],
    negative repels, ``softening`` [m]), ``vortex`` (``point``, ``axis``, ``circulation`` Γ
    [m²/s], ``coefficient`` k, ``core_radius`` [m]) and ``gravitation`` among the targets (``G``,
    ``softening``, ``method`` direct or barnes_hut, ``theta``).
    """

    type: Literal["force"]
    name: Name | None = None
    kind: ForceKind = Field(description=", ".join(FORCE_KINDS))
    targets: Names | None = Field(None, description="entity names (default: every particle)")
    coefficient: NonNegative | None = Field(None, description="drag coefficient")
    velocity: Vector | None = Field(None, description="air velocity [m/s]")
    rate: NonNegative | None = Field(None, description="damping rate [1/s]")
    point: Vector | None = Field(None, description="centre or point on the axis [m]")
    strength: Finite | None = Field(None, description="attractor strength [m^3/s^2]")
    softening: NonNegative | None = Field(None, description="softening length [m]")
    axis: Vector | None = Field(None, description="vortex axis")
    circulation: Finite | None = Field(None, description="vortex circulation [m^2/s]")
    core_radius: Positive | None = Field(None, description="vortex core radius [m]")
    G: Positive | None = Field(None, description="constant of gravitation [m^3/(kg s^2)]")
    method: Literal["direct", "barnes_hut"] | None = Field(None, description="gravity method")
    theta: Annotated[float, Field(strict=True, gt=0, le=1)] | None = Field(
        None, description="Barnes-Hut opening angle"
    )

    @model_validator(mode="after")
    def _parameters_of_the_kind(self) -> ForceField:
        allowed = FORCE_PARAMETERS[self.kind]
        for field in FORCE_PARAMETERS_ALL:
            given = getattr(self, field) is not None
            if given and field not in allowed:
                raise PydanticCustomError(
                    "not_a_parameter",
                    "`{field}` is not a parameter of a {kind} force (its parameters: {valid})",
                    {"field": field, "kind": self.kind, "valid": ", ".join(allowed)},
                )
            if not given and allowed.get(field):
                raise PydanticCustomError(
                    "missing_parameter",
                    "a {kind} force needs `{field}` (its parameters: {valid})",
                    {"field": field, "kind": self.kind, "valid": ", ".join(allowed)},
                )
        if self.kind == "attractor" and self.softening == 0.0:
            raise PydanticCustomError(
                "softening", "an attractor's `softening` must be positive (it caps the force)"
            )
        if self.axis is not None and not any(self.axis):
            raise PydanticCustomError("zero_vector", "`axis` must not be the zero vector")
        return self


FORCE_PARAMETERS_ALL: tuple[str, ...] = tuple(
    dict.fromkeys(name for parameters in FORCE_PARAMETERS.values() for name in parameters)
)

#: The fields each collider shape uses (besides the response settings every shape has).
COLLIDER_FIELDS: dict[str, tuple[str, ...]] = {
    "plane": ("point", "normal", "thickness"),
    "sphere": ("center", "radius"),
    "box": ("center", "size", "orientation"),
    "mesh": ("vertices", "triangles"),
}
_REQUIRED_COLLIDER_FIELDS = {
    "sphere": ("radius",),
    "box": ("size",),
    "mesh": COLLIDER_FIELDS["mesh"],
}


class Collider(Strict):
    """``type = "collider"``: a static shape that particles bounce off or are pushed out of.

    Shapes: ``plane`` (``point``, outward ``normal``, optional ``thickness`` [m]: a thin wall;
    without it, a half-space), ``sphere`` (``center``, ``radius``), ``box`` (``center``, ``size``:
    edge lengths, ``orientation`` as a unit quaternion w, x, y, z) and ``mesh`` (a closed
    ``vertices`` / ``triangles`` surface). ``response = "impulse"`` reflects the normal velocity
    with ``restitution`` (seed 002: v' = v − (1 + e)(v·N)N) and applies Coulomb ``friction``;
    ``response = "penalty"`` pushes penetrating particles out with a spring of ``stiffness``
    [N/m] and a damper of ``damping`` [N·s/m] (seeds 000 and 002).
    """

    type: Literal["collider"]
    name: Name | None = None
    shape: ColliderShape = Field(description=", ".join(COLLIDER_SHAPES))
    point: Vector | None = Field(None, description="a point on a plane [m]")
    normal: Vector | None = Field(None, description="a plane's outward normal")
    thickness: Positive | None = Field(None, description="a plane's thickness [m]")
    center: Vector | None = Field(None, description="centre of a sphere or box [m]")
    radius: Positive | None = Field(None, description="a sphere's radius [m]")
    size: tuple[Positive, Positive, Positive] | None = Field(
        None, description="a box's edge lengths [m]"
    )
    orientation: tuple[Finite, Finite, Finite, Finite] | None = Field(
        None, description="a box's orientation, unit quaternion (w, x, y, z)"
    )
    vertices: Annotated[list[Vector], Field(min_length=4)] | None = Field(
        None, description="a mesh's vertices [m]"
    )
    triangles: Annotated[list[tuple[int, int, int]], Field(min_length=4)] | None = Field(
        None, description="a mesh's triangles (vertex indices, counter-clockwise from outside)"
    )
    restitution: Fraction = Field(0.5, description="coefficient of restitution e in [0, 1]")
    friction: NonNegative = Field(0.0, description="Coulomb friction coefficient")
    response: Literal["impulse", "penalty"] = Field("impulse", description="impulse or penalty")
    stiffness: Positive | None = Field(None, description="penalty spring stiffness [N/m]")
    damping: NonNegative | None = Field(None, description="penalty damper [N s/m]")
    time_of_impact: bool = Field(
        True, description="find when, within a step, a particle hits (no tunnelling)"
    )
    resting_speed: NonNegative | None = Field(
        None, description="normal speed below which a contact rests [m/s] (default: 2|g|dt)"
    )
    targets: Names | None = Field(None, description="entity names (default: every particle)")
    color: Color | None = Field(
        None, description="sRGB colour drawn in the outputs, each in [0, 1] (default: grey)"
    )

    @model_validator(mode="after")
    def _fields_of_the_shape(self) -> Collider:
        used = COLLIDER_FIELDS[self.shape]
        for shape, fields in COLLIDER_FIELDS.items():
            for field in fields:
                if field not in used and getattr(self, field) is not None:
                    raise PydanticCustomError(
                        "not_a_parameter",
                        "`{field}` belongs to a {shape} collider, not a {this} (its fields: "
                        "{valid})",
                        {
                            "field": field,
                            "shape": shape,
                            "this": self.shape,
                            "valid": ", ".join(used),
                        },
                    )
        for field in _REQUIRED_COLLIDER_FIELDS.get(self.shape, ()):
            if getattr(self, field) is None:
                raise PydanticCustomError(
                    "missing_parameter",
                    "a {shape} collider needs `{field}`",
                    {"shape": self.shape, "field": field},
                )
        if self.normal is not None and not any(self.normal):
            raise PydanticCustomError("zero_vector", "`normal` must not be the zero vector")
        penalty = self.response == "penalty"
        if not penalty and (self.stiffness is not None or self.damping is not None):
            raise PydanticCustomError(
                "not_a_parameter",
                '`{field}` belongs to response = "penalty"',
                {"field": "stiffness" if self.stiffness is not None else "damping"},
            )
        if penalty and self.stiffness is None:
            raise PydanticCustomError(
                "missing_parameter", 'response = "penalty" needs `stiffness` [N/m]'
            )
        return self


Entity = Annotated[
    Particles
    | ParticleCloud
    | Rope
    | Hair
    | SpringGraph
    | Cloth
    | ClothMesh
    | SoftLattice
    | SoftMesh
    | RigidBody
    | Emitter
    | System
    | ForceField
    | Collider
    | ParticleCollisionSettings
    | Boids
    | Crowd,
    Field(discriminator="type"),
]
ENTITY_TYPES: dict[str, type[BaseModel]] = {
    "particles": Particles,
    "particle_cloud": ParticleCloud,
    "rope": Rope,
    "hair": Hair,
    "springs": SpringGraph,
    "cloth": Cloth,
    "cloth_mesh": ClothMesh,
    "soft_lattice": SoftLattice,
    "soft_mesh": SoftMesh,
    "body": RigidBody,
    "emitter": Emitter,
    "system": System,
    "force": ForceField,
    "collider": Collider,
    "particle_collisions": ParticleCollisionSettings,
    "boids": Boids,
    "crowd": Crowd,
}


class Scene(Strict):
    """A whole scene."""

    scene: SceneInfo = SceneInfo()
    world: World = World()
    integration: Integration = Integration()
    output: Output = Output()
    entities: list[Entity] = Field(default_factory=list)
