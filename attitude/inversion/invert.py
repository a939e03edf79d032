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

import numpy as np
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from attitude.foundations.errors import PhotometryError
from attitude.foundations.quantities import to_si
from attitude.inversion.convex import ConvexFit, ConvexModel, fit_convex
from attitude.inversion.gaussian_image import GaussianImage
from attitude.inversion.minkowski import polyhedron_from_areas
from attitude.inversion.observations import ObservedLightcurve
from attitude.model.body import RigidBody
from attitude.model.shape import Polyhedron
from attitude.model.state import AttitudeState
from attitude.photometry.geometry import Geometry

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
                max_iterations: int = 20) -> PeriodScan:
    """chi2 of the best convex fit against trial period (``convexinv``'s period scan).

    Parameters
    ----------
    observations : list of ObservedLightcurve
    periods : array or Quantity
        Trial periods (s), spaced finely enough (:func:`period_grid`).
    poles : int
        Pole starts per trial period.
    rows, degree : int
        Resolution of the shape (coarser than the final fit: the scan asks only where
        chi2 is lowest).
    max_iterations : int
        Iterations per fit.

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
    model = ConvexModel(list(observations), GaussianImage(rows, degree))
    chi2 = np.empty(periods.size)
    ended = np.empty(periods.size)
    for i, p in enumerate(periods):
        fits = [fit_convex(model, lon, lat, p, max_iterations=max_iterations)
                for lon, lat in pole_starts(poles)]
        best = min(fits, key=lambda f: f.chi2)
        chi2[i], ended[i] = best.chi2, best.period
    return PeriodScan(periods, chi2, ended)


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
        The rotation at the first epoch, ``ECLIPJ2000``: about the model's ``z`` axis.
    period : float
        Sidereal period, s.
    pole : tuple
        ``(longitude, latitude)`` of the spin axis, deg, ecliptic J2000.
    chi2 : float
        Sum of the squared residuals of the data (without the convexity term).
    rms : float
        ``sqrt(chi2 / n)``: relative flux for relative lightcurves.
    regime : str
        ``"PA-short"`` (a principal-axis rotator is what was fitted).
    alternatives : list of (chi2, description)
        The other solutions: the mirror pole, the next best pole.
    dark_facet : float
        Relative area of the facet that closes the Gaussian image.
    spin_axis_tilt : float
        Angle (deg) between the spin axis and the shape's axis of largest inertia at
        uniform density: near 0 for a body that could rotate so in equilibrium.
    fit : ConvexFit
        The underlying fit.

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
    fit: ConvexFit = field(repr=False)


def invert(observations, rotation: str = "auto", *, period=None, poles: int = 10,
           rows: int = 8, degree: int = 6, convexity: float = 0.1,
           max_iterations: int = 100) -> InversionResult:
    """Shape, pole and rotation state from lightcurves alone.

    Parameters
    ----------
    observations : list of ObservedLightcurve
        Lightcurves with their geometry (:func:`read_damit_lightcurves`).
    rotation : {"auto", "principal"}
        The rotation fitted; ``"auto"`` is the principal-axis model (the tumbling
        inversion is not built yet).
    period : float, Quantity or (min, max)
        Sidereal period (s), or a range to scan (:func:`period_scan`).  Required.
    poles : int
        Pole starts.
    rows, degree : int
        Resolution of the Gaussian image and degree of its harmonic series.
    convexity : float
        Weight of the convexity term.
    max_iterations : int

    Returns
    -------
    InversionResult

    Raises
    ------
    PhotometryError
        For an unknown rotation, a missing period, or too few points for the parameters.

    Examples
    --------
    Lightcurves of an elongated body of pole (28.6, 57.3) deg and period 2 h:

    >>> res = invert(_example_observations(), period=7200.0, poles=10, rows=4, degree=2)
    >>> bool(res.rms < 1e-9), round(res.period, 6), [round(x, 6) for x in res.pole]
    (True, 7200.0, [28.64789, 57.29578])
    >>> res.shape.volume                        # relative data: unit volume
    1.0...
    """
    if rotation not in ("auto", "principal"):
        raise PhotometryError(f"rotation {rotation!r} is not available: the tumbling "
                              "inversion is not built yet; use 'principal' or 'auto'",
                              key="rotation")
    observations = list(observations)
    if period is None:
        raise PhotometryError("give the period (s) or a range (min, max) to scan",
                              key="period")
    model = ConvexModel(observations, GaussianImage(rows, degree))
    n_parameters = model.image.n_coefficients + 3
    if model.n_points <= n_parameters:
        raise PhotometryError(f"{model.n_points} points for {n_parameters} parameters: "
                              "more data, or a lower degree", key="observations")
    p = np.atleast_1d(to_si(period, "s", name="period", error=PhotometryError))
    if p.size == 2:
        span = float(np.ptp(model.time))
        p0 = period_scan(observations, period_grid(span, *np.sort(p))).best
    elif p.size == 1:
        p0 = float(p[0])
    else:
        raise PhotometryError(f"expected a period or a (min, max) range, got {p.size} "
                              "values", key="period")
    # the pole from starts over the sphere at the period found (a free period lets a fit
    # from a poor pole wander to a neighbouring minimum), then the best and its mirror
    # refined with the period free
    fixed = sorted((fit_convex(model, lon, lat, p0, free_period=False, convexity=convexity,
                               max_iterations=max_iterations)
                    for lon, lat in pole_starts(poles)), key=lambda f: f.chi2)
    best, mirror = (fit_convex(model, lon, fixed[0].latitude, p0,
                               coefficients=fixed[0].coefficients, convexity=convexity,
                               max_iterations=max_iterations)
                    for lon in (fixed[0].longitude, fixed[0].longitude + np.pi))
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
                           spin_axis_tilt=tilt, fit=best)


def _pole_distance(a: ConvexFit, b: ConvexFit) -> float:
    """Angle between two fitted poles, rad."""
    u = [np.cos(a.latitude) * np.cos(a.longitude), np.cos(a.latitude) * np.sin(a.longitude),
         np.sin(a.latitude)]
    v = [np.cos(b.latitude) * np.cos(b.longitude), np.cos(b.latitude) * np.sin(b.longitude),
         np.sin(b.latitude)]
    return float(np.arccos(np.clip(np.dot(u, v), -1.0, 1.0)))


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
