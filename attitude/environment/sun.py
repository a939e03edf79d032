"""The Sun seen from the Earth, and how much of its disk the Earth hides from a satellite.

:class:`SunPath` tabulates the geocentric position of the Sun (astropy's built-in
ephemeris, ``get_body("sun")``: apparent, with light time, in the GCRS) and interpolates
it; it is a path like :class:`attitude.model.orbit.KeplerOrbit` (``position(t)``, m, inertial).

:func:`illumination` gives the fraction of the solar disk that a satellite sees:

- ``"cylindrical"``: 0 inside the cylinder of the Earth's radius behind the Earth, 1
  elsewhere (no penumbra);
- ``"conical"``: the apparent disks of the Sun (radius ``a``) and of the Earth (radius
  ``b``), their centres ``c`` apart, overlap in a lens whose area is subtracted from the
  Sun's disk (Montenbruck & Gill 2000, *Satellite Orbits*, Sec. 3.4.2): umbra (0),
  penumbra (continuous from 0 to 1), annular eclipse (``1 - b^2/a^2``) and full light (1).
"""

from __future__ import annotations

import math

import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta

from ..foundations.constants import EARTH_RADIUS, SUN_RADIUS
from ..foundations.errors import OrbitError
from .frames import check_frame, gcrf_to_frame
from .tabulation import TimeTable

__all__ = ["SunPath", "illumination", "EARTH_RADIUS", "SUN_RADIUS", "SHADOW_MODELS"]

#: Shadow models of :func:`illumination`.
SHADOW_MODELS = ("conical", "cylindrical")


class SunPath:
    """Position of the Sun relative to the Earth's centre, inertial, m.

    Parameters
    ----------
    epoch : astropy Time
        Time ``t = 0``.
    frame : str
        Inertial frame (``"GCRF"``, ``"ICRF"``, ``"EME2000"`` or ``"TEME"``).
    spacing : float
        Node spacing, s (the Sun moves 1 deg a day: 1 h nodes interpolate to 1e-9).

    Examples
    --------
    >>> from astropy.time import Time
    >>> sun = SunPath(Time("2024-03-20T03:06:00", scale="utc"))     # March equinox
    >>> d = sun.position(0.0) / np.linalg.norm(sun.position(0.0))
    >>> np.round(d, 3)     # toward the equinox of date (24 years of precession from GCRF's x)
    array([ 1.   , -0.005, -0.002])
    """

    def __init__(self, epoch, *, frame: str = "GCRF", spacing: float = 3600.0):
        self.epoch = Time(epoch)
        self.frame = check_frame(frame)
        self._table = TimeTable(self._evaluate, spacing=spacing, segment=48 * spacing)

    def _evaluate(self, t: np.ndarray) -> np.ndarray:
        from astropy.coordinates import get_body  # costly (~1 s to import): used here
        from astropy.utils import iers  # costly (its tables load astropy.table, ~0.5 s)

        times = self.epoch + TimeDelta(t, format="sec")
        with iers.conf.set_temp("auto_download", False):
            xyz = get_body("sun", times).cartesian.xyz.to_value(u.m).T
        if self.frame not in ("GCRF", "ICRF"):
            xyz = np.einsum("nij,nj->ni", gcrf_to_frame(self.frame, times), xyz)
        return xyz

    def compiled_parameters(self, t_span=None) -> tuple[str, dict] | None:
        """``("piecewise_cubic", {breakpoints, coefficients})``: the tabulated path over
        ``t_span = (t0, t1)`` (s) for a compiled kernel, or None without a span.

        Examples
        --------
        >>> from astropy.time import Time
        >>> sun = SunPath(Time("2024-03-20T03:06:00", scale="utc"))
        >>> sun.compiled_parameters((0.0, 3600.0))[1]["breakpoints"].shape
        (49,)
        """
        if t_span is None:
            return None
        x, c = self._table.piecewise(*t_span)
        return ("piecewise_cubic", {"breakpoints": x, "coefficients": c})

    def position(self, t) -> np.ndarray:
        """Geocentric position of the Sun at ``t`` (s), inertial, m, ``t.shape + (3,)``."""
        return self._table(t)

    def __repr__(self) -> str:
        return f"SunPath(epoch {self.epoch.utc.isot} UTC, frame {self.frame!r})"


