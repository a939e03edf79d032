"""The Earth rotation angle: the one place the package turns an epoch into the angle of
the Earth about the celestial intermediate pole (the tilted-dipole field of
:mod:`attitude.model.torques` and the Earth-fixed frames of
:mod:`attitude.environment.frames` both read it).

UT1 comes from the IERS Earth-orientation tables bundled with astropy (nothing is
downloaded): exact where the table has measured values, the IERS predictions where it has
only those, whatever their age, and the table's last UT1 - UTC beyond its end (|UT1 -
UTC| < 0.9 s: 6.6e-5 rad at most).  Taking UT1 = UTC instead would be off by as much
everywhere, and would jump by 1 s (7.3e-5 rad) at each leap second, which the frames'
interpolation of the slowly varying rest of the Earth's orientation cannot follow.
"""

from __future__ import annotations

import warnings

import erfa
import numpy as np

__all__ = ["earth_rotation_angle"]


def earth_rotation_angle(times) -> float | np.ndarray:
    """Earth rotation angle (IAU 2000, ``erfa.era00``) at ``times``, rad in ``[0, 2 pi)``.

    .. math::

        \\theta = 2\\pi\\,(0.7790572732640 + 1.00273781191135448\\,D_U),

    ``D_U`` the UT1 Julian date minus 2451545.0.

    Parameters
    ----------
    times : astropy Time
        Any scale (converted to UT1 through the IERS tables bundled with astropy: no
        download; beyond the tables the last UT1 - UTC, and no warning for the years
        the leap-second table does not reach).

    Returns
    -------
    float or ndarray
        A float for a scalar Time, else an array of the Time's shape.

    References
    ----------
    .. [1] Petit, G. & Luzum, B. (eds.) (2010). *IERS Conventions (2010)*. IERS
       Technical Note 36, eq. 5.15.

    Examples
    --------
    >>> from astropy.time import Time
    >>> t = Time("2000-01-01T12:00:00", scale="utc")
    >>> round(earth_rotation_angle(t), 6)        # UT1 - UTC = +0.355 s that day
    4.894987
    >>> earth_rotation_angle(Time(["2024-03-01", "2024-03-02"], scale="utc")).shape
    (2,)
    """
    from astropy.utils import iers  # costly (its tables load astropy.table, ~0.5 s)

    with iers.conf.set_temp("auto_download", False), \
            iers.conf.set_temp("auto_max_age", None), \
            iers.conf.set_temp("iers_degraded_accuracy", "warn"), \
            warnings.catch_warnings():
        # "dubious year": a date past the leap-second table, whose last TAI - UTC is used
        warnings.simplefilter("ignore", erfa.ErfaWarning)
        ut1 = times.ut1
    era = erfa.era00(ut1.jd1, ut1.jd2)
    return float(era) if np.ndim(era) == 0 else era
