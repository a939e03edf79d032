"""The Earth-orbit environment: real orbits, the geomagnetic field, the Sun and its shadow.

Everything here depends on time and on the orbit, never on the attitude, so it is
evaluated once on a time grid and interpolated (:mod:`attitude.environment.tabulation`)
before a propagation calls it at every step.

- :class:`TLEOrbit` -- a two-line element set through SGP4, in the run's inertial frame;
- :class:`IGRF` -- the International Geomagnetic Reference Field (IGRF-14, through
  ``ppigrf``) along an orbit, inertial components, a drop-in for
  :class:`attitude.model.torques.TiltedDipoleField`;
- :class:`SunPath` and :func:`illumination` -- where the Sun is and how much of its disk the
  Earth hides (cylindrical or conical shadow, with the penumbra);
- :class:`SolarRadiationPressure` and :class:`AerodynamicDrag` -- torques of sunlight
  and of the upper atmosphere on the facets of a body (:class:`Facets`, from the same
  surface description photometry uses), with :class:`ExponentialAtmosphere` or NRLMSIS
  (:class:`MSISAtmosphere`, ``pymsis``: the ``msis`` extra); in scenario files the
  ``[[torques]]`` types ``"solar_radiation"`` and ``"drag"`` (:mod:`.config`).

The packages ``sgp4`` and ``ppigrf`` come with the ``environment`` extra
(``pip install "attitude-dynamics[environment]"``).
"""

from ..foundations.errors import OrbitError
from ..model import torques as _torques
from .drag import VALLADO_EXPONENTIAL_TABLE, AerodynamicDrag, ExponentialAtmosphere
from .facets import Facets
from .frames import EARTH_FRAMES, inertial_to_earth_fixed, teme_to_inertial
from .igrf import IGRF, IGRF_VALIDITY
from .msis import MSISAtmosphere
from .radiation import ASTRONOMICAL_UNIT, SOLAR_PRESSURE_1AU, SolarRadiationPressure
from .sun import EARTH_RADIUS, SUN_RADIUS, SunPath, illumination
from .tabulation import TimeTable
from .tle import TLEOrbit


def _tle_source(lines, base_epoch, frame="GCRF"):
    if not (isinstance(lines, (list, tuple)) and len(lines) == 2):
        raise OrbitError("expected the two lines of the element set, [line1, line2]",
                         key="tle")
    return TLEOrbit(*lines, epoch=base_epoch, frame=frame)


def _igrf_source(orbit, base_epoch, max_degree):
    return IGRF(orbit, epoch=base_epoch, max_degree=max_degree)


# scenario files: orbit = { tle = [...] } and field = "igrf" in [[torques]] tables
_torques.ORBIT_SOURCES["tle"] = _tle_source
_torques.FIELD_SOURCES["igrf"] = _igrf_source
# att.torques.SolarRadiationPressure / AerodynamicDrag, as the API names them (the models
# live here, in the wing; torques cannot import them without a cycle)
_torques.SolarRadiationPressure = SolarRadiationPressure
_torques.AerodynamicDrag = AerodynamicDrag
# [[torques]] types "solar_radiation" and "drag" (registered with the torques module)
from . import config as _config  # noqa: E402,F401  (after the names above: it uses them)

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
    "Facets",
    "SolarRadiationPressure",
    "AerodynamicDrag",
    "ExponentialAtmosphere",
    "MSISAtmosphere",
    "VALLADO_EXPONENTIAL_TABLE",
    "SOLAR_PRESSURE_1AU",
    "ASTRONOMICAL_UNIT",
]
