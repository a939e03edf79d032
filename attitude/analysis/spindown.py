r"""The spin period of a run and its trend: how fast a body spins down (or up).

A tumbling satellite is followed by its spin period and by how that period changes:
Envisat's grew by 75 ms a day (Sommer et al. 2017), the spheres Larets and Stella slowed
exponentially with e-folding times of 50.7 and 231.9 days (Kucharski et al. 2014).  This
module turns an ephemeris into those numbers (docs/environment.md, "Published tumblers").

The **spin period** is ``P = 2 pi |L| / (2 E) = 2 pi / (omega . L_hat)``, the period of
the rotation about the angular momentum.  For a principal-axis spin and for a sphere it
is ``2 pi / |omega|``; for a tumbler it is a constant of the torque-free motion (``E`` and
``|L|`` are), so its change over a run is the work of the torques alone, not the polhode
modulation of ``|omega|``.  (A tumbler's own periods, polhode and precession, are
measured by :func:`attitude.analysis.diagnostics.measure_periods`; the run summary lists both.)

The **trend** ``dP/dt`` is the least-squares slope of ``P(t)`` over the run, with its
formal standard error; the **e-folding time** is ``1 / (d ln P / dt)`` from the
least-squares slope of ``ln P(t)``: exactly ``tau`` for an exponential spin-down
``P = P0 exp(t / tau)``, and ``P / (dP/dt)`` at the middle of a short run otherwise.  The
standard errors treat the residuals as independent; residuals that oscillate with the
orbit or the spin are correlated, so they are a lower bound on the real uncertainty.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..foundations.errors import DiagnosticsError, InsufficientDataError

__all__ = ["SpinTrend", "fit_spin_trend", "spin_period_series", "spin_trend"]

_SECONDS_PER_DAY = 86400.0


@dataclass(frozen=True)
class SpinTrend:
    """The spin period of a run at its ends and its least-squares trend.

    Attributes
    ----------
    period_start, period_end : float
        The spin period at the first and last epochs, s.
    trend, trend_stderr : float
        ``dP/dt`` (s per s, dimensionless) and its formal standard error: the slope of
        the straight line fitted to ``P(t)``.
    efolding, efolding_stderr : float
        ``1 / (d ln P / dt)``, s, from the straight line fitted to ``ln P(t)``: positive
        for a spin-down, negative for a spin-up, infinite without a trend.
    span : float
        Seconds between the first and last epochs.
    samples : int
        Epochs fitted.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 2 * 86400.0, 97)                  # two days
    >>> trend = fit_spin_trend(t, 134.74 + 0.075 / 86400.0 * t) # +75 ms/day
    >>> round(trend.trend_ms_per_day, 6), round(trend.period_end, 2)
    (75.0, 134.89)
    """

    period_start: float
    period_end: float
    trend: float
    trend_stderr: float
    efolding: float
    efolding_stderr: float
    span: float
    samples: int

    @property
    def trend_ms_per_day(self) -> float:
        """``dP/dt`` in milliseconds per day, the unit spin-down rates are published in.

        Examples
        --------
        >>> t = np.linspace(0.0, 86400.0, 25)
        >>> round(fit_spin_trend(t, 100.0 + 1e-6 * t).trend_ms_per_day, 6)   # 1 us/s
        86.4
        """
        return self.trend * _SECONDS_PER_DAY * 1e3

    def as_dict(self) -> dict:
        """Plain floats for the JSON report, with ``trend_ms_per_day`` and the e-folding
        time in days (``efolding_days``) added.

        Examples
        --------
        >>> t = np.linspace(0.0, 86400.0, 25)
        >>> d = fit_spin_trend(t, 10.0 * np.exp(t / (50.7 * 86400.0))).as_dict()
        >>> round(d["efolding_days"], 9), d["samples"]
        (50.7, 25)
        """
        out = {k: (float(v) if isinstance(v, float) else v) for k, v in asdict(self).items()}
        out["trend_ms_per_day"] = self.trend_ms_per_day
        out["efolding_days"] = self.efolding / _SECONDS_PER_DAY
        return out


def _line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of ``y = a + b x`` and its standard error (residual variance
    with ``n - 2`` degrees of freedom)."""
    dx = x - x.mean()
    sxx = float(dx @ dx)
    b = float(dx @ (y - y.mean())) / sxx
    r = (y - y.mean()) - b * dx
    return b, math.sqrt(float(r @ r) / (x.size - 2) / sxx)


