"""The scene table of a force field on particles, or gravitation among them (``type = "force"``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Literal, get_args

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..fields import (
    Finite,
    Name,
    Names,
    NonNegative,
    Positive,
    Strict,
    Vector,
)
from ..methods import Builds, Triple, given

__all__ = ["FORCE_KINDS", "FORCE_PARAMETERS", "ForceField"]


ForceKind = Literal[
    "drag", "wind", "quadratic_drag", "damping", "attractor", "vortex", "gravitation"
]


FORCE_KINDS: tuple[str, ...] = get_args(ForceKind)


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


class ForceFieldMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_force(
        self: Builds,
        kind: str,
        *,
        targets: Sequence[str] | None = None,
        coefficient: float | None = None,
        velocity: Triple | None = None,
        rate: float | None = None,
        point: Triple | None = None,
        strength: float | None = None,
        softening: float | None = None,
        axis: Triple | None = None,
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
        return self.add("force", **given(locals()))
