"""Conservation drift and attitude noise of an ephemeris: the drift of ``|L|`` and ``E``
and their rates (which torque-free motion keeps constant), and the rounding noise of
the attitude samples.

Part of :mod:`attitude.analysis.diagnostics`, which re-exports every name.
"""

from __future__ import annotations

import math

import numpy as np

from .angles import PrincipalSeries, invariants
from .periods import linear_fit

__all__ = ["conservation_drift", "attitude_noise"]


# ===========================================================================
# conservation and noise
# ===========================================================================
def conservation_drift(series: PrincipalSeries) -> dict:
    """Drift of ``|L|`` and ``E`` and their rates.

    Returns
    -------
    dict
        Series (T,): ``L`` (kg m^2/s), ``E`` (J), ``L_drift`` ``|L|/|L_0| - 1``,
        ``E_drift`` ``E/E_0 - 1``, ``L_rate`` ``d|L|/dt`` (kg m^2/s^2), ``E_rate``
        ``dE/dt`` (W), ``L_direction_drift`` (rad, angle between ``L(t)`` and
        ``L(t_0)`` in the inertial frame); scalars: ``L_rel_drift``, ``E_rel_drift``
        (largest ``|drift|``), ``L_drift_rate``, ``E_drift_rate`` (least-squares slope of
        the relative drift, 1/s).  Derivatives are second-order finite differences
        (``numpy.gradient``).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series, conservation_drift
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> drift = conservation_drift(principal_series(eph))
    >>> bool(drift["E_rel_drift"] < 1e-14 and drift["L_rel_drift"] < 1e-14)
    True
    >>> drift["E"].shape
    (1501,)
    """
    t = series.time
    inv = invariants(series.omega, series.moments)
    L, E = inv["L"], inv["E"]
    Li = series.momentum_inertial
    with np.errstate(invalid="ignore", divide="ignore"):
        Ld = L / L[0] - 1.0 if L[0] > 0 else np.zeros_like(L)
        Ed = E / E[0] - 1.0 if E[0] > 0 else np.zeros_like(E)
        c = np.cross(Li, Li[0])
        ang = np.arctan2(np.linalg.norm(c, axis=-1), Li @ Li[0])
    if t.size > 1:
        Lr, Er = np.gradient(L, t), np.gradient(E, t)
        Lslope = linear_fit(t, Ld)[0] if t.size > 2 else float(Ld[-1] / (t[-1] - t[0]))
        Eslope = linear_fit(t, Ed)[0] if t.size > 2 else float(Ed[-1] / (t[-1] - t[0]))
    else:
        Lr, Er = np.zeros_like(L), np.zeros_like(E)
        Lslope = Eslope = 0.0
    return {"L": L, "E": E, "L_drift": Ld, "E_drift": Ed, "L_rate": Lr, "E_rate": Er,
            "L_direction_drift": ang,
            "L_rel_drift": float(np.max(np.abs(Ld))), "E_rel_drift": float(np.max(np.abs(Ed))),
            "L_drift_rate": float(Lslope), "E_drift_rate": float(Eslope)}


def attitude_noise(series: PrincipalSeries) -> float:
    """Estimate of white attitude noise (rad per axis) from the jitter of the inertial
    direction of ``L``.

    A rigid body's angular momentum turns only under torque, smoothly; sample-to-sample
    jitter of its direction computed from the attitude is measurement noise.  The
    estimate is the median norm of the fourth differences of the unit vector, scaled for
    white noise (``var(Delta^4 x) = 70 sigma^2``; a 2-D Gaussian's median norm is
    ``1.177 sigma``), which removes smooth motion up to cubic in time (D 15).  Zero for an
    exact torque-free ephemeris (to rounding).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series, attitude_noise, PrincipalSeries
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> s = principal_series(eph)
    >>> bool(attitude_noise(s) < 1e-12)                    # exact ephemeris
    True
    >>> rng = np.random.default_rng(1)                     # add 1e-4 rad per axis
    >>> kick = Rotation.from_rotvec(rng.normal(0.0, 1e-4, (1501, 3)))
    >>> noisy = (Rotation.from_quat(s.quaternion) * kick).as_quat()
    >>> sigma = attitude_noise(PrincipalSeries(s.time, noisy, s.omega, s.moments, s.body))
    >>> bool(0.8e-4 < sigma < 1.2e-4)
    True
    """
    Li = series.momentum_inertial
    n = np.linalg.norm(Li, axis=-1)
    ok = n > 0
    if ok.sum() < 6:
        return 0.0
    u = Li[ok] / n[ok, None]
    d4 = np.diff(u, n=4, axis=0)
    return float(np.median(np.linalg.norm(d4, axis=-1)) / (1.1774 * math.sqrt(70.0)))
