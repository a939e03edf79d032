r"""Rotation-state classification of an attitude ephemeris (``att.classify``).

From any ephemeris (any propagator, or a file read back) this module names the regime
(docs/diagnostics.md, "Classification rules": ``PA-short``, ``PA-long``, ``SAM``, ``LAM``,
``separatrix``, ``axisymmetric``, ``spherical``, ``at-rest``, ``chaotic``), with its
measured periods, nutation, excitation, the margin to the nearest boundary and a
confidence; resolves it in time over sliding
windows; and, when asked, tests for chaos with a finite-time Lyapunov exponent.

Every threshold is a field of :class:`Thresholds` (documented there and in
``docs/diagnostics.md``), and each result says which one decided (``decided_by``).

The classification of a window rests on *osculating* torque-free quantities computed
from every sample's body rates (:func:`attitude.analysis.diagnostics.invariants`): the signed
separatrix distance ``m1`` (sign of ``L^2 - 2EB``) and the largest nutation angle of the
torque-free cycle through the sample.  They are exact for torque-free motion and
follow a perturbed motion sample by sample; measured periods and angles come from the
series themselves (:mod:`attitude.analysis.diagnostics`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.special import ndtr

from ..foundations.errors import ClassificationError
from ..foundations.quantities import to_si
from ..model.body import symmetry_of
from ..model.ephemeris import Ephemeris
from ..model.regimes import PERIOD_KEYS, REGIMES, Thresholds
from ..model.state import AttitudeState
from .diagnostics import (
    DiagnosticsError,
    InsufficientDataError,
    PrincipalSeries,
    attitude_noise,
    invariants,
    measure_periods,
    momentum_frame_angles,
    osculating_polhode_period,
    principal_series,
    reference_axis_for,
)
from .lyapunov import LyapunovResult, lyapunov_exponent

__all__ = [
    "Window",
    "Transition",
    "Classification",
    "classify",
    "initial_state",
    "format_classification",
    "classification_json",
]



# ===========================================================================
@dataclass(frozen=True)
class Window:
    """Classification of one sliding window.

    ``start``/``stop`` (s since the epoch) bound the samples used; ``regime``,
    ``margin`` (in ``margin_units``) to ``boundary``, ``confidence``, ``decided_by`` as in
    :class:`Classification`; ``periods`` measured inside the window (s, may be empty).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 6000.0, 3001))
    >>> w = att.classify(eph, window="3000 s").windows[0]
    >>> w.regime, w.start
    ('SAM', 0.0)
    """

    start: float
    stop: float
    regime: str
    margin: float
    margin_units: str
    boundary: str
    confidence: float
    decided_by: str
    agreement: float
    periods: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Transition:
    """A change of regime at ``epoch`` (s since the epoch), refined from the per-sample
    osculating quantities: ``quantity`` crossed ``threshold`` there.

    Examples
    --------
    >>> from attitude.analysis.classification import Transition
    >>> Transition(epoch=120.0, before="LAM", after="SAM", quantity="m1", threshold=0.0)
    Transition(epoch=120.0, before='LAM', after='SAM', quantity='m1', threshold=0.0)
    """

    epoch: float
    before: str
    after: str
    quantity: str
    threshold: float


@dataclass(frozen=True)
class Classification:
    """The rotation state of an ephemeris (``att.classify``).

    Attributes
    ----------
    regime : str
        Regime name of docs/diagnostics.md (the dominant one for a run that changes regime; see
        :attr:`segments`), or ``"chaotic"``.
    periods : dict
        Measured periods (s), keys of docs/diagnostics.md (``polhode``, ``precession``,
        ``rotation``, ``spin``), over the span of the dominant regime.
    period_uncertainties : dict
        One-sigma uncertainties (s) of :attr:`periods`.
    margin : float
        Distance to the nearest boundary of the regime, in :attr:`margin_units` (positive
        inside the regime).
    margin_units : str
        ``"rad"`` (nutation angle vs ``principal_axis_angle``), ``"1"`` (separatrix
        distance ``m1`` or relative moment difference), ``"rad s-1"`` (rest) or
        ``"e-folds"`` (excess separation over the regular control: chaos).
    boundary : str
        The nearest boundary (the regime on the other side).
    decided_by : str
        The :class:`Thresholds` field that decided the regime.
    confidence : float
        In [0, 1]: ``min(Phi(margin/width), agreement) * exp(-noise/noise_angle)``: the
        probability that the deciding quantity is on the reported side of its threshold
        (normal CDF of the margin over the threshold's width, combined with the scatter
        of the quantity), capped by the fraction of samples whose own osculating regime
        agrees, times an attitude-noise factor (see :class:`Thresholds`);
        :attr:`confidence_factors` holds the three factors.
    segments : list of (start_s, stop_s, regime)
        Time-resolved classification: consecutive windows with the same regime merged;
        the boundaries are those of the windows (see :attr:`transitions` for refined
        epochs).
    transitions : list of Transition
    windows : list of Window
    window_length : float
        s.
    nutation_range : (float, float)
        Measured range of the nutation angle ``theta`` (rad) about :attr:`reference_axis`.
    nutation_amplitude : float
        ``(theta_max - theta_min)/2`` (rad).
    reference_axis : str
        ``"C"`` or ``"A"``.
    excitation, dynamic_inertia, separatrix_distance : float
        Medians over the dominant span (dimensionless, kg m^2, dimensionless).
    attitude_noise : float
        Estimated attitude noise (rad).
    stationary : bool
        True when every window has the same regime.
    lyapunov : LyapunovResult or None
    span : (float, float)
        First and last sample (s since the epoch).
    thresholds : Thresholds

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> c = att.classify(att.propagate(body, state, np.linspace(0.0, 6000.0, 3001)))
    >>> c.regime, c.boundary              # well inside SAM: nearest is the spin about C
    ('SAM', 'PA-short')
    """

    regime: str
    periods: dict
    period_uncertainties: dict
    margin: float
    margin_units: str
    boundary: str
    decided_by: str
    confidence: float
    confidence_factors: dict
    segments: list
    transitions: list
    windows: list
    window_length: float
    nutation_range: tuple
    nutation_amplitude: float
    reference_axis: str
    excitation: float
    dynamic_inertia: float
    separatrix_distance: float
    attitude_noise: float
    stationary: bool
    span: tuple
    lyapunov: LyapunovResult | None = None
    thresholds: Thresholds = field(default_factory=Thresholds, repr=False)


# ===========================================================================
# per-sample osculating labels
# ===========================================================================
def _phi(x):
    """Standard normal CDF."""
    return float(ndtr(x))


def _sample_quantities(series: PrincipalSeries, th: Thresholds) -> dict:
    """Per-sample osculating quantities and labels (vectorised)."""
    inv = invariants(series.omega, series.moments)
    rate = np.linalg.norm(series.omega, axis=-1)
    Lb = series.momentum_body
    Ln = np.linalg.norm(Lb, axis=-1)
    La = np.abs(Lb)
    axis = np.column_stack([np.arctan2(np.hypot(La[:, 1], La[:, 2]), La[:, 0]),
                            np.arctan2(np.hypot(La[:, 0], La[:, 2]), La[:, 1]),
                            np.arctan2(np.hypot(La[:, 0], La[:, 1]), La[:, 2])])
    axis[Ln == 0] = np.nan                                    # angle to each axis line
    sym = symmetry_of(series.moments, th.symmetry_rtol)
    T = rate.size
    m1 = inv["separatrix_distance"]
    if sym == "spherical":
        labels = np.full(T, "spherical", dtype=object)
        nut = np.full(T, np.nan)
    elif sym in ("oblate", "prolate"):
        j = 2 if sym == "oblate" else 0
        nut = axis[:, j]
        pa = "PA-short" if sym == "oblate" else "PA-long"
        labels = np.where(nut <= th.principal_axis_angle, pa, "axisymmetric").astype(object)
    else:
        nC, nA = inv["nutation_max_C"], inv["nutation_max_A"]
        nut = np.where(m1 >= 0, nC, nA)
        labels = np.where(
            np.abs(m1) <= th.separatrix, "separatrix",
            np.where(m1 > 0, np.where(nC <= th.principal_axis_angle, "PA-short", "SAM"),
                     np.where(nA <= th.principal_axis_angle, "PA-long", "LAM"))).astype(object)
    labels[rate <= th.rest_rate] = "at-rest"
    return {"labels": labels, "rate": rate, "m1": m1, "nutation_max": nut,
            "excitation": inv["excitation"], "dynamic_inertia": inv["dynamic_inertia"],
            "symmetry": sym}


def _finite(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return x[np.isfinite(x)]


def _nanmedian(x) -> float:
    x = _finite(x)
    return float(np.median(x)) if x.size else math.nan


def _nanmax(x) -> float:
    x = _finite(x)
    return float(x.max()) if x.size else math.nan


def _nanmin(x) -> float:
    x = _finite(x)
    return float(x.min()) if x.size else math.nan


def _robust_sigma(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    if x.size < 2:
        return 0.0
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def _judge(q: dict, sl: slice, th: Thresholds, moments) -> dict:
    """Regime, margin, boundary, confidence factor of the samples ``sl``."""
    labels = q["labels"][sl]
    m1 = q["m1"][sl]
    nut = q["nutation_max"][sl]
    sym = q["symmetry"]
    A, B, C = moments
    values, counts = np.unique(labels.astype(str), return_counts=True)
    regime = str(values[np.argmax(counts)])
    crossing = (sym == "triaxial" and _nanmax(m1) > th.separatrix
                and _nanmin(m1) < -th.separatrix)
    soft = th.softness
    if crossing:
        lo, hi = -_nanmin(m1), _nanmax(m1)
        return dict(regime="separatrix", margin=0.0, units="1", boundary="SAM/LAM",
                    decided_by="separatrix (sign change of L^2 - 2EB in the window)",
                    p=_phi(min(lo, hi) / (soft * th.separatrix)), agreement=1.0)
    agreement = float(np.mean(labels == regime))
    if regime == "at-rest":
        x = float(np.max(q["rate"][sl]))
        margin, units, boundary, by = th.rest_rate - x, "rad s-1", "rotating", "rest_rate"
        width = soft * th.rest_rate or 1e-300
        sig = 0.0
    elif regime == "spherical":
        x = (C - A) / C
        margin, units, boundary, by = th.symmetry_rtol - x, "1", "axisymmetric", \
            "symmetry_rtol"
        width, sig = soft * th.symmetry_rtol or 1e-300, 0.0
    elif regime in ("axisymmetric",) or (sym in ("oblate", "prolate")
                                         and regime in ("PA-short", "PA-long")):
        pa = "PA-short" if sym == "oblate" else "PA-long"
        x = _nanmedian(nut)
        sig = _robust_sigma(nut)
        if regime == "axisymmetric":
            margin, boundary = x - th.principal_axis_angle, pa
            by = "symmetry_rtol"
        else:
            margin, boundary = th.principal_axis_angle - x, "axisymmetric"
            by = "principal_axis_angle"
        units, width = "rad", soft * th.principal_axis_angle
    elif regime in ("PA-short", "PA-long"):
        x = _nanmedian(nut)
        sig = _robust_sigma(nut)
        margin, units = th.principal_axis_angle - x, "rad"
        boundary = "SAM" if regime == "PA-short" else "LAM"
        by, width = "principal_axis_angle", soft * th.principal_axis_angle
    elif regime == "separatrix":
        x = _nanmedian(np.abs(m1))
        sig = _robust_sigma(m1)
        margin, units = th.separatrix - x, "1"
        boundary = "SAM" if _nanmedian(m1) >= 0 else "LAM"
        by, width = "separatrix", soft * th.separatrix
    else:  # SAM / LAM
        a = _nanmedian(np.abs(m1))
        if a < 0.5:                        # nearer the separatrix (m1 = 0) than PA (1)
            sig = _robust_sigma(m1)
            margin, units, boundary = a - th.separatrix, "1", "separatrix"
            by, width = "separatrix", soft * th.separatrix
        else:
            x = _nanmedian(nut)
            sig = _robust_sigma(nut)
            margin, units = x - th.principal_axis_angle, "rad"
            boundary = "PA-short" if regime == "SAM" else "PA-long"
            by, width = "principal_axis_angle", soft * th.principal_axis_angle
    p = _phi(margin / math.hypot(sig, width))
    return dict(regime=regime, margin=float(margin), units=units, boundary=boundary,
                decided_by=by, p=p, agreement=agreement)


_PERIODS_OF = {
    "SAM": ("polhode", "precession", "rotation"),
    "LAM": ("polhode", "precession", "rotation"),
    "PA-short": ("spin",),
    "PA-long": ("spin",),
    "spherical": ("spin",),
    "axisymmetric": None,          # measure_periods decides (nutating or transverse spin)
    "separatrix": (),
    "at-rest": (),
    "chaotic": None,
}


def _reference_axis(regime: str, moments, dyn) -> int:
    sym = symmetry_of(moments)
    if sym != "triaxial":
        return reference_axis_for(moments, dyn)
    if regime in ("LAM", "PA-long"):
        return 1
    if regime in ("SAM", "PA-short"):
        return 3
    return reference_axis_for(moments, dyn)


def _measure(series: PrincipalSeries, regime: str, ref: int, require: bool):
    keys = _PERIODS_OF.get(regime, None)
    if keys == ():
        return {}, {}
    try:
        m = measure_periods(series, reference_axis=ref, keys=keys)
    except InsufficientDataError:
        if require:
            raise
        return {}, {}
    if keys == ("spin",) and regime != "spherical":
        # a principal-axis spin within the threshold may still wobble: its polhode
        # (free-nutation) period, e.g. the Earth's Euler period, when measurable
        try:
            m.update(measure_periods(series, reference_axis=ref, keys=("polhode",)))
        except InsufficientDataError:
            pass
    return ({k: float(v.value) for k, v in m.items()},
            {k: float(v.uncertainty) for k, v in m.items()})


# ===========================================================================
# windows
# ===========================================================================
def _window_length(series: PrincipalSeries, q: dict, th: Thresholds) -> float:
    P = osculating_polhode_period(series.omega, series.moments)
    P = P[np.isfinite(P) & (P > 0)]
    rate = q["rate"]
    if P.size:
        base = float(np.median(P))
    elif np.any(rate > 0):
        base = 2 * math.pi / float(np.median(rate[rate > 0]))
    else:
        base = float(series.time[-1] - series.time[0])
    return th.window_cycles * base


def _windows(t: np.ndarray, length: float, th: Thresholds):
    """Index slices of sliding windows of ``length`` seconds covering ``t``."""
    span = float(t[-1] - t[0])
    T = t.size
    if length >= span or T <= th.min_window_samples:
        return [slice(0, T)], span
    # enough samples per window
    dt = span / (T - 1)
    length = max(length, th.min_window_samples * dt)
    if length >= span:
        return [slice(0, T)], span
    step = length * (1.0 - th.window_overlap)
    n = int(math.ceil((span - length) / step)) + 1
    starts = t[0] + np.minimum(np.arange(n) * step, span - length)
    lo = np.searchsorted(t, starts, side="left")
    hi = np.searchsorted(t, starts + length, side="right")
    return [slice(int(a), int(b)) for a, b in zip(lo, hi)], length


def _segments(t, wins, results):
    """Merge consecutive windows with one regime; each window owns the span between the
    midpoints of its centre and its neighbours' centres."""
    centres = np.array([0.5 * (t[w.start] + t[w.stop - 1]) for w in wins])
    bounds = np.concatenate([[t[0]], 0.5 * (centres[1:] + centres[:-1]), [t[-1]]])
    segs = []
    for i, r in enumerate(results):
        if segs and segs[-1][2] == r["regime"]:
            segs[-1][1] = float(bounds[i + 1])
        else:
            segs.append([float(bounds[i]), float(bounds[i + 1]), r["regime"]])
    return [tuple(s) for s in segs]


