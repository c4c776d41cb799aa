"""Names the scene vocabulary gave up, and what replaced them.

One quantity has one name across kinds (issue 26, "One vocabulary"): ``stiffness``,
``bending``, ``shear`` and ``damping`` [N·s/m] for every spring kind; rates in 1/s end in
``_rate``; ``areal_density`` [kg/m²] for sheets beside ``density`` [kg/m³] for volumes; a
field that takes degrees ends in ``_deg``; boids bound an acceleration, ``max_acceleration``.
A scene file (or a :class:`~visviva.model.SceneBuilder` call) that still uses an old name is
refused with the new one named, at the field: ``entities[2].bend: field "bend" of cloth
"sheet" was renamed; did you mean "bending"?`` (:mod:`.scene_errors`,
:mod:`visviva.model.builder`, and the named systems' parameters in :mod:`.build`).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any

__all__ = [
    "RENAMED_FIELDS",
    "RENAMED_PARAMETERS",
    "entity_owner",
    "new_name",
    "renamed_message",
]

_SHEET = MappingProxyType({"stretch": "stiffness", "bend": "bending", "density": "areal_density"})

#: Entity type → {old field: new field}.
RENAMED_FIELDS: MappingProxyType[str, MappingProxyType[str, str]] = MappingProxyType(
    {
        "cloth": _SHEET,
        "cloth_mesh": _SHEET,
        "soft_lattice": MappingProxyType({"stretch": "stiffness"}),
        "body": MappingProxyType(
            {"linear_damping": "linear_damping_rate", "angular_damping": "angular_damping_rate"}
        ),
        "emitter": MappingProxyType({"spread": "spread_deg"}),
        "boids": MappingProxyType({"fov": "fov_deg", "max_force": "max_acceleration"}),
    }
)

#: Named system (``type = "system"``) → {old parameter: new parameter}.
RENAMED_PARAMETERS: MappingProxyType[str, MappingProxyType[str, str]] = MappingProxyType(
    {"constrained-pendulum": MappingProxyType({"stabilization": "stabilization_rate"})}
)


def new_name(kind: str, old: str) -> str | None:
    """The new name of the field ``old`` of an entity of type ``kind``, if it was renamed."""
    table = RENAMED_FIELDS.get(kind)
    return None if table is None else table.get(old)


def renamed_message(old: str, new: str, owner: str, what: str = "field") -> str:
    """``field "bend" of cloth "sheet" was renamed; did you mean "bending"?``: the ``what``
    called ``old`` of ``owner`` (see :func:`entity_owner`) is now called ``new``."""
    return f'{what} "{old}" of {owner} was renamed; did you mean "{new}"?'


def entity_owner(kind: str, name: Any = None) -> str:
    """An entity of type ``kind`` in a message: ``cloth "sheet"`` if it is called ``name``,
    else ``the cloth entity``."""
    return f'{kind} "{name}"' if isinstance(name, str) else f"the {kind} entity"
