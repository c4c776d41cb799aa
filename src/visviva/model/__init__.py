"""Scenes as data: the scene description, the builder, the frozen Model and its build, generic
over the entity kinds (:mod:`visviva.entities`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names

if TYPE_CHECKING:
    from .build import build_model
    from .builder import SceneBuilder
    from .model import Integration, Model
    from .scene import Scene

__all__ = ["Integration", "Model", "Scene", "SceneBuilder", "build_model"]

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
        "Scene": "scene",
    },
)