def _crossing_epoch(t, x, level, lo, hi):
    """Epoch nearest the middle of ``[lo, hi)`` (indices) where ``x`` crosses ``level``
    (linear interpolation), or None."""
    xs = x[lo:hi] - level
    s = np.sign(xs)
    k = np.flatnonzero((s[:-1] * s[1:] < 0) & np.isfinite(xs[:-1]) & np.isfinite(xs[1:]))
    if k.size == 0:
        return None
    mid = 0.5 * (hi - lo)
    k = k[np.argmin(np.abs(k - mid))]
    a, b = xs[k], xs[k + 1]
    i = lo + k
    return float(t[i] + (t[i + 1] - t[i]) * a / (a - b))


def _transitions(t, q, segs, length, th):
    out = []
    for (_, s1, a), (_, _, b) in zip(segs[:-1], segs[1:]):
        lo = int(np.searchsorted(t, s1 - length, side="left"))
        hi = int(np.searchsorted(t, s1 + length, side="right"))
        hi = min(hi, t.size)
        pair = {a, b}
        epoch, quantity, level = None, "", math.nan
        if "separatrix" in pair or pair == {"SAM", "LAM"}:
            quantity, level = "separatrix_distance", 0.0
            epoch = _crossing_epoch(t, q["m1"], 0.0, lo, hi)
        elif pair & {"PA-short", "PA-long"}:
            quantity, level = "nutation_max", th.principal_axis_angle
            epoch = _crossing_epoch(t, q["nutation_max"], level, lo, hi)
        elif "at-rest" in pair:
            quantity, level = "rate", th.rest_rate
            epoch = _crossing_epoch(t, q["rate"], level, lo, hi)
        out.append(Transition(float(epoch if epoch is not None else s1), a, b, quantity,
                              level))
    return out


