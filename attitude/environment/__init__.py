"""The Earth-orbit environment: real orbits, the geomagnetic field, the Sun and its shadow.

Everything here depends on time and on the orbit, never on the attitude, so it is
evaluated once on a time grid and interpolated (:mod:`attitude.environment.tabulation`)
before a propagation calls it at every step.

- :class:`TLEOrbit` -- a two-line element set through SGP4, in the run's inertial frame;
- :class:`IGRF` -- the International Geomagnetic Reference Field (IGRF-14, through
  ``ppigrf``) along an orbit, inertial components, a drop-in for
  :class:`attitude.torques.TiltedDipoleField`;
- :class:`SunPath` and :func:`illumination` -- where the Sun is and how much of its disk the
  Earth hides (cylindrical or conical shadow, with the penumbra).

The packages ``sgp4`` and ``ppigrf`` come with the ``environment`` extra
(``pip install "attitude-dynamics[environment]"``).
"""

from .frames import EARTH_FRAMES, inertial_to_earth_fixed, teme_to_inertial
from .igrf import IGRF, IGRF_VALIDITY
from .sun import EARTH_RADIUS, SUN_RADIUS, SunPath, illumination
from .tabulation import TimeTable
from .tle import TLEOrbit

__all__ = [
    "TLEOrbit",
    "IGRF",
    "IGRF_VALIDITY",
    "SunPath",
    "illumination",
    "EARTH_RADIUS",
    "SUN_RADIUS",
    "TimeTable",
    "EARTH_FRAMES",
    "teme_to_inertial",
    "inertial_to_earth_fixed",
]
