"""Mass-spring deformables: the spring topologies of ropes and cloth (and, next, hair, soft
lattices and meshes), built as particles joined by :class:`~visviva.forces.Springs`."""

from .topology import SpringNetwork, cloth_grid, rope

__all__ = ["SpringNetwork", "cloth_grid", "rope"]
