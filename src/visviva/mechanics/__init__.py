"""Mechanics in generalized coordinates and gravitation."""

from __future__ import annotations

from .lagrangian import LagrangianSystem

__all__: list[str] = ["LagrangianSystem"]
