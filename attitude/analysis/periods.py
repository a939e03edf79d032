r"""Periods measured on an ephemeris: the polhode period from the zero crossings of the
intermediate-axis rate (placed to a fraction of a sample by local interpolation), and
the precession and rotation periods from the slopes of the unwrapped Euler angles, each
with its standard error (``docs/diagnostics.md``, D 10-14).

Part of :mod:`attitude.analysis.diagnostics`, which re-exports every name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..foundations.errors import InsufficientDataError
from ..model.body import SYMMETRY_RTOL
from .angles import (
    PrincipalSeries,
    invariants,
    momentum_frame_angles,
    osculating_polhode_period,
    principal_series,
    reference_axis_for,
)

__all__ = [
    "MeasuredPeriod",
    "measure_periods",
    "linear_fit",
    "MIN_NUTATION",
    "MAX_ANGLE_STEP",
    "STENCIL",
    "HYSTERESIS",
]

_TWO_PI = 2.0 * math.pi

#: Relative amplitude of the intermediate-axis rate ``|omega_2| / |omega|`` below which the
#: body is taken not to nutate (pure principal-axis spin, rounding noise only): no polhode.
MIN_NUTATION = 1e-10
#: Points of the local interpolating polynomial used to place zero crossings (degree 5):
#: with >= 20 samples per period the crossing times are good to ~1e-8 of a period.
STENCIL = 6
#: Hysteresis of the zero-crossing detector, as a fraction of the signal's amplitude: a
#: crossing counts only when the signal goes from below ``-h`` to above ``+h``.
HYSTERESIS = 0.25


# ===========================================================================
# zero crossings with sub-sample interpolation (D 10-12)
# ===========================================================================
def _upward_crossings(x: np.ndarray, h: float) -> np.ndarray:
    """Indices ``i`` of upward zero crossings between samples ``i`` and ``i + 1``, with
    hysteresis ``h``: the last sign change before the signal enters ``x > h`` coming
    from ``x < -h``."""
    n = x.size
    state = np.where(x > h, 1, np.where(x < -h, -1, 0))
    idx = np.where(state != 0, np.arange(n), 0)
    np.maximum.accumulate(idx, out=idx)
    filled = state[idx]
    filled[(idx == 0) & (state[0] == 0)] = 0
    enter = np.flatnonzero((filled[1:] == 1) & (filled[:-1] == -1)) + 1
    up = np.flatnonzero((x[:-1] <= 0) & (x[1:] > 0))
    if enter.size == 0 or up.size == 0:
        return np.empty(0, dtype=int)
    j = np.searchsorted(up, enter, side="left") - 1
    ok = j >= 0
    return up[j[ok]]


def _poly_coeffs(t: np.ndarray, ys: np.ndarray, i: np.ndarray, m: int):
    """Coefficients (n, m, k) of the degree ``m - 1`` polynomials through ``m`` samples
    around each interval ``[t_i, t_i+1]`` in the local abscissa
    ``tau = (t - t_i)/(t_i+1 - t_i)``, for every series in ``ys`` (T, k)."""
    T = t.size
    s = np.clip(i - (m // 2 - 1), 0, T - m)
    j = s[:, None] + np.arange(m)[None, :]
    h = (t[i + 1] - t[i])[:, None]
    tau = (t[j] - t[i][:, None]) / h
    V = tau[:, :, None] ** np.arange(m)[None, None, :]
    return np.linalg.solve(V, ys[j])


def _horner(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Evaluate polynomials ``c`` (n, m, k) at ``tau`` (n,) -> (n, k)."""
    out = c[:, -1, :].copy()
    for k in range(c.shape[1] - 2, -1, -1):
        out = out * tau[:, None] + c[:, k, :]
    return out


