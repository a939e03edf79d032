r"""Forced libration in longitude of a synchronous moon: linear theory and measurement.

Linear theory (Murray & Dermott 1999, sec. 5.3; Willner et al. 2010 for Phobos).  Write
``gamma = theta - M`` for the angle of the long axis from the mean direction of the
primary (the libration in longitude relative to the mean longitude).  To first order in
``e``, ``f - M = 2 e sin M`` and ``(a/r)^3 = 1 + O(e)``, so the planar equation
``theta'' = -(omega0^2/2) (a/r)^3 sin 2 (theta - f)`` becomes, with time in units of
``1/n``,

.. math::

    \ddot\gamma + \omega_0^2\,\gamma = 2 e\,\omega_0^2 \sin M ,

whose forced solution is ``gamma = A sin M`` with

.. math::

    A = \frac{2 e\,\omega_0^2}{\omega_0^2 - 1}
      = \frac{2e}{1 - n^2/\omega_0^2}, \qquad \omega_0^2 = 3\,\frac{B - A}{C}\,n^2 .

``A < 0`` (``omega0 < n``, every moon whose ``(B - A)/C < 1/3``): the long axis lags
the direction of the primary after periapsis.  The corrections are ``O(e^2)``
relative (harmonics ``2M`` and the cubic term of ``sin 2 gamma``), and the theory fails
near the resonance ``omega0 = n``.

Measurement: the angle of the long axis in the orbit plane is read from a propagated
ephemeris, ``gamma(t) = theta(t) - M(t)``, and its spectrum at the orbital frequency is
taken by least squares on ``1, cos kM, sin kM`` (``k = 1..3``): the amplitude at ``k = 1``
is the forced libration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations.errors import SpinOrbitError
from ..model.orbit import KeplerOrbit

__all__ = ["forced_libration_amplitude", "orbit_basis", "long_axis_angle",
           "LibrationMeasurement", "measure_libration"]


def forced_libration_amplitude(omega0: float, e: float) -> float:
    """Signed linear amplitude ``A = 2 e omega0^2 / (omega0^2 - 1)`` (rad) of
    ``gamma = A sin M``; ``omega0`` in units of the mean motion.

    Raises
    ------
    SpinOrbitError
        At the resonance ``omega0 = 1`` (the linear theory diverges).

    Examples
    --------
    >>> import math
    >>> round(math.degrees(forced_libration_amplitude(math.sqrt(0.3986), 0.0151)), 3)
    -1.147
    """
    w2 = float(omega0) ** 2
    if abs(w2 - 1.0) < 1e-12:
        raise SpinOrbitError("omega0 = n: the forced libration is resonant and the linear "
                             "theory diverges", key="omega0")
    return 2.0 * float(e) * w2 / (w2 - 1.0)


def orbit_basis(orbit: KeplerOrbit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors ``P`` (towards periapsis), ``Q`` and ``W`` (orbit normal), inertial.

    From the public orbit: ``W`` along the angular momentum, ``P`` the position at the
    periapsis passage (``M = 0``), ``Q = W x P``.

    Examples
    --------
    >>> o = KeplerOrbit(mu=1.0, a=1.0, e=0.1, argp=0.5)
    >>> [v.round(6).tolist() for v in orbit_basis(o)][2]
    [0.0, 0.0, 1.0]
    """
    if not isinstance(orbit, KeplerOrbit):
        raise SpinOrbitError(f"the spin-orbit problem needs a KeplerOrbit, got "
                             f"{type(orbit).__name__}", key="orbit")
    h = orbit.specific_angular_momentum
    W = h / np.linalg.norm(h)
    r = orbit.position(-orbit.mean_anomaly / orbit.mean_motion)
    P = r / np.linalg.norm(r)
    return P, np.cross(W, P), W


def long_axis_angle(quaternion, body, orbit: KeplerOrbit) -> np.ndarray:
    """Angle (rad, unwrapped) of the long axis (moment ``A``) from the periapsis
    direction, measured in the orbit plane about the orbit normal.

    Parameters
    ----------
    quaternion : array-like, shape (T, 4)
        Body -> inertial attitudes, scalar-last.
    body : RigidBody
    orbit : KeplerOrbit

    Examples
    --------
    >>> import attitude as att
    >>> orbit = att.KeplerOrbit(mu=1.0, a=1.0, e=0.0)
    >>> so = att.SpinOrbit.from_omega0(0.6, orbit)
    >>> eph = so.propagate(np.linspace(0.0, 2 * np.pi, 5))        # one circular orbit, locked
    >>> gamma = long_axis_angle(eph.dataset.quaternion.values, so.body, orbit)
    >>> bool(np.allclose(gamma, np.linspace(0.0, 2 * np.pi, 5), atol=1e-9))  # follows M
    True
    """
    P, Q, _ = orbit_basis(orbit)
    a_body = body.principal_axes[:, 0]
    a = Rotation.from_quat(np.asarray(quaternion, dtype=float)).apply(a_body)
    return np.unwrap(np.arctan2(a @ Q, a @ P))


