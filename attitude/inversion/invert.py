"""Lightcurve inversion from the data alone: period scan, pole search, shape.

:func:`invert` runs the stages of convex inversion for a principal-axis rotator:

1. the sidereal period, from a period given or scanned over a range
   (:func:`period_scan`: at each trial period the best convex fit from a few poles, on a
   grid of spacing ``0.5 p P^2 / T`` for a time span ``T``, the step below which the
   minima of chi2 cannot be skipped);
2. the pole, fitted from starts spread over the sphere; the best and its mirror
   (``lambda + 180 deg``, the ambiguity of observations near the ecliptic) are both
   refined and reported;
3. the shape: the Gaussian image turned into a convex polyhedron
   (:func:`~attitude.inversion.minkowski.polyhedron_from_areas`) of unit volume, the
   body at uniform density, and the rotation state at the first epoch.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from attitude.foundations.constants import OBLIQUITY_J2000
from attitude.foundations.errors import PhotometryError
from attitude.foundations.progress import activity, track
from attitude.foundations.quantities import to_si
from attitude.inversion.convex import ConvexFit, ConvexModel, fit_convex
from attitude.inversion.gaussian_image import GaussianImage
from attitude.inversion.minkowski import polyhedron_from_areas
from attitude.inversion.observations import ObservedLightcurve, engine_blocks
from attitude.inversion.tumbler import (
    EXAMPLE_SHAPE,
    EXAMPLE_STATE,
    PARAMETERS,
    TumblerFit,
    energy_for_period_ratio,
    example_model,
    fit_tumbler,
    search_tumbler,
    tumbler_directions,
)
from attitude.model.body import RigidBody
from attitude.model.freebody import diagnose_many
from attitude.model.sampling import TUMBLING_PARAMETERS, tumbling_parameters, tumbling_state
from attitude.model.shape import Polyhedron
from attitude.model.state import AttitudeState
from attitude.photometry.geometry import Geometry
from attitude.propagation.torquefree import free_rotation

__all__ = ["InversionResult", "PeriodScan", "invert", "period_scan", "period_grid", "pole_starts"]


def pole_starts(count: int) -> np.ndarray:
    """``count`` pole directions spread evenly over the sphere (a Fibonacci lattice),
    ``(count, 2)`` longitude and latitude, rad.

    Examples
    --------
    >>> np.degrees(pole_starts(4)).round(1).tolist()
    [[0.0, 48.6], [137.5, 14.5], [275.0, -14.5], [52.5, -48.6]]
    """
    k = np.arange(count) + 0.5
    latitude = np.arcsin(1.0 - 2.0 * k / count)
    longitude = (np.pi * (3.0 - np.sqrt(5.0)) * np.arange(count)) % (2.0 * np.pi)
    return np.stack([longitude, latitude], axis=1)


@dataclass(frozen=True, eq=False)
class PeriodScan:
    """chi2 of the best convex model against trial period.

    Attributes
    ----------
    periods : (n,) array
        Trial periods, s.
    chi2 : (n,) array
        Lowest chi2 over the pole starts, per trial period.
    fitted_periods : (n,) array
        Where each fit ended (the period is free within each fit).
    best : float
        The fitted period of the lowest chi2, s.

    Examples
    --------
    >>> scan = PeriodScan(np.array([1.0, 2.0]), np.array([5.0, 3.0]), np.array([1.1, 2.2]))
    >>> scan.best
    2.2
    """

    periods: np.ndarray
    chi2: np.ndarray
    fitted_periods: np.ndarray

    @property
    def best(self) -> float:
        return float(self.fitted_periods[int(np.argmin(self.chi2))])


def period_grid(span: float, p_min: float, p_max: float, step: float = 0.8) -> np.ndarray:
    """Trial periods from ``p_min`` to ``p_max`` (s) spaced ``step * 0.5 P^2 / span``.

    Examples
    --------
    >>> grid = period_grid(86400.0 * 10, 3600.0, 3700.0)
    >>> grid.size, round(float(grid[1] - grid[0]), 3)
    (18, 6.0)
    """
    periods = [float(p_min)]
    while periods[-1] < p_max:
        periods.append(periods[-1] + step * 0.5 * periods[-1] ** 2 / span)
    return np.array(periods)


def period_scan(observations, periods, *, poles: int = 6, rows: int = 6, degree: int = 4,
                max_iterations: int = 20, client=None, chunks: int | None = None
                ) -> PeriodScan:
    """chi2 of the best convex fit against trial period (``convexinv``'s period scan).

    Parameters
    ----------
    observations : LightcurveObservations or list of them
        As for :func:`invert`.
    periods : array or Quantity
        Trial periods (s), spaced finely enough (:func:`period_grid`).
    poles : int
        Pole starts per trial period.
    rows, degree : int
        Resolution of the shape (coarser than the final fit: the scan asks only where
        chi2 is lowest).
    max_iterations : int
        Iterations per fit.
    client : dask.distributed.Client, optional
        Scan on a dask cluster: one task per chunk of consecutive trial periods; the
        result equals the sequential scan (each trial period's fits are independent of
        the others').
    chunks : int, optional
        Number of chunks (default: twice the cluster's workers, at most one per period).

    Returns
    -------
    PeriodScan

    Examples
    --------
    >>> obs = _example_observations()
    >>> scan = period_scan(obs, [7100.0, 7200.0], poles=2, rows=3, degree=2,
    ...                    max_iterations=5)
    >>> scan.chi2.shape, bool(scan.chi2[1] < scan.chi2[0])
    ((2,), True)
    """
    periods = np.atleast_1d(to_si(periods, "s", name="periods", error=PhotometryError))
    blocks = engine_blocks(observations)
    options = (poles, rows, degree, max_iterations)
    if client is None:
        chi2, ended = _scan_chunk(blocks, periods, options)
    else:
        n = chunks or 2 * max(1, len(client.scheduler_info().get("workers", {})))
        parts = [c for c in np.array_split(periods, min(n, periods.size)) if c.size]
        futures = [client.submit(_scan_chunk, blocks, part, options, pure=False)
                   for part in parts]
        results = client.gather(futures)
        chi2 = np.concatenate([r[0] for r in results])
        ended = np.concatenate([r[1] for r in results])
    return PeriodScan(periods, chi2, ended)


def _scan_chunk(blocks, periods, options) -> tuple[np.ndarray, np.ndarray]:
    """The scan of some trial periods: the lowest chi2 over the pole starts and where
    that fit ended, per period (one dask task)."""
    poles, rows, degree, max_iterations = options
    model = ConvexModel(blocks, GaussianImage(rows, degree))
    chi2 = np.empty(periods.size)
    ended = np.empty(periods.size)
    for i, p in enumerate(track(periods, periods.size, "period scan", unit="periods")):
        fits = [fit_convex(model, lon, lat, p, max_iterations=max_iterations)
                for lon, lat in pole_starts(poles)]
        best = min(fits, key=lambda f: f.chi2)
        chi2[i], ended[i] = best.chi2, best.period
    return chi2, ended


@dataclass(frozen=True, eq=False)
class InversionResult:
    """What :func:`invert` found.

    Attributes
    ----------
    shape : Polyhedron
        The convex shape, unit volume (relative data carry no size).
    body : RigidBody
        The shape at uniform unit density (its moment ratios are what count).
    state : AttitudeState
        The rotation at the first epoch, ``ECLIPJ2000``: about the model's ``z`` axis
        (a tumbler: the fitted non-principal-axis state, the model's axes its principal
        axes).
    period : float
        Sidereal period, s (a tumbler: the precession period ``P_phi``).
    pole : tuple
        ``(longitude, latitude)`` of the spin axis (a tumbler: of L), deg, ecliptic
        J2000.
    chi2 : float
        Sum of the squared residuals of the data (without the convexity term).
    rms : float
        ``sqrt(chi2 / n)``: relative flux for relative lightcurves.
    regime : str
        ``"PA-short"`` (a principal-axis rotator is what was fitted), or the tumbler's
        mode, ``"SAM"`` or ``"LAM"``.
    alternatives : list of (chi2, description)
        The other solutions: the mirror pole, the next best pole; for a tumbler the
        other mode and the mirror L.
    dark_facet : float
        Relative area of the facet that closes the Gaussian image.
    spin_axis_tilt : float
        Angle (deg) between the spin axis and the shape's axis of largest inertia at
        uniform density: near 0 for a body that could rotate so in equilibrium (for a
        tumbler: between the model's axes and the shape's principal axes).
    fit : ConvexFit or TumblerFit
        The underlying fit (a tumbler's carries the eight parameters, their errors and
        the moment ratios of the shape: :class:`~attitude.inversion.tumbler.TumblerFit`).
    scan : PeriodScan or None
        The period scan, when a range was scanned.

    Examples
    --------
    See :func:`invert`.
    >>> InversionResult.__dataclass_fields__["pole"].type
    'tuple'
    """

    shape: Polyhedron
    body: RigidBody
    state: AttitudeState
    period: float
    pole: tuple
    chi2: float
    rms: float
    regime: str
    alternatives: list
    dark_facet: float
    spin_axis_tilt: float
    fit: ConvexFit | TumblerFit = field(repr=False)
    scan: PeriodScan | None = field(default=None, repr=False)


def invert(observations, rotation: str = "auto", *, period=None, poles: int = 10,
           rows: int = 8, degree: int = 6, convexity: float = 0.1,
           max_iterations: int = 100, start=None,
           alternatives: bool = True, client=None) -> InversionResult:
    """Shape, pole and rotation state from lightcurves alone.

    Parameters
    ----------
    observations : LightcurveObservations or list of them
        Lightcurves with their geometry (:func:`read_damit_lightcurves`,
        :func:`attitude.read_lightcurve` with ``geometry=``); each session of each is a
        lightcurve of its own (a relative one: divided by its mean).
    rotation : {"auto", "principal", "tumbling"}
        The rotation fitted; ``"auto"`` is the principal-axis model; ``"tumbling"`` the
        non-principal-axis model of :mod:`attitude.inversion.tumbler`.
    period : float, Quantity or (min, max)
        Sidereal period (s), or a range to scan (:func:`period_scan`).  Required for a
        principal-axis rotator.
        Tumbling: optional, the two fundamental periods of the lightcurve (s; default
        from :func:`~attitude.photometry.fit_periods`) when there is no ``start``.
    start : dict, TumblerFit, InversionResult, (RigidBody, AttitudeState), optional
        Tumbling only: the starting state, the eight parameters of
        :data:`~attitude.inversion.tumbler.PARAMETERS` (SI: rad, s), an earlier fit, or a
        body and a state (a tuple, or a scenario with ``.body`` and ``.state``: the state
        in ECLIPJ2000 or an equatorial J2000 frame, at any epoch: it is propagated,
        torque free, to the first data epoch); without it the state is searched from the
        data alone
        (:func:`~attitude.inversion.tumbler.search_tumbler`, a minute or more).
    alternatives : bool
        Tumbling only: also fit the other mode (SAM/LAM, at the same period ratio) and the
        mirror L, and report their chi2.
    poles : int
        Pole starts.
    rows, degree : int
        Resolution of the Gaussian image and degree of its harmonic series.
    convexity : float
        Weight of the convexity term.
    max_iterations : int
    client : dask.distributed.Client, optional
        Run the period scan (a range given) on a dask cluster (:func:`period_scan`).

    Returns
    -------
    InversionResult

    Raises
    ------
    PhotometryError
        For an unknown rotation, a missing period, fewer points than parameters (naming
        the files), a single lightcurve shorter than the period asked (naming it).

    Examples
    --------
    Lightcurves of an elongated body of pole (28.6, 57.3) deg and period 2 h:

    >>> res = invert(_example_observations(), period=7200.0, poles=10, rows=4, degree=2)
    >>> bool(res.rms < 1e-9), round(res.period, 6), [round(x, 6) for x in res.pole]
    (True, 7200.0, [28.64789, 57.29578])
    >>> res.shape.volume                        # relative data: unit volume
    1.0...

    A tumbler from a start near its state (:mod:`attitude.inversion.tumbler`):

    >>> obs, truth = _example_tumbler()
    >>> res = invert(obs, rotation="tumbling", start=truth, rows=4, degree=2,
    ...              alternatives=False)
    >>> res.regime, round(res.period, 3), bool(res.rms < 1e-6)
    ('SAM', 7200.0, True)
    """
    if rotation not in ("auto", "principal", "tumbling"):
        raise PhotometryError(f"rotation {rotation!r} is unknown; use 'auto', 'principal' "
                              "or 'tumbling'", key="rotation")
    observations = engine_blocks(observations)
    if rotation == "tumbling" and start is not None and not isinstance(
            start, (dict, TumblerFit, InversionResult, np.ndarray)):
        start = _parameters_of_state(start, observations)
    _check_span(observations, period)
    _check_enough_points(observations, GaussianImage(rows, degree).n_coefficients
                         + (8 if rotation == "tumbling" else 3), rows, degree)
    if rotation == "tumbling":
        return _invert_tumbling(observations, start, period, rows=rows, degree=degree,
                                convexity=convexity, max_iterations=max_iterations,
                                alternatives=alternatives)
    if period is None:
        raise PhotometryError("give the period (s) or a range (min, max) to scan",
                              key="period")
    model = ConvexModel(observations, GaussianImage(rows, degree))
    n_parameters = model.image.n_coefficients + 3
    if model.n_points <= n_parameters:
        raise PhotometryError(f"{model.n_points} points for {n_parameters} parameters: "
                              "more data, or a lower degree", key="observations")
    p = np.atleast_1d(to_si(period, "s", name="period", error=PhotometryError))
    scan = None
    if p.size == 2:
        span = float(np.ptp(model.time))
        # the scan's model is coarser than the fit's (convexinv's practice), never finer
        # than the one asked
        scan = period_scan(observations, period_grid(span, *np.sort(p)), rows=min(rows, 6),
                           degree=min(degree, 4), client=client)
        p0 = scan.best
    elif p.size == 1:
        p0 = float(p[0])
    else:
        raise PhotometryError(f"expected a period or a (min, max) range, got {p.size} "
                              "values", key="period")
    # the pole from starts over the sphere at the period found (a free period lets a fit
    # from a poor pole wander to a neighbouring minimum), then the best and its mirror
    # refined with the period free; the mirror (lambda + 180 deg) gets a shape of its
    # own first, fitted from the sphere there: the best pole's shape does not suit it,
    # and refined from that shape its chi2 would not be a fair comparison
    fixed = sorted((fit_convex(model, lon, lat, p0, free_period=False, convexity=convexity,
                               max_iterations=max_iterations)
                    for lon, lat in track(pole_starts(poles), poles, "pole search",
                                          unit="pole starts")), key=lambda f: f.chi2)
    own = fit_convex(model, fixed[0].longitude + np.pi, fixed[0].latitude, p0,
                     free_period=False, convexity=convexity, max_iterations=max_iterations)
    best, mirror = (fit_convex(model, start.longitude, start.latitude, p0,
                               coefficients=start.coefficients, convexity=convexity,
                               max_iterations=max_iterations)
                    for start in (fixed[0], own))
    fits = fixed
    if mirror.chi2 < best.chi2:
        best, mirror = mirror, best
    alternatives = [(mirror.chi2, "mirror pole ({:.1f}, {:.1f}) deg".format(*mirror.pole))]
    for other in fits[1:]:
        if _pole_distance(other, best) > 0.2 and _pole_distance(other, mirror) > 0.2:
            alternatives.append((other.chi2, "pole ({:.1f}, {:.1f}) deg".format(*other.pole)))
            break
    shape, _ = polyhedron_from_areas(model.image.normals, best.areas)
    mass, com, inertia = shape.mass_properties(1.0)
    body = RigidBody(inertia, mass=mass, center_of_mass=com, name="inverted convex shape")
    largest = body.principal_axes[:, 2]
    tilt = float(np.degrees(np.arccos(min(1.0, abs(largest[2])))))
    attitude = Rotation.from_euler("ZYZ", [best.longitude, np.pi / 2 - best.latitude,
                                           model.phi0])
    epoch = observations[0].epoch + TimeDelta(model.t0, format="sec")
    state = AttitudeState(epoch, attitude, [0.0, 0.0, 2.0 * np.pi / best.period],
                          frame="ECLIPJ2000")
    return InversionResult(shape=shape, body=body, state=state, period=best.period,
                           pole=best.pole,
                           chi2=best.chi2, rms=best.rms, regime="PA-short",
                           alternatives=alternatives, dark_facet=best.dark_facet,
                           spin_axis_tilt=tilt, fit=best, scan=scan)


def _files(observations) -> str:
    """The distinct files (or names) of the lightcurves, for messages."""
    names = list(dict.fromkeys(o.name.split(": ")[0] for o in observations))
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def _check_enough_points(observations, n_parameters: int, rows: int, degree: int) -> None:
    """More points than parameters (the shape's coefficients and the rotation's), or a
    :class:`PhotometryError` naming the files."""
    n = sum(len(o) for o in observations)
    if n <= n_parameters:
        raise PhotometryError(
            f"{_files(observations)}: {n} points for {n_parameters} parameters (a shape of "
            f"rows {rows}, degree {degree}, and the rotation): give more lightcurves, or "
            "a lower degree", key="observations")


def _check_span(observations, period) -> None:
    """A single lightcurve must cover the longest period asked for, else a
    :class:`PhotometryError` naming it."""
    if len(observations) != 1 or period is None:
        return
    p = np.atleast_1d(to_si(period, "s", name="period", error=PhotometryError))
    [obs] = observations
    span = float(np.ptp(obs.time))
    if span < p.max():
        raise PhotometryError(
            f"{obs.name}: a single lightcurve of {span / 3600:.4g} h cannot give a period "
            f"of {p.max() / 3600:.4g} h (less than one rotation is seen): give more "
            "sessions, or a shorter period", key="period")


def _pole_distance(a: ConvexFit, b: ConvexFit) -> float:
    """Angle between two fitted poles, rad."""
    u = [np.cos(a.latitude) * np.cos(a.longitude), np.cos(a.latitude) * np.sin(a.longitude),
         np.sin(a.latitude)]
    v = [np.cos(b.latitude) * np.cos(b.longitude), np.cos(b.latitude) * np.sin(b.longitude),
         np.sin(b.latitude)]
    return float(np.arccos(np.clip(np.dot(u, v), -1.0, 1.0)))


@lru_cache(maxsize=1)
def _example_result() -> InversionResult:
    """The inversion of :func:`_example_observations` (computed once, for the examples of
    the figures)."""
    return invert(_example_observations(), period=7200.0, poles=10, rows=4, degree=2)


def _example_observations():
    """Relative lightcurves of a convex model (``z`` its shortest axis, ``x`` its longest;
    pole 0.5, 1.0 rad, P 2 h) from three nights, for the examples."""


    image = GaussianImage(rows=4, degree=2)
    t = np.linspace(0.0, 8 * 3600.0, 60)
    epoch = Time("2026-01-01", scale="tdb")
    obs = [ObservedLightcurve(epoch, t + 86400.0 * 20 * k, np.ones(60),
                              Geometry(sun=[1, 0.3 * k, 0.1], observer=[1, 0.3 * k - 0.2, 0]))
           for k in range(3)]
    truth = np.zeros(9)
    truth[6], truth[8] = 0.3, 0.4        # flattened along z, elongated along x
    model = ConvexModel(obs, image)
    y = model.brightness(truth, 0.5, 1.0, 7200.0)
    return [ObservedLightcurve(o.epoch, o.time, y[model.block == k], o.geometry)
            for k, o in enumerate(obs)]


def _start_parameters(start) -> np.ndarray:
    """The eight parameters of a start: a dict, an array, a TumblerFit or a tumbling
    InversionResult."""
    if isinstance(start, InversionResult):
        start = start.fit
    if isinstance(start, TumblerFit):
        start = start.parameters
    if isinstance(start, dict):
        missing = [k for k in PARAMETERS if k not in start]
        if missing:
            raise PhotometryError(f"start: missing {', '.join(missing)}", key="start")
        start = [to_si(start[k], "s" if k == "precession_period" else
                       ("" if k in ("energy_ratio", "ratio_a", "ratio_b") else "rad"),
                       name=f"start.{k}", error=PhotometryError) for k in PARAMETERS]
    p = np.asarray(start, dtype=float)
    if p.shape != (8,):
        raise PhotometryError(f"start: expected the 8 parameters {PARAMETERS}, got shape "
                              f"{p.shape}", key="start")
    return p


#: Equatorial J2000 frames a start's state may be given in (turned to the ecliptic, the
#: frame of the lightcurves' vectors; the ICRF's frame bias, 0.02 arcsec, is neglected
#: in a start).
_EQUATORIAL = ("ICRF", "GCRF", "EME2000", "J2000")


def _parameters_of_state(start, observations) -> np.ndarray:
    """The eight tumbler parameters at the first data epoch of a start given as a body and
    a state: ``(RigidBody, AttitudeState)``, or any object with ``body`` and ``state``
    (a scenario loaded by :func:`attitude.load_scenario`)."""
    if isinstance(start, (tuple, list)) and len(start) == 2:
        body, state = start
    else:
        body, state = getattr(start, "body", None), getattr(start, "state", None)
    if not (isinstance(body, RigidBody) and isinstance(state, AttitudeState)):
        raise PhotometryError("start: expected the eight parameters (a dict), a fit, or a "
                              "body and a state ((RigidBody, AttitudeState) or a scenario "
                              f"with .body and .state), got {type(start).__name__}",
                              key="start")
    frame = state.frame.upper()
    attitude = state.attitude
    if frame in _EQUATORIAL:
        attitude = Rotation.from_rotvec([-OBLIQUITY_J2000, 0.0, 0.0]) * attitude
    elif frame not in ("ECLIPJ2000", "ECLIPTIC_J2000"):
        raise PhotometryError(f"start: the state's frame {state.frame} cannot be turned to "
                              "the lightcurves' ecliptic J2000: give it in ECLIPJ2000 or an "
                              "equatorial J2000 frame (ICRF, EME2000)", key="start.frame")
    # the first data epoch: the tumbler's parameters are those of its state then
    first = observations[0].epoch
    t0 = min(float(o.time.min()) + float((o.epoch - first).to_value("s"))
             for o in observations)
    dt = float((first + TimeDelta(t0, format="sec") - state.epoch).to_value("s"))
    moments = np.asarray(body.principal_moments, dtype=float)
    b2p = body.body_to_principal
    q, w = free_rotation(moments, (attitude * b2p.inv()).as_quat(),
                         b2p.apply(state.omega_body), np.array([dt]))
    moved = AttitudeState(state.epoch + TimeDelta(dt, format="sec"),
                          Rotation.from_quat(q[0]) * b2p, b2p.inv().apply(w[0]),
                          frame="ECLIPJ2000")
    try:
        params, _ = tumbling_parameters(body, moved)
    except ValueError as err:
        raise PhotometryError(f"start: {err}", key="start") from None
    return np.array([params[k] for k in TUMBLING_PARAMETERS])


def _other_mode(p: np.ndarray, regime: str):
    """The start in the other mode at the same ``P_psi / P_phi`` (None if out of reach)."""
    moments, _, w, _ = tumbling_state(*p)
    d = diagnose_many(moments, w)
    other = "LAM" if regime == "SAM" else "SAM"
    er = energy_for_period_ratio(p[3], p[4], d["rotation"][0] / d["precession"][0], other)
    if not np.isfinite(er[0]):
        return None, other
    q = p.copy()
    q[2] = er[0]
    return q, other


def _invert_tumbling(observations, start, periods, *, rows, degree, convexity,
                     max_iterations, alternatives) -> InversionResult:
    """:func:`invert` for ``rotation="tumbling"``."""
    model = ConvexModel(observations, GaussianImage(rows, degree))
    n_parameters = model.image.n_coefficients + 8
    if model.n_points <= n_parameters:
        raise PhotometryError(f"{model.n_points} points for {n_parameters} parameters: "
                              "more data, or a lower degree", key="observations")
    others = []
    if start is None:
        if periods is not None:
            periods = np.atleast_1d(to_si(periods, "s", name="period", error=PhotometryError))
        with activity("tumbler search from the data alone"):
            fits = search_tumbler(model, periods, max_iterations=max_iterations)
        best = fits[0]
        others = [(f, "{} P_phi {:.6g} h, P_psi {:.6g} h, L ({:.1f}, {:.1f}) deg".format(
            f.regime, f.periods["precession"] / 3600, f.periods["rotation"] / 3600,
            *f.pole)) for f in fits[1:]]
    else:
        with activity("tumbler fit from the start"):
            best = fit_tumbler(model, _start_parameters(start), convexity=convexity,
                               max_iterations=max_iterations)
    if alternatives and start is not None:
        p0 = _start_parameters(start)
        other, mode = _other_mode(p0, best.regime)
        if other is not None:
            fit = fit_tumbler(model, other, regime=mode, convexity=convexity,
                              max_iterations=max_iterations)
            others.append((fit, f"{mode} (P_phi {fit.periods['precession'] / 3600:.4f} h)"))
        mirror = np.array([best.parameters[k] for k in PARAMETERS])
        mirror[0] += np.pi
        fit = fit_tumbler(model, mirror, regime=best.regime, convexity=convexity,
                          max_iterations=max_iterations)
        others.append((fit, "mirror L ({:.1f}, {:.1f}) deg".format(*fit.pole)))
        ranked = sorted([(best, "")] + others, key=lambda f: f[0].chi2)
        if ranked[0][0] is not best:
            winner = ranked[0][0]
            others = [(best, f"{best.regime} L ({best.pole[0]:.1f}, {best.pole[1]:.1f}) deg")
                      ] + [o for o in others if o[0] is not winner]
            best = winner
    shape, _ = polyhedron_from_areas(model.image.normals, best.shape.areas)
    mass, com, inertia = shape.mass_properties(1.0)
    c_moment = float(np.max(np.diag(inertia)))
    p = np.array([best.parameters[k] for k in PARAMETERS])
    moments, q, w, _ = tumbling_state(*p, moment_c=c_moment)
    body = RigidBody(np.diag(moments[0]), mass=mass, center_of_mass=com,
                     name="inverted convex tumbler (fitted moment ratios)")
    epoch = observations[0].epoch + TimeDelta(model.t0, format="sec")
    state = AttitudeState(epoch, Rotation.from_quat(q[0]), w[0], frame="ECLIPJ2000")
    return InversionResult(shape=shape, body=body, state=state, period=float(p[5]),
                           pole=best.pole,
                           chi2=best.chi2, rms=best.rms, regime=best.regime,
                           alternatives=[(f.chi2, text) for f, text in others],
                           dark_facet=best.shape.dark_facet,
                           spin_axis_tilt=best.axis_misalignment, fit=best)


def _example_tumbler():
    """Relative lightcurves of a convex tumbler (the SAM of the tumbler module's
    examples, P_phi 2 h) and its parameters."""
    model = example_model()
    truth = np.array(EXAMPLE_STATE)
    y = model.brightness_of(EXAMPLE_SHAPE, *tumbler_directions(model, truth))
    return [ObservedLightcurve(o.epoch, o.time, y[model.block == k], o.geometry)
            for k, o in enumerate(model.observations)], truth
