"""The scene description: what a scene (a ``.toml`` / ``.json`` file, or a
:class:`~visviva.model.SceneBuilder`) may hold, as plain data validated by pydantic 2.

Unknown keys are errors (``extra="forbid"``), every number must be finite, a value of the wrong
type is refused rather than converted (``dt = "0.005"`` and ``duration = true`` are errors; an
integer is accepted where a real number belongs), and each entity carries a ``type`` tag that
selects its kind: its table is validated by that kind's schema (:mod:`visviva.entities`, the
built-in kinds and those of installed plugins). ``visviva schema`` prints the JSON Schema built
from these classes for editor completion. Cross-entity rules (unique names, targets that exist,
total sizes) live in :mod:`visviva.model.build`, which turns a validated :class:`Scene` into the
frozen :class:`~visviva.model.Model`. Files are read and written by :mod:`visviva.io.scene_files`;
nothing here knows about files.

"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union, get_args

from pydantic import (
    BaseModel,
    Field,
    GetCoreSchemaHandler,
    GetJsonSchemaHandler,
    TypeAdapter,
    ValidationError,
    field_validator,
)
from pydantic_core import CoreSchema, PydanticCustomError, core_schema

from .._registry import did_you_mean
from ..entities import entity_kinds
from ..entities.fields import MAX_PARTICLES, Name, NonNegative, Positive, Strict, Vector

__all__ = [
    "MAX_PARTICLES",
    "OUTPUT_FORMATS",
    "Entities",
    "Integration",
    "Output",
    "OutputFormat",
    "Scene",
    "SceneInfo",
    "World",
]

#: Output formats ``visviva run`` can write besides ``recording.h5`` and ``summary.json``.
OutputFormat = Literal["mp4", "gif", "html", "usd", "glb", "obj", "pc2"]
OUTPUT_FORMATS: tuple[str, ...] = get_args(OutputFormat)

#: Most steps between recorded frames: a run takes at most 1e9 steps (model.MAX_STEPS).
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


class OutputCamera(Strict):
    """``[output] camera``: the view of videos and the viewer's first view."""

    eye: Vector = Field(description="camera position [m]")
    target: Vector = Field(description="point at the centre of the picture [m]")
    up: Vector = Field((0.0, 1.0, 0.0), description="direction shown upward (the viewer: +Y)")
    fov: Annotated[float, Field(strict=False, gt=0, lt=180, allow_inf_nan=False)] = Field(
        45.0, description="vertical field of view [degrees]"
    )

    def text(self) -> str:
        """``"eye=x,y,z target=x,y,z up=x,y,z fov=deg"``: how recordings keep it and
        ``--camera`` takes it (:func:`visviva.viz.framing.parse_camera`)."""

        def numbers(vector: Any) -> str:
            return ",".join(repr(float(v)) for v in vector)

        return (
            f"eye={numbers(self.eye)} target={numbers(self.target)} up={numbers(self.up)} "
            f"fov={float(self.fov)!r}"
        )


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
    camera: OutputCamera | None = Field(
        None, description="the view {eye, target, up, fov}; default: a framing (see frame)"
    )
    style: Literal["auto", "day", "night"] = Field(
        "auto",
        description="how videos and the viewer draw the points: auto, day (shaded spheres on "
        "a ground) or night (spots of light on a night sky: fireworks, galaxies)",
    )
    follow: Name | None = Field(
        None, description="a rigid body the camera follows, moving with it (instead of camera)"
    )
    frame: Name = Field(
        "all",
        description="without camera, what the view keeps in the picture for the whole run: "
        "all, or the name of one rigid body",
    )


class Entities:
    """The scene's list of entities, each validated by the schema of its kind (its ``type``),
    from the registry of kinds at the time (:func:`visviva.entities.entity_kinds`: the built-in
    kinds and those of installed plugins). Problems are located at the entity's index and
    field, as pydantic locates a table's (``entities[3].stiffness``)."""

    @classmethod
    def __get_pydantic_core_schema__(cls, source: Any, handler: GetCoreSchemaHandler) -> CoreSchema:
        return core_schema.no_info_plain_validator_function(_entities)

    @classmethod
    def __get_pydantic_json_schema__(
        cls, schema: CoreSchema, handler: GetJsonSchemaHandler
    ) -> dict[str, Any]:
        tables = tuple(kind.schema for kind in entity_kinds().values())
        union: TypeAdapter[Any] = TypeAdapter(
            Annotated[Union[tables], Field(discriminator="type")]  # type: ignore[arg-type]  # noqa: UP007
        )
        return {"type": "array", "items": handler(union.core_schema)}


def _entities(value: Any) -> list[BaseModel]:
    """Each entity validated by its kind's schema (an entity already validated is kept)."""
    if not isinstance(value, (list, tuple)):
        raise PydanticCustomError("list_type", "must be a list of entity tables")
    kinds = entity_kinds()
    entities: list[BaseModel] = []
    errors: list[Any] = []
    for index, item in enumerate(value):
        tag = getattr(item, "type", None)  # an entity table already validated keeps its schema
        if isinstance(item, BaseModel) and tag in kinds and type(item) is kinds.get(tag).schema:
            entities.append(item)
            continue
        raw = item.model_dump() if isinstance(item, BaseModel) else item
        tag = raw.get("type") if isinstance(raw, dict) else None
        if not isinstance(raw, dict):
            error = PydanticCustomError("dict_type", "must be a table of the entity's fields")
            errors.append({"type": error, "loc": (index,), "input": raw})
        elif not isinstance(tag, str) or tag not in kinds:
            error = PydanticCustomError("union_tag_invalid", "unknown entity type")
            errors.append({"type": error, "loc": (index,), "input": raw})
        else:
            try:
                entities.append(kinds.get(tag).schema.model_validate(raw))
            except ValidationError as invalid:
                errors += [_at(index, problem) for problem in invalid.errors(include_url=False)]
    if errors:
        raise ValidationError.from_exception_data("entities", errors)
    return entities


def _at(index: int, problem: Any) -> dict[str, Any]:
    """A problem of entity ``index``'s table as a problem of the scene's entity list: its
    type, message and context as they were, its location under the entity's index."""
    message = problem["msg"].replace("{", "{{").replace("}", "}}")
    error = PydanticCustomError(problem["type"], message, problem.get("ctx"))
    return {"type": error, "loc": (index, *problem["loc"]), "input": problem["input"]}


class Scene(Strict):
    """A whole scene."""

    scene: SceneInfo = SceneInfo()
    world: World = World()
    integration: Integration = Integration()
    output: Output = Output()
    entities: Annotated[list[Any], Entities] = Field(default_factory=list)
