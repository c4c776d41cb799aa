"""The scene file schema: what a ``.toml`` / ``.json`` scene may hold, validated by pydantic 2.

Unknown keys are errors (``extra="forbid"``), every number must be finite, a value of the wrong
type is refused rather than converted (``dt = "0.005"`` and ``duration = true`` are errors; an
integer is accepted where a real number belongs), and each entity
carries a ``type`` tag that selects its fields. ``visviva schema`` prints the JSON Schema built
from these classes for editor completion. Cross-entity rules (unique names, what may be mixed,
total sizes) live in :mod:`visviva.model.build`, which turns a validated :class:`Scene` into the
frozen :class:`~visviva.model.Model`.
"""

from __future__ import annotations

from typing import Annotated, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, field_validator
from pydantic_core import PydanticCustomError

from .._validation import did_you_mean

__all__ = [
    "MAX_PARTICLES",
    "OUTPUT_FORMATS",
    "Entity",
    "Integration",
    "Output",
    "ParticleCloud",
    "Particles",
    "Scene",
    "SceneInfo",
    "System",
    "World",
]

#: Most particles one scene may create: 50 million is ~2.4 GB of state; more is a typo.
MAX_PARTICLES = 50_000_000
#: Output formats ``visviva run`` can write besides ``recording.h5`` and ``summary.json``.
OutputFormat = Literal["mp4", "gif", "html", "usd", "glb", "obj", "pc2"]
OUTPUT_FORMATS: tuple[str, ...] = get_args(OutputFormat)

Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]
Positive = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)]
Vector = tuple[Finite, Finite, Finite]
Name = Annotated[str, Field(strict=True, min_length=1, max_length=200, pattern=r"^[^\x00-\x1f]*$")]
#: Most steps between recorded frames: a run takes at most 1e9 steps (simulation.loop).
MAX_RECORD_EVERY = 10**9


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class SceneInfo(_Strict):
    """``[scene]``: what the scene is."""

    name: Name = "untitled"
    description: Annotated[str, Field(strict=True, max_length=10_000)] = ""


class World(_Strict):
    """``[world]``: gravity and conventions (SI units, Y up)."""

    gravity: Vector = Field((0.0, -9.81, 0.0), description="gravitational acceleration [m/s^2]")
    up: Literal["y"] = Field("y", description="up axis; visviva is Y-up throughout")
    units: Literal["SI"] = Field("SI", description="unit system: metres, kilograms, seconds")


class Integration(_Strict):
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


class Output(_Strict):
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


class Particles(_Strict):
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
        0.05, description="radius [m] (drawing and, later, collisions)"
    )


class ParticleCloud(_Strict):
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
    seed: Annotated[int, Field(strict=True, ge=0, lt=2**63)] = Field(0, description="random seed")


class System(_Strict):
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


Entity = Annotated[Particles | ParticleCloud | System, Field(discriminator="type")]


class Scene(_Strict):
    """A whole scene file."""

    scene: SceneInfo = SceneInfo()
    world: World = World()
    integration: Integration = Integration()
    output: Output = Output()
    entities: list[Entity] = Field(default_factory=list)
