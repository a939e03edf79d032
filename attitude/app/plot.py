r"""Figures of an attitude ephemeris (matplotlib, the optional extra ``plot``).

Each function takes an :class:`~attitude.model.ephemeris.Ephemeris` (one body) and returns a
:class:`matplotlib.figure.Figure`; nothing is shown or saved (``fig.savefig(...)``).

* :func:`polhode` - the Binet construction: the angular velocity on the energy ellipsoid
  ``omega . I omega = 2E`` and the body-frame angular momentum on the sphere ``|L| = L``
  cut by the ellipsoid ``L_A^2/A + L_B^2/B + L_C^2/C = 2E``, with the separatrix.
* :func:`herpolhode` - the tip of ``omega`` on the invariable plane (normal to ``L``).
* :func:`body_axes` - the principal axes on the inertial unit sphere over time.
* :func:`euler_angles` - precession ``phi``, nutation ``theta``, rotation ``psi`` (3-1-3 in
  the angular-momentum frame, :func:`attitude.analysis.diagnostics.momentum_frame_angles`) and their
  rates against time.
* :func:`regime_timeline` - the time-resolved regime (``classify(eph).segments``) and the
  excitation ``L^2 / (2 E B)`` over time, for perturbed runs.

:func:`figures` builds them all and :func:`save_figures` writes them as PNG (what
``attitude run --plot`` does).  A binary's ephemeris (issue 28) gets
:data:`BINARY_FIGURES` instead (:func:`binary_separation`, :func:`binary_libration`,
:func:`binary_spins`), an ensemble of binaries :func:`binary_ensemble`.  matplotlib is
imported lazily; without it these functions raise :class:`PlotUnavailableError`.  For
example::

    import numpy as np, attitude as att
    from scipy.spatial.transform import Rotation
    from attitude.app.plot import polhode
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    polhode(att.propagate(body, state, np.linspace(0, 3000, 1501))).savefig("p.png")
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.classification import classify
from ..analysis.diagnostics import (
    momentum_frame_angles,
    momentum_frame_x,
    principal_series,
    reference_axis_for,
)
from ..analysis.statistics import attitude_spread
from ..binary.diagnostics import libration_angle
from ..binary.propagate import is_binary_dataset
from ..foundations.errors import AttitudeError
from ..foundations.figures import agg_figure
from ..foundations.quaternion import rotate
from ..model.freebody import diagnose_many

__all__ = ["agg_figure", "polhode", "herpolhode", "body_axes", "euler_angles",
           "regime_timeline", "ensemble_regimes", "ensemble_spread", "figures",
           "save_figures", "FIGURES", "ENSEMBLE_FIGURES", "binary_separation",
           "binary_libration", "binary_spins", "binary_ensemble", "BINARY_FIGURES"]

_AXIS_COLOURS = ("tab:red", "tab:green", "tab:blue")      # A (long), B, C (short)
_REGIME_COLOURS = {"PA-short": "tab:blue", "PA-long": "tab:red", "SAM": "tab:cyan",
                   "LAM": "tab:orange", "separatrix": "tab:purple",
                   "axisymmetric": "tab:olive", "spherical": "tab:gray",
                   "at-rest": "black", "chaotic": "tab:pink"}
_MAX_POINTS = 4000



def _series(eph):
    if eph.is_batch:
        raise AttitudeError("plots take one body: select it from the batch first")
    return principal_series(eph)


def _thin(n: int) -> slice:
    return slice(None, None, max(1, int(np.ceil(n / _MAX_POINTS))))


def _time_axis(t: np.ndarray) -> tuple[np.ndarray, str]:
    span = float(t[-1] - t[0]) if t.size else 0.0
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if span >= 3 * size:
            return t / size, unit
    return t, "s"


def _invariants(series):
    I = series.moments
    L = np.linalg.norm(series.omega * I, axis=-1)
    E2 = np.einsum("ij,ij->i", series.omega, series.omega * I)   # 2E
    return I, L, E2


def _wire_ellipsoid(ax, semi, colour="0.75"):
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 37), np.linspace(0, np.pi, 19))
    ax.plot_wireframe(semi[0] * np.cos(u) * np.sin(v), semi[1] * np.sin(u) * np.sin(v),
                      semi[2] * np.cos(v), color=colour, linewidth=0.4)


def _equal_3d(ax, r):
    for setter in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        setter(-r, r)
    ax.set_box_aspect((1, 1, 1))


def polhode(eph):
    """Binet construction: the polhode on the energy ellipsoid (``omega`` in principal
    axes) and on the angular-momentum sphere (``L`` in principal axes), with the
    separatrix on the sphere.  The surfaces are those of the initial state: for a run
    with torques the curve leaves them as ``E`` and ``|L|`` change.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> from attitude.app.plot import polhode
    >>> fig = polhode(eph)
    >>> len(fig.axes)                   # the energy ellipsoid and the momentum sphere
    2
    """
    series = _series(eph)
    I, L, E2 = _invariants(series)
    sl = _thin(series.time.size)
    fig = agg_figure(figsize=(11, 5.2))
    t = series.time[sl]

    ax = fig.add_subplot(1, 2, 1, projection="3d")
    semi = np.sqrt(E2[0] / I)                       # omega . I omega = 2E
    _wire_ellipsoid(ax, semi)
    w = series.omega[sl]
    ax.scatter(w[:, 0], w[:, 1], w[:, 2], c=t, cmap="viridis", s=3)
    ax.plot(w[:, 0], w[:, 1], w[:, 2], color="tab:red", linewidth=0.8)
    _equal_3d(ax, float(semi.max()) * 1.05)
    ax.set_xlabel(r"$\omega_A$ (rad/s)")
    ax.set_ylabel(r"$\omega_B$")
    ax.set_zlabel(r"$\omega_C$")
    ax.set_title("polhode on the energy ellipsoid")

    ax = fig.add_subplot(1, 2, 2, projection="3d")
    Lb = series.momentum_body[sl]
    r = float(L[0])
    _wire_ellipsoid(ax, np.array([r, r, r]))
    A, B, C = I
    if C - A > 1e-9 * C and (1 / A - 1 / B) > 0 and (1 / B - 1 / C) > 0:
        # separatrix: L_A^2 (1/A - 1/B) = L_C^2 (1/B - 1/C), two great circles through B
        slope = np.sqrt((1 / A - 1 / B) / (1 / B - 1 / C))
        s = np.linspace(0, 2 * np.pi, 361)
        for sign in (1, -1):
            n = np.array([1.0, 0.0, sign * slope]) / np.hypot(1.0, slope)
            ax.plot(r * n[0] * np.cos(s), r * np.sin(s), r * n[2] * np.cos(s),
                    color="tab:purple", linewidth=1.0, linestyle="--",
                    label="separatrix" if sign == 1 else None)
    ax.plot(Lb[:, 0], Lb[:, 1], Lb[:, 2], color="tab:red", linewidth=1.2, label="polhode")
    for j, name in enumerate("ABC"):
        e = np.zeros(3)
        e[j] = 1.15 * r
        ax.plot([0, e[0]], [0, e[1]], [0, e[2]], color=_AXIS_COLOURS[j], linewidth=1.5)
        ax.text(*e, name, color=_AXIS_COLOURS[j])
    _equal_3d(ax, r * 1.15)
    ax.set_xlabel(r"$L_A$ (kg m$^2$/s)")
    ax.set_ylabel(r"$L_B$")
    ax.set_zlabel(r"$L_C$")
    ax.set_title("polhode on the angular-momentum sphere")
    ax.legend(loc="upper left", fontsize="small")
    fig.suptitle(_title(eph, "Polhode (Binet construction)"))
    return fig


def herpolhode(eph):
    """The herpolhode: the tip of the inertial ``omega`` projected on the invariable plane
    (the plane normal to the initial angular momentum).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> from attitude.app.plot import herpolhode
    >>> fig = herpolhode(eph)
    >>> fig.axes[0].get_ylabel().endswith("(rad/s)")
    True
    """
    series = _series(eph)
    Li = series.momentum_inertial
    Z = Li[0] / np.linalg.norm(Li[0])
    X = momentum_frame_x(Z[None, :])[0]
    Y = np.cross(Z, X)
    wi = rotate(series.quaternion, series.omega)
    sl = _thin(series.time.size)
    x, y = wi[sl] @ X, wi[sl] @ Y
    fig = agg_figure(figsize=(6.4, 6.0))
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(x, y, color="tab:blue", linewidth=0.8)
    pts = ax.scatter(x, y, c=series.time[sl], cmap="viridis", s=4, zorder=3)
    ax.plot([0], [0], marker="+", color="black", markersize=12)
    ax.plot([x[0]], [y[0]], marker="o", color="tab:red", label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(r"$\omega \cdot X$ (rad/s)")
    ax.set_ylabel(r"$\omega \cdot Y$ (rad/s)")
    ax.legend(loc="upper right", fontsize="small")
    fig.colorbar(pts, ax=ax, label="time (s)")
    ax.set_title(_title(eph, "Herpolhode on the invariable plane"))
    return fig


def body_axes(eph):
    """The principal axes A, B, C (inertial frame) on the unit sphere over time, and the
    direction of the angular momentum.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> from attitude.app.plot import body_axes
    >>> fig = body_axes(eph)
    >>> fig.axes[0].name
    '3d'
    """
    series = _series(eph)
    sl = _thin(series.time.size)
    q = series.quaternion[sl]
    fig = agg_figure(figsize=(6.8, 6.4))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    _wire_ellipsoid(ax, np.ones(3), colour="0.85")
    for j, name in enumerate("ABC"):
        e = np.zeros(3)
        e[j] = 1.0
        a = rotate(q, e)
        ax.plot(a[:, 0], a[:, 1], a[:, 2], color=_AXIS_COLOURS[j], linewidth=0.8,
                label=f"axis {name}")
        ax.scatter(*a[0], color=_AXIS_COLOURS[j], s=30, marker="o")
    Li = series.momentum_inertial[sl]
    norm = np.linalg.norm(Li, axis=-1, keepdims=True)
    Lh = np.where(norm > 0, Li / np.where(norm > 0, norm, 1), np.nan)
    ax.plot(Lh[:, 0], Lh[:, 1], Lh[:, 2], color="black", linewidth=2.0, label="L direction")
    ax.scatter(*Lh[0], color="black", s=40, marker="*")
    _equal_3d(ax, 1.05)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.legend(loc="upper left", fontsize="small")
    frame = eph.dataset.attrs.get("frame", "inertial")
    ax.set_title(_title(eph, f"Body axes on the unit sphere ({frame})"))
    return fig


def euler_angles(eph, reference_axis: int | None = None):
    """Precession ``phi``, nutation ``theta`` and rotation ``psi`` (3-1-3 in the
    angular-momentum frame, degrees) and their rates (deg per time unit) against time.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> from attitude.app.plot import euler_angles
    >>> fig = euler_angles(eph)
    >>> len(fig.axes)                   # angles and rates of phi, theta, psi
    6
    """
    series = _series(eph)
    I, L, E2 = _invariants(series)
    with np.errstate(divide="ignore", invalid="ignore"):
        dyn = L ** 2 / E2
    ref = reference_axis or reference_axis_for(I, dyn)
    ang = momentum_frame_angles(series, ref)
    t, unit = _time_axis(series.time)
    fig = agg_figure(figsize=(11, 7), layout="constrained")
    axes = fig.subplots(3, 2, sharex=True)
    names = (("precession", r"precession $\phi$"), ("nutation", r"nutation $\theta$"),
             ("rotation", r"rotation $\psi$"))
    for row, (key, label) in enumerate(names):
        a = np.degrees(ang[key])
        axes[row, 0].plot(t, a, color=_AXIS_COLOURS[row], linewidth=0.9)
        axes[row, 0].set_ylabel(f"{label} (deg)")
        rate = np.gradient(a, t) if t.size > 2 else np.zeros_like(a)
        axes[row, 1].plot(t, rate, color=_AXIS_COLOURS[row], linewidth=0.9)
        axes[row, 1].set_ylabel(f"d{label.split()[1]}/dt (deg/{unit})")
        for ax in axes[row]:
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(f"time ({unit})")
    fig.suptitle(_title(eph, f"Euler angles (3-1-3 about L, reference axis "
                             f"{'A' if ref == 1 else 'C'})"))
    return fig


def regime_timeline(eph, classification=None):
    """The regime over time (``classify(eph).segments``; pass ``classification`` to reuse
    one) above the excitation ``L^2 / (2 E B)`` (1 on the separatrix, > 1 SAM, < 1 LAM).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> from attitude.app.plot import regime_timeline
    >>> fig = regime_timeline(eph)
    >>> len(fig.axes)
    2
    """
    if classification is None:
        classification = classify(eph, require_periods=False)
    series = _series(eph)
    I, L, E2 = _invariants(series)
    t, unit = _time_axis(series.time)
    scale = (series.time[-1] / t[-1]) if t.size and t[-1] else 1.0
    fig = agg_figure(figsize=(10, 5), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(1, 2.5))
    seen = set()
    for start, stop, regime in classification.segments:
        colour = _REGIME_COLOURS.get(regime, "tab:brown")
        top.axvspan(start / scale, stop / scale, color=colour, alpha=0.8,
                    label=None if regime in seen else regime)
        seen.add(regime)
    top.set_yticks([])
    top.set_ylabel("regime")
    top.legend(loc="upper left", ncol=min(4, len(seen)) or 1, fontsize="small")
    top.set_title(f"classified: {classification.regime} "
                  f"(confidence {classification.confidence:.2f})")
    with np.errstate(divide="ignore", invalid="ignore"):
        excitation = L ** 2 / (E2 * I[1])
    bottom.plot(t, excitation, color="tab:blue", linewidth=0.9)
    bottom.axhline(1.0, color="tab:purple", linestyle="--", linewidth=1.0,
                   label="separatrix")
    bottom.set_ylabel(r"$L^2 / (2 E B)$")
    bottom.set_xlabel(f"time ({unit})")
    bottom.grid(True, alpha=0.3)
    bottom.legend(loc="best", fontsize="small")
    fig.suptitle(_title(eph, "Regime over time"))
    return fig


def ensemble_spread(eph, quantiles=(0.5, 0.9, 0.99), nominal=0):
    """An ensemble's attitude uncertainty: quantiles over the bodies of the angle from
    the nominal attitude (:func:`attitude.ensemble.spread_quantiles`) against time, and
    the distribution of that angle at the last epoch.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     20, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0})
    >>> eph = att.propagate(ens, np.linspace(0.0, 86400.0, 25))
    >>> from attitude.app.plot import ensemble_spread
    >>> fig = ensemble_spread(eph)
    >>> len(fig.axes) >= 1
    True
    """
    spread = attitude_spread(eph, nominal)
    if hasattr(spread.data, "dask"):
        spread = spread.compute()
    angle = np.degrees(np.asarray(spread.values, dtype=float))            # (body, time)
    t, unit = _time_axis(eph.time)
    fig = agg_figure(figsize=(10, 4.5), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=(2.2, 1))
    for q, colour in zip(quantiles, ("tab:blue", "tab:orange", "tab:red", "tab:purple")):
        left.plot(t, np.nanquantile(angle, q, axis=0), color=colour, linewidth=1.2,
                  label=f"{100 * q:g} % of bodies within")
    left.set_xlabel(f"time ({unit})")
    left.set_ylabel("angle from the nominal attitude (deg)")
    left.set_ylim(0, 180)
    left.grid(True, alpha=0.3)
    left.legend(loc="upper left", fontsize="small")
    final = angle[:, -1]
    right.hist(final[np.isfinite(final)], bins=36, range=(0, 180), color="tab:gray")
    right.set_xlabel("angle at the last epoch (deg)")
    right.set_ylabel("bodies")
    n = int(np.isfinite(final).sum())
    fig.suptitle(_title(eph, f"Attitude spread of {n} bodies"))
    return fig


def ensemble_regimes(eph):
    """A population at a glance: the torque-free regime of each valid body at the first
    epoch (bar chart of the fractions) and the distribution of the precession and
    rotation periods (log scale).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.sample(
    ...     20, rng=1, epoch="2029-04-13",
    ...     mean={"angular_momentum_ra": 4.36, "angular_momentum_dec": -1.31,
    ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
    ...           "precession_period": 98568.0})
    >>> eph = att.propagate(ens, np.linspace(0.0, 86400.0, 25))
    >>> from attitude.app.plot import ensemble_regimes
    >>> fig = ensemble_regimes(eph)
    >>> len(fig.axes) >= 1
    True
    """
    ds = eph.dataset
    ok = ds["status"].values == 0 if "status" in ds else np.ones(ds.sizes["body"], bool)
    moments = np.asarray(ds["principal_moments"].values, dtype=float)[ok]
    inertia = np.asarray(ds["inertia"].values, dtype=float).reshape(-1, 3, 3)[ok]
    w = np.asarray(ds["angular_velocity"].values[:, 0], dtype=float)[ok]
    _, axes = np.linalg.eigh(inertia)                     # principal axes as columns
    d = diagnose_many(moments, np.einsum("nji,nj->ni", axes, w))
    fig = agg_figure(figsize=(10, 4.2), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=(1, 1.6))
    names, counts = np.unique(d["regime"], return_counts=True)
    left.bar(names, counts / max(counts.sum(), 1),
             color=[_REGIME_COLOURS.get(r, "tab:brown") for r in names])
    left.set_ylabel("fraction of the bodies")
    left.set_title(f"regimes of {int(ok.sum())} bodies")
    periods = [(k, d[k][np.isfinite(d[k])]) for k in ("precession", "rotation", "spin")]
    periods = [(k, v) for k, v in periods if v.size]
    if periods:
        lo = min(v.min() for _, v in periods)
        hi = max(v.max() for _, v in periods)
        bins = np.geomspace(lo / 1.01, hi * 1.01, 30)
        for k, v in periods:
            right.hist(v, bins=bins, alpha=0.6, label=f"{k} ({v.size})")
        right.set_xscale("log")
        right.legend(loc="best", fontsize="small")
    right.set_xlabel("period (s)")
    right.set_ylabel("bodies")
    fig.suptitle(_title(eph, "Population"))
    return fig


def _title(eph, what: str) -> str:
    name = eph.dataset.attrs.get("title") or ""
    return f"{what} - {name}" if name else what


def binary_separation(eph):
    """A binary's separation ``|R|`` (the secondary's centre from the primary's) against
    time.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 2 * np.pi / 8136.0],
    ...                         Rotation.from_euler("z", 5, degrees=True), [0, 0, n])
    >>> eph = att.propagate(system, state, np.linspace(0.0, 4 * np.pi / n, 200))
    >>> from attitude.app.plot import binary_separation
    >>> fig = binary_separation(eph)
    >>> fig.axes[0].get_ylabel()
    'separation (m)'
    """
    ds = eph.dataset
    r = np.linalg.norm(np.asarray(ds["relative_position"].values, dtype=float), axis=-1)
    t, unit = _time_axis(np.asarray(ds["time"].values, dtype=float))
    fig = agg_figure(figsize=(10, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.plot(t, r, color="tab:blue", linewidth=0.9)
    ax.set_xlabel(f"time ({unit})")
    ax.set_ylabel("separation (m)")
    ax.grid(True, alpha=0.3)
    ax.set_title(_title(eph, "Mutual orbit"))
    return fig


def binary_libration(eph):
    """The secondary's libration angle (its long axis from the direction to the primary,
    in the orbit plane, :func:`attitude.binary.libration_angle`) against time, deg.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 2 * np.pi / 8136.0],
    ...                         Rotation.from_euler("z", 5, degrees=True), [0, 0, n])
    >>> eph = att.propagate(system, state, np.linspace(0.0, 4 * np.pi / n, 200))
    >>> from attitude.app.plot import binary_libration
    >>> fig = binary_libration(eph)
    >>> [float(y) for y in fig.axes[0].get_ylim()]
    [-90.0, 90.0]
    """
    angle = np.degrees(libration_angle(eph))
    t, unit = _time_axis(np.asarray(eph.dataset["time"].values, dtype=float))
    fig = agg_figure(figsize=(10, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.plot(t, angle, ".", color="tab:red", markersize=2)
    ax.set_xlabel(f"time ({unit})")
    ax.set_ylabel("libration angle (deg)")
    ax.set_ylim(-90.0, 90.0)
    ax.grid(True, alpha=0.3)
    ax.set_title(_title(eph, "The secondary's libration"))
    return fig


def binary_spins(eph):
    """Each body's spin: the body-frame angular velocity's components and its norm
    against time, one panel a body (rad/s).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 2 * np.pi / 8136.0],
    ...                         Rotation.from_euler("z", 5, degrees=True), [0, 0, n])
    >>> eph = att.propagate(system, state, np.linspace(0.0, 4 * np.pi / n, 200))
    >>> from attitude.app.plot import binary_spins
    >>> fig = binary_spins(eph)
    >>> [a.get_title() for a in fig.axes]
    ['primary', 'secondary']
    """
    ds = eph.dataset
    w = np.asarray(ds["angular_velocity"].values, dtype=float)          # (body, time, 3)
    t, unit = _time_axis(np.asarray(ds["time"].values, dtype=float))
    fig = agg_figure(figsize=(10, 5.5), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    for k, (ax, name) in enumerate(zip(axes, ("primary", "secondary"))):
        for i, colour in enumerate(_AXIS_COLOURS):
            ax.plot(t, w[k, :, i], color=colour, linewidth=0.9, label="xyz"[i])
        ax.plot(t, np.linalg.norm(w[k], axis=-1), color="black", linewidth=1.1,
                label="|omega|")
        ax.set_ylabel("omega (rad/s, body frame)")
        ax.set_title(name)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize="small", ncol=4)
    axes[-1].set_xlabel(f"time ({unit})")
    return fig


def binary_ensemble(ds):
    """An ensemble of binaries (:func:`attitude.binary.ensemble`'s Dataset) at a glance:
    the secondary's regime fractions and, when measured, the distribution of the period
    change across the first impulse (min).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> from attitude.app.plot import binary_ensemble
    >>> ds = xr.Dataset({"status": ("member", [0, 0, 1]),
    ...                  "period_change": ("member", [-2000.0, -1990.0, np.nan])},
    ...                 attrs={"regime_fractions": {"librating": 1.0}})
    >>> len(binary_ensemble(ds).axes)
    2
    """
    fractions = dict(ds.attrs.get("regime_fractions", {}))
    fig = agg_figure(figsize=(10, 4.0), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=(1, 1.6))
    left.bar(list(fractions), list(fractions.values()), color="tab:cyan")
    left.set_ylim(0, 1)
    left.set_ylabel("fraction of the members that ran")
    ok = np.asarray(ds["status"].values) == 0
    left.set_title(f"secondary's regime ({int(ok.sum())} of {ok.size} ran)")
    change = (np.asarray(ds["period_change"].values, dtype=float)[ok] / 60.0
              if "period_change" in ds else np.array([]))
    change = change[np.isfinite(change)]
    if change.size:
        right.hist(change, bins=max(5, min(40, change.size // 3)), color="tab:gray")
    right.set_xlabel("period change across the impulse (min)")
    right.set_ylabel("members")
    fig.suptitle(ds.attrs.get("title", "Ensemble of binaries"))
    return fig


#: A binary's figures (``attitude run --plot`` on a ``[binary]`` scenario).
BINARY_FIGURES = {"separation": binary_separation, "libration": binary_libration,
                  "spins": binary_spins}
#: Figure name -> function, in the order :func:`figures` builds them.
FIGURES = {"polhode": polhode, "herpolhode": herpolhode, "body_axes": body_axes,
           "euler_angles": euler_angles, "regime": regime_timeline}
#: The figures of an ensemble (batch) ephemeris; ``spread`` only when it has a nominal
#: body (a sampled cloud: the ``nominal_body`` attribute).
ENSEMBLE_FIGURES = {"regimes": ensemble_regimes, "spread": ensemble_spread}


def figures(eph, classification=None, *, regime: bool | None = None) -> dict:
    """Every figure of :data:`FIGURES` for ``eph``: ``{name: Figure}``.  The regime
    timeline is included when ``regime`` is true, or by default when a
    ``classification`` is given (perturbed runs).  A batch (ensemble) ephemeris gets
    :data:`ENSEMBLE_FIGURES` instead, a binary's :data:`BINARY_FIGURES`.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> from attitude.app.plot import figures
    >>> sorted(figures(eph))
    ['body_axes', 'euler_angles', 'herpolhode', 'polhode']
    """
    if is_binary_dataset(eph.dataset):
        return {name: func(eph) for name, func in BINARY_FIGURES.items()}
    if eph.is_batch:
        nominal = eph.dataset.attrs.get("nominal_body")
        out = {"regimes": ensemble_regimes(eph)}
        if nominal is not None:
            out["spread"] = ensemble_spread(eph, nominal=int(nominal))
        return out
    include_regime = classification is not None if regime is None else regime
    out = {}
    for name, func in FIGURES.items():
        if name == "regime":
            if include_regime:
                out[name] = func(eph, classification)
        else:
            out[name] = func(eph)
    return out


def save_figures(eph, stem: str | Path, classification=None, *, regime: bool | None = None,
                 dpi: int = 100) -> list[Path]:
    """Write :func:`figures` as ``<stem>_<name>.png``; returns the paths.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 301))
    >>> import tempfile, pathlib
    >>> from attitude.app.plot import save_figures
    >>> with tempfile.TemporaryDirectory() as d:
    ...     paths = save_figures(eph, pathlib.Path(d) / "run")
    ...     sorted(p.name for p in map(pathlib.Path, paths))
    ['run_body_axes.png', 'run_euler_angles.png', 'run_herpolhode.png', 'run_polhode.png']
    """
    stem = Path(stem)
    paths = []
    for name, fig in figures(eph, classification, regime=regime).items():
        path = stem.with_name(f"{stem.name}_{name}.png")
        fig.savefig(path, dpi=dpi)
        paths.append(path)
    return paths
