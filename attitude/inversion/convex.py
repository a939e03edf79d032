"""Convex inversion of a principal-axis rotator: the model and its least-squares fit.

The model (Kaasalainen & Torppa 2001; Kaasalainen, Torppa & Muinonen 2001): a convex
body given by its Gaussian image (:class:`~attitude.inversion.gaussian_image.GaussianImage`),
spinning about its ``z`` axis with sidereal period ``P`` about a pole of ecliptic
longitude ``lambda`` and latitude ``beta``:

.. math::

    r_{ecl} = R_z(\\lambda)\\, R_y(90^\\circ - \\beta)\\, R_z(\\varphi_0 + 2\\pi (t - t_0)/P)\\,
    r_{body},

seen with the scattering law ``S = f(alpha) [mu mu0 / (mu + mu0) + c mu mu0]`` (Lommel-
Seeliger plus a Lambert part ``c``) and the phase function ``f(alpha) = 1 + a exp(-alpha/d)
+ k alpha``; the brightness of a point is ``L = sum_j A_j S(mu_j, mu0_j, alpha)`` over the
facets both lit and seen (``mu = n_j . o``, ``mu0 = n_j . s`` in body axes).  A relative
lightcurve is compared after dividing model and data by their means over the lightcurve,
a calibrated one as it is.

The fit is damped least squares (Levenberg-Marquardt, :func:`scipy.optimize.least_squares`)
with the Jacobian computed exactly for the shape and scattering parameters and by central
differences for the pole and the period; a convexity term keeps the areas the Gaussian
image of a closed body (the *dark facet*, ``|sum A_j n_j| / sum A_j``, is reported).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from attitude.foundations.errors import PhotometryError
from attitude.inversion.gaussian_image import GaussianImage

__all__ = ["ConvexModel", "ConvexFit", "ShapeFit", "fit_convex", "fit_shape_rotation",
           "difference_columns", "spin_to_body"]


#: The residuals of a trial step whose areas overflow (each; squared and summed over a few
#: million points it stays finite, and above the cost of any real model).
OVERFLOWED_RESIDUAL = 1e100

def spin_to_body(longitude, latitude, period, t, phi0, vectors) -> np.ndarray:
    """Ecliptic vectors (``(n, 3)``, one per time ``t``) in the body frame of a body
    spinning about its ``z`` axis: ``R_z(-phi) R_y(beta - 90 deg) R_z(-lambda) v`` with
    ``phi = phi0 + 2 pi t / P`` (angles in radians, ``t`` and ``P`` in seconds).

    Examples
    --------
    >>> v = spin_to_body(0.0, np.pi / 2, 3600.0, np.array([900.0]), 0.0, [[1.0, 0.0, 0.0]])
    >>> np.round(v, 12).tolist()        # a quarter turn later, x is seen along -y
    [[0.0, -1.0, 0.0]]
    """
    v = np.asarray(vectors, dtype=float)
    cl, sl = np.cos(longitude), np.sin(longitude)
    x = cl * v[:, 0] + sl * v[:, 1]
    y = -sl * v[:, 0] + cl * v[:, 1]
    z = v[:, 2]
    tilt = np.pi / 2 - latitude                     # R_y(-(90 deg - beta))
    ct, st = np.cos(tilt), np.sin(tilt)
    x, z = ct * x - st * z, st * x + ct * z
    phi = phi0 + 2.0 * np.pi * np.asarray(t, dtype=float) / period
    cp, sp = np.cos(phi), np.sin(phi)
    return np.stack([cp * x + sp * y, -sp * x + cp * y, z], axis=-1)


@dataclass(frozen=True, eq=False)
class ConvexModel:
    """The data of a convex inversion laid out for the model, and the model itself.

    Parameters
    ----------
    observations : list of ObservedLightcurve
        The lightcurves with their geometry (one inertial frame, ecliptic for a pole in
        ecliptic coordinates).
    image : GaussianImage
        Directions and harmonic basis of the shape.
    t0 : float
        Time origin of the rotation phase, seconds on the observations' clock (default:
        the first point).

    Examples
    --------
    >>> import numpy as np
    >>> from astropy.time import Time
    >>> from attitude.photometry import Geometry
    >>> from attitude.inversion import ObservedLightcurve, GaussianImage
    >>> obs = ObservedLightcurve(Time("2026-01-01", scale="tdb"),
    ...                              np.linspace(0, 3600, 7), np.ones(7),
    ...                              Geometry(sun=[1, 0, 0], observer=[1, 0.2, 0]))
    >>> model = ConvexModel([obs], GaussianImage(rows=4, degree=2))
    >>> L = model.brightness(np.zeros(9), 0.0, np.pi / 2, 3600.0)
    >>> bool(np.ptp(L) < 0.02 * L.mean())  # a (triangulated) sphere: a nearly flat curve
    True
    """

    observations: list
    image: GaussianImage
    t0: float | None = None
    phi0: float = 0.0
    time: np.ndarray = field(init=False, repr=False)
    sun: np.ndarray = field(init=False, repr=False)
    observer: np.ndarray = field(init=False, repr=False)
    alpha: np.ndarray = field(init=False, repr=False)
    data: np.ndarray = field(init=False, repr=False)
    sigma: np.ndarray = field(init=False, repr=False)
    block: np.ndarray = field(init=False, repr=False)
    calibrated: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        obs = list(self.observations)
        if not obs:
            raise PhotometryError("no lightcurve given", key="observations")
        epoch = obs[0].epoch
        times, suns, seen, data, sigma, block, calibrated = [], [], [], [], [], [], []
        for k, o in enumerate(obs):
            shift = float((o.epoch - epoch).to_value("s"))
            times.append(o.time + shift)
            s, v = o.sun_and_observer()
            suns.append(s)
            seen.append(v)
            data.append(o.brightness)
            sigma.append(np.broadcast_to(o.sigma, o.brightness.shape))
            block.append(np.full(len(o), k))
            calibrated.append(o.calibrated)
        time = np.concatenate(times)
        t0 = float(time.min()) if self.t0 is None else float(self.t0)
        sun, observer = np.concatenate(suns), np.concatenate(seen)
        alpha = np.arctan2(np.linalg.norm(np.cross(sun, observer), axis=1),
                           np.einsum("ij,ij->i", sun, observer))
        object.__setattr__(self, "t0", t0)
        for name, value in (("time", time - t0), ("sun", sun), ("observer", observer),
                            ("alpha", alpha), ("data", np.concatenate(data)),
                            ("sigma", np.concatenate(sigma)),
                            ("block", np.concatenate(block)),
                            ("calibrated", np.array(calibrated))):
            object.__setattr__(self, name, value)

    @property
    def n_points(self) -> int:
        """Number of data points."""
        return self.time.size

    def directions(self, longitude, latitude, period):
        """Observer and Sun directions in the body frame, ``(n, 3)`` each."""
        return (spin_to_body(longitude, latitude, period, self.time, self.phi0,
                             self.observer),
                spin_to_body(longitude, latitude, period, self.time, self.phi0, self.sun))

    def cosines(self, longitude, latitude, period):
        """``mu = n_j . o`` and ``mu0 = n_j . s`` per point and facet (``(n, F)``, clamped at
        zero) and the body-frame observer and Sun directions (``(n, 3)``)."""
        o, s = self.directions(longitude, latitude, period)
        mu, mu0 = self.cosines_of(o, s)
        return mu, mu0, o, s

    def cosines_of(self, observer, sun):
        """``mu = n_j . o`` and ``mu0 = n_j . s`` (``(n, F)``, clamped at zero) for
        body-frame observer and Sun directions (``(n, 3)`` each) from any attitude
        history: the spin of :meth:`directions` or a tumbler's
        (:mod:`attitude.inversion.tumbler`)."""
        normals_t = self.image.normals.T
        return np.maximum(observer @ normals_t, 0.0), np.maximum(sun @ normals_t, 0.0)

    @staticmethod
    def law(mu, mu0, lambert):
        """``mu mu0 / (mu + mu0) + c mu mu0`` from clamped cosines: zero unless the facet
        is both lit and seen.

        Examples
        --------
        >>> ConvexModel.law(np.array([0.5, 0.0]), np.array([0.5, 0.7]), 0.1).tolist()
        [0.275, 0.0]
        """
        total = mu + mu0
        law = np.divide(mu * mu0, total, out=np.zeros_like(total), where=total > 0.0)
        law += lambert * mu * mu0
        return law

    @staticmethod
    def law_derivatives(mu, mu0, lambert):
        """Derivatives of :meth:`law` by ``mu`` and by ``mu0`` where the facet is both lit
        and seen (zero elsewhere: a facet crossing the terminator or the limb adds
        nothing to first order).

        Examples
        --------
        >>> d_mu, d_mu0 = ConvexModel.law_derivatives(np.array([0.5]), np.array([0.5]), 0.1)
        >>> d_mu.tolist(), d_mu0.tolist()
        ([0.3], [0.3])
        """
        both = (mu > 0.0) & (mu0 > 0.0)
        total = mu + mu0
        inverse2 = np.divide(1.0, total * total, out=np.zeros_like(total), where=both)
        d_mu = mu0 * mu0 * inverse2
        d_mu += lambert * np.where(both, mu0, 0.0)
        d_mu0 = mu * mu * inverse2
        d_mu0 += lambert * np.where(both, mu, 0.0)
        return d_mu, d_mu0

    def scattering(self, longitude, latitude, period, lambert):
        """:meth:`law` per point and facet (``(n, F)``) for a pole and a period."""
        mu, mu0, _, _ = self.cosines(longitude, latitude, period)
        return self.law(mu, mu0, lambert)

    def phase_function(self, a, d, k):
        """``f(alpha) = 1 + a exp(-alpha/d) + k alpha`` per point."""
        return 1.0 + a * np.exp(-self.alpha / d) + k * self.alpha

    def brightness(self, coefficients, longitude, latitude, period, *, phase=(0.0, 0.1, 0.0),
                   lambert=0.1):
        """The model brightness at every point, ``(n,)``.

        Parameters
        ----------
        coefficients : ((L + 1)^2,) array
            Harmonic coefficients of the log areas.
        longitude, latitude : float
            Pole, ecliptic, rad.
        period : float
            Sidereal period, s.
        phase : (a, d, k)
            Phase function.
        lambert : float
            Weight ``c`` of the Lambert part.
        """
        o, s = self.directions(longitude, latitude, period)
        return self.brightness_of(coefficients, o, s, phase=phase, lambert=lambert)

    def brightness_of(self, coefficients, observer, sun, *, phase=(0.0, 0.1, 0.0),
                      lambert=0.1):
        """The model brightness ``f(alpha) sum_j A_j S_ij``, ``(n,)``, for body-frame
        observer and Sun directions (``(n, 3)`` each) from any attitude history: the one
        brightness formula of the spin (:meth:`brightness`) and tumbler models."""
        law = self.law(*self.cosines_of(observer, sun), lambert)
        return self.phase_function(*phase) * (law @ self.image.areas(coefficients))


@dataclass(frozen=True, eq=False)
class ConvexFit:
    """The result of :func:`fit_convex` (angles in radians, period in seconds).

    Attributes
    ----------
    coefficients : array
        Harmonic coefficients of the log areas.
    areas : (F,) array
        Facet areas of the Gaussian image (the model's normals in ``image.normals``).
    longitude, latitude, period : float
        Pole (ecliptic, rad, as fitted: the latitude may leave [-90, 90] deg, see
        :attr:`pole`) and sidereal period (s).
    phase : tuple
        ``(a, d, k)`` of the phase function.
    lambert : float
    chi2 : float
        Sum of squared (weighted) residuals of the data, without the convexity term.
    rms : float
        ``sqrt(chi2 / n)`` (relative flux for relative lightcurves of unit weight).
    dark_facet : float
        Relative area of the dark facet.
    model : (n,) array
        The model brightness as compared (divided by its lightcurve mean when relative).
    status : str
        The optimiser's message.

    Examples
    --------
    >>> fit = ConvexFit(np.zeros(1), np.ones(8), 0.0, 2.0, 3600.0, (0.0, 0.1, 0.0), 0.1,
    ...                 0.0, 0.0, 0.0, np.ones(3), 1, "done")
    >>> [round(x, 6) for x in fit.pole]      # a latitude past the pole, made canonical
    [180.0, 65.408441]
    """

    coefficients: np.ndarray
    areas: np.ndarray
    longitude: float
    latitude: float
    period: float
    phase: tuple
    lambert: float
    chi2: float
    rms: float
    dark_facet: float
    model: np.ndarray
    n_evaluations: int
    status: str

    @property
    def pole(self) -> tuple[float, float]:
        """The spin axis ``(longitude, latitude)``, deg, longitude in [0, 360)."""
        lon, lat = _canonical_pole(self.longitude, self.latitude)
        return float(np.degrees(lon)), float(np.degrees(lat))


def _block_means(values, block, n_blocks):
    """Mean of ``values`` (``(n,)`` or ``(n, p)``) over each lightcurve, per point."""
    counts = np.bincount(block, minlength=n_blocks).astype(float)
    if values.ndim == 1:
        return (np.bincount(block, values, minlength=n_blocks) / counts)[block]
    sums = np.zeros((n_blocks,) + values.shape[1:])
    np.add.at(sums, block, values)
    return (sums / counts[:, None])[block]


@dataclass(frozen=True, eq=False)
class ShapeFit:
    """The result of :func:`fit_shape_rotation`: a convex shape fitted with the
    parameters of any attitude history.

    Attributes
    ----------
    coefficients : array
        Harmonic coefficients of the log areas.
    areas : (F,) array
        Facet areas of the Gaussian image.
    rotation : (k,) array
        The rotation parameters as fitted.
    phase : tuple
        ``(a, d, k)`` of the phase function.
    lambert : float
    chi2, rms, dark_facet : float
        As in :class:`ConvexFit`.
    model : (n,) array
        The model brightness as compared.
    jacobian : (n, p) array
        d(weighted residual)/d(free parameter) of the data at the end: shape
        coefficients first, then the rotation, then the phase function.
    n_evaluations : int
    status : str

    Examples
    --------
    >>> fit = ShapeFit(np.zeros(1), np.ones(8), np.array([3600.0]), (0.0, 0.1, 0.0), 0.1,
    ...                0.0, 0.0, 0.0, np.ones(3), np.zeros((3, 1)), 1, "done")
    >>> fit.rotation.tolist()
    [3600.0]
    """

    coefficients: np.ndarray
    areas: np.ndarray
    rotation: np.ndarray
    phase: tuple
    lambert: float
    chi2: float
    rms: float
    dark_facet: float
    model: np.ndarray
    jacobian: np.ndarray
    n_evaluations: int
    status: str


def difference_columns(directions, rotation, steps, grad_o, grad_s) -> np.ndarray:
    """``d(sum_j A_j S_ij)/dr`` (``(n, k)``) by central differences of the body-frame
    directions only: ``sum_j A_j (S_mu n_j . do/dr + S_mu0 n_j . ds/dr)``, with
    ``grad_o = sum_j A_j S_mu n_j`` and ``grad_s`` likewise (``(n, 3)`` each).

    Examples
    --------
    >>> turn = lambda r: (np.array([[np.cos(r[0]), np.sin(r[0]), 0.0]]),
    ...                   np.array([[1.0, 0.0, 0.0]]))
    >>> difference_columns(turn, np.array([0.0]), [1e-6], np.array([[0.0, 2.0, 0.0]]),
    ...                    np.zeros((1, 3))).round(9).tolist()
    [[2.0]]
    """
    r = np.asarray(rotation, dtype=float)
    columns = np.empty((grad_o.shape[0], r.size))
    for i, h in enumerate(np.broadcast_to(steps, r.shape)):
        up, down = r.copy(), r.copy()
        up[i] += h
        down[i] -= h
        (o_up, s_up), (o_dn, s_dn) = directions(up), directions(down)
        columns[:, i] = (np.einsum("ij,ij->i", grad_o, o_up - o_dn)
                         + np.einsum("ij,ij->i", grad_s, s_up - s_dn)) / (2.0 * h)
    return columns


def fit_shape_rotation(model: ConvexModel, directions, rotation=(), *, columns=None,
                       bounds=None, coefficients=None, free_shape=True,
                       phase=(0.0, 0.1, 0.0), free_phase=False, lambert=0.1,
                       convexity=0.1, max_iterations=100, tolerance=1e-8) -> ShapeFit:
    """Fit a convex shape with the parameters of any attitude history (damped least
    squares; the engine of :func:`fit_convex` and of the tumbler inversion).

    Parameters
    ----------
    model : ConvexModel
        The data and the Gaussian image.
    directions : callable
        ``directions(r) -> (observer, sun)``: body-frame unit vectors (``(n, 3)`` each)
        at the data points for rotation parameters ``r``.
    rotation : (k,) array
        Starting rotation parameters (``k = 0``: the attitude history is fixed).
    columns : callable, optional
        ``columns(r, observer, sun, grad_o, grad_s) -> (n, k)``: ``d(sum_j A_j S_ij)/dr``
        (default: :func:`difference_columns` with steps ``1e-6 max(1, |r|)``).
    bounds : (lower, upper), optional
        Bounds of the rotation parameters (then the trust-region method, else
        Levenberg-Marquardt).
    coefficients : array, optional
        Starting shape (default: the sphere).
    free_shape : bool
        Fit the shape (default) or keep ``coefficients``.
    phase, free_phase, lambert, convexity, max_iterations, tolerance
        As in :func:`fit_convex`.

    Returns
    -------
    ShapeFit

    Examples
    --------
    The shape alone, for a fixed attitude history (here a spin of 2 h):

    >>> from astropy.time import Time
    >>> from attitude.photometry import Geometry
    >>> from attitude.inversion import ObservedLightcurve
    >>> t = np.linspace(0.0, 8 * 3600.0, 60)
    >>> obs = [ObservedLightcurve(Time("2026-01-01", scale="tdb"), t + 86400.0 * k,
    ...                           np.ones(60), Geometry(sun=[1, 0.3 * k, 0.1],
    ...                                                 observer=[1, 0.3 * k - 0.2, 0]))
    ...        for k in range(3)]
    >>> m = ConvexModel(obs, GaussianImage(rows=4, degree=2))
    >>> truth = np.zeros(9); truth[8] = 0.4
    >>> y = m.brightness(truth, 0.5, 1.0, 7200.0)
    >>> m = ConvexModel([ObservedLightcurve(o.epoch, o.time, y[m.block == k], o.geometry)
    ...                  for k, o in enumerate(obs)], m.image)
    >>> spin = lambda r: m.directions(0.5, 1.0, 7200.0)
    >>> fit = fit_shape_rotation(m, spin)
    >>> bool(fit.rms < 1e-6), fit.rotation.size
    (True, 0)
    """
    image = model.image
    n_coef = image.n_coefficients
    relative = ~model.calibrated[model.block]
    all_relative = bool(relative.all())
    n_blocks = len(model.calibrated)
    c_start = np.zeros(n_coef) if coefficients is None else np.array(coefficients, float)
    # the overall size is free only when a calibrated lightcurve fixes it
    shape_index = (np.arange(1 if all_relative else 0, n_coef) if free_shape
                   else np.arange(0))
    r_start = np.atleast_1d(np.asarray(rotation, dtype=float))
    n_shape, n_rot = shape_index.size, r_start.size
    x0 = np.concatenate([c_start[shape_index], r_start,
                         np.asarray(phase, float) if free_phase else []])
    if columns is None:
        def columns(r, o, s, grad_o, grad_s):
            return difference_columns(directions, r, 1e-6 * np.maximum(1.0, np.abs(r)),
                                      grad_o, grad_s)
    means = _block_means(model.data, model.block, n_blocks)
    data_rel = np.where(relative, model.data / means, model.data)
    weight = 1.0 / np.where(relative, model.sigma / means, model.sigma)
    reg = convexity * np.sqrt(model.n_points)

    def unpack(x):
        c = c_start.copy()
        c[shape_index] = x[:n_shape]
        r = x[n_shape:n_shape + n_rot]
        ph = tuple(x[n_shape + n_rot:]) if free_phase else tuple(phase)
        return c, r, ph

    def compared(raw):
        """The model as compared with the data (relative: over its lightcurve mean)."""
        return np.where(relative, raw / _block_means(raw, model.block, n_blocks), raw)

    cache = {}

    def evaluate(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            c, r, ph = unpack(x)
            o, s = directions(r)
            mu, mu0 = model.cosines_of(o, s)
            law = model.law(mu, mu0, lambert)
            areas = image.areas(c)
            f = model.phase_function(*ph)
            raw = f * (law @ areas)
            closing = areas @ image.normals / areas.sum()
            cache[key] = (raw, law, areas, f, closing, mu, mu0, o, s)
        return cache[key]

    def residuals(x):
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            raw, _, _, _, closing = evaluate(x)[:5]
            res = np.concatenate([(data_rel - compared(raw)) * weight, reg * closing])
        if not np.all(np.isfinite(res)):
            # a trial step so long that exp(basis @ c) overflows (a high degree on few
            # points): a cost above any finite one, so the optimiser rejects the step
            # and shortens the next
            return np.full(res.size, OVERFLOWED_RESIDUAL)
        return res

    def jacobian(x):
        c, r, ph = unpack(x)
        raw, law, areas, f, closing, mu, mu0, o, s = evaluate(x)
        blocks = []
        # shape: dL/da_k = f sum_j S_ij A_j Y_jk
        basis = image.basis[:, shape_index]
        blocks.append(f[:, None] * (law @ (areas[:, None] * basis)))
        if n_rot:
            # rotation: dL/dr = f sum_j A_j (S_mu n_j . do/dr + S_mu0 n_j . ds/dr)
            d_mu, d_mu0 = model.law_derivatives(mu, mu0, lambert)
            grad_o = (d_mu * areas) @ image.normals             # (n, 3)
            grad_s = (d_mu0 * areas) @ image.normals
            blocks.append(f[:, None] * columns(r, o, s, grad_o, grad_s))
        if free_phase:
            a, d, _k = ph
            e = np.exp(-model.alpha / d)
            base = law @ areas
            blocks.append(np.stack([e * base, a * e * model.alpha / d**2 * base,
                                    model.alpha * base], axis=1))
        d_raw = np.concatenate(blocks, axis=1)
        # relative: d(L / <L>) = (dL - (L / <L>) d<L>) / <L>
        mean = _block_means(raw, model.block, n_blocks)
        d_mean = _block_means(d_raw, model.block, n_blocks)
        d_cmp = np.where(relative[:, None], (d_raw - (raw / mean)[:, None] * d_mean)
                         / mean[:, None], d_raw)
        jac = -d_cmp * weight[:, None]
        # convexity: d(sum A n / sum A)/da_k
        total = areas.sum()
        d_close = np.zeros((3, x.size))
        d_close[:, :n_shape] = ((areas[:, None] * basis).T @ image.normals).T / total \
            - np.outer(closing, areas @ basis) / total
        return np.concatenate([jac, reg * d_close], axis=0)

    if x0.size == 0:
        n_evaluations, status, x_end = 1, "nothing to fit", x0
    else:
        if bounds is None:
            kwargs = {"method": "lm"}
        else:
            lower = np.full(x0.size, -np.inf)
            upper = np.full(x0.size, np.inf)
            lower[n_shape:n_shape + n_rot], upper[n_shape:n_shape + n_rot] = bounds
            x0 = np.clip(x0, lower, upper)
            kwargs = {"method": "trf", "bounds": (lower, upper)}
        result = least_squares(residuals, x0, jac=jacobian, x_scale="jac", ftol=tolerance,
                               xtol=1e-12, gtol=1e-12, max_nfev=max_iterations, **kwargs)
        n_evaluations, status, x_end = int(result.nfev), str(result.message), result.x
    c, r, ph = unpack(x_end)
    raw, _, areas, _, closing = evaluate(x_end)[:5]
    resid = (data_rel - compared(raw)) * weight
    chi2 = float(resid @ resid)
    jac_end = jacobian(x_end)[:model.n_points] if x_end.size else np.zeros((resid.size, 0))
    return ShapeFit(coefficients=c, areas=areas, rotation=np.array(r, dtype=float),
                    phase=tuple(float(v) for v in ph), lambert=float(lambert), chi2=chi2,
                    rms=float(np.sqrt(chi2 / model.n_points)),
                    dark_facet=float(np.linalg.norm(closing)), model=compared(raw),
                    jacobian=jac_end, n_evaluations=n_evaluations, status=status)


def fit_convex(model: ConvexModel, longitude, latitude, period, *, coefficients=None,
               free_period=True, phase=(0.0, 0.1, 0.0), free_phase=False, lambert=0.1,
               convexity=0.1, max_iterations=100, tolerance=1e-8) -> ConvexFit:
    """Fit shape, pole and period from a start (damped least squares).

    Parameters
    ----------
    model : ConvexModel
    longitude, latitude : float
        Starting pole, ecliptic, rad.
    period : float
        Starting sidereal period, s.
    coefficients : array, optional
        Starting shape (default: the sphere).
    free_period : bool
        Fit the period (default) or keep it.
    phase : (a, d, k)
        Phase function; fitted when ``free_phase`` (needs calibrated data).
    lambert : float
        Lambert weight ``c`` (kept fixed, as it matters little).
    convexity : float
        Weight of the convexity term (the dark facet's share of the residuals).
    max_iterations : int
        Iterations of the optimiser (each one Jacobian).
    tolerance : float
        Relative change of the cost that ends the fit.

    Returns
    -------
    ConvexFit

    Examples
    --------
    A two-facet-like elongated body is recovered from its own lightcurves:

    >>> import numpy as np
    >>> from astropy.time import Time
    >>> from attitude.photometry import Geometry
    >>> from attitude.inversion import ObservedLightcurve, GaussianImage
    >>> image = GaussianImage(rows=4, degree=2)
    >>> t = np.linspace(0.0, 8 * 3600.0, 60)
    >>> obs = [ObservedLightcurve(Time("2026-01-01", scale="tdb"), t + 86400.0 * k,
    ...                               np.ones(60), Geometry(sun=[1, 0.3 * k, 0.1],
    ...                                                     observer=[1, 0.3 * k - 0.2, 0]))
    ...        for k in range(3)]
    >>> truth = np.zeros(9); truth[8] = 0.4            # Y_22: longer along x
    >>> m = ConvexModel(obs, image)
    >>> y = m.brightness(truth, 0.5, 1.0, 7200.0)
    >>> obs = [ObservedLightcurve(o.epoch, o.time, y[m.block == k], o.geometry)
    ...        for k, o in enumerate(obs)]
    >>> fit = fit_convex(ConvexModel(obs, image), 0.6, 0.9, 7200.0 * (1 + 1e-5))
    >>> bool(fit.rms < 1e-6), round(fit.period, 3)
    (True, 7200.0)
    """
    def directions(r):
        return model.directions(r[0], r[1], r[2] if free_period else period)

    def columns(r, o, s, grad_o, grad_s):
        pole = difference_columns(lambda q: directions(np.concatenate([q, r[2:]])), r[:2],
                                  1e-6, grad_o, grad_s)
        if not free_period:
            return pole
        # d(R_z(-phi) w)/dphi = (y, -x, 0) of the body-frame vector; dphi/dP
        dphi = -2.0 * np.pi * model.time / (r[2] * r[2])
        rate = (grad_o[:, 0] * o[:, 1] - grad_o[:, 1] * o[:, 0]
                + grad_s[:, 0] * s[:, 1] - grad_s[:, 1] * s[:, 0])
        return np.concatenate([pole, (rate * dphi)[:, None]], axis=1)

    start = [longitude, latitude] + ([period] if free_period else [])
    fit = fit_shape_rotation(model, directions, start, columns=columns,
                             coefficients=coefficients, phase=phase, free_phase=free_phase,
                             lambert=lambert, convexity=convexity,
                             max_iterations=max_iterations, tolerance=tolerance)
    lon, lat = fit.rotation[:2]
    p = fit.rotation[2] if free_period else period
    return ConvexFit(coefficients=fit.coefficients, areas=fit.areas, longitude=float(lon),
                     latitude=float(lat), period=float(p), phase=fit.phase,
                     lambert=fit.lambert, chi2=fit.chi2, rms=fit.rms,
                     dark_facet=fit.dark_facet, model=fit.model,
                     n_evaluations=fit.n_evaluations, status=fit.status)


def _canonical_pole(longitude, latitude):
    """The pole with latitude in [-90, 90] deg and longitude in [0, 360) (rad)."""
    v = np.array([np.cos(latitude) * np.cos(longitude), np.cos(latitude) * np.sin(longitude),
                  np.sin(latitude)])
    return float(np.arctan2(v[1], v[0]) % (2.0 * np.pi)), float(np.arcsin(np.clip(v[2], -1,
                                                                                     1)))

