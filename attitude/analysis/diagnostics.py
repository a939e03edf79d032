r"""Diagnostics of an attitude ephemeris: Euler angles in the angular-momentum frame,
nutation, excitation, measured periods, conservation drift.

Everything here reads an :class:`~attitude.model.ephemeris.Ephemeris` (from any propagator or
from a file) and never propagates.  The formulas, the period-measurement method and its
accuracy are in ``docs/diagnostics.md``; equation numbers ``(D n)`` refer to it.

Conventions: principal moments ``A <= B <= C``; the principal frame carries ``A, B, C``
on its x, y, z axes (:attr:`attitude.model.body.RigidBody.body_to_principal`); quaternions
scalar-last, principal (or body) -> inertial; rates in rad/s.

The **angular-momentum frame** ``(X, Y, Z)`` has ``Z`` along the instantaneous inertial
angular momentum ``L(t)``.  ``X`` starts along the ascending node of the plane normal to
``L(t0)`` on the inertial xy plane (``z x L``) and is carried along with ``L`` by the
minimal rotation that takes ``L(t_a)`` to ``L(t)``, re-anchored at ``t_a`` whenever ``L``
has turned by more than 90 degrees since the last anchor: for a fixed ``L`` (torque-free
motion) it is a fixed frame, the invariable frame of Euler–Poinsot theory (D 1).

The **3-1-3 Euler angles** of the principal frame relative to that frame,
``R_{L->principal} = R_z(phi) R_x(theta) R_z(psi)``, take as their third axis the
*reference axis*: ``C`` (short axis) for short-axis modes and oblate bodies, ``A`` (long
axis) for long-axis modes and prolate bodies (Samarasinha & A'Hearn 1991; Kaasalainen
2001).  For ``A`` the frame ``(C, -B, A)`` is used so that it stays right-handed (the
relabelling of :mod:`attitude.propagation.torquefree`).  ``phi`` is the precession angle of the
reference axis about ``L``, ``theta`` the nutation angle between them, ``psi`` the
rotation angle about the reference axis (D 2-4).

The diagnostics live in three modules, one idea each, all re-exported here:
:mod:`attitude.analysis.angles` (the principal-frame series, its invariants and the
Euler angles in the angular-momentum frame), :mod:`attitude.analysis.periods` (measured
periods) and :mod:`attitude.analysis.drift` (conservation drift and attitude noise);
this module adds them to an ephemeris as dataset variables (:func:`add_diagnostics`).
"""

from __future__ import annotations

import numpy as np

from ..foundations.errors import DiagnosticsError, InsufficientDataError
from ..model.ephemeris import Ephemeris
from .angles import (  # noqa: F401  (momentum_frame_x: app.plot imports it from here)
    PrincipalSeries,
    invariants,
    momentum_frame_angles,
    momentum_frame_x,
    osculating_polhode_period,
    principal_series,
    reference_axis_for,
)
from .drift import attitude_noise, conservation_drift
from .periods import (  # noqa: F401  (HYSTERESIS: a constant this module offered)
    HYSTERESIS,
    MAX_ANGLE_STEP,
    MIN_NUTATION,
    STENCIL,
    MeasuredPeriod,
    measure_periods,
)

__all__ = [
    "PrincipalSeries",
    "MeasuredPeriod",
    "principal_series",
    "momentum_frame_angles",
    "invariants",
    "osculating_polhode_period",
    "measure_periods",
    "conservation_drift",
    "attitude_noise",
    "add_diagnostics",
    "reference_axis_for",
    "DIAGNOSTIC_VARIABLES",
    "MIN_NUTATION",
    "MAX_ANGLE_STEP",
    "STENCIL",
]


