"""How a ``cloth_mesh`` is built: its mesh file read (if it names one), then a particle at each
vertex, stretch springs on the edges and bending springs across them, drawn by its
triangles."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ...deformables import SpringNetwork, cloth_mesh
from ..deformable_build import deformable_build
from ..mesh_files import with_mesh_file
from .schema import ClothMesh

__all__ = ["BUILD"]


def _network(entity: ClothMesh) -> SpringNetwork:
    return cloth_mesh(
        np.array(entity.vertices, dtype=np.float64),
        np.array(entity.triangles, dtype=np.int64).reshape(-1, 3),
        entity.areal_density,
        entity.stiffness,
        entity.bending,
    )


def _prepare(entity: Any, where: str) -> Any:
    def check(vertices: np.ndarray, triangles: np.ndarray) -> None:
        cloth_mesh(vertices, triangles, entity.areal_density, entity.stiffness, entity.bending)

    return with_mesh_file(entity, where, check, tuple(entity.pinned))


BUILD = replace(deformable_build("cloth_mesh", _network, "vertices"), prepare=_prepare)
