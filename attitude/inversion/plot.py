"""Figures of an inversion: the lightcurves with the model, the period scan, the chi2
map over the pole (or over the direction of L for a tumbler) and the convex shape.

matplotlib is optional (the ``plot`` extra): it is imported only when a figure is drawn
(:func:`attitude.foundations.figures.agg_figure`), and a missing matplotlib raises
:class:`~attitude.foundations.errors.PlotUnavailableError`.

The chi2 map is *conditional*: at each direction on a grid the shape alone is refitted
with the rest of the rotation kept at the solution (the period for a principal-axis
rotator; the energy, moment ratios, periods and angles for a tumbler).  It shows where
the data put the pole and how sharply; the solution's own chi2 is its minimum (up to the
grid's spacing).  ``attitude invert SCENARIO.toml --plot`` writes all four figures.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from attitude.foundations.figures import agg_figure
from attitude.inversion.convex import ConvexModel, fit_shape_rotation
from attitude.inversion.gaussian_image import GaussianImage
from attitude.inversion.invert import InversionResult, PeriodScan
from attitude.inversion.observations import engine_blocks
from attitude.inversion.tumbler import PARAMETERS, tumbler_directions
from attitude.model.ephemeris import write_atomically

__all__ = ["PoleMap", "pole_map", "lightcurve_figure", "periodogram_figure",
           "pole_map_figure", "shape_figure", "save_inversion_figures"]

#: Lightcurves drawn at most in the figure of the data and the model (the first ones).
MAX_PANELS = 36


@dataclass(frozen=True, eq=False)
class PoleMap:
    """chi2 of the shape refitted at each direction of a longitude-latitude grid.

    Attributes
    ----------
    longitude, latitude : (n_lon,), (n_lat,) arrays
        The grid, deg, ecliptic J2000.
    chi2 : (n_lat, n_lon) array
    kind : str
        ``"pole"`` (the spin axis) or ``"L"`` (a tumbler's angular momentum).

    Examples
    --------
    >>> m = PoleMap(np.array([0.0, 180.0]), np.array([0.0]), np.array([[2.0, 1.0]]), "pole")
    >>> m.best
    (180.0, 0.0)
    """

    longitude: np.ndarray
    latitude: np.ndarray
    chi2: np.ndarray
    kind: str

    @property
    def best(self) -> tuple[float, float]:
        """The grid direction of the lowest chi2, deg."""
        i, j = np.unravel_index(int(np.argmin(self.chi2)), self.chi2.shape)
        return float(self.longitude[j]), float(self.latitude[i])


def _image_of(result: InversionResult) -> GaussianImage:
    """The Gaussian image of a result: ``8 rows^2`` facets, ``(degree + 1)^2``
    coefficients."""
    shape = getattr(result.fit, "shape", result.fit)         # a tumbler's ShapeFit
    rows = int(round(np.sqrt(shape.areas.size / 8)))
    degree = int(round(np.sqrt(shape.coefficients.size))) - 1
    return GaussianImage(rows, degree)


def _model_and_blocks(observations, result: InversionResult):
    blocks = engine_blocks(observations)
    return ConvexModel(blocks, _image_of(result)), blocks


def pole_map(observations, result: InversionResult, *, n_longitude: int = 18,
             n_latitude: int = 9, max_iterations: int = 15) -> PoleMap:
    """The conditional chi2 over the pole (principal axis) or the direction of L
    (tumbler): the shape refitted at each grid direction, the rest kept at the solution.

    Parameters
    ----------
    observations : LightcurveObservations or list of them
        The data of the inversion.
    result : InversionResult
    n_longitude, n_latitude : int
        Grid: longitudes ``0, 360/n, ...`` and latitudes from -90 to 90 deg inclusive.
    max_iterations : int
        Iterations of each shape fit (each starts from the solution's shape).

    Returns
    -------
    PoleMap

    Examples
    --------
    >>> from attitude.inversion.invert import _example_observations, _example_result
    >>> obs, res = _example_observations(), _example_result()
    >>> m = pole_map(obs, res, n_longitude=8, n_latitude=5, max_iterations=5)
    >>> m.chi2.shape, bool(m.chi2.min() >= 0.0)
    ((5, 8), True)
    """
    model, _ = _model_and_blocks(observations, result)
    longitude = np.arange(n_longitude) * 360.0 / n_longitude
    latitude = np.linspace(-90.0, 90.0, n_latitude)
    fit = result.fit
    tumbler = hasattr(fit, "parameters") and isinstance(fit.parameters, dict)
    start = getattr(fit, "shape", fit).coefficients
    if tumbler:
        p = np.array([fit.parameters[k] for k in PARAMETERS])

        def directions(lon, lat):
            q = p.copy()
            q[0], q[1] = lon, lat
            return tumbler_directions(model, q)
    else:
        def directions(lon, lat):
            return model.directions(lon, lat, result.period)
    chi2 = np.empty((n_latitude, n_longitude))
    for i, lat in enumerate(np.radians(latitude)):
        for j, lon in enumerate(np.radians(longitude)):
            seen = directions(lon, lat)
            chi2[i, j] = fit_shape_rotation(model, lambda r, seen=seen: seen,
                                            coefficients=start,
                                            max_iterations=max_iterations).chi2
    return PoleMap(longitude, latitude, chi2, "L" if tumbler else "pole")


def lightcurve_figure(observations, result: InversionResult):
    """The data (relative lightcurves over their mean) and the model, one panel per
    lightcurve (the first :data:`MAX_PANELS`), against hours since the lightcurve's
    start.

    Examples
    --------
    >>> from attitude.inversion.invert import _example_observations, _example_result
    >>> obs, res = _example_observations(), _example_result()
    >>> fig = lightcurve_figure(obs, res)
    >>> len(fig.axes), [line.get_label() for line in fig.axes[0].lines]
    (3, ['data', 'model'])
    """
    blocks = engine_blocks(observations)
    model = result.fit.model
    n = min(len(blocks), MAX_PANELS)
    cols = min(n, 4)
    rows = -(-n // cols)
    fig = agg_figure(figsize=(3.2 * cols, 2.2 * rows + 0.6), layout="constrained")
    start = 0
    for k, block in enumerate(blocks[:n]):
        y = block.brightness if block.calibrated else \
            block.brightness / block.brightness.mean()
        m = model[start:start + len(block)]
        start += len(block)
        hours = (block.time - block.time[0]) / 3600.0
        ax = fig.add_subplot(rows, cols, k + 1)
        ax.plot(hours, y, ".", ms=3, color="k", label="data")
        ax.plot(hours, m, "-", lw=1, color="C3", label="model")
        ax.set_title(block.name[-40:], fontsize="x-small")
        ax.tick_params(labelsize="x-small")
    shown = f" (the first {n})" if n < len(blocks) else ""
    fig.suptitle(f"{len(blocks)} lightcurves{shown}: data and model, rms {result.rms:.3g}",
                 fontsize="small")
    fig.supxlabel("hours since the lightcurve's start", fontsize="small")
    fig.supylabel("relative brightness", fontsize="small")
    return fig


def periodogram_figure(scan: PeriodScan):
    """chi2 of the best convex model against the trial period (h), the best marked.

    Examples
    --------
    >>> scan = PeriodScan(np.array([7100.0, 7200.0, 7300.0]), np.array([5.0, 1.0, 4.0]),
    ...                   np.array([7100.0, 7200.0, 7300.0]))
    >>> fig = periodogram_figure(scan)
    >>> fig.axes[0].lines[0].get_ydata().tolist()
    [5.0, 1.0, 4.0]
    """
    fig = agg_figure(figsize=(7, 3.2), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(scan.periods / 3600.0, scan.chi2, "-", lw=1, color="k")
    ax.axvline(scan.best / 3600.0, color="C3", lw=0.8, ls="--",
               label=f"best {scan.best / 3600.0:.6f} h")
    ax.set_xlabel("trial period (h)")
    ax.set_ylabel("chi2")
    ax.legend(fontsize="small")
    ax.set_title("period scan", fontsize="small")
    return fig


def pole_map_figure(pole: PoleMap, result: InversionResult | None = None):
    """The conditional chi2 over the sky (longitude, latitude; colour ``log10 chi2``),
    with the solution's pole (or L) and its mirror marked.

    Examples
    --------
    >>> m = PoleMap(np.array([0.0, 90.0, 180.0, 270.0]), np.array([-45.0, 45.0]),
    ...             np.array([[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]]), "pole")
    >>> fig = pole_map_figure(m)
    >>> fig.axes[0].collections[0].get_array().reshape(2, 4).round(3).tolist()[0]
    [0.0, 0.301, 0.477, 0.602]
    """
    fig = agg_figure(figsize=(7, 3.8), layout="constrained")
    ax = fig.add_subplot()
    with np.errstate(divide="ignore"):
        level = np.log10(np.maximum(pole.chi2, np.finfo(float).tiny))
    mesh = ax.pcolormesh(pole.longitude, pole.latitude, level, shading="nearest",
                         cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="log10 chi2")
    if result is not None:
        lon, lat = result.pole
        ax.plot([lon % 360.0], [lat], "r*", ms=12, label=f"solution ({lon:.1f}, {lat:.1f})")
        ax.plot([(lon + 180.0) % 360.0], [lat], "w+", ms=10, label="mirror")
        ax.legend(fontsize="x-small", loc="lower right")
    ax.set_xlabel("ecliptic longitude (deg)")
    ax.set_ylabel("ecliptic latitude (deg)")
    what = "spin axis" if pole.kind == "pole" else "angular momentum L"
    ax.set_title(f"chi2 of the shape refitted at each direction of the {what}",
                 fontsize="small")
    return fig


def shape_figure(result: InversionResult):
    """The convex polyhedron seen from three directions (matplotlib's shading).

    Examples
    --------
    >>> from attitude.inversion.invert import _example_result
    >>> res = _example_result()
    >>> fig = shape_figure(res)
    >>> [len(ax.collections[0].get_facecolor()) for ax in fig.axes] == [len(res.shape.faces)] * 3
    True
    """
    shape = result.shape
    x, y, z = shape.vertices.T
    extent = float(np.abs(shape.vertices).max())
    fig = agg_figure(figsize=(9, 3.4), layout="constrained")
    for k, (elev, azim, title) in enumerate(((90, -90, "from +z (spin axis / C)"),
                                             (0, -90, "from -y"), (0, 0, "from +x"))):
        ax = fig.add_subplot(1, 3, k + 1, projection="3d")
        ax.plot_trisurf(x, y, z, triangles=shape.faces, color="0.8", shade=True,
                        linewidth=0.0, antialiased=False)
        for set_lim in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
            set_lim(-extent, extent)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=elev, azim=azim)
        ax.set_axis_off()
        ax.set_title(title, fontsize="small")
    fig.suptitle(f"convex shape ({len(shape.faces)} facets, unit volume)", fontsize="small")
    return fig


def save_inversion_figures(observations, result: InversionResult, stem, *,
                           pole: PoleMap | None = None) -> list[Path]:
    """Write ``STEM_fit.png`` (data and model), ``STEM_periodogram.png`` (when a period
    scan ran: ``result.scan``), ``STEM_pole_map.png`` and ``STEM_shape_view.png``, each
    atomically; returns the paths.

    Parameters
    ----------
    observations : LightcurveObservations or list of them
    result : InversionResult
    stem : path
    pole : PoleMap, optional
        Default: :func:`pole_map` with its defaults.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from attitude.inversion.invert import _example_observations, _example_result
    >>> obs, res = _example_observations(), _example_result()
    >>> stem = pathlib.Path(tempfile.mkdtemp()) / "demo"
    >>> pole = pole_map(obs, res, n_longitude=4, n_latitude=3, max_iterations=3)
    >>> [p.name for p in save_inversion_figures(obs, res, stem, pole=pole)]
    ['demo_fit.png', 'demo_pole_map.png', 'demo_shape_view.png']
    """
    stem = Path(stem)
    figures = {"fit": lightcurve_figure(observations, result)}
    if getattr(result, "scan", None) is not None:
        figures["periodogram"] = periodogram_figure(result.scan)
    figures["pole_map"] = pole_map_figure(
        pole if pole is not None else pole_map(observations, result), result)
    figures["shape_view"] = shape_figure(result)
    paths = []
    for name, fig in figures.items():
        path = stem.parent / f"{stem.name}_{name}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomically(path, lambda tmp, fig=fig: fig.savefig(tmp, format="png", dpi=110))
        paths.append(path)
    return paths