def fit_spin_trend(t, period) -> SpinTrend:
    """Fit the trend of a spin-period series: ``dP/dt`` and the e-folding time.

    Parameters
    ----------
    t : (n,) array-like
        Epochs, s (increasing; at least 3).
    period : (n,) array-like
        The spin period at each epoch, s (finite, > 0).

    Returns
    -------
    SpinTrend

    Raises
    ------
    InsufficientDataError
        Fewer than three epochs, or all at one time.
    DiagnosticsError
        A period that is not finite and positive (a body at rest has none).

    Examples
    --------
    An exact exponential spin-down (a sphere in a uniform field,
    ``omega(t) = omega0 exp(-t / tau)``) gives ``tau`` back:

    >>> import numpy as np
    >>> tau = 50.7 * 86400.0                        # Larets, Kucharski et al. 2014
    >>> t = np.linspace(0.0, 3 * 86400.0, 73)
    >>> trend = fit_spin_trend(t, 2.0 * np.exp(t / tau))
    >>> round(trend.efolding / 86400.0, 9), trend.efolding_stderr < 1e-3
    (50.7, True)
    >>> round(trend.trend_ms_per_day, 2)           # ~ P(middle) / tau
    40.64
    """
    t = np.asarray(t, dtype=float).ravel()
    p = np.asarray(period, dtype=float).ravel()
    if t.shape != p.shape:
        raise DiagnosticsError(f"t has {t.size} epochs but period has {p.size} values",
                               key="period")
    if t.size < 3 or not np.ptp(t) > 0:
        raise InsufficientDataError(f"a trend needs at least 3 distinct epochs, got "
                                    f"{t.size}", key="t")
    if not np.all(np.isfinite(p) & (p > 0)):
        raise DiagnosticsError("the spin period must be finite and positive at every "
                               "epoch (a body at rest has none)", key="period")
    slope, slope_se = _line(t, p)
    rate, rate_se = _line(t, np.log(p))            # d ln P / dt
    efolding = math.inf if rate == 0.0 else 1.0 / rate
    efolding_se = math.inf if rate == 0.0 else rate_se / rate**2
    return SpinTrend(float(p[0]), float(p[-1]), slope, slope_se, efolding, efolding_se,
                     float(t[-1] - t[0]), int(t.size))


def spin_period_series(eph, body_index: int | None = None) -> np.ndarray:
    """The spin period ``2 pi |L| / (2 E)`` at every epoch of an ephemeris, s.

    ``2 pi / |omega|`` for a principal-axis spin or a sphere; for a tumbler the period of
    the rotation about ``L``, constant without torques.  Infinite for a body at rest.

    Parameters
    ----------
    eph : Ephemeris
    body_index : int, optional
        The body of an ensemble ephemeris (required for one).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState.from_quaternion([0, 0, 0, 1], epoch="2030-01-01",
    ...                                           omega_body=[0.0, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 100.0, 5))
    >>> np.round(spin_period_series(eph), 6)          # 2 pi / 0.1 rad/s
    array([62.831853, 62.831853, 62.831853, 62.831853, 62.831853])
    """
    ds = eph.dataset
    if "body" in ds.dims:
        if body_index is None:
            raise DiagnosticsError("an ensemble ephemeris: give body_index",
                                   key="body_index")
        ds = ds.isel(body=body_index)
    L = np.linalg.norm(np.asarray(ds["angular_momentum"].values, dtype=float), axis=-1)
    E = np.asarray(ds["kinetic_energy"].values, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(E > 0, math.pi * L / np.where(E > 0, E, 1.0), np.inf)


def spin_trend(eph, body_index: int | None = None) -> SpinTrend:
    """The spin period of an ephemeris at its ends and its trend (:func:`fit_spin_trend`
    of :func:`spin_period_series`): what ``attitude run`` reports.

    Examples
    --------
    A sphere spun across a uniform field slows as ``exp(-t / tau)``,
    ``tau = I / (m B^2)`` (``m`` the magnetic tensor of
    :class:`attitude.model.torques.EddyCurrentDamping`):

    >>> import numpy as np, attitude as att
    >>> from attitude.model.torques import EddyCurrentDamping, UniformField
    >>> body = att.RigidBody.from_principal_moments([0.1, 0.1, 0.1])
    >>> damper = EddyCurrentDamping(20.0, UniformField([3e-5, 0.0, 0.0]))
    >>> state = att.AttitudeState.from_quaternion([0, 0, 0, 1], epoch="2030-01-01",
    ...                                           omega_body=[0.0, 0.0, 2.0])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 86400.0, 25), torques=[damper])
    >>> tau = 0.1 / (20.0 * 3e-5**2)                # s
    >>> bool(abs(spin_trend(eph).efolding / tau - 1) < 1e-6)
    True
    """
    return fit_spin_trend(np.asarray(eph.dataset["time"].values, dtype=float),
                          spin_period_series(eph, body_index))
