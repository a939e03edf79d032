"""Periods of a lightcurve: Lomb-Scargle for one period, the two-period Fourier series
of Pravec et al. (2005) for a tumbler.

A principal-axis rotator's lightcurve is a Fourier series in one frequency; the
lightcurve of a body in non-principal-axis rotation is a two-dimensional Fourier series
whose frequencies are all combinations ``n1 f_phi + n2 f_psi`` of the rotation state's
frequencies (precession and rotation, :func:`attitude.diagnose`).  The fit gives two
fundamental frequencies ``f1 = 1/P1``, ``f2 = 1/P2`` that span the same lattice; they
need not be ``f_phi`` and ``f_psi`` themselves (any unimodular change of basis spans the
same lattice, and a shape symmetric under a half-turn about the rotation axis shows only
even multiples of ``f_psi``).  Identifying them is left to a model fit.

Method (one period): the Lomb-Scargle periodogram with harmonics gives candidate
fundamentals; each and its half are scored by the Fourier series of the given order.
Method (two periods): the Lomb-Scargle periodogram gives the strongest single
frequencies; pairs of fundamentals built from them (the peaks, their halves and their
differences) are scored by the least-squares fit of the 2-D Fourier series of the
given order (Pravec et al. 2005, eq. 1: all terms ``j f1 + k f2`` with
``|j| + |k| <= order``); the best pair is refined by minimising the chi-square over
``(f1, f2)`` with the linear coefficients solved at each step (variable projection).
The uncertainties come from the covariance of the full non-linear least-squares
problem (frequencies and coefficients), scaled by the reduced chi-square.

The *lightcurve period* reported is the double-peaked period of the strongest Fourier
term: ``2 / f_strongest``.  A plain periodogram (one sine) peaks at ``f_strongest``,
half of it; an ellipsoid shows two maxima per rotation, so observers quote the
double-peaked period.  For a tumbler in short-axis mode this is
``1 / (1/P_phi - 1/P_psi)`` when the strongest term is ``2 (f_phi - f_psi)``, as for
Apophis (30.56 h, Pravec et al. 2014).

References
----------
.. [1] P. Pravec et al., "Tumbling asteroids", Icarus 173, 108-131 (2005), eq. (1).
.. [2] P. Pravec et al., "The tumbling spin state of (99942) Apophis", Icarus 233,
   48-60 (2014).
.. [3] J. T. VanderPlas, "Understanding the Lomb-Scargle periodogram", ApJS 236, 16
   (2018); astropy.timeseries.LombScargle.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.optimize import least_squares

from attitude.foundations.errors import PhotometryError

__all__ = ["PeriodFit", "fit_periods", "fourier_terms", "lattice_combination"]

#: Largest periodogram grid (trial frequencies) fit_periods builds on its own.
_MAX_GRID = 2e6


def fourier_terms(order: int, n_periods: int = 2) -> np.ndarray:
    """Integer multipliers ``(j, k)`` of the Fourier terms ``j f1 + k f2``.

    Pravec et al. (2005), eq. 1: ``k = 0, j = 1..m`` and ``k = 1..m, j = -m..m``, with
    ``|j| + |k| <= m``.  One period: ``(j, 0)``, ``j = 1..m``.

    Examples
    --------
    >>> from attitude.photometry.periods import fourier_terms
    >>> fourier_terms(2).tolist()
    [[1, 0], [2, 0], [-1, 1], [0, 1], [1, 1], [0, 2]]
    """
    terms = [(j, 0) for j in range(1, order + 1)]
    if n_periods == 2:
        terms += [(j, k) for k in range(1, order + 1) for j in range(-order, order + 1)
                  if abs(j) + k <= order]
    return np.array(terms, dtype=int).reshape(-1, 2)


def lattice_combination(f, f1, f2, max_order: int = 6):
    """The combination ``n1 f1 + n2 f2`` nearest to ``f`` with ``|n1|, |n2| <= max_order``.

    Returns ``(n1, n2, relative error)``.

    Examples
    --------
    >>> from attitude.photometry.periods import lattice_combination
    >>> lattice_combination(0.7, 0.5, 0.1)
    (1, 2, 0.0)
    """
    n = np.arange(-max_order, max_order + 1)
    n1, n2 = np.meshgrid(n, n, indexing="ij")
    err = np.abs(n1 * f1 + n2 * f2 - f)
    k = np.unravel_index(np.argmin(err), err.shape)
    return int(n1[k]), int(n2[k]), round(float(err[k] / abs(f)), 15)


@dataclass(frozen=True, eq=False)
class PeriodFit:
    """The result of :func:`fit_periods`.

    Attributes
    ----------
    periods : ndarray
        s: the fundamental periods ``P1 (, P2)`` of the Fourier series (``P1`` the one
        of the strongest term's lattice direction, see the module notes).
    uncertainties : ndarray
        s, 1 sigma.
    frequencies, frequency_uncertainties : ndarray
        1/s.
    lightcurve_period : float
        s: the double-peaked period ``2 / f_strongest`` (see the module notes).
    strongest : tuple
        ``(j, k)`` of the strongest term, ``f_strongest = j f1 + k f2``.
    terms : list of dict
        Every fitted term: ``j``, ``k``, ``frequency`` (1/s), ``period`` (s),
        ``amplitude`` (mag, half peak-to-peak of the term), ``amplitude_error``,
        ``significant`` (``amplitude > significance x amplitude_error``).
    rms : float
        Residual rms, mag.
    order, n_periods : int
    note : str
        What the periods are and are not.

    Examples
    --------
    >>> t = np.linspace(0.0, 4 * 86400.0, 800)
    >>> y = 0.2 * np.cos(2 * np.pi * t / 21600.0) + 0.1 * np.cos(2 * np.pi * t / 50000.0)
    >>> fit = fit_periods(t, y, n_periods=2, order=2)
    >>> np.round(fit.periods, 3).tolist(), fit.strongest       # 21600 s is 2 f1
    ([43200.0, 50000.0], (2, 0))
    >>> round(fit.lightcurve_period, 3)
    43200.0
    """

    periods: np.ndarray
    uncertainties: np.ndarray
    frequencies: np.ndarray
    frequency_uncertainties: np.ndarray
    lightcurve_period: float
    strongest: tuple
    terms: list = field(repr=False)
    rms: float = 0.0
    order: int = 4
    n_periods: int = 2
    note: str = ""

    @property
    def significant_terms(self) -> list[dict]:
        """The terms whose amplitude exceeds its uncertainty by the significance factor."""
        return [t for t in self.terms if t["significant"]]

    def model(self, times) -> np.ndarray:
        """The fitted magnitudes at ``times`` (s, the fit's time origin; with sessions,
        the zero point of the first session).

        Examples
        --------
        >>> import numpy as np
        >>> from attitude.photometry.periods import fit_periods
        >>> t = np.linspace(0, 86400.0, 500)
        >>> m = 0.3 * np.cos(2 * np.pi * t / 7200.0)
        >>> fit = fit_periods(t, m, n_periods=1, order=2)
        >>> bool(np.allclose(fit.model(t), m, atol=1e-9))
        True
        """
        t0, freqs, terms, coef, n0 = self._state
        tt = np.atleast_1d(np.asarray(times, dtype=float)) - t0
        return _design(tt, freqs, terms, None)[:, 1:] @ coef[n0:] + coef[0]

    def summary(self) -> dict:
        """Periods in hours, as the CLI prints them.

        Examples
        --------
        >>> import numpy as np
        >>> from attitude.photometry.periods import fit_periods
        >>> t = np.linspace(0, 10 * 3600.0, 400)
        >>> m = 0.3 * np.cos(2 * np.pi * 2 * t / 7200.0)
        >>> s = fit_periods(t, m, n_periods=1, order=2).summary()
        >>> round(s["lightcurve_period_h"], 3)
        2.0
        """
        return {"periods_h": [float(p / 3600) for p in self.periods],
                "uncertainties_h": [float(p / 3600) for p in self.uncertainties],
                "lightcurve_period_h": float(self.lightcurve_period / 3600),
                "strongest_term": list(self.strongest), "rms_mag": float(self.rms),
                "significant_terms": [(t["j"], t["k"]) for t in self.significant_terms]}


def _design(t, freqs, terms, offsets=None):
    """Columns: 1 (or one per session), then cos and sin of each term."""
    f = terms @ freqs                                   # (n_terms,)
    phase = 2 * np.pi * np.outer(t, f)
    cols = [np.ones((len(t), 1))] if offsets is None else [offsets]
    return np.hstack(cols + [np.cos(phase), np.sin(phase)])


def _chi2_fit(t, y, w, freqs, terms, offsets):
    """Weighted linear least squares by the normal equations (a Cholesky solve of the
    small Gram matrix; SVD only when it is singular, for commensurate frequencies)."""
    A = _design(t, freqs, terms, offsets) * w[:, None]
    yw = y * w
    gram, rhs = A.T @ A, A.T @ yw
    try:
        coef = cho_solve(cho_factor(gram), rhs)
    except np.linalg.LinAlgError:
        coef = np.linalg.lstsq(A, yw, rcond=None)[0]
    resid = yw - A @ coef
    return float(resid @ resid), coef, resid


def blas_single_thread():
    """Small matrix products run faster on one BLAS thread (much faster on a loaded
    machine, where OpenBLAS threads spin); threadpoolctl is optional."""
    try:
        from threadpoolctl import threadpool_limits  # optional: only limits BLAS threads
    except ImportError:
        return contextlib.nullcontext()
    return threadpool_limits(1, user_api="blas")


def _peaks(t, y, w, f_min, f_max, n_peaks, oversample, nterms):
    # astropy is a costly import; only the period analysis needs it
    from astropy.timeseries import LombScargle  # costly import: period analysis only

    ls = LombScargle(t, y, dy=1.0 / w, fit_mean=True, center_data=True, nterms=nterms)
    freq, power = ls.autopower(minimum_frequency=f_min, maximum_frequency=f_max,
                               samples_per_peak=oversample)
    is_peak = np.r_[False, (power[1:-1] > power[:-2]) & (power[1:-1] >= power[2:]), False]
    idx = np.flatnonzero(is_peak)
    idx = idx[np.argsort(power[idx])[::-1]]
    span = t.max() - t.min()
    chosen = []
    for i in idx:
        if all(abs(freq[i] - freq[j]) > 2.0 / span for j in chosen):
            chosen.append(i)
        if len(chosen) == n_peaks:
            break
    return freq[chosen], power[chosen]


def fit_periods(times, magnitudes, sigma=None, n_periods: int = 2, order: int = 4, *,
                sessions=None, min_period=None, max_period=None, n_peaks: int = 6,
                oversample: int = 10, significance: float = 3.0,
                initial=None) -> PeriodFit:
    """Periods of a lightcurve.

    Parameters
    ----------
    times : array_like, shape (n,)
        s (any origin).
    magnitudes : array_like, shape (n,)
        mag.
    sigma : array_like or float, optional
        1-sigma magnitude errors (default: equal weights, uncertainties scaled by the
        residual rms).
    n_periods : 1 or 2
        One period (principal-axis rotator) or two (tumbler).
    order : int
        Order of the Fourier series (2 to 8); for two periods, terms with
        ``|j| + |k| <= order``.
    sessions : array_like of int, optional
        Session of each point: one free magnitude offset per session (differential
        photometry with independent zero points).
    min_period, max_period : float, optional
        s: the period search range of the periodogram (default: twice the median
        sampling interval to the time span).
    n_peaks : int
        Periodogram peaks from which the pairs of fundamentals are built.
    oversample : int
        Periodogram samples per peak width.
    significance : float
        A term is significant when its amplitude exceeds this many standard errors.
    initial : sequence of float, optional
        s: starting periods ``(P1[, P2])`` for the refinement instead of the periodogram
        search (to test a hypothesis, e.g. the precession and rotation periods of a
        model).

    Returns
    -------
    PeriodFit

    Raises
    ------
    PhotometryError
        On mismatched or non-finite arrays, too few points for the series, or a bad
        order or number of periods.

    Examples
    --------
    A double-peaked 6 h lightcurve: the periodogram's strongest frequency is 2/(6 h),
    and the double-peaked period is reported.  (The times are irregular and the curve
    has a third harmonic, so that neither an alias of an even sampling nor 12 h, whose
    harmonics 2 and 4 would repeat a curve of harmonics 1 and 2 of 6 h, fits as well.)

    >>> import numpy as np
    >>> from attitude.photometry.periods import fit_periods
    >>> t = np.sort(np.random.default_rng(1).uniform(0, 3 * 86400.0, 600))
    >>> f = 1 / (6 * 3600.0)
    >>> m = (0.4 * np.cos(4 * np.pi * f * t) + 0.05 * np.cos(2 * np.pi * f * t + 1)
    ...      + 0.03 * np.cos(6 * np.pi * f * t + 2))
    >>> fit = fit_periods(t, m, n_periods=1, order=4)
    >>> round(float(fit.periods[0]) / 3600, 4), round(fit.lightcurve_period / 3600, 4)
    (6.0, 6.0)
    """
    with blas_single_thread():
        return _fit_periods(times, magnitudes, sigma, n_periods, order, sessions,
                            min_period, max_period, n_peaks, oversample, significance,
                            initial)


def _fit_periods(times, magnitudes, sigma, n_periods, order, sessions, min_period,
                 max_period, n_peaks, oversample, significance, initial) -> PeriodFit:
    t = np.asarray(times, dtype=float).ravel()
    y = np.asarray(magnitudes, dtype=float).ravel()
    if t.shape != y.shape:
        raise PhotometryError(f"times has {t.size} values but magnitudes has {y.size}",
                              key="magnitudes")
    w = np.ones_like(y) if sigma is None else \
        1.0 / np.broadcast_to(np.asarray(sigma, dtype=float), y.shape)
    if not (np.isfinite(t).all() and np.isfinite(y).all() and np.isfinite(w).all()
            and (w > 0).all()):
        raise PhotometryError("times, magnitudes and sigma must be finite (sigma > 0)",
                              key="magnitudes")
    if n_periods not in (1, 2):
        raise PhotometryError(f"must be 1 or 2, got {n_periods!r}", key="n_periods")
    if not (isinstance(order, (int, np.integer)) and 1 <= order <= 8):
        raise PhotometryError(f"must be an integer in 1..8, got {order!r}", key="order")
    terms = fourier_terms(order, n_periods)[:, :n_periods]
    offsets = None
    if sessions is not None:
        codes, inverse = np.unique(np.asarray(sessions).ravel(), return_inverse=True)
        offsets = (inverse[:, None] == np.arange(len(codes))[None, :]).astype(float)
    n_par = 2 * len(terms) + (1 if offsets is None else offsets.shape[1]) + n_periods
    if y.size <= n_par:
        raise PhotometryError(f"{y.size} points are too few for a Fourier series with "
                              f"{n_par} parameters (n_periods={n_periods}, order={order})",
                              key="magnitudes")
    order_t = np.argsort(t)
    t, y, w = t[order_t], y[order_t], w[order_t]
    offsets = None if offsets is None else offsets[order_t]
    t0 = 0.5 * (t[0] + t[-1])
    tc = t - t0
    span = t[-1] - t[0]
    dt = np.median(np.diff(t)) if t.size > 1 else span
    f_max = 1.0 / min_period if min_period else 0.5 / max(dt, 1e-300)
    f_min = 1.0 / max_period if max_period else 1.0 / span
    n_grid = (f_max - f_min) * span * oversample
    if not n_grid < _MAX_GRID:
        raise PhotometryError(
            f"the period search would take {n_grid:.3g} trial frequencies (a span of "
            f"{span / 86400:.4g} d sampled every {dt:.3g} s); give min_period and "
            "max_period around the expected periods, or fit shorter stretches",
            key="min_period")
    # one period: the periodogram with harmonics (nterms = order) peaks at the
    # fundamental of a multi-harmonic curve; two periods: single sines, whose peaks are
    # the strongest lattice frequencies the pairs are built from
    if initial is not None:
        guess = np.asarray(initial, dtype=float).ravel()
        if guess.shape != (n_periods,) or not np.all(np.isfinite(guess) & (guess > 0)):
            raise PhotometryError(f"expected {n_periods} positive periods (s), got "
                                  f"{initial!r}", key="initial")
        return _refined(tc, y, w, 1.0 / guess, terms, offsets, span, t0, sigma, n_periods,
                        order, significance)
    # (session zero points removed first: the periodogram has no per-session offsets)
    y_ls = y if offsets is None else y - offsets @ (
        (offsets * w[:, None] ** 2).T @ y / ((offsets * w[:, None] ** 2).sum(axis=0)))
    peaks, _ = _peaks(tc, y_ls, w, f_min, f_max, n_peaks, oversample,
                      min(order, 4) if n_periods == 1 else 1)
    if peaks.size == 0:
        raise PhotometryError("the periodogram has no peak: is the lightcurve constant?",
                              key="magnitudes")

    if n_periods == 1:
        candidates = [np.array([f]) for p in peaks for f in (p, p / 2)]
    else:
        base = set()
        for p in peaks:
            base.update((p, p / 2))
        for p, q in combinations(peaks, 2):
            base.update((abs(p - q), abs(p - q) / 2))
        base = sorted(b for b in base if b > 0.5 / span)
        candidates = [np.array([a, b]) for a, b in combinations(base[::-1], 2)
                      if not _degenerate(a, b, order, span)]
    if not candidates:
        raise PhotometryError("no pair of independent frequencies in the periodogram; fit "
                              "one period (n_periods=1) or observe longer", key="n_periods")
    scores = [_chi2_fit(tc, y, w, c, terms, offsets)[0] for c in candidates]
    # Among equally good candidates prefer the lowest frequencies (the full lattice).
    best = candidates[int(np.argmin(scores))]
    return _refined(tc, y, w, best, terms, offsets, span, t0, sigma, n_periods, order,
                    significance)


def _refined(tc, y, w, best, terms, offsets, span, t0, sigma, n_periods, order,
             significance) -> PeriodFit:
    """Variable-projection refinement from ``best`` (1/s), covariance and the result."""

    def residual(freqs):
        return _chi2_fit(tc, y, w, freqs, terms, offsets)[2]

    sol = least_squares(residual, best, x_scale=1.0 / span, diff_step=1e-3 / (span * best))
    freqs = np.abs(sol.x)
    chi2, coef, resid = _chi2_fit(tc, y, w, freqs, terms, offsets)
    freqs, cov = _covariance(tc, w, freqs, coef, terms, offsets, chi2, y.size,
                             scale=sigma is None)
    n0 = 1 if offsets is None else offsets.shape[1]
    cos_c, sin_c = coef[n0:n0 + len(terms)], coef[n0 + len(terms):]
    amp = np.hypot(cos_c, sin_c)
    k_f = n_periods
    var_c = np.diag(cov)[k_f + n0:k_f + n0 + len(terms)]
    var_s = np.diag(cov)[k_f + n0 + len(terms):]
    amp_err = np.sqrt((cos_c**2 * var_c + sin_c**2 * var_s) / np.maximum(amp, 1e-300) ** 2)
    f_terms = terms @ freqs
    jk = np.hstack([terms, np.zeros((len(terms), 2 - n_periods), dtype=int)])
    table = [{"j": int(j), "k": int(k), "frequency": float(f), "period": float(1 / abs(f))
              if f else np.inf, "amplitude": float(a), "amplitude_error": float(e),
              "significant": bool(a > significance * e)}
             for (j, k), f, a, e in zip(jk, f_terms, amp, amp_err)]
    strongest = int(np.argmax(amp))
    f_err = np.sqrt(np.diag(cov)[:n_periods])
    note = ("periods: the fundamental periods of the Fourier series; every lightcurve "
            "frequency is a combination j/P1 + k/P2, but P1 and P2 need not be the "
            "precession and rotation periods (a model fit identifies them); "
            "lightcurve_period: the double-peaked period 2/f of the strongest term"
            if n_periods == 2 else
            "periods: the fundamental of the Fourier series; lightcurve_period: the "
            "double-peaked period 2/f of the strongest term (a single-sine periodogram "
            "finds half of it)")
    result = PeriodFit(periods=1.0 / freqs, uncertainties=f_err / freqs**2,
                       frequencies=freqs, frequency_uncertainties=f_err,
                       lightcurve_period=float(2.0 / abs(f_terms[strongest])),
                       strongest=tuple(int(x) for x in jk[strongest]), terms=table,
                       rms=float(np.sqrt(np.mean((resid / w) ** 2))), order=int(order),
                       n_periods=n_periods, note=note)
    object.__setattr__(result, "_state", (t0, freqs, terms, coef, n0))   # for model()
    return result


def _degenerate(a, b, order, span):
    """True when ``a`` and ``b`` are (nearly) commensurate in small integers, so that
    the two-period series would have repeated columns."""
    for p in range(1, 2 * order + 1):
        for q in range(1, 2 * order + 1):
            if abs(p * a - q * b) < 1.0 / span:
                return True
    return False


def _covariance(t, w, freqs, coef, terms, offsets, chi2, n, *, scale: bool):
    """Covariance of (frequencies, coefficients) from the full Jacobian at the optimum."""
    A = _design(t, freqs, terms, offsets)
    n0 = 1 if offsets is None else offsets.shape[1]
    nt = len(terms)
    cos_c, sin_c = coef[n0:n0 + nt], coef[n0 + nt:]
    phase = 2 * np.pi * np.outer(t, terms @ freqs)
    # d model / d phase_i = -C_i sin + S_i cos; d phase_i / d f_p = 2 pi t terms[i, p]
    dphase = -cos_c * np.sin(phase) + sin_c * np.cos(phase)          # (n, nt)
    jac_f = (2 * np.pi * t[:, None]) * (dphase @ terms)              # (n, n_periods)
    J = np.hstack([jac_f, A]) * w[:, None]
    dof = max(n - J.shape[1], 1)
    # (J^T J)^-1 from the SVD of J with unit columns (the frequency columns are ~2 pi t
    # larger than the coefficients'): V S^-2 V^T is positive semi-definite by
    # construction, where a pseudo-inverse of J^T J squares the condition number and,
    # ill-conditioned, gave negative variances; directions below J's numerical rank
    # (numpy's matrix_rank rule) are left out
    norms = np.sqrt(np.sum(J * J, axis=0))
    norms = np.where(norms > 0, norms, 1.0)
    _, sv, vt = np.linalg.svd(J / norms, full_matrices=False)
    keep = sv > sv[0] * max(J.shape) * np.finfo(float).eps
    cov = ((vt[keep].T / sv[keep] ** 2) @ vt[keep]) / np.outer(norms, norms)
    if scale:
        cov *= chi2 / dof
    else:
        cov *= max(1.0, chi2 / dof)
    return freqs, cov