def illumination(r_sat, r_sun, model: str = "conical", *, earth_radius=EARTH_RADIUS,
                 sun_radius=SUN_RADIUS) -> np.ndarray:
    """Fraction of the solar disk visible from the satellite, in ``[0, 1]``.

    Parameters
    ----------
    r_sat, r_sun : array (..., 3)
        Geocentric positions of the satellite and of the Sun, same frame, m.
    model : {"conical", "cylindrical"}
        Shadow geometry (see the module docstring).

    Examples
    --------
    >>> sun = np.array([1.496e11, 0.0, 0.0])
    >>> illumination(np.array([[7e6, 0, 0], [-7e6, 0, 0], [0, 7e6, 0]]), sun)
    array([1., 0., 1.])
    """
    if model not in SHADOW_MODELS:
        raise OrbitError(f"unknown shadow model {model!r}; use one of "
                         f"{', '.join(SHADOW_MODELS)}", key="shadow")
    r_sat = np.asarray(r_sat, dtype=float)
    r_sun = np.asarray(r_sun, dtype=float)
    if r_sat.shape == (3,) and r_sun.shape == (3,):   # one epoch: plain floats, 10x faster
        return np.float64(_illumination_one(r_sat.tolist(), r_sun.tolist(), model,
                                            earth_radius, sun_radius))
    if model == "cylindrical":
        s_hat = r_sun / np.linalg.norm(r_sun, axis=-1, keepdims=True)
        along = np.sum(r_sat * s_hat, axis=-1)
        across = np.linalg.norm(r_sat - along[..., None] * s_hat, axis=-1)
        return np.where((along < 0) & (across < earth_radius), 0.0, 1.0)
    to_sun = r_sun - r_sat
    d_sun = np.linalg.norm(to_sun, axis=-1)
    d_earth = np.linalg.norm(r_sat, axis=-1)
    a = np.arcsin(sun_radius / d_sun)
    b = np.arcsin(np.clip(earth_radius / d_earth, -1.0, 1.0))
    cos_c = -np.sum(r_sat * to_sun, axis=-1) / (d_earth * d_sun)
    c = np.arccos(np.clip(cos_c, -1.0, 1.0))
    # lens area of two overlapping disks of radii a, b with centres c apart
    with np.errstate(invalid="ignore", divide="ignore"):
        x = (c * c + a * a - b * b) / (2 * c)
        y = np.sqrt(np.maximum(a * a - x * x, 0.0))
        lens = (a * a * np.arccos(np.clip(x / a, -1, 1)) + b * b
                * np.arccos(np.clip((c - x) / b, -1, 1)) - c * y)
    partial = 1.0 - lens / (np.pi * a * a)
    return np.select([c >= a + b, c <= b - a, c <= a - b],
                     [1.0, 0.0, 1.0 - (b * b) / (a * a)], np.clip(partial, 0.0, 1.0))


def _illumination_one(r_sat, r_sun, model, earth_radius, sun_radius) -> float:
    """:func:`illumination` for one epoch, in floats (the same formulas)."""
    x, y, z = r_sat
    if model == "cylindrical":
        d_sun = math.sqrt(r_sun[0] ** 2 + r_sun[1] ** 2 + r_sun[2] ** 2)
        along = (x * r_sun[0] + y * r_sun[1] + z * r_sun[2]) / d_sun
        across2 = max(x * x + y * y + z * z - along * along, 0.0)
        return 0.0 if (along < 0 and math.sqrt(across2) < earth_radius) else 1.0
    tx, ty, tz = r_sun[0] - x, r_sun[1] - y, r_sun[2] - z
    d_sun = math.sqrt(tx * tx + ty * ty + tz * tz)
    d_earth = math.sqrt(x * x + y * y + z * z)
    a = math.asin(sun_radius / d_sun)
    b = math.asin(min(max(earth_radius / d_earth, -1.0), 1.0))
    cos_c = -(x * tx + y * ty + z * tz) / (d_earth * d_sun)
    c = math.acos(min(max(cos_c, -1.0), 1.0))
    if c >= a + b:
        return 1.0
    if c <= b - a:
        return 0.0
    if c <= a - b:
        return 1.0 - (b * b) / (a * a)
    u = (c * c + a * a - b * b) / (2 * c)
    v = math.sqrt(max(a * a - u * u, 0.0))
    lens = (a * a * math.acos(min(max(u / a, -1.0), 1.0))
            + b * b * math.acos(min(max((c - u) / b, -1.0), 1.0)) - c * v)
    return min(max(1.0 - lens / (math.pi * a * a), 0.0), 1.0)
