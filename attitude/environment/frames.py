"""Rotations between the inertial frames of a run and the frames of the Earth models.

SGP4 gives positions in TEME (true equator, mean equinox of date); IGRF is expanded in
Earth-fixed (ITRS) coordinates; a run's ephemeris names its inertial frame.  The
rotations come from astropy (IAU 2006/2000A precession-nutation, Earth rotation angle,
polar motion from the IERS tables bundled with astropy; nothing is downloaded), as
``(n, 3, 3)`` matrices applied as ``v_to = M @ v_from``.

Supported inertial frames (:data:`EARTH_FRAMES`): ``"GCRF"`` (geocentric celestial
reference frame; its axes are the ICRF's, so ``"ICRF"`` is accepted as the same axes),
``"EME2000"`` (mean equator and equinox of J2000, the GCRF turned by the IAU 2000 frame
bias, 23 mas), and ``"TEME"`` (SGP4's own frame, no rotation).
"""

from __future__ import annotations

import erfa
import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta
from scipy.interpolate import CubicSpline

from ..foundations.earth_rotation import earth_rotation_angle
from ..foundations.errors import OrbitError

__all__ = ["EARTH_FRAMES", "teme_to_inertial", "inertial_to_earth_fixed", "gcrf_to_frame"]

#: Inertial frames (labels of :data:`attitude.model.state.INERTIAL_FRAMES`) that the Earth
#: models can be expressed in; ``"J2000"`` is read as ``"EME2000"``.
EARTH_FRAMES = ("GCRF", "ICRF", "EME2000", "J2000", "TEME")


def check_frame(frame: str) -> str:
    """The frame name, upper-case, or an :class:`~attitude.foundations.errors.OrbitError`.

    Examples
    --------
    >>> check_frame("gcrf")
    'GCRF'
    """
    name = str(frame).upper()
    if name not in EARTH_FRAMES:
        raise OrbitError(f"the Earth models cannot be expressed in frame {frame!r}; use "
                         f"one of {', '.join(EARTH_FRAMES)}", key="frame")
    return "EME2000" if name == "J2000" else name


def _columns(frame_from: str, frame_to: str, times: Time) -> np.ndarray:
    """``(n, 3, 3)``: the images of the three unit vectors of the astropy frame named
    ``frame_from`` (``"TEME"``, ``"GCRS"``) in ``frame_to`` (``"GCRS"``, ``"ITRS"``)."""
    from astropy import coordinates  # costly (~1 s to import): only when a frame turns
    from astropy.utils import iers  # costly (its tables load astropy.table, ~0.5 s)

    frame_from, frame_to = getattr(coordinates, frame_from), getattr(coordinates, frame_to)
    n = times.size
    out = np.empty((n, 3, 3))
    with iers.conf.set_temp("auto_download", False), \
            iers.conf.set_temp("iers_degraded_accuracy", "warn"):
        for j in range(3):
            e = np.zeros((3, n))
            e[j] = 1.0
            rep = coordinates.CartesianRepresentation(e * u.km)
            moved = frame_from(rep, obstime=times).transform_to(frame_to(obstime=times))
            out[:, :, j] = moved.cartesian.xyz.to_value(u.km).T
    return out


#: Node spacing (s) of the exact astropy rotations, interpolated in between.  What is
#: left after taking out the Earth rotation angle varies with nutation (5.5 d and longer)
#: and polar motion (1e-6 rad, daily once turned): a cubic through hourly nodes is
#: exact to 1e-11 rad.
NODE_SPACING = 3600.0


def _era_matrices(times: Time) -> np.ndarray:
    """``R3(ERA)``, the Earth's rotation about the celestial intermediate pole."""
    era = earth_rotation_angle(times)
    return erfa.rz(era, np.broadcast_to(np.eye(3), (times.size, 3, 3)))


def _interpolated(times: Time, exact, *, spin: bool) -> np.ndarray:
    """``exact(times)`` from hourly astropy nodes, the Earth rotation (if ``spin``) exact."""
    t = (times - times[0]).to_value("s")
    lo, hi = np.floor(t.min() / NODE_SPACING) - 1, np.ceil(t.max() / NODE_SPACING) + 2
    nodes_s = NODE_SPACING * np.arange(lo, hi + 1)
    nodes = times[0] + TimeDelta(nodes_s, format="sec")
    slow = exact(nodes)
    if spin:
        slow = np.swapaxes(_era_matrices(nodes), -1, -2) @ slow
    out = CubicSpline(nodes_s, slow, axis=0)(t)
    if spin:
        out = _era_matrices(times) @ out
    # re-orthonormalise what the spline left (below 1e-11) through the polar decomposition
    u_, _, vt = np.linalg.svd(out)
    return u_ @ vt


def gcrf_to_frame(frame: str, times: Time) -> np.ndarray:
    """``(n, 3, 3)`` rotation from GCRF axes to ``frame``'s at ``times`` (``frame``
    already checked: GCRF, ICRF, EME2000 or TEME).

    Examples
    --------
    >>> from astropy.time import Time
    >>> m = gcrf_to_frame("EME2000", Time(["2024-03-01T00:00:00"], scale="tt"))
    >>> float(abs(m[0] - np.eye(3)).max()) < 2e-7            # the 23 mas frame bias
    True
    """
    if frame == "TEME":
        return np.swapaxes(_interpolated(times, lambda n: _columns("TEME", "GCRS", n),
                                         spin=False), -1, -2)
    if frame == "EME2000":
        tt = times.tt
        bias, _, _ = erfa.bp00(tt.jd1, tt.jd2)
        return np.broadcast_to(bias, (times.size, 3, 3))
    return np.broadcast_to(np.eye(3), (times.size, 3, 3))


def teme_to_inertial(times: Time, frame: str = "GCRF") -> np.ndarray:
    """Rotation matrices from TEME to ``frame`` at ``times``, shape ``(n, 3, 3)``.

    Examples
    --------
    >>> from astropy.time import Time, TimeDelta
    >>> m = teme_to_inertial(Time(["2024-03-01T00:00:00"], scale="utc"))
    >>> bool(abs(m[0] @ m[0].T - np.eye(3)).max() < 1e-12)
    True
    """
    frame = check_frame(frame)
    times = Time(times).reshape(-1)
    if frame == "TEME":
        return np.broadcast_to(np.eye(3), (times.size, 3, 3)).copy()
    return gcrf_to_frame(frame, times) @ _interpolated(
        times, lambda n: _columns("TEME", "GCRS", n), spin=False)


def inertial_to_earth_fixed(times: Time, frame: str = "GCRF") -> np.ndarray:
    """Rotation matrices from ``frame`` to the Earth-fixed ITRS at ``times``, ``(n, 3, 3)``.

    Examples
    --------
    >>> from astropy.time import Time, TimeDelta
    >>> m = inertial_to_earth_fixed(Time(["2024-03-01T00:00:00"], scale="utc"))
    >>> round(float(np.linalg.det(m[0])), 12)
    1.0
    """
    frame = check_frame(frame)
    times = Time(times).reshape(-1)
    if frame == "TEME":
        return _interpolated(times, lambda n: _columns("TEME", "ITRS", n), spin=True)
    to_frame = gcrf_to_frame(frame, times)
    return (_interpolated(times, lambda n: _columns("GCRS", "ITRS", n), spin=True)
            @ np.swapaxes(to_frame, -1, -2))
