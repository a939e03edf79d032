"""Physical constants: one home for every value the package uses, each with its source.

SI units throughout.  Modules import from here and never redefine a value (the model is
skyfield's ``constants.py``).  Model parameters that are fits rather than constants (the
Earth's dipole) are here too, with the model and epoch they come from.

Examples
--------
>>> from attitude.foundations.constants import SOLAR_PRESSURE_1AU
>>> print(f"{SOLAR_PRESSURE_1AU:.4e} N/m^2")
4.5598e-06 N/m^2
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "AU",
    "SPEED_OF_LIGHT",
    "G",
    "MU0_OVER_4PI",
    "STANDARD_GRAVITY",
    "EARTH_MU",
    "EARTH_RADIUS",
    "EARTH_ROTATION_RATE",
    "EARTH_DIPOLE_MOMENT",
    "EARTH_DIPOLE_TILT",
    "EARTH_DIPOLE_POLE_LONGITUDE",
    "SUN_RADIUS",
    "OBLIQUITY_J2000",
    "SOLAR_IRRADIANCE_1AU",
    "SOLAR_PRESSURE_1AU",
]

# --- defining and fundamental constants -----------------------------------------------

#: The astronomical unit, m (IAU 2012 Resolution B2: exact by definition).
AU = 149_597_870_700.0
#: Speed of light in vacuum, m/s (SI: exact by definition).
SPEED_OF_LIGHT = 299_792_458.0
#: Newtonian constant of gravitation, m^3 kg^-1 s^-2 (CODATA 2018).
G = 6.67430e-11
#: Magnetic constant over 4 pi, ``mu0 / 4 pi``, T m / A (exact in the SI before 2019;
#: CODATA 2018 gives 1.00000000055e-7, a relative change of 5.5e-10).
MU0_OVER_4PI = 1e-7
#: Standard acceleration of gravity, m/s^2 (3rd CGPM, 1901: exact by definition).
STANDARD_GRAVITY = 9.80665

# --- the Earth ------------------------------------------------------------------------

#: Gravitational parameter of the Earth, m^3/s^2 (EGM2008 / WGS 84; IERS Conventions
#: 2010, Table 1.1).
EARTH_MU = 3.986004418e14
#: Equatorial radius of the Earth, m (WGS 84).
EARTH_RADIUS = 6378137.0
#: Nominal sidereal rotation rate of the Earth, rad/s (IERS Conventions 2010, Table 1.2;
#: GRS 80 / WGS 84).
EARTH_ROTATION_RATE = 7.292115e-5
#: Magnitude of the Earth's dipole moment, A m^2 (``B0 = 1e-7 m / R^3 = 3.07e-5 T`` at
#: the equator for R = 6371.2 km, IGRF-13 2020; Wertz's 3.12e-5 T corresponds to
#: 8.1e22 A m^2).
EARTH_DIPOLE_MOMENT = 7.94e22
#: Angle between the dipole axis and the rotation axis, rad (IGRF-13, epoch 2020:
#: 9.4 deg; Alken et al. 2021).
EARTH_DIPOLE_TILT = np.radians(9.4)
#: East longitude of the northern geomagnetic pole, rad (IGRF-13, epoch 2020: 72.7 deg W).
EARTH_DIPOLE_POLE_LONGITUDE = np.radians(-72.7)

# --- the Sun --------------------------------------------------------------------------

#: Nominal solar radius, m (IAU 2015 Resolution B3).
SUN_RADIUS = 6.957e8
#: Obliquity of the ecliptic at J2000, rad (IAU 1976: 84381.448 arcsec): the rotation
#: ICRF -> ECLIPJ2000.
OBLIQUITY_J2000 = np.deg2rad(84381.448 / 3600.0)
#: Total solar irradiance at 1 au, W/m^2: the "solar constant" 1367 W/m^2 of Montenbruck
#: & Gill 2000, Sec. 3.4.1 (Wertz 1978 and Basilisk use 1368 W/m^2; the IAU 2015
#: Resolution B3 nominal value is 1361 W/m^2).
SOLAR_IRRADIANCE_1AU = 1367.0
#: Solar radiation pressure at 1 au on an absorbing surface, N/m^2: the irradiance over
#: the speed of light (Montenbruck & Gill 2000, eq. 3.71), 4.5598e-6.
SOLAR_PRESSURE_1AU = SOLAR_IRRADIANCE_1AU / SPEED_OF_LIGHT
