"""The scene table of a named mechanical system (``type = "system"``)."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Literal

from pydantic import Field, field_validator
from pydantic_core import PydanticCustomError

from ..._registry import did_you_mean
from ..fields import (
    Finite,
    Name,
    Strict,
)
from ..methods import Builds, given

__all__ = ["RENAMED_PARAMETERS", "System"]

#: Named system → {parameter it gave up: its replacement} (issue 26, one vocabulary).
RENAMED_PARAMETERS = MappingProxyType(
    {"constrained-pendulum": MappingProxyType({"stabilization": "stabilization_rate"})}
)


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
        from .systems import SYSTEMS

        if system not in SYSTEMS:
            raise PydanticCustomError(
                "unknown_system",
                "unknown system.{hint} Valid: {valid}",
                {"hint": did_you_mean(system, SYSTEMS), "valid": ", ".join(SYSTEMS)},
            )
        return system


class SystemMethods:
    """The builder's method of this kind (:mod:`visviva.entities.methods`)."""

    def add_system(
        self: Builds,
        system: str,
        parameters: Mapping[str, float] | None = None,
        *,
        name: str | None = None,
    ) -> int:
        """Add a named system (``visviva schema`` lists them: ``pendulum``, ``kepler``, ...)
        with parameter values (omitted ones take their defaults)."""
        return self.add("system", **given(locals()))