# ===========================================================================
# add_diagnostics: everything as dataset variables
# ===========================================================================
#: Variables :func:`add_diagnostics` adds, with their units (CF) and long names.
DIAGNOSTIC_VARIABLES = {
    "precession_angle": ("rad", "precession angle phi of the reference axis about the "
                                "angular momentum (3-1-3, unwrapped)"),
    "nutation_angle": ("rad", "nutation angle theta between the angular momentum and the "
                              "reference axis (3-1-3)"),
    "rotation_angle": ("rad", "rotation angle psi about the reference axis (3-1-3, "
                              "unwrapped)"),
    "spin_angle": ("rad", "rotation angle phi + psi about the angular momentum (unwrapped)"),
    "momentum_axis_angle": ("rad", "angle between the angular momentum and each principal "
                                   "axis (A, B, C)"),
    "excitation": ("1", "rotational excitation (E - E_min)/(E_max - E_min) at fixed |L|, "
                        "E_min = L^2/2C, E_max = L^2/2A"),
    "dynamic_inertia": ("kg m2", "dynamic moment of inertia L^2/2E"),
    "separatrix_distance": ("1", "signed complementary Jacobi parameter m1 = 1 - k^2 of the "
                                 "osculating torque-free motion (> 0 SAM, < 0 LAM)"),
    "osculating_polhode_period": ("s", "polhode period 4K/lambda of the osculating "
                                       "torque-free motion"),
    "angular_momentum_magnitude": ("kg m2 s-1", "magnitude of the angular momentum |L|"),
    "angular_momentum_magnitude_drift": ("1", "relative drift of |L| from the first sample"),
    "energy_drift": ("1", "relative drift of the rotational kinetic energy from the first "
                          "sample"),
    "angular_momentum_magnitude_rate": ("kg m2 s-2", "rate of change of |L|"),
    "energy_rate": ("W", "rate of change of the rotational kinetic energy"),
    "angular_momentum_direction_drift": ("rad", "angle between L(t) and L(t0), inertial"),
}

_PERIOD_LONG = {
    "polhode": "measured polhode period (period of omega in the body frame)",
    "precession": "measured mean precession period P_phi",
    "rotation": "measured rotation period P_psi",
    "spin": "measured spin period 2 pi/|omega| (principal-axis rotation)",
}


def _nan_result(template):
    """The diagnostics of a body without motion (an ensemble's invalid input): NaN with
    the shapes of ``template``, no periods."""
    ref, series, scalars, _, _ = template
    return (ref, {k: np.full_like(np.asarray(v, dtype=float), np.nan)
                  for k, v in series.items()},
            {k: np.nan for k in scalars}, {}, "")


def _diagnose_one(series: PrincipalSeries, reference_axis, periods):
    inv = invariants(series.omega, series.moments)
    ref = reference_axis or reference_axis_for(series.moments, inv["dynamic_inertia"])
    ang = momentum_frame_angles(series, ref)
    drift = conservation_drift(series)
    per_sample = {
        "precession_angle": ang["precession"],
        "nutation_angle": ang["nutation"],
        "rotation_angle": ang["rotation"],
        "spin_angle": ang["spin"],
        "momentum_axis_angle": ang["axis_angles"],
        "excitation": inv["excitation"],
        "dynamic_inertia": inv["dynamic_inertia"],
        "separatrix_distance": inv["separatrix_distance"],
        "osculating_polhode_period": osculating_polhode_period(series.omega, series.moments),
        "angular_momentum_magnitude": drift["L"],
        "angular_momentum_magnitude_drift": drift["L_drift"],
        "energy_drift": drift["E_drift"],
        "angular_momentum_magnitude_rate": drift["L_rate"],
        "energy_rate": drift["E_rate"],
        "angular_momentum_direction_drift": drift["L_direction_drift"],
    }
    scalars = {k: drift[k] for k in ("L_rel_drift", "E_rel_drift", "L_drift_rate",
                                     "E_drift_rate")}
    scalars["attitude_noise"] = attitude_noise(series)
    measured, note = {}, ""
    if periods:
        try:
            measured = measure_periods(series, reference_axis=ref)
        except InsufficientDataError as exc:
            if periods == "require":
                raise
            note = str(exc)
    return ref, per_sample, scalars, measured, note


SCALAR_DIAGNOSTICS = {
    "L_rel_drift": ("angular_momentum_magnitude_rel_drift", "1",
                    "largest relative drift of |L| from the first sample"),
    "E_rel_drift": ("energy_rel_drift", "1",
                    "largest relative drift of the kinetic energy from the first sample"),
    "L_drift_rate": ("angular_momentum_magnitude_drift_rate", "s-1",
                     "least-squares rate of the relative drift of |L|"),
    "E_drift_rate": ("energy_drift_rate", "s-1",
                     "least-squares rate of the relative drift of the kinetic energy"),
    "attitude_noise": ("attitude_noise", "rad",
                       "estimated white attitude noise (jitter of the direction of L)"),
}


