"""Mass-spring deformables: the spring topologies of ropes, hair, spring graphs, cloth (grids
and triangle meshes) and soft bodies (lattices and tetrahedral meshes), built as particles
joined by :class:`~visviva.forces.Springs`."""

from .meshes import cloth_mesh, soft_mesh
from .topology import (
    DeformableError,
    SpringNetwork,
    cloth_grid,
    hair,
    rope,
    soft_lattice,
    spring_graph,
)

__all__ = [
    "DeformableError",
    "SpringNetwork",
    "cloth_grid",
    "cloth_mesh",
    "hair",
    "rope",
    "soft_lattice",
    "soft_mesh",
    "spring_graph",
]