# ===========================================================================
# classify
# ===========================================================================
def _method_of(eph: Ephemeris) -> str | None:
    m = re.search(r"method=(\w+)", str(eph.dataset.attrs.get("source", "")))
    return m.group(1) if m else None


def initial_state(eph: Ephemeris, body_index: int | None = None) -> AttitudeState:
    """The state at the first sample of an ephemeris (to restart a propagation, e.g.
    for :func:`lyapunov_exponent`); its epoch is that of the first sample.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.analysis.classification import initial_state
    >>> eph = att.propagate(body, state, [100.0, 200.0])
    >>> s = initial_state(eph)
    >>> bool(np.allclose(s.omega_body, eph.dataset["angular_velocity"].values[0]))
    True
    """
    ds = eph.dataset
    q = ds["quaternion"].values
    w = ds["angular_velocity"].values
    if eph.is_batch:
        if body_index is None:
            raise ClassificationError("a batch ephemeris: give body_index")
        q, w = q[body_index], w[body_index]
    epoch = eph.times[0]
    return AttitudeState(epoch, Rotation.from_quat(q[0]), w[0], eph.frame)


def classify(eph: Ephemeris, *, window=None, body_index: int | None = None,
             thresholds: Thresholds | None = None, chaos=False, torques=None,
             lyapunov_options: dict | None = None, require_periods: bool = True):
    """Classify the rotation of an ephemeris (``att.classify``).

    Parameters
    ----------
    eph : Ephemeris
        From any propagator or file (needs ``quaternion``, ``angular_velocity`` and the
        body's inertia).
    window : float, Quantity or str, optional
        Length of the sliding windows (s, or e.g. ``"2 h"``).  Default
        ``thresholds.window_cycles`` osculating polhode periods (median over the run).
        A window longer than the run gives one window.
    body_index : int, optional
        Body of a batch ephemeris; without it a batch gives a list, one result per body.
    thresholds : Thresholds, optional
    chaos : bool or LyapunovResult
        ``True`` computes a finite-time Lyapunov exponent from the first sample of
        ``eph`` with ``torques`` over the span of ``eph`` (:func:`lyapunov_exponent`;
        options in ``lyapunov_options``, the propagator method defaulting to the one
        named in the ephemeris' ``source`` attribute); a :class:`LyapunovResult` is used
        as given.  ``chaotic`` replaces the regime when the exponent is significant.
    torques : sequence of torque models, optional
        The torques that produced ``eph`` (an ephemeris does not record them); needed
        for ``chaos=True``.
    lyapunov_options : dict, optional
        Extra keywords for :func:`lyapunov_exponent`.
    require_periods : bool
        Raise :class:`~attitude.foundations.errors.InsufficientDataError` when the periods of
        the regime cannot be measured (less than one cycle); otherwise leave them out.

    Returns
    -------
    Classification (or a list of them for a batch without ``body_index``)

    Raises
    ------
    InsufficientDataError
        Fewer than 2 samples, or (``require_periods``) less than one cycle of a period
        of the regime.
    ClassificationError
        ``chaos=True`` without ``torques``, or an unusable ``window``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.classification import classify
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> c = classify(att.propagate(body, state, np.linspace(0.0, 3000.0, 1501)))
    >>> c.regime, c.boundary, round(c.margin, 3), c.confidence > 0.99
    ('SAM', 'PA-short', 0.523, True)
    >>> P = att.diagnose(body, state).periods
    >>> all(abs(c.periods[k] / P[k] - 1) < 1e-8 for k in P)
    True
    """
    th = thresholds or Thresholds()
    if eph.is_batch and body_index is None:
        n = eph.dataset.sizes["body"]
        return [classify(eph, window=window, body_index=i, thresholds=th, chaos=chaos,
                         torques=torques, lyapunov_options=lyapunov_options,
                         require_periods=require_periods) for i in range(n)]
    series = principal_series(eph, body_index if eph.is_batch else None)
    t = series.time
    if t.size < 2:
        raise InsufficientDataError(f"{t.size} sample(s): a classification needs a time "
                                    "series (at least 2 samples, and one cycle for the "
                                    "periods)")
    q = _sample_quantities(series, th)
    if window is None:
        length = _window_length(series, q, th)
    else:
        length = to_si(window, "s", key="window", shape=(), positive=True,
                       error=ClassificationError)
    wins, length = _windows(t, length, th)
    moments = tuple(float(x) for x in series.moments)
    results = [_judge(q, w, th, moments) for w in wins]
    noise = attitude_noise(series)
    quality = math.exp(-noise / th.noise_angle) if th.noise_angle > 0 else 1.0
    windows = []
    for w, r in zip(wins, results):
        sub = series.slice(w)
        ref = _reference_axis(r["regime"], series.moments, q["dynamic_inertia"][w])
        per = _measure(sub, r["regime"], ref, False)[0] if w.stop - w.start > 8 else {}
        windows.append(Window(float(t[w.start]), float(t[w.stop - 1]), r["regime"],
                              r["margin"], r["units"], r["boundary"],
                              min(r["p"], r["agreement"]) * quality, r["decided_by"],
                              r["agreement"], per))
    segs = _segments(t, wins, results)
    stationary = len(segs) == 1
    if stationary:
        span_sl = slice(0, t.size)
    else:
        totals: dict[str, float] = {}
        for s0, s1, r in segs:
            totals[r] = totals.get(r, 0.0) + (s1 - s0)
        dominant = max(totals, key=totals.get)
        longest = max((s for s in segs if s[2] == dominant), key=lambda s: s[1] - s[0])
        span_sl = slice(int(np.searchsorted(t, longest[0], side="left")),
                        int(np.searchsorted(t, longest[1], side="right")))
    overall = _judge(q, span_sl, th, moments)
    regime = overall["regime"]
    sub = series.slice(span_sl)
    ref = _reference_axis(regime, series.moments, q["dynamic_inertia"][span_sl])
    periods, uncs = _measure(sub, regime, ref, require_periods)
    periods = {k: periods[k] for k in PERIOD_KEYS if k in periods}
    angles = momentum_frame_angles(sub, ref)
    nut = angles["nutation"]
    nut_range = (_nanmin(nut), _nanmax(nut))
    factors = {"margin": overall["p"], "agreement": overall["agreement"], "noise": quality}
    margin, units, boundary, by = (overall["margin"], overall["units"], overall["boundary"],
                                   overall["decided_by"])
    lyap = None
    if chaos is not False and chaos is not None:
        if isinstance(chaos, LyapunovResult):
            lyap = chaos
        else:
            if torques is None:
                raise ClassificationError(
                    "chaos=True needs the torques that produced the ephemeris (an "
                    "ephemeris does not record them): classify(eph, chaos=True, "
                    "torques=[...]), or pass a LyapunovResult from lyapunov_exponent()")
            opts = dict(lyapunov_options or {})
            opts.setdefault("method", _method_of(eph))
            opts.setdefault("thresholds", th)
            lyap = lyapunov_exponent(series.body, initial_state(eph, body_index), torques,
                                     float(t[-1] - t[0]), **opts)
        if lyap.chaotic:
            regime = "chaotic"
            margin, units = lyap.excess_efolds - th.lyapunov_efolds, "e-folds"
            boundary, by = "regular", "lyapunov_efolds"
            factors = {"margin": _phi(margin / (th.softness * th.lyapunov_efolds)),
                       "agreement": 1.0, "noise": quality}
    confidence = float(min(factors["margin"], factors["agreement"]) * factors["noise"])
    if regime not in REGIMES:                                # pragma: no cover - guard
        raise DiagnosticsError(f"internal: unknown regime {regime!r}")
    return Classification(
        regime=regime, periods=periods, period_uncertainties=uncs, margin=float(margin),
        margin_units=units, boundary=boundary, decided_by=by, confidence=confidence,
        confidence_factors=factors, segments=segs,
        transitions=_transitions(t, q, segs, length, th), windows=windows,
        window_length=float(length), nutation_range=nut_range,
        nutation_amplitude=0.5 * (nut_range[1] - nut_range[0]),
        reference_axis="A" if ref == 1 else "C",
        excitation=_nanmedian(q["excitation"][span_sl]),
        dynamic_inertia=_nanmedian(q["dynamic_inertia"][span_sl]),
        separatrix_distance=_nanmedian(q["m1"][span_sl]),
        attitude_noise=noise, stationary=stationary,
        span=(float(t[0]), float(t[-1])), lyapunov=lyap, thresholds=th)


