"""Mass properties of the primitive shapes in closed form, for a uniform density ρ [kg/m³].

Conventions, shared with the scene builder: Y is up; each shape is centred on the origin of its
coordinates, except the cone, whose base lies in the plane y = 0 and apex at y = h; the axis of
the cylinder, the capsule and the cone is +y. Every result is about the centre of mass, in the
shape's axes. With m = ρ V:

=========  ============================  ===========  ========================================
shape      dimensions                    V            inertia about the centre of mass
=========  ============================  ===========  ========================================
box        full edges a, b, c            abc          m (b² + c², a² + c², a² + b²)/12
sphere     radius r                      4πr³/3       2mr²/5 about every axis
ellipsoid  semi-axes a, b, c             4πabc/3      m (b² + c², a² + c², a² + b²)/5
cylinder   radius r, height h            πr²h         Iₓₓ = I_zz = m (3r² + h²)/12, I_yy = mr²/2
cone       base radius r, height h       πr²h/3       Iₓₓ = I_zz = m (3r²/20 + 3h²/80),
                                                      I_yy = 3mr²/10; centre of mass y = h/4
capsule    radius r, height h between    πr²h         see :func:`capsule_mass_properties`
           the hemispheres' centres      + 4πr³/3
=========  ============================  ===========  ========================================

The cone's figures are about its centre of mass, a quarter of the height above the base: about
the apex, Iₓₓ = m (3r²/20 + 3h²/5), and the parallel-axis shift by 3h/4 removes m (3h/4)².
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validation import describe, with_article
from ..errors import ModelError
from .mass_properties import MassProperties

__all__ = [
    "box_mass_properties",
    "capsule_mass_properties",
    "cone_mass_properties",
    "cylinder_mass_properties",
    "ellipsoid_mass_properties",
    "sphere_mass_properties",
]


def dimension(shape: str, name: str, value: Any, unit: str, *, zero: bool = False) -> float:
    """``value`` as a positive (or, with ``zero``, non-negative) finite float, or a
    ModelError naming ``name`` of a ``shape``."""
    requirement = "zero or positive" if zero else "positive"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(
            f"`{name}` of {with_article(shape)} must be a {requirement} number in {unit} "
            f"(got {describe(value)})"
        )
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number) or not (number >= 0.0 if zero else number > 0.0):
        raise ModelError(
            f"`{name}` of {with_article(shape)} must be {requirement} and finite, in {unit} "
            f"(got {describe(value)})"
        )
    return number


def dimensions3(shape: str, name: str, value: Any, meaning: str) -> np.ndarray:
    """``value`` as three positive finite floats [m], or a ModelError naming ``name``."""
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        array = None
    if array is None or array.shape != (3,):
        raise ModelError(
            f"`{name}` of {with_article(shape)} must be 3 positive numbers in m, its {meaning} "
            f"(got {describe(value)})"
        )
    bad = ~(np.isfinite(array) & (array > 0.0))
    if bad.any():
        raise ModelError(
            f"`{name}` of {with_article(shape)} must be 3 positive finite numbers in m, its "
            f"{meaning}; "
            f"entry {int(np.flatnonzero(bad)[0])} is {describe(array[bad][0])}"
        )
    return array


def _density(shape: str, value: Any) -> float:
    return dimension(shape, "density", value, "kg/m³")


def _result(
    shape: str,
    described: str,
    density: float,
    volume: float,
    moments: tuple[float, float, float],
    center_y: float = 0.0,
) -> MassProperties:
    """The validated properties, or a ModelError when float64 cannot hold them."""
    mass = density * volume
    figures = np.array([volume, mass, *moments])
    if not (np.isfinite(figures).all() and (figures > 0.0).all()):
        raise ModelError(
            f"{with_article(shape)} of {described} and `density` {density!r} kg/m³ has volume "
            f"{volume:.3g} "
            f"m³, mass {mass:.3g} kg and principal moments {describe(np.array(moments))} "
            "kg·m²: beyond what float64 holds (about 1e-308 to 1e308); express its "
            "dimensions and density in other units"
        )
    return MassProperties(mass, np.array([0.0, center_y, 0.0]), np.diag(moments), volume)


def box_mass_properties(extents: Any, density: Any) -> MassProperties:
    """A box of full edge lengths ``extents`` ``(a, b, c)`` [m] along x, y, z, centred on the
    origin: V = abc, I = m diag(b² + c², a² + c², a² + b²)/12.

    >>> box_mass_properties([1.0, 2.0, 3.0], density=1000.0).inertia.diagonal().tolist()
    [6500.0, 5000.0, 2500.0]
    """
    a, b, c = dimensions3("box", "extents", extents, "full edge lengths along x, y, z").tolist()
    rho = _density("box", density)
    volume = a * b * c
    m = rho * volume
    moments = (m * (b * b + c * c) / 12.0, m * (a * a + c * c) / 12.0, m * (a * a + b * b) / 12.0)
    return _result("box", f"extents {describe([a, b, c])} m", rho, volume, moments)


def sphere_mass_properties(radius: Any, density: Any) -> MassProperties:
    """A solid sphere of ``radius`` [m] centred on the origin: V = 4πr³/3, I = 2mr²/5 E."""
    r = dimension("sphere", "radius", radius, "m")
    rho = _density("sphere", density)
    volume = 4.0 / 3.0 * math.pi * r * r * r
    moment = 0.4 * rho * volume * r * r
    return _result("sphere", f"radius {r!r} m", rho, volume, (moment, moment, moment))


def ellipsoid_mass_properties(semi_axes: Any, density: Any) -> MassProperties:
    """A solid ellipsoid of ``semi_axes`` ``(a, b, c)`` [m] along x, y, z, centred on the
    origin: V = 4πabc/3, I = m diag(b² + c², a² + c², a² + b²)/5."""
    a, b, c = dimensions3("ellipsoid", "semi_axes", semi_axes, "semi-axes along x, y, z").tolist()
    rho = _density("ellipsoid", density)
    volume = 4.0 / 3.0 * math.pi * a * b * c
    m = rho * volume
    moments = (m * (b * b + c * c) / 5.0, m * (a * a + c * c) / 5.0, m * (a * a + b * b) / 5.0)
    return _result("ellipsoid", f"semi-axes {describe([a, b, c])} m", rho, volume, moments)


def cylinder_mass_properties(radius: Any, height: Any, density: Any) -> MassProperties:
    """A solid cylinder of ``radius`` and ``height`` [m], axis along y, centred on the origin:
    V = πr²h, Iₓₓ = I_zz = m (3r² + h²)/12, I_yy = mr²/2."""
    r = dimension("cylinder", "radius", radius, "m")
    h = dimension("cylinder", "height", height, "m")
    rho = _density("cylinder", density)
    volume = math.pi * r * r * h
    m = rho * volume
    across = m * (3.0 * r * r + h * h) / 12.0
    described = f"radius {r!r} m, height {h!r} m"
    return _result("cylinder", described, rho, volume, (across, 0.5 * m * r * r, across))


def cone_mass_properties(radius: Any, height: Any, density: Any) -> MassProperties:
    """A solid right circular cone of base ``radius`` and ``height`` [m], base in the plane
    y = 0 and apex at y = h: V = πr²h/3, centre of mass (0, h/4, 0), and about it
    Iₓₓ = I_zz = m (3r²/20 + 3h²/80), I_yy = 3mr²/10."""
    r = dimension("cone", "radius", radius, "m")
    h = dimension("cone", "height", height, "m")
    rho = _density("cone", density)
    volume = math.pi * r * r * h / 3.0
    m = rho * volume
    across = m * (0.15 * r * r + 0.0375 * h * h)
    described = f"radius {r!r} m, height {h!r} m"
    return _result("cone", described, rho, volume, (across, 0.3 * m * r * r, across), 0.25 * h)


def capsule_mass_properties(radius: Any, height: Any, density: Any) -> MassProperties:
    """A capsule: a cylinder of ``radius`` and ``height`` [m] (axis along y, centred on the
    origin) capped by two hemispheres of the same radius, whose centres are ``height`` apart;
    its total length is h + 2r. A height of zero is a sphere.

    With m_c = ρπr²h (the cylinder) and m_s = 4ρπr³/3 (both hemispheres):
    I_yy = m_c r²/2 + 2 m_s r²/5 and Iₓₓ = I_zz = m_c (r²/4 + h²/12) + m_s (2r²/5 + h²/4 + 3hr/8).
    Each hemisphere's term: its inertia about its flat face's centre, 2(m_s/2)r²/5, less the
    shift to its own centre of mass 3r/8 inside, plus the shift from there to the origin
    h/2 + 3r/8 away: (m_s/2)(2r²/5 − (3r/8)² + (h/2 + 3r/8)²).
    """
    r = dimension("capsule", "radius", radius, "m")
    h = dimension("capsule", "height", height, "m", zero=True)
    rho = _density("capsule", density)
    cylinder = math.pi * r * r * h
    spheres = 4.0 / 3.0 * math.pi * r * r * r
    m_c = rho * cylinder
    m_s = rho * spheres
    along = 0.5 * m_c * r * r + 0.4 * m_s * r * r
    across = m_c * (0.25 * r * r + h * h / 12.0) + m_s * (
        0.4 * r * r + 0.25 * h * h + 0.375 * h * r
    )
    described = f"radius {r!r} m, height {h!r} m"
    return _result("capsule", described, rho, cylinder + spheres, (across, along, across))
