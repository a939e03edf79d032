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

The formulas are those of :func:`attitude.model.shadow.illumination_fraction`, their one
source (which the compiled radiation-pressure kernel runs compiled).
"""

from __future__ import annotations

import numpy as np
from astropy import units as u
from astropy.time import TimeDelta

from ..foundations.constants import EARTH_RADIUS, SUN_RADIUS
from ..foundations.errors import OrbitError, TorqueConfigError
from ..foundations.quantities import to_time
from ..model.shadow import illumination_fraction
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
        self.epoch = to_time(epoch, key="epoch", error=TorqueConfigError)
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
        return self._table.compiled_parameters(t_span)

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
    conical = model == "conical"
    if r_sat.shape == (3,) and r_sun.shape == (3,):   # one epoch: plain floats
        return np.float64(illumination_fraction(*r_sat.tolist(), *r_sun.tolist(), conical,
                                                earth_radius, sun_radius))
    # the one source of the shadow test (attitude.model.shadow) epoch by epoch: a few
    # microseconds each, as plain Python (the compiled kernels run it compiled)
    r_sat, r_sun = np.broadcast_arrays(r_sat, r_sun)
    out = _FRACTION(r_sat[..., 0], r_sat[..., 1], r_sat[..., 2], r_sun[..., 0],
                    r_sun[..., 1], r_sun[..., 2], conical, float(earth_radius),
                    float(sun_radius))
    return np.asarray(out, dtype=float)


#: :func:`illumination_fraction` as a numpy ufunc over arrays of positions.
_FRACTION = np.frompyfunc(illumination_fraction, 9, 1)