# ===========================================================================
# report: table and JSON (for ``attitude classify FILE.nc [--json]``)
# ===========================================================================
def _fmt_s(s: float) -> str:
    if not math.isfinite(s):
        return str(s)
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if abs(s) >= 2 * size:
            return f"{s / size:.10g} {unit}"
    return f"{s:.10g} s"


def _fmt_margin(value: float, units: str) -> str:
    if units == "rad":
        return f"{value:.6g} rad ({math.degrees(value):.4g} deg)"
    if units == "1":
        return f"{value:.6g}"
    return f"{value:.6g} {units}"


def format_classification(c: Classification) -> str:
    """A readable table of a :class:`Classification` (what ``attitude classify`` prints).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.classification import classify, format_classification
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.0, 0.0, 0.5])
    >>> print(format_classification(classify(att.propagate(body, state,
    ...                                          np.linspace(0, 100, 201)))))
    regime          PA-short  (confidence 1.000)
    decided by      principal_axis_angle: margin 0.01 rad (0.573 deg) to SAM
    periods         spin 12.56637061 s +/- ...
    ...
    """
    th = c.thresholds
    lines = [f"regime          {c.regime}  (confidence {c.confidence:.3f})",
             f"decided by      {c.decided_by}: margin {_fmt_margin(c.margin, c.margin_units)}"
             f" to {c.boundary}"]
    if c.periods:
        parts = [f"{k} {_fmt_s(v)} +/- {c.period_uncertainties.get(k, math.nan):.2g} s"
                 for k, v in c.periods.items()]
        lines.append("periods         " + "; ".join(parts))
    else:
        lines.append("periods         none for this regime")
    lo, hi = c.nutation_range
    lines += [
        f"nutation        theta about {c.reference_axis} in [{math.degrees(lo):.6g}, "
        f"{math.degrees(hi):.6g}] deg, amplitude {math.degrees(c.nutation_amplitude):.6g} deg",
        f"excitation      {c.excitation:.6g}   (E - E_min)/(E_max - E_min)",
        f"L^2/2E          {c.dynamic_inertia:.6g} kg m^2   separatrix distance m1 "
        f"{c.separatrix_distance:.6g}",
        f"attitude noise  {c.attitude_noise:.3g} rad",
        "confidence      " + ", ".join(f"{k} {v:.3f}" for k, v in
                                          c.confidence_factors.items()),
        f"span            {_fmt_s(c.span[0])} .. {_fmt_s(c.span[1])}, "
        f"{len(c.windows)} window(s) of {_fmt_s(c.window_length)}"
        + ("" if c.stationary else ", regime changes"),
    ]
    lines.append("segments        " + "start .. stop  regime")
    for s0, s1, r in c.segments:
        lines.append(f"                {_fmt_s(s0)} .. {_fmt_s(s1)}  {r}")
    for tr in c.transitions:
        lines.append(f"transition      {_fmt_s(tr.epoch)}  {tr.before} -> {tr.after}"
                     + (f"  ({tr.quantity} = {tr.threshold:.3g})" if tr.quantity else ""))
    if c.lyapunov is not None:
        ly = c.lyapunov
        ctrl = ("" if ly.control_exponent is None else
                f"; control {ly.control_exponent:.4g} +/- {ly.control_uncertainty:.2g} 1/s")
        lines.append(f"lyapunov        {ly.exponent:.4g} +/- {ly.uncertainty:.2g} 1/s "
                     f"(time {_fmt_s(ly.lyapunov_time)}){ctrl}; excess "
                     f"{ly.excess_efolds:.3g} e-folds -> "
                     + ("chaotic" if ly.chaotic else "regular"))
    lines.append(f"thresholds      principal_axis_angle {th.principal_axis_angle:g} rad, "
                 f"separatrix {th.separatrix:g}, symmetry_rtol {th.symmetry_rtol:g}, "
                 f"lyapunov_efolds {th.lyapunov_efolds:g}")
    return "\n".join(lines)