def _horner_d(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    m = c.shape[1]
    out = (m - 1) * c[:, -1, :]
    for k in range(m - 2, 0, -1):
        out = out * tau[:, None] + k * c[:, k, :]
    return out


def _refine(t: np.ndarray, x: np.ndarray, others: np.ndarray, i: np.ndarray, m: int):
    """Crossing times of ``x`` in the intervals ``i`` by Newton's method on the local
    interpolating polynomial, the values of ``others`` (T, k) there, and an estimate of
    the interpolation error of each crossing time (difference with a polynomial of
    degree two lower)."""
    ys = np.column_stack([x, others])
    h = t[i + 1] - t[i]

    def root(mm):
        c = _poly_coeffs(t, ys, i, mm)
        cx = c[:, :, :1]
        tau = -x[i] / (x[i + 1] - x[i])                    # linear start
        for _ in range(30):
            f = _horner(cx, tau)[:, 0]
            d = _horner_d(cx, tau)[:, 0]
            with np.errstate(invalid="ignore", divide="ignore"):
                step = np.where(d != 0, f / d, 0.0)
            tau = np.clip(tau - step, -0.5, 1.5)
            if np.all(np.abs(step) < 1e-15):
                break
        return tau, _horner(c, tau)[:, 1:]

    m = min(m, t.size)
    tau, vals = root(m)
    if m >= 4:
        tau_lo, _ = root(m - 2)
        err = np.abs(tau - tau_lo) * h
    else:
        err = np.abs(h) * 0.5
    return t[i] + tau * h, vals, err


# ===========================================================================
# measured periods (D 10-14)
# ===========================================================================
@dataclass(frozen=True)
class MeasuredPeriod:
    """A period measured from an ephemeris.

    Attributes
    ----------
    value : float
        Seconds.
    uncertainty : float
        One-sigma uncertainty, seconds: the standard error of the least-squares fit
        combined with the interpolation error of the crossing times.
    cycles : float
        Number of cycles of the defining signal used.
    method : str
        How it was measured (``"omega_2 zero crossings"``, ...).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import measure_periods
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> p = measure_periods(eph)["polhode"]
    >>> p.method, p.cycles
    ('omega_2 zero crossings', 5.0)
    >>> exact = att.diagnose(body, state).periods["polhode"]
    >>> bool(abs(float(p) - exact) < 5 * p.uncertainty + 1e-9 * exact)
    True
    """

    value: float
    uncertainty: float
    cycles: float
    method: str

    def __float__(self) -> float:
        return float(self.value)


def linear_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares slope, its standard error and the intercept of ``y = a + b x``
    (the period slopes here, the drift rates of :mod:`.drift`).

    Examples
    --------
    >>> b, se, a = linear_fit(np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 5.0]))
    >>> b, se, float(a)
    (2.0, 0.0, 1.0)
    """
    n = x.size
    xm, ym = x.mean(), y.mean()
    dx = x - xm
    sxx = float(dx @ dx)
    b = float(dx @ (y - ym)) / sxx
    a = ym - b * xm
    if n > 2:
        r = y - a - b * x
        s2 = float(r @ r) / (n - 2)
        se = math.sqrt(s2 / sxx)
    else:
        se = 0.0
    return b, se, a


def _robust_amplitude(x: np.ndarray) -> float:
    lo, hi = np.percentile(x, [2.0, 98.0])
    return 0.5 * float(hi - lo)


def _polhode_crossings(series: PrincipalSeries, angles: dict, stencil: int):
    """Upward zero crossings of ``omega_2`` (the intermediate-axis rate: ``sn`` in SAM and
    LAM, a sinusoid for an axisymmetric body) with ``phi`` and ``psi`` there."""
    w2 = series.omega[:, 1]
    wn = np.linalg.norm(series.omega, axis=-1)
    amp = _robust_amplitude(w2)
    if not amp > MIN_NUTATION * float(np.median(wn)):
        return None
    i = _upward_crossings(w2, HYSTERESIS * amp)
    if i.size == 0:
        return np.empty(0), np.empty((0, 2)), np.empty(0)
    others = np.column_stack([angles["precession"], angles["rotation"]])
    return _refine(series.time, w2, others, i, stencil)


def measure_periods(source, *, body_index: int | None = None, reference_axis: int | None = None,
                    keys=None, stencil: int = STENCIL) -> dict[str, MeasuredPeriod]:
    """Periods measured from the series of an ephemeris (the keys of docs/diagnostics.md,
    "Measured periods").

    Parameters
    ----------
    source : Ephemeris or PrincipalSeries
    body_index : int, optional
        Body of a batch ephemeris.
    reference_axis : {1, 3}, optional
        Axis of the Euler angles (default: :func:`reference_axis_for`).
    keys : iterable of str, optional
        Which periods to measure.  Default: ``polhode``, ``precession``, ``rotation`` if
        the body nutates (``omega_2`` oscillates), else ``spin`` (plus ``precession`` for
        an axisymmetric body spinning about a transverse axis).
    stencil : int
        Points of the local interpolating polynomial (D 11).

    Returns
    -------
    dict
        ``{key: MeasuredPeriod}``.

    Raises
    ------
    InsufficientDataError
        If the series is too short (less than one cycle of the defining signal: two
        upward zero crossings of ``omega_2``, or one turn of the spin angle) or has too
        few samples.

    Notes
    -----
    *Polhode*: upward zero crossings ``t_n`` of ``omega_2`` (with hysteresis), placed
    by Newton's method on a local degree-5 interpolating polynomial; the period is the
    least-squares slope of ``t_n`` against the cycle number ``n`` (D 12).
    *Precession*: ``phi`` interpolated at the same crossing times advances by the same
    amount every polhode cycle in torque-free motion, so the slope of ``phi(t_n)``
    against ``t_n`` is exactly the mean precession rate ``<dphi/dt>`` and
    ``P_phi = 2 pi / |<dphi/dt>|`` (D 13); *rotation* likewise from ``psi(t_n)``.
    *Spin* (principal-axis rotation): ``2 pi`` over the slope of the spin angle
    ``phi + psi`` (D 14).  On torque-free ephemerides sampled 20 times per period or more
    these agree with :func:`attitude.diagnose` to better than 1e-8 relative.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import measure_periods
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> periods = measure_periods(eph)
    >>> sorted(periods)
    ['polhode', 'precession', 'rotation']
    >>> exact = att.diagnose(body, state).periods          # the closed form
    >>> bool(abs(periods["precession"].value / exact["precession"] - 1) < 1e-8)
    True
    """
    series = source if isinstance(source, PrincipalSeries) else principal_series(
        source, body_index)
    t = series.time
    if t.size < max(stencil, 4):
        raise InsufficientDataError(f"{t.size} samples: at least {max(stencil, 4)} are "
                                    "needed to measure a period")
    inv = invariants(series.omega, series.moments)
    if not np.any(inv["L"] > 0):
        raise InsufficientDataError("the body is at rest: no period to measure")
    ref = reference_axis or reference_axis_for(series.moments, inv["dynamic_inertia"])
    angles = momentum_frame_angles(series, ref)
    cross = _polhode_crossings(series, angles, stencil)
    if keys is None:
        if cross is not None:
            keys = ("polhode", "precession", "rotation")
        else:
            keys = ("spin",)
            A, B, C = series.moments
            tol = SYMMETRY_RTOL * C
            axisym = ((B - A) <= tol or (C - B) <= tol) and (C - A) > tol
            nut = angles["nutation"][np.isfinite(angles["nutation"])]
            if axisym and nut.size and float(nut.min()) > 1e-3:
                keys = ("spin", "precession")
    keys = tuple(keys)
    out: dict[str, MeasuredPeriod] = {}
    span = float(t[-1] - t[0])
    need_polhode = any(k in ("polhode", "rotation") for k in keys) or (
        "precession" in keys and cross is not None)
    if need_polhode:
        if cross is None:
            raise InsufficientDataError(
                "the body does not nutate (omega_2 is constant): no polhode period; "
                "ask for keys=('spin',)")
        tc, vals, err = cross
        for key, name in (("precession", "precession"), ("rotation", "rotation")):
            if key in keys:
                _check_sampling(angles[name], name, t)
        if tc.size < 2:
            P_osc = osculating_polhode_period(series.omega, series.moments)
            P_osc = P_osc[~np.isnan(P_osc)]
            P_osc = float(np.median(P_osc)) if P_osc.size else math.inf
            why = ("on the separatrix the polhode period is infinite" if not
                   np.isfinite(P_osc) else f"the expected polhode period is about "
                   f"{P_osc:.6g} s ({span / P_osc:.3g} of it covered)")
            raise InsufficientDataError(
                f"the ephemeris spans {span:.6g} s with {tc.size} upward zero crossing(s) "
                f"of omega_2: at least one full polhode cycle (two crossings) is needed; "
                f"{why}")
        gaps = np.diff(tc)
        n = np.concatenate([[0.0], np.cumsum(np.rint(gaps / np.median(gaps)))])
        P, se, _ = linear_fit(n, tc)
        ierr = float(np.sqrt(np.mean(err ** 2)))
        unc = math.hypot(se, math.sqrt(2.0) * ierr / n[-1])
        cycles = float(n[-1])
        if "polhode" in keys:
            out["polhode"] = MeasuredPeriod(P, unc, cycles, "omega_2 zero crossings")
        for key, col, name in (("precession", 0, "phi"), ("rotation", 1, "psi")):
            if key not in keys:
                continue
            rate, rse, _ = linear_fit(tc, vals[:, col])
            if rate == 0.0:
                continue
            Pk = _TWO_PI / abs(rate)
            # the angle's slope error plus the crossing-time errors propagated through it
            rel = math.hypot(rse / abs(rate), math.sqrt(2.0) * ierr / (tc[-1] - tc[0]))
            out[key] = MeasuredPeriod(Pk, Pk * rel, cycles,
                                      f"{name} at omega_2 zero crossings")
    elif "precession" in keys:
        _check_sampling(angles["precession"], "precession", t)
        out["precession"] = _slope_period(t, angles["precession"], "phi slope")
    if "spin" in keys:
        _check_sampling(angles["spin"], "spin", t)
        out["spin"] = _slope_period(t, angles["spin"], "spin-angle slope")
    return out


#: Largest step of an unwrapped angle between samples accepted for a period (rad): beyond
#: it the unwrapping may have aliased (it needs less than pi).
MAX_ANGLE_STEP = 0.75 * math.pi


def _check_sampling(angle: np.ndarray, name: str, t: np.ndarray) -> None:
    steps = np.abs(np.diff(angle))
    steps = steps[np.isfinite(steps)]
    step = float(steps.max()) if steps.size else 0.0
    if step > MAX_ANGLE_STEP:
        raise InsufficientDataError(
            f"the {name} angle turns by up to {math.degrees(step):.0f} deg between samples "
            f"(limit {math.degrees(MAX_ANGLE_STEP):.0f} deg): the ephemeris is sampled too "
            "coarsely to follow it; resample at least 4 times per period of the fastest "
            "angle")


def _slope_period(t: np.ndarray, angle: np.ndarray, method: str) -> MeasuredPeriod:
    turns = abs(float(angle[-1] - angle[0])) / _TWO_PI
    if not turns >= 1.0:
        raise InsufficientDataError(
            f"the ephemeris spans {t[-1] - t[0]:.6g} s, {turns:.3g} turn(s) of the angle "
            "that defines the period: at least one full turn is needed")
    step = max(1, t.size // 200_000)
    rate, se, _ = linear_fit(t[::step], angle[::step])
    P = _TWO_PI / abs(rate)
    return MeasuredPeriod(P, P * se / abs(rate), turns, method)
