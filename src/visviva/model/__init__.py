"""Scenes as data: the scene description, the builder, the frozen Model and the named systems."""

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
