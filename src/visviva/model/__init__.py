"""Scenes as data: the scene description, the builder, the frozen Model and the named systems."""

from .build import build_model
from .builder import SceneBuilder
from .model import Integration, Model, ParticleGroup, SystemInstance
from .scene import Scene
from .systems import SYSTEMS

__all__ = [
    "SYSTEMS",
    "Integration",
    "Model",
    "ParticleGroup",
    "Scene",
    "SceneBuilder",
    "SystemInstance",
    "build_model",
]
