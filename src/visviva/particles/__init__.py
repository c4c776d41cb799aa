"""Particle systems: emitters, their births and deaths, and counter-based random numbers.

* :mod:`~visviva.particles.emitters`: an emitter in numbers (:class:`EmitterSpec`);
* :mod:`~visviva.particles.emission`: the stage that makes particles live and die;
* :mod:`~visviva.geometry.neighbour_grid`: which points are near which, every step (a hashed
  uniform grid; :func:`neighbours` and :class:`NeighbourGrid`);
* :mod:`~visviva.particles.boids`: flocking, Reynolds' boids as a post-step stage
  (:class:`Boids`, :func:`polarisation`);
* :mod:`~visviva.particles.crowd`: crowds, the social-force model as a post-step stage, with
  walls and exits (:class:`Crowd`);
* :mod:`~visviva.particles.random`: random numbers that depend on who a particle is, not on
  when or where it was computed.
"""

from ..geometry.neighbour_grid import NeighbourGrid, neighbours
from .boids import Boids, polarisation
from .crowd import Crowd
from .emission import Emission
from .emitters import EmitterSpec

__all__ = [
    "Boids",
    "Crowd",
    "Emission",
    "EmitterSpec",
    "NeighbourGrid",
    "neighbours",
    "polarisation",
]
