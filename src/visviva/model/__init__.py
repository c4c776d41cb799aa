"""Scenes as data: the scene description, the builder, the frozen Model and the named systems."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .build import build_model
    from .builder import SceneBuilder
    from .model import Integration, Model, ParticleGroup, SystemInstance
    from .scene import Scene
    from .scene_handles import Handle
    from .systems import SYSTEMS

__all__ = [
    "SYSTEMS",
    "Handle",
    "Integration",
    "Model",
    "ParticleGroup",
    "Scene",
    "SceneBuilder",
    "SystemInstance",
    "build_model",
]

# Names load on first use (visviva._lazy): the scene description (`scene`) is plain data, and
# `visviva schema` reads it without the builder and the physics packages it assembles.
__getattr__, __dir__ = lazy_names(
    __name__,
    __all__,
    {
        "build_model": "build",
        "SceneBuilder": "builder",
        "Integration": "model",
        "Model": "model",
        "ParticleGroup": "model",
        "SystemInstance": "model",
        "Scene": "scene",
        "Handle": "scene_handles",
        "SYSTEMS": "systems",
    },
)
