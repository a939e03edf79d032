"""Statistics of populations: regimes, periods and the spread of attitudes.

The analysis of an :class:`~attitude.Ensemble` (analytic, from its initial states) or of
a batch :class:`~attitude.Ephemeris` (from the propagated motion): the torque-free
diagnosis of every body (:func:`diagnose_ensemble`), the classification of every body's
motion (:func:`classify_ensemble`), the fraction of bodies in each regime
(:func:`regime_fractions`), period quantiles (:func:`period_quantiles`) and the angle of
each attitude from the nominal (:func:`attitude_spread`, :func:`spread_quantiles`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..foundations.errors import AttitudeError, InvalidStateError
from ..model.ephemeris import Ephemeris
from ..model.freebody import diagnose_many
from ..model.population import Ensemble
from ..propagation.batch import STATUS_INVALID, STATUS_OK
from .classification import classify

__all__ = ["diagnose_ensemble", "classify_ensemble", "regime_fractions", "period_quantiles",
           "attitude_spread", "spread_quantiles"]


def diagnose_ensemble(ensemble: Ensemble) -> xr.Dataset:
    """Analytic torque-free diagnosis of every body (vectorised
    :func:`attitude.model.freebody.diagnose_many`): a Dataset along ``body`` with
    ``regime``, the periods ``polhode precession rotation spin`` (s, NaN where absent),
    ``energy_ratio``, ``separatrix_distance``, ``nutation_min``/``nutation_max`` (rad) and
    ``valid``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     50, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0},
    ...     sigma={"energy_ratio": 0.006})
    >>> from attitude.analysis.statistics import diagnose_ensemble
    >>> d = diagnose_ensemble(ens)
    >>> d["precession"].sizes["body"], str(d["regime"].values[0])
    (50, 'SAM')
    """
    ok = ensemble.valid
    n = len(ensemble)
    units = {"polhode": "s", "precession": "s", "rotation": "s", "spin": "s",
             "energy_ratio": "1", "separatrix_distance": "1", "nutation_min": "rad",
             "nutation_max": "rad"}
    data = {k: ("body", np.full(n, np.nan), {"units": v}) for k, v in units.items()}
    regime = np.full(n, "invalid", dtype=object)
    if ok.any():
        d = diagnose_many(ensemble.principal_moments[ok], ensemble.omega_principal()[ok])
        for k in units:
            data[k][1][ok] = d[k]
        regime[ok] = d["regime"]
    data["regime"] = ("body", regime.astype(str))
    data["valid"] = ("body", ok)
    return xr.Dataset(data, coords={"body": np.arange(len(ensemble))})


def regime_fractions(source) -> dict[str, float]:
    """Fraction of the valid bodies in each regime, largest first.

    ``source``: an :class:`Ensemble` (analytic torque-free regimes), the Dataset of
    :func:`diagnose_ensemble` or :func:`classify_ensemble`, or a batch
    :class:`~attitude.Ephemeris` (each body classified from its propagated motion by
    :func:`classify_ensemble`, which also sees regime changes under torques).  Bodies
    that are invalid or could not be classified are left out.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     50, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0},
    ...     sigma={"energy_ratio": 0.006})
    >>> from attitude.analysis.statistics import regime_fractions
    >>> f = regime_fractions(ens)       # E/E0 scattered across the separatrix C/B = 1.036
    >>> list(f), round(sum(f.values()), 12)
    (['SAM', 'LAM'], 1.0)
    """
    if isinstance(source, Ensemble):
        source = diagnose_ensemble(source)
    if isinstance(source, Ephemeris):
        source = classify_ensemble(source) if source.is_batch else xr.Dataset(
            {"regime": ("body", [_classify_one(source)])})
    regimes = np.asarray(source["regime"].values)
    regimes = regimes[(regimes != "invalid") & (regimes != "unclassified")]
    if regimes.size == 0:
        return {}
    names, counts = np.unique(regimes, return_counts=True)
    order = np.argsort(-counts, kind="stable")
    return {str(names[i]): float(counts[i] / regimes.size) for i in order}


def classify_ensemble(eph, **options) -> xr.Dataset:
    """:func:`attitude.analysis.classification` of every body of a batch ephemeris, one by one: a
    Dataset along ``body`` with ``regime`` (``"invalid"`` for bodies whose ``status`` is
    not 0, ``"unclassified"`` when the classification failed, e.g. a run shorter than a
    cycle), ``confidence``, ``margin`` and ``reason`` (why a body is not classified).
    One body that cannot be classified does not stop the others.  ``options`` go to
    :func:`attitude.analysis.classification` (default ``require_periods=False``).  A dask-backed
    ephemeris is read one chunk of bodies at a time (its own chunks along ``body``), so
    the memory held is one chunk, not the ensemble.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.from_arrays(principal_moments=[[1, 2, 3]] * 2,
    ...     omega_body=[[0.1, 0.0, 1.0], [1.0, 0.0, 0.1]], epoch="2030-01-01")
    >>> table = classify_ensemble(att.propagate(ens, np.linspace(0, 200, 400), chunks=1))
    >>> table.regime.values.tolist()
    ['SAM', 'LAM']
    """
    if not eph.is_batch:
        raise InvalidStateError("classify_ensemble takes a batch ephemeris (dims body, "
                                "time); use attitude.classify for one body")
    ds = eph.dataset
    options.setdefault("require_periods", False)
    n, lazy = ds.sizes["body"], _lazy(ds)
    regime = np.full(n, "invalid", dtype=object)
    confidence, margin = np.full(n, np.nan), np.full(n, np.nan)
    reason = np.full(n, "", dtype=object)
    for a, b in _body_chunks(ds):
        # one chunk in memory at a time (its status read with it: computing the status
        # of a lazy run alone would propagate every chunk once more)
        part = Ephemeris(ds.isel(body=slice(a, b)).load()) if lazy else eph
        status = part.dataset["status"].values if "status" in part.dataset else \
            np.zeros(part.dataset.sizes["body"], dtype=np.int8)
        offset = a if lazy else 0
        for i in range(a, b):
            if status[i - offset] != STATUS_OK:
                reason[i] = "invalid input" if status[i - offset] == STATUS_INVALID else \
                    "propagation failed"
                continue
            try:
                c = classify(part, body_index=i - offset, **options)
            except AttitudeError as exc:
                regime[i], reason[i] = "unclassified", str(exc)
                continue
            regime[i], confidence[i], margin[i] = c.regime, c.confidence, c.margin
    return xr.Dataset({"regime": ("body", regime.astype(str)),
                       "confidence": ("body", confidence),
                       "margin": ("body", margin),
                       "reason": ("body", reason.astype(str))},
                      coords={"body": np.arange(n)})


def _lazy(ds: xr.Dataset) -> bool:
    return any(hasattr(v.data, "dask") for v in ds.data_vars.values())


def _body_chunks(ds: xr.Dataset) -> list[tuple[int, int]]:
    """``(start, stop)`` of the chunks of bodies to read one at a time: the dask chunks of
    the quaternions along ``body`` (one chunk, the whole, for numpy-backed data)."""
    n = ds.sizes["body"]
    chunks = getattr(ds["quaternion"].data, "chunks", None) if _lazy(ds) else None
    if not chunks:
        return [(0, n)]
    stops = np.cumsum(chunks[0])
    return [(int(b - c), int(b)) for b, c in zip(stops, chunks[0])]


def _classify_one(eph) -> str:
    return classify(eph, require_periods=False).regime


def period_quantiles(source, q=(0.05, 0.5, 0.95)) -> xr.DataArray:
    """Quantiles of each period over the bodies that have it: a DataArray
    ``(period, quantile)`` in seconds, with the number of bodies that have each period
    as the coordinate ``bodies``.  ``source``: an :class:`Ensemble` or :func:`diagnose_ensemble`
    output.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     50, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0},
    ...     sigma={"energy_ratio": 0.006})
    >>> from attitude.analysis.statistics import period_quantiles
    >>> p = period_quantiles(ens)
    >>> round(float(p.sel(period="precession", quantile=0.5)) / 3600, 1)      # hours
    27.4
    """
    d = diagnose_ensemble(source) if isinstance(source, Ensemble) else source
    keys = [k for k in ("polhode", "precession", "rotation", "spin")
            if np.isfinite(d[k].values).any()]
    q = np.atleast_1d(np.asarray(q, dtype=float))
    values = np.array([np.nanquantile(d[k].values, q) for k in keys]).reshape(len(keys),
                                                                               q.size)
    counts = [int(np.isfinite(d[k].values).sum()) for k in keys]
    return xr.DataArray(values, dims=("period", "quantile"),
                        coords={"period": keys, "quantile": q,
                                "bodies": ("period", counts)},
                        attrs={"units": "s", "long_name": "period quantiles over bodies"})


def attitude_spread(eph, nominal=0) -> xr.DataArray:
    """Angle (rad) between each body's attitude and the nominal's, ``(body, time)``:
    the angle of the rotation taking one to the other (``2 arccos |q . q_nominal|``,
    computed as ``4 atan2(|q - q_nominal|, |q + q_nominal|)``, accurate also near 0).

    ``nominal``: a body index of the batch (default 0, the nominal of
    :meth:`Ensemble.sample`) or a single-body :class:`~attitude.Ephemeris` on the same
    times.  Lazy (dask) when the ephemeris is.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     50, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0},
    ...     sigma={"energy_ratio": 0.006})
    >>> from attitude.analysis.statistics import attitude_spread
    >>> eph = att.propagate(ens, [0.0, 86400.0])
    >>> spread = attitude_spread(eph)
    >>> spread.dims, float(spread.isel(body=0).max())         # body 0 is the nominal
    (('body', 'time'), 0.0)
    """
    q = eph.dataset["quaternion"]
    if isinstance(nominal, Ephemeris):
        qn = nominal.dataset["quaternion"]
        if qn.sizes["time"] != q.sizes["time"]:
            raise InvalidStateError("nominal: the ephemeris must have the same times")
        qn = qn.assign_coords(time=q["time"])
    else:
        qn = q.isel(body=int(nominal))
    # 4 atan2(|q - s qn|, |q + s qn|), s = sign(q . qn): the chord and its complement are
    # 2 sin(angle / 4) and 2 cos(angle / 4).  2 arccos|q . qn| is the same angle but
    # loses half the digits near 0 (an ulp of the dot product is 3e-8 rad), so two runs
    # that agree to ulps would not agree on the spread
    s = xr.where((q * qn).sum("quaternion_component") < 0, -1.0, 1.0)
    chord = np.sqrt(((q - s * qn) ** 2).sum("quaternion_component"))
    other = np.sqrt(((q + s * qn) ** 2).sum("quaternion_component"))
    angle = 4.0 * np.arctan2(chord, other)
    angle.attrs = {"units": "rad", "long_name": "angle from the nominal attitude"}
    return angle.rename("attitude_spread")


def spread_quantiles(eph, q=(0.5, 0.9, 0.99), nominal=0) -> xr.DataArray:
    """Quantiles over the bodies of :func:`attitude_spread` against time: ``(quantile,
    time)`` in rad (NaN bodies are skipped).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     50, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0},
    ...     sigma={"energy_ratio": 0.006})
    >>> from attitude.analysis.statistics import spread_quantiles
    >>> s = spread_quantiles(att.propagate(ens, [0.0, 86400.0]))
    >>> s.dims
    ('quantile', 'time')
    """
    spread = attitude_spread(eph, nominal)
    if hasattr(spread.data, "dask"):   # all bodies of an epoch in one chunk, epochs split
        spread = spread.chunk({"body": -1, "time": "auto"})
    out = spread.quantile(np.atleast_1d(q), dim="body", skipna=True)
    out.attrs = {"units": "rad", "long_name": "quantiles of the angle from the nominal"}
    return out


