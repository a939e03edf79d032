"""How much of the solar disk a body sees past a spherical primary: the one source of
the shadow test, in plain floats.

:func:`illumination_fraction` is written so that numba compiles it as it is: the
compiled radiation-pressure kernel (:mod:`attitude.propagation.compiled_torques`) runs
it compiled, :func:`attitude.environment.illumination` (positions, with the models'
names and checks) runs it as plain Python, once per epoch.

- cylindrical: 0 inside the cylinder of the primary's radius behind the primary, 1
  elsewhere (no penumbra);
- conical: the apparent disks of the Sun (radius ``a``) and of the primary (radius
  ``b``), their centres ``c`` apart, overlap in a lens whose area is subtracted from the
  Sun's disk: umbra (0), penumbra (continuous from 0 to 1), annular eclipse
  (``1 - b^2/a^2``) and full light (1).

References
----------
.. [1] Montenbruck, O. & Gill, E. (2000). *Satellite Orbits*, Springer, Sec. 3.4.2.
"""

from __future__ import annotations

import math

__all__ = ["illumination_fraction"]


def illumination_fraction(x, y, z, sx, sy, sz, conical, primary_radius, sun_radius):
    """Fraction of the solar disk visible from ``(x, y, z)``, in ``[0, 1]``.

    Parameters
    ----------
    x, y, z : float
        Position of the body relative to the primary's centre, m.
    sx, sy, sz : float
        Position of the Sun relative to the primary's centre, same frame, m.
    conical : bool
        The conical model (penumbra); else the cylindrical one.
    primary_radius, sun_radius : float
        Radii, m.

    Examples
    --------
    >>> illumination_fraction(-7e6, 0.0, 0.0, 1.496e11, 0.0, 0.0, True, 6378137.0, 6.957e8)
    0.0
    >>> illumination_fraction(0.0, 7e6, 0.0, 1.496e11, 0.0, 0.0, False, 6378137.0, 6.957e8)
    1.0
    """
    if not conical:
        d_sun = math.sqrt(sx * sx + sy * sy + sz * sz)
        along = (x * sx + y * sy + z * sz) / d_sun
        across2 = max(x * x + y * y + z * z - along * along, 0.0)
        return 0.0 if (along < 0 and math.sqrt(across2) < primary_radius) else 1.0
    tx, ty, tz = sx - x, sy - y, sz - z
    d_sun = math.sqrt(tx * tx + ty * ty + tz * tz)
    d_primary = math.sqrt(x * x + y * y + z * z)
    a = math.asin(sun_radius / d_sun)
    b = math.asin(min(max(primary_radius / d_primary, -1.0), 1.0))
    cos_c = -(x * tx + y * ty + z * tz) / (d_primary * d_sun)
    c = math.acos(min(max(cos_c, -1.0), 1.0))
    if c >= a + b:                                    # full light
        return 1.0
    if c <= b - a:                                    # umbra
        return 0.0
    if c <= a - b:                                    # annular
        return 1.0 - (b * b) / (a * a)
    # lens area of two overlapping disks of radii a, b with centres c apart
    u = (c * c + a * a - b * b) / (2 * c)
    v = math.sqrt(max(a * a - u * u, 0.0))
    lens = (a * a * math.acos(min(max(u / a, -1.0), 1.0))
            + b * b * math.acos(min(max((c - u) / b, -1.0), 1.0)) - c * v)
    return min(max(1.0 - lens / (math.pi * a * a), 0.0), 1.0)