def add_diagnostics(eph: Ephemeris, *, reference_axis: int | None = None,
                    periods: bool | str = True) -> Ephemeris:
    """A new ephemeris with the diagnostics added as dataset variables.

    Parameters
    ----------
    eph : Ephemeris
        Single body or batch (a leading ``body`` dimension).
    reference_axis : {1, 3}, optional
        Third axis of the Euler angles: 3 (``C``) or 1 (``A``); default per body from
        :func:`reference_axis_for`.  Stored as the attribute ``reference_axis``
        (``"A"``/``"C"``) of the angle variables (a per-body variable for a batch).
    periods : bool or ``"require"``
        Measure the periods (:func:`measure_periods`).  With ``True`` an ephemeris too
        short for them gets none (the reason goes to the attribute
        ``periods_not_measured``); with ``"require"`` that raises.

    Returns
    -------
    Ephemeris
        The variables of :data:`DIAGNOSTIC_VARIABLES` (dims ``[body,] time`` and
        ``principal_axis`` for ``momentum_axis_angle``), the scalars
        ``angular_momentum_magnitude_rel_drift``, ``energy_rel_drift``,
        ``angular_momentum_magnitude_drift_rate``, ``energy_drift_rate``, ``attitude_noise``, and
        measured periods ``period_<key>`` with ``period_<key>_uncertainty`` (s), each with
        ``units`` and ``long_name``: they go to netCDF with the rest.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import add_diagnostics
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = add_diagnostics(att.propagate(body, state, np.linspace(0, 3000, 1501)))
    >>> ds = eph.dataset
    >>> ds["nutation_angle"].attrs["units"], ds["nutation_angle"].attrs["reference_axis"]
    ('rad', 'C')
    >>> P = att.diagnose(body, state).periods["precession"]
    >>> bool(abs(float(ds["period_precession"]) / P - 1) < 1e-8)
    True
    """
    n = eph.dataset.sizes["body"] if eph.is_batch else 1
    status = (np.asarray(eph.dataset["status"].values) if "status" in eph.dataset
              else np.zeros(n, dtype=int))
    results = [None if status[i] else
               _diagnose_one(principal_series(eph, i if eph.is_batch else None),
                             reference_axis, periods) for i in range(n)]
    if all(r is None for r in results):
        raise DiagnosticsError("no body with a valid motion (every status is non-zero)")
    template = next(r for r in results if r is not None)
    results = [r if r is not None else _nan_result(template) for r in results]
    ds = eph.dataset.copy()
    lead = ("body", "time") if eph.is_batch else ("time",)
    sl = ("body",) if eph.is_batch else ()
    ref_names = ["A" if r[0] == 1 else "C" for r in results]

    def stack(values):
        return np.stack(values) if eph.is_batch else values[0]

    drop = [v for v in ds.data_vars if v in DIAGNOSTIC_VARIABLES or v.startswith("period_")
            or v in {m[0] for m in SCALAR_DIAGNOSTICS.values()}]
    ds = ds.drop_vars(drop)
    for name, (units, long_name) in DIAGNOSTIC_VARIABLES.items():
        data = stack([r[1][name] for r in results])
        dims = lead + (("principal_axis",) if name == "momentum_axis_angle" else ())
        attrs = {"units": units, "long_name": long_name}
        if name in ("precession_angle", "nutation_angle", "rotation_angle", "spin_angle"):
            if not eph.is_batch:
                attrs["reference_axis"] = ref_names[0]
            else:
                attrs["reference_axis"] = "see variable reference_axis"
        ds[name] = (dims, data, attrs)
    if "momentum_axis_angle" in ds:
        ds = ds.assign_coords(principal_axis=("principal_axis", ["A", "B", "C"]))
    if eph.is_batch:
        ds["reference_axis"] = (("body",), np.array(ref_names), {
            "long_name": "principal axis carried by the third Euler axis"})
    for key, (name, units, long_name) in SCALAR_DIAGNOSTICS.items():
        ds[name] = (sl, stack([np.float64(r[2][key]) for r in results]),
                    {"units": units, "long_name": long_name})
    keys = sorted({k for r in results for k in r[3]})
    for key in keys:
        val = stack([np.float64(r[3][key].value if key in r[3] else np.nan) for r in results])
        unc = stack([np.float64(r[3][key].uncertainty if key in r[3] else np.nan)
                     for r in results])
        ds[f"period_{key}"] = (sl, val, {"units": "s", "long_name": _PERIOD_LONG[key],
                                         "ancillary_variables": f"period_{key}_uncertainty"})
        ds[f"period_{key}_uncertainty"] = (sl, unc, {
            "units": "s", "long_name": f"one-sigma uncertainty of period_{key}"})
    notes = [r[4] for r in results if r[4]]
    if notes:
        ds.attrs["periods_not_measured"] = "; ".join(notes)
    elif "periods_not_measured" in ds.attrs:
        del ds.attrs["periods_not_measured"]
    return Ephemeris(ds)

