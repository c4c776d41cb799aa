"""Mechanics in generalized coordinates and gravitation."""

from __future__ import annotations

from . import chaos, classic
from .classic import (
    constrained_pendulum,
    damped_oscillator,
    double_pendulum,
    pendulum,
    pendulum_period,
    rock,
    spring_pendulum,
)
from .lagrangian import LagrangianSystem

__all__: list[str] = [
    "LagrangianSystem",
    "chaos",
    "classic",
    "constrained_pendulum",
    "damped_oscillator",
    "double_pendulum",
    "pendulum",
    "pendulum_period",
    "rock",
    "spring_pendulum",
]