@dataclass(frozen=True, eq=False)
class LibrationMeasurement:
    """The spectrum of the libration in longitude at the harmonics of the orbit.

    Attributes
    ----------
    amplitude : float
        ``|c_1|``: amplitude at the orbital frequency, rad (the forced libration).
    phase : float
        ``gamma ~ amplitude sin(M + phase)``; ``0`` in phase with ``sin M``, ``pi`` in
        antiphase (``omega0 < n``).
    signed_amplitude : float
        The coefficient of ``sin M`` (compare with :func:`forced_libration_amplitude`).
    mean : float
        Mean offset of the long axis from the mean direction of the primary, rad.
    harmonics : ndarray
        Amplitudes at ``1, 2, 3`` times the orbital frequency, rad.
    residual_rms : float
        RMS of what the harmonics do not explain (free libration, noise), rad.
    orbits : float
        Orbits covered.

    Examples
    --------
    >>> import attitude as att
    >>> orbit = att.KeplerOrbit(mu=4.282837e13, a=9.376e6, e=0.0151)     # Phobos
    >>> so = att.SpinOrbit.from_omega0(0.631, orbit)
    >>> m = measure_libration(so.propagate(np.linspace(0.0, orbit.period, 33)), orbit)
    >>> round(float(np.degrees(m.amplitude)), 2), round(m.orbits, 6)
    (1.14, 1.0)
    >>> bool(m.residual_rms < 1e-2 * m.amplitude)                # the forced term dominates
    True
    """

    amplitude: float
    phase: float
    signed_amplitude: float
    mean: float
    harmonics: np.ndarray
    residual_rms: float
    orbits: float


def measure_libration(ephemeris, orbit: KeplerOrbit, *, harmonics: int = 3
                      ) -> LibrationMeasurement:
    """Measure the forced libration in longitude from a propagated ephemeris.

    ``gamma(t) = theta(t) - M(t)``, with ``theta`` the angle of the long axis from the
    periapsis direction in the orbit plane and ``M`` the mean anomaly, reduced by the
    nearest multiple of ``pi`` (the body is symmetric under a half turn about ``C``);
    then a least-squares fit of ``c0 + sum_k (a_k cos kM + b_k sin kM)``.

    Parameters
    ----------
    ephemeris : Ephemeris
        One body (a propagated synchronous moon), covering at least one orbit.
    orbit : KeplerOrbit
        The orbit of the run (for ``M(t)`` and the orbit plane).
    harmonics : int
        Harmonics of the orbital frequency fitted.

    Raises
    ------
    SpinOrbitError
        A batch ephemeris, fewer than one orbit, or too few samples.

    Examples
    --------
    >>> import attitude as att
    >>> orbit = att.KeplerOrbit(mu=4.282837e13, a=9.376e6, e=0.02)
    >>> so = att.SpinOrbit.from_omega0(0.6, orbit)
    >>> eph = so.propagate(np.linspace(0.0, orbit.period, 33))     # one orbit, locked
    >>> m = measure_libration(eph, orbit)
    >>> round(m.signed_amplitude / forced_libration_amplitude(0.6, 0.02), 3)
    0.997
    """
    if ephemeris.is_batch:
        raise SpinOrbitError("measure one body at a time (select it with "
                             "ephemeris.dataset.isel(body=i))", key="ephemeris")
    t = np.asarray(ephemeris.time, dtype=float)
    q = ephemeris.dataset["quaternion"].values
    theta = long_axis_angle(q, ephemeris.body, orbit)
    M = orbit.mean_anomaly_at(t)
    span = (t[-1] - t[0]) / orbit.period
    if span < 1.0 - 1e-9:
        raise SpinOrbitError(f"the ephemeris covers {span:.3g} orbits; the libration "
                             f"spectrum needs at least one", key="ephemeris")
    if t.size < 4 * harmonics + 4:
        raise SpinOrbitError(f"{t.size} samples are too few for {harmonics} harmonics",
                             key="ephemeris")
    gamma = theta - M
    gamma = gamma - math.pi * np.round(np.mean(gamma) / math.pi)
    cols = [np.ones_like(M)]
    for k in range(1, harmonics + 1):
        cols += [np.cos(k * M), np.sin(k * M)]
    X = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(X, gamma, rcond=None)
    a = coef[1::2]
    b = coef[2::2]
    amps = np.hypot(a, b)
    resid = gamma - X @ coef
    return LibrationMeasurement(
        amplitude=float(amps[0]), phase=float(math.atan2(a[0], b[0])),
        signed_amplitude=float(b[0]), mean=float(coef[0]), harmonics=amps,
        residual_rms=float(np.sqrt(np.mean(resid**2))), orbits=float(span))
