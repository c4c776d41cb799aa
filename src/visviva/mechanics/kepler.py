"""The two-body problem in closed form, and the Sun, the Earth and the Moon.

Two point masses attract each other; their separation ``r = x₂ − x₁`` moves on a Kepler
ellipse about the centre of mass (seed 004). With ``μ = G (m₁ + m₂)``, semi-major axis ``a``
and eccentricity ``e``, the mean motion is ``n = √(μ/a³)`` and the period ``T = 2π/n``. At
time ``t`` after periapsis the mean anomaly is ``M = n t`` and the eccentric anomaly ``E``
solves Kepler's equation ``M = E − e sin E`` (solved here by Newton's method); then, in the
orbital plane, ``ξ = a (cos E − e)``, ``η = a √(1 − e²) sin E``. Energy
``−G m₁ m₂ / (2a)`` and angular momentum ``m₁ m₂/(m₁ + m₂) · √(μ a (1 − e²))`` are constant.

Frame: the orbit lies in the x–z plane (Y is up), periapsis along +x, and the bodies go round
counter-clockwise seen from above, so the angular momentum points along +y. Reference: e.g.
H. D. Curtis, *Orbital Mechanics for Engineering Students*, ch. 3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import real_number
from ..errors import ModelError
from .gravity import GRAVITATIONAL_CONSTANT
from .nbody import Bodies

__all__ = ["KeplerOrbit", "eccentric_anomaly", "kepler_orbit", "sun_earth_moon"]

#: Newton's method on Kepler's equation stops when the update is below this [rad] ...
_ANOMALY_TOLERANCE = 1e-15
#: ... or after this many iterations (it converges in at most ~6 for e < 0.99).
_MAX_ITERATIONS = 50


def eccentric_anomaly(mean_anomaly: Any, eccentricity: float) -> np.ndarray:
    """Solve Kepler's equation ``M = E − e sin E`` for ``E`` [rad] by Newton's method.

    Args:
        mean_anomaly: ``M`` [rad], any shape.
        eccentricity: ``e`` in ``[0, 1)``.

    Example:
        >>> import numpy as np, visviva as vv
        >>> E = vv.mechanics.eccentric_anomaly(1.0, 0.5)
        >>> bool(abs(E - 0.5 * np.sin(E) - 1.0) < 1e-15)
        True
    """
    e = _eccentricity(eccentricity)
    m = np.asarray(mean_anomaly, dtype=np.float64)
    # Reduce to (−π, π]: the equation is 2π-periodic in M and E together.
    turns = np.round(m / (2.0 * math.pi))
    reduced = m - 2.0 * math.pi * turns
    # Start at M + e sin M, or at π for the nearly radial orbits where that overshoots.
    anomaly = np.where(e < 0.8, reduced + e * np.sin(reduced), math.pi * np.sign(reduced))
    for _ in range(_MAX_ITERATIONS):
        step = (anomaly - e * np.sin(anomaly) - reduced) / (1.0 - e * np.cos(anomaly))
        anomaly = anomaly - step
        if np.all(np.abs(step) <= _ANOMALY_TOLERANCE):
            break
    return anomaly + 2.0 * math.pi * turns


def _eccentricity(value: Any) -> float:
    e = real_number("eccentricity", value, nonnegative=True)
    if not e < 1.0:
        raise ModelError(
            f"`eccentricity` must be below 1 for a closed orbit (got {e!r}); 1 and above are "
            "parabolic and hyperbolic flybys"
        )
    return e


@dataclass(frozen=True)
class KeplerOrbit:
    """Two bodies on a Kepler ellipse about their centre of mass (at rest at the origin).

    Attributes:
        semi_major_axis: ``a`` of the relative orbit [m].
        eccentricity: ``e`` in ``[0, 1)``.
        masses: ``(m₁, m₂)`` [kg].
        G: Constant of gravitation [m³/(kg s²)].
    """

    semi_major_axis: float
    eccentricity: float
    masses: tuple[float, float]
    G: float = GRAVITATIONAL_CONSTANT

    @property
    def mean_motion(self) -> float:
        """``n = √(G (m₁ + m₂) / a³)`` [rad/s]."""
        return math.sqrt(self.G * sum(self.masses) / self.semi_major_axis**3)

    @property
    def period(self) -> float:
        """``T = 2π / n`` [s]."""
        return 2.0 * math.pi / self.mean_motion

    @property
    def energy(self) -> float:
        """Total energy ``−G m₁ m₂ / (2a)`` [J]."""
        return -self.G * self.masses[0] * self.masses[1] / (2.0 * self.semi_major_axis)

    @property
    def angular_momentum(self) -> float:
        """Magnitude of the total angular momentum about the centre of mass [kg m²/s]."""
        m1, m2 = self.masses
        mu = self.G * (m1 + m2)
        semi_latus = self.semi_major_axis * (1.0 - self.eccentricity**2)
        return m1 * m2 / (m1 + m2) * math.sqrt(mu * semi_latus)

    def relative_state(self, t: Any) -> tuple[np.ndarray, np.ndarray]:
        """Separation ``x₂ − x₁`` [m] and its rate [m/s] at times ``t`` [s] after periapsis.

        Returns:
            Two arrays of shape ``t.shape + (3,)``.
        """
        a, e, n = self.semi_major_axis, self.eccentricity, self.mean_motion
        anomaly = eccentric_anomaly(n * np.asarray(t, dtype=np.float64), e)
        cos_e, sin_e = np.cos(anomaly), np.sin(anomaly)
        root = math.sqrt(1.0 - e * e)
        rate = n / (1.0 - e * cos_e)  # dE/dt
        xi, eta = a * (cos_e - e), a * root * sin_e
        xi_rate, eta_rate = -a * sin_e * rate, a * root * cos_e * rate
        zero = np.zeros_like(xi)
        # In-plane (ξ, η) → world (x, z) = (ξ, −η): counter-clockwise seen from +y.
        position = np.stack([xi, zero, -eta], axis=-1)
        velocity = np.stack([xi_rate, zero, -eta_rate], axis=-1)
        return position, velocity

    def positions(self, t: Any) -> np.ndarray:
        """Positions of both bodies [m] at times ``t`` [s], shape ``t.shape + (2, 3)``."""
        return self._split(self.relative_state(t)[0])

    def velocities(self, t: Any) -> np.ndarray:
        """Velocities of both bodies [m/s] at times ``t`` [s], shape ``t.shape + (2, 3)``."""
        return self._split(self.relative_state(t)[1])

    def _split(self, relative: np.ndarray) -> np.ndarray:
        m1, m2 = self.masses
        total = m1 + m2
        return np.stack([-(m2 / total) * relative, (m1 / total) * relative], axis=-2)

    def bodies(self, t: float = 0.0) -> Bodies:
        """The two bodies at time ``t`` [s] after periapsis, as initial conditions."""
        return Bodies(self.positions(t), self.velocities(t), np.array(self.masses), self.G)


def kepler_orbit(
    semi_major_axis: float,
    eccentricity: float,
    *,
    masses: tuple[float, float],
    G: float = GRAVITATIONAL_CONSTANT,
) -> KeplerOrbit:
    """A checked :class:`KeplerOrbit`.

    Args:
        semi_major_axis: ``a`` of the relative orbit [m], positive.
        eccentricity: ``e`` in ``[0, 1)``.
        masses: ``(m₁, m₂)`` [kg], positive.
        G: Constant of gravitation [m³/(kg s²)].

    Example:
        >>> import numpy as np, visviva as vv
        >>> orbit = vv.mechanics.kepler_orbit(1.0, 0.5, masses=(1.0, 1e-3), G=1.0)
        >>> sol = vv.solve(orbit.bodies().problem(), "leapfrog", dt=orbit.period / 1000,
        ...                until=orbit.period)
        >>> bool(np.abs(sol.q[-1] - sol.q[0]).max() < 1e-3)  # back at periapsis
        True
    """
    a = real_number("semi_major_axis", semi_major_axis, positive=True, unit=" m")
    e = _eccentricity(eccentricity)
    if np.shape(masses) != (2,):
        raise ModelError(f"`masses` must be two masses (m1, m2) [kg] (got {masses!r})")
    m1, m2 = (real_number(f"masses[{k}]", m, positive=True) for k, m in enumerate(masses))
    return KeplerOrbit(a, e, (m1, m2), real_number("G", G, positive=True))


# Sun, Earth and Moon at J2000.0 (2000 January 1, 12:00 TT). Gravitational parameters GM
# [m³/s²] are known far better than G, so masses are GM / G: Sun, IAU 2015 Resolution B3
# nominal value; Earth, IERS Conventions 2010; Moon, JPL DE440 (Park et al. 2021). Earth–Moon
# barycentre: J2000 mean elements of E. M. Standish (JPL, "Keplerian elements for approximate
# positions of the major planets"): a = 1.00000261 au, e = 0.01671123, longitude of perihelion
# 102.93768193°, mean longitude 100.46457166°. au = 149,597,870,700 m (IAU 2012 B2, exact).
_ASTRONOMICAL_UNIT = 149_597_870_700.0
_GM_SUN = 1.3271244e20
_GM_EARTH = 3.986004418e14
_GM_MOON = 4.9028e12
_BARYCENTRE_ORBIT = (1.00000261 * _ASTRONOMICAL_UNIT, 0.01671123)
_PERIHELION_LONGITUDE = math.radians(102.93768193)
_MEAN_LONGITUDE = math.radians(100.46457166)
_JULIAN_CENTURY = 36525.0 * 86400.0  # s
#: Step of the central difference that gives the Moon's velocity from its position series [s].
_DIFFERENCE_STEP = 60.0

_ARCSECOND = math.pi / (180.0 * 3600.0)


def _moon_ecliptic(centuries: float) -> np.ndarray:
    """Geocentric Moon [m] in ecliptic coordinates, ``centuries`` after J2000.

    The low-precision lunar theory of O. Montenbruck & E. Gill, *Satellite Orbits*, Springer
    2000, §3.3.2 (a truncated Brown theory, about 0.1° and 500 km): the largest periodic terms
    in longitude, latitude and distance, evection and variation among them.
    """
    t = centuries
    mean_longitude = math.radians(218.31617 + 481267.88088 * t)
    lm = math.radians(134.96292 + 477198.86753 * t)  # Moon's mean anomaly
    ls = math.radians(357.52543 + 35999.04944 * t)  # Sun's mean anomaly
    f = math.radians(93.27283 + 483202.01873 * t)  # mean argument of latitude
    d = math.radians(297.85027 + 445267.11135 * t)  # mean elongation from the Sun
    sin = math.sin
    longitude_terms = (
        22640 * sin(lm) + 769 * sin(2 * lm) - 4586 * sin(lm - 2 * d) + 2370 * sin(2 * d)
        - 668 * sin(ls) - 412 * sin(2 * f) - 212 * sin(2 * lm - 2 * d)
        - 206 * sin(lm + ls - 2 * d) + 192 * sin(lm + 2 * d) - 165 * sin(ls - 2 * d)
        + 148 * sin(lm - ls) - 125 * sin(d) - 110 * sin(lm + ls) - 55 * sin(2 * f - 2 * d)
    ) * _ARCSECOND  # fmt: skip
    longitude = mean_longitude + longitude_terms
    latitude = (
        18520 * sin(f + longitude_terms + (412 * sin(2 * f) + 541 * sin(ls)) * _ARCSECOND)
        - 526 * sin(f - 2 * d) + 44 * sin(lm + f - 2 * d) - 31 * sin(-lm + f - 2 * d)
        - 25 * sin(-2 * lm + f) - 23 * sin(ls + f - 2 * d) + 21 * sin(-lm + f)
        + 11 * sin(-ls + f - 2 * d)
    ) * _ARCSECOND  # fmt: skip
    cos = math.cos
    distance = 1e3 * (
        385000 - 20905 * cos(lm) - 3699 * cos(2 * d - lm) - 2956 * cos(2 * d)
        - 570 * cos(2 * lm) + 246 * cos(2 * lm - 2 * d) - 205 * cos(ls - 2 * d)
        - 171 * cos(lm + 2 * d) - 152 * cos(lm + ls - 2 * d)
    )  # fmt: skip
    return distance * np.array(
        [cos(latitude) * cos(longitude), cos(latitude) * sin(longitude), sin(latitude)]
    )


def _ecliptic_to_world(vector: np.ndarray) -> np.ndarray:
    """Ecliptic (X to the equinox, Z to the ecliptic north) → world (x, y up, z) = (X, Z, −Y).

    So that increasing ecliptic longitude is counter-clockwise seen from +y, as everywhere.
    """
    return np.array([vector[0], vector[2], -vector[1]])


def _about_y(angle: float) -> np.ndarray:
    """Rotation by ``angle`` counter-clockwise seen from +y (x towards −z)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def sun_earth_moon(*, G: float = GRAVITATIONAL_CONSTANT) -> Bodies:
    """The Sun, the Earth and the Moon at J2000.0 in SI units, in their centre-of-mass frame.

    The ecliptic is the x–z plane with its north along +y (Y up); ecliptic longitude grows
    counter-clockwise seen from above, from +x (the J2000 equinox) towards −z. The Earth–Moon
    barycentre is placed on its J2000 mean Kepler ellipse about the Sun, and the Moon about the
    Earth by a truncated lunar theory (see the module's sources); no other planet. Total
    momentum is zero and the centre of mass is at the origin.

    Integrated, this gives a sidereal year of 365.254 d (observed 365.256 d) and a sidereal
    month of 27.28 d (observed 27.32 d: the truncated theory starts the Moon with a velocity
    off by about 0.1%).

    Example:
        >>> import visviva as vv
        >>> system = vv.mechanics.sun_earth_moon()
        >>> system.names, f"{system.masses[1]:.4e}"
        (('Sun', 'Earth', 'Moon'), '5.9722e+24')
    """
    gravity = real_number("G", G, positive=True)
    sun, earth, moon = (gm / gravity for gm in (_GM_SUN, _GM_EARTH, _GM_MOON))
    year = KeplerOrbit(*_BARYCENTRE_ORBIT, (sun, earth + moon), gravity)
    since_perihelion = (_MEAN_LONGITUDE - _PERIHELION_LONGITUDE) / year.mean_motion
    turn = _about_y(_PERIHELION_LONGITUDE)
    around_sun = year.bodies(since_perihelion)
    step = _DIFFERENCE_STEP / _JULIAN_CENTURY
    moon_offset = _ecliptic_to_world(_moon_ecliptic(0.0))
    moon_rate = _ecliptic_to_world(
        (_moon_ecliptic(step) - _moon_ecliptic(-step)) / (2.0 * _DIFFERENCE_STEP)
    )
    barycentre_x = turn @ around_sun.positions[1]
    barycentre_v = turn @ around_sun.velocities[1]
    share = np.array([-moon, earth]) / (earth + moon)  # Earth and Moon about their barycentre
    positions = np.vstack(
        [turn @ around_sun.positions[0], barycentre_x + np.outer(share, moon_offset)]
    )
    velocities = np.vstack(
        [turn @ around_sun.velocities[0], barycentre_v + np.outer(share, moon_rate)]
    )
    masses = np.array([sun, earth, moon])
    # Exact in exact arithmetic; remove the rounding so the frame is truly the barycentric one.
    positions -= masses @ positions / masses.sum()
    velocities -= masses @ velocities / masses.sum()
    return Bodies(positions, velocities, masses, gravity, ("Sun", "Earth", "Moon"))