def _plain(x):
    if isinstance(x, float | np.floating):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.ndarray):
        return [_plain(v) for v in x.tolist()]
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    return x


def classification_json(c: Classification, *, windows: bool = False) -> dict:
    """A JSON-ready dict of a :class:`Classification` (``attitude classify --json``).

    Non-finite numbers become ``null``.  Keys: ``regime``, ``periods``,
    ``period_uncertainties``, ``margin`` ``{value, units, boundary}``, ``decided_by``,
    ``confidence``, ``confidence_factors``, ``nutation`` ``{reference_axis, range_rad,
    amplitude_rad}``, ``excitation``, ``dynamic_inertia``, ``separatrix_distance``,
    ``attitude_noise``, ``stationary``, ``span``, ``window_length``, ``segments``
    (``[{start, stop, regime}]``), ``transitions``, ``lyapunov`` (or null),
    ``thresholds``; with ``windows=True`` also the per-window results.

    Examples
    --------
    >>> import json, numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.classification import classify, classification_json
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.0, 0.0, 0.5])
    >>> d = classification_json(classify(att.propagate(body, state, np.linspace(0, 100, 201))))
    >>> d["regime"], sorted(d["periods"]), json.loads(json.dumps(d))["margin"]["units"]
    ('PA-short', ['spin'], 'rad')
    """
    out = {
        "regime": c.regime,
        "periods": _plain(dict(c.periods)),
        "period_uncertainties": _plain(dict(c.period_uncertainties)),
        "margin": {"value": _plain(c.margin), "units": c.margin_units,
                   "boundary": c.boundary},
        "decided_by": c.decided_by,
        "confidence": _plain(c.confidence),
        "confidence_factors": _plain(c.confidence_factors),
        "nutation": {"reference_axis": c.reference_axis,
                     "range_rad": _plain(list(c.nutation_range)),
                     "amplitude_rad": _plain(c.nutation_amplitude)},
        "excitation": _plain(c.excitation),
        "dynamic_inertia": _plain(c.dynamic_inertia),
        "separatrix_distance": _plain(c.separatrix_distance),
        "attitude_noise": _plain(c.attitude_noise),
        "stationary": c.stationary,
        "span": _plain(list(c.span)),
        "window_length": _plain(c.window_length),
        "segments": [{"start": _plain(a), "stop": _plain(b), "regime": r}
                     for a, b, r in c.segments],
        "transitions": [{"epoch": _plain(tr.epoch), "before": tr.before, "after": tr.after,
                         "quantity": tr.quantity, "threshold": _plain(tr.threshold)}
                        for tr in c.transitions],
        "lyapunov": None,
        "thresholds": _plain(dataclasses.asdict(c.thresholds)),
    }
    if c.lyapunov is not None:
        ly = c.lyapunov
        out["lyapunov"] = {
            "exponent": _plain(ly.exponent), "uncertainty": _plain(ly.uncertainty),
            "lyapunov_time": _plain(ly.lyapunov_time),
            "control_exponent": _plain(ly.control_exponent),
            "control_uncertainty": _plain(ly.control_uncertainty),
            "excess_efolds": _plain(ly.excess_efolds),
            "significance": _plain(ly.significance), "chaotic": ly.chaotic,
            "duration": _plain(ly.duration), "interval": _plain(ly.interval),
            "separation": _plain(ly.separation), "method": ly.method}
    if windows:
        out["windows"] = [_plain(dataclasses.asdict(w)) for w in c.windows]
    json.dumps(out)                                     # fail here, not in the caller
    return out

