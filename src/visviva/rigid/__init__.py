"""Rigid bodies: mass properties (closed forms, Mirtich's polyhedral integrals, sampling).

Every result is a :class:`MassProperties`: mass [kg], centre of mass [m] in the shape's
coordinates, inertia [kg·m²] about the centre of mass in the shape's axes, and volume [m³].

* :func:`mass_properties` by a shape's name and dimensions, as a scene names them;
* closed forms: :func:`box_mass_properties`, :func:`sphere_mass_properties`,
  :func:`cylinder_mass_properties`, :func:`capsule_mass_properties`,
  :func:`cone_mass_properties`, :func:`ellipsoid_mass_properties`;
* closed triangle meshes (Mirtich's algorithm): :func:`mesh_mass_properties` (a mesh file's
  arrays are :func:`visviva.io.read_triangle_mesh`'s);
* a Monte-Carlo estimate with its error bars: :func:`sampled_mass_properties`.

>>> import visviva as vv
>>> box = vv.rigid.mass_properties("box", 1000.0, size=[1.0, 2.0, 3.0])
>>> box.mass, box.inertia.diagonal().tolist()
(6000.0, [6500.0, 5000.0, 2500.0])
"""

from .mass_properties import MassProperties, check_inertia
from .mesh_integrals import mesh_mass_properties
from .primitives import (
    box_mass_properties,
    capsule_mass_properties,
    cone_mass_properties,
    cylinder_mass_properties,
    ellipsoid_mass_properties,
    sphere_mass_properties,
)
from .sampling import SampledMassProperties, sampled_mass_properties
from .shapes import SHAPES, mass_properties

__all__ = [
    "SHAPES",
    "MassProperties",
    "SampledMassProperties",
    "box_mass_properties",
    "capsule_mass_properties",
    "check_inertia",
    "cone_mass_properties",
    "cylinder_mass_properties",
    "ellipsoid_mass_properties",
    "mass_properties",
    "mesh_mass_properties",
    "sampled_mass_properties",
    "sphere_mass_properties",
]
