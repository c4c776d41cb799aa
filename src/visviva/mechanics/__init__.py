"""Mechanics in generalized coordinates and gravitation."""

from __future__ import annotations

__all__: list[str] = []
