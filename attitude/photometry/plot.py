"""Lightcurve figures: the curve, the periodogram, the folded curve and the frequency
map of the two-period fit.  matplotlib is imported on use (``attitude-dynamics[plot]``).

Examples
--------
>>> import numpy as np
>>> from astropy.time import Time
>>> from attitude.photometry import Lightcurve, fit_periods
>>> from attitude.photometry.plot import lightcurve_figure
>>> t = np.linspace(0, 86400.0, 300)
>>> lc = Lightcurve.from_arrays(t, magnitude=0.2 * np.cos(4 * np.pi * t / 21600.0),
...                             epoch=Time("2030-01-01"))
>>> fig = lightcurve_figure(lc, fit_periods(t, lc.magnitude, n_periods=1, order=2))
>>> len(fig.axes)
1
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from attitude.photometry.dataset import Lightcurve
from attitude.photometry.periods import PeriodFit

from ..foundations.figures import agg_figure

__all__ = ["lightcurve_figure", "periodogram_figure", "folded_figure",
           "frequency_map_figure", "save_lightcurve_figures"]




def _hours(t):
    return np.asarray(t, dtype=float) / 3600.0


def lightcurve_figure(lc: Lightcurve, fit: PeriodFit | None = None):
    """Magnitude against time (hours), with the fitted model when given.

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.photometry import Lightcurve, fit_periods
    >>> t = np.linspace(0.0, 4 * 86400.0, 800)
    >>> y = 0.2 * np.cos(2 * np.pi * t / 21600.0) + 0.1 * np.cos(2 * np.pi * t / 50000.0)
    >>> lc = Lightcurve.from_arrays(t, magnitude=y, epoch=Time("2024-01-01"))
    >>> fit = fit_periods(t, y, n_periods=2, order=2)
    >>> fig = lightcurve_figure(lc, fit)
    >>> len(fig.axes[0].lines)                          # the data and the model
    2
    """
    fig = agg_figure(figsize=(8, 3.5), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(_hours(lc.time), lc.magnitude, ".", ms=2, label="lightcurve")
    if fit is not None:
        tt = np.linspace(lc.time.min(), lc.time.max(), 4000)
        ax.plot(_hours(tt), fit.model(tt), "-", lw=0.8, label="Fourier fit")
    ax.invert_yaxis()
    ax.set_xlabel(f"time since {lc.dataset.attrs['epoch']} (h)")
    ax.set_ylabel("magnitude")
    ax.legend(loc="upper right", fontsize="small")
    return fig


def periodogram_figure(lc: Lightcurve, fit: PeriodFit | None = None):
    """Lomb-Scargle power against frequency (cycles/day), the fitted terms marked.

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.photometry import Lightcurve, fit_periods
    >>> t = np.linspace(0.0, 4 * 86400.0, 800)
    >>> y = 0.2 * np.cos(2 * np.pi * t / 21600.0) + 0.1 * np.cos(2 * np.pi * t / 50000.0)
    >>> lc = Lightcurve.from_arrays(t, magnitude=y, epoch=Time("2024-01-01"))
    >>> fit = fit_periods(t, y, n_periods=2, order=2)
    >>> periodogram_figure(lc, fit).axes[0].get_xlabel()
    'frequency (cycles/day)'
    """
    from astropy.timeseries import LombScargle  # costly import: only for this figure

    t = lc.time
    span = t.max() - t.min()
    dt = np.median(np.diff(t))
    freq, power = LombScargle(t, lc.magnitude).autopower(
        minimum_frequency=1 / span, maximum_frequency=0.5 / dt, samples_per_peak=10)
    fig = agg_figure(figsize=(8, 3.5), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(freq * 86400, power, lw=0.8)
    if fit is not None:
        for term in fit.significant_terms:
            ax.axvline(abs(term["frequency"]) * 86400, color="C3", lw=0.5, alpha=0.6)
    ax.set_xlabel("frequency (cycles/day)")
    ax.set_ylabel("Lomb-Scargle power")
    ax.set_xlim(0, min(freq.max() * 86400, 20))
    return fig


def folded_figure(lc: Lightcurve, fit: PeriodFit):
    """The lightcurve folded on the double-peaked period.

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.photometry import Lightcurve, fit_periods
    >>> t = np.linspace(0.0, 4 * 86400.0, 800)
    >>> y = 0.2 * np.cos(2 * np.pi * t / 21600.0) + 0.1 * np.cos(2 * np.pi * t / 50000.0)
    >>> lc = Lightcurve.from_arrays(t, magnitude=y, epoch=Time("2024-01-01"))
    >>> fit = fit_periods(t, y, n_periods=2, order=2)
    >>> folded_figure(lc, fit).axes[0].get_xlabel()       # folded on 2 / f_strongest
    'phase (P = 12.0000 h)'
    """
    period = fit.lightcurve_period
    fig = agg_figure(figsize=(6, 3.5), layout="constrained")
    ax = fig.add_subplot()
    phase = np.mod(lc.time, period) / period
    ax.scatter(phase, lc.magnitude, s=2, c=lc.time, cmap="viridis")
    ax.invert_yaxis()
    ax.set_xlabel(f"phase (P = {period / 3600:.4f} h)")
    ax.set_ylabel("magnitude")
    return fig


def frequency_map_figure(fit: PeriodFit):
    """Amplitude of each term ``j f1 + k f2`` on the (j, k) lattice.

    Examples
    --------
    >>> from astropy.time import Time
    >>> from attitude.photometry import Lightcurve, fit_periods
    >>> t = np.linspace(0.0, 4 * 86400.0, 800)
    >>> y = 0.2 * np.cos(2 * np.pi * t / 21600.0) + 0.1 * np.cos(2 * np.pi * t / 50000.0)
    >>> lc = Lightcurve.from_arrays(t, magnitude=y, epoch=Time("2024-01-01"))
    >>> fit = fit_periods(t, y, n_periods=2, order=2)
    >>> frequency_map_figure(fit).axes[0].get_xlabel()
    'j (f1 = 1/12.0000 h)'
    """
    fig = agg_figure(figsize=(5, 4), layout="constrained")
    ax = fig.add_subplot()
    j = np.array([t["j"] for t in fit.terms])
    k = np.array([t["k"] for t in fit.terms])
    amp = np.array([t["amplitude"] for t in fit.terms])
    sig = np.array([t["significant"] for t in fit.terms])
    sc = ax.scatter(j, k, s=20 + 400 * amp / max(amp.max(), 1e-300), c=amp, cmap="magma_r",
                    edgecolors=np.where(sig, "k", "0.7"))
    fig.colorbar(sc, ax=ax, label="amplitude (mag)")
    p = fit.periods / 3600
    ax.set_xlabel(f"j (f1 = 1/{p[0]:.4f} h)")
    ax.set_ylabel(f"k (f2 = 1/{p[-1]:.4f} h)" if fit.n_periods == 2 else "k")
    ax.set_title("Fourier terms j f1 + k f2 (black edge: significant)", fontsize="small")
    return fig


def save_lightcurve_figures(lc: Lightcurve, fit: PeriodFit, stem) -> list[Path]:
    """Write ``<stem>_lightcurve.png``, ``_periodogram``, ``_folded`` and (two periods)
    ``_frequency_map``; returns the paths.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from astropy.time import Time
    >>> from attitude.photometry import Lightcurve, fit_periods
    >>> t = np.linspace(0.0, 4 * 86400.0, 800)
    >>> y = 0.2 * np.cos(2 * np.pi * t / 21600.0) + 0.1 * np.cos(2 * np.pi * t / 50000.0)
    >>> lc = Lightcurve.from_arrays(t, magnitude=y, epoch=Time("2024-01-01"))
    >>> fit = fit_periods(t, y, n_periods=2, order=2)
    >>> stem = pathlib.Path(tempfile.mkdtemp()) / "tumbler"
    >>> for path in save_lightcurve_figures(lc, fit, stem):    # two periods: four figures
    ...     print(path.name, path.stat().st_size > 1000)
    tumbler_lightcurve.png True
    tumbler_periodogram.png True
    tumbler_folded.png True
    tumbler_frequency_map.png True
    """
    stem = Path(stem)
    figures = {"lightcurve": lightcurve_figure(lc, fit), "periodogram":
               periodogram_figure(lc, fit), "folded": folded_figure(lc, fit)}
    if fit.n_periods == 2:
        figures["frequency_map"] = frequency_map_figure(fit)
    paths = []
    for name, fig in figures.items():
        path = stem.parent / f"{stem.name}_{name}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
        paths.append(path)
    return paths
