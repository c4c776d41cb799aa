"""Mass-spring deformables: the spring topologies of ropes, cloth and soft lattices (and, next,
hair and meshes), built as particles joined by :class:`~visviva.forces.Springs`."""

from .topology import SpringNetwork, cloth_grid, rope, soft_lattice

__all__ = ["SpringNetwork", "cloth_grid", "rope", "soft_lattice"]
