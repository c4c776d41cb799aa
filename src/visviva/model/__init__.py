"""Scenes as data: the frozen Model, the builder and the named systems."""

from .build import build_model
from .builder import SceneBuilder
from .model import Integration, Model, ParticleGroup, SystemInstance
from .systems import SYSTEMS

__all__ = [
    "SYSTEMS",
    "Integration",
    "Model",
    "ParticleGroup",
    "SceneBuilder",
    "SystemInstance",
    "build_model",
]
