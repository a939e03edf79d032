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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ellipkm1

from ..foundations import quaternion as quat
from ..foundations.errors import DiagnosticsError, InsufficientDataError
from ..model import freebody as fb
from ..model.body import SYMMETRY_RTOL, RigidBody, to_principal_frame
from ..model.ephemeris import Ephemeris

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

_TWO_PI = 2.0 * math.pi

#: Relative amplitude of the intermediate-axis rate ``|omega_2| / |omega|`` below which the
#: body is taken not to nutate (pure principal-axis spin, rounding noise only): no polhode.
MIN_NUTATION = 1e-10
#: Points of the local interpolating polynomial used to place zero crossings (degree 5):
#: with >= 20 samples per period the crossing times are good to ~1e-8 of a period.
STENCIL = 6
#: Hysteresis of the zero-crossing detector, as a fraction of the signal's amplitude: a
#: crossing counts only when the signal goes from below ``-h`` to above ``+h``.
HYSTERESIS = 0.25



# ===========================================================================
# principal-frame series
# ===========================================================================
@dataclass(frozen=True)
class PrincipalSeries:
    """An ephemeris of one body in its principal frame.

    Attributes
    ----------
    time : (T,) ndarray
        Seconds since the epoch.
    quaternion : (T, 4) ndarray
        Principal -> inertial, scalar-last.
    omega : (T, 3) ndarray
        Angular velocity in principal components, rad/s.
    moments : (3,) ndarray
        ``A <= B <= C``, kg m^2.
    body : RigidBody

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> series = principal_series(eph)
    >>> series.quaternion.shape, series.moments.tolist()
    ((1501, 4), [0.61, 0.965, 1.0])
    >>> L = np.linalg.norm(series.momentum_inertial, axis=1)   # conserved without torque
    >>> bool(np.ptp(L) < 1e-14 * L[0])
    True
    """

    time: np.ndarray
    quaternion: np.ndarray
    omega: np.ndarray
    moments: np.ndarray
    body: RigidBody

    @property
    def momentum_body(self) -> np.ndarray:
        """``L`` in principal components, (T, 3), kg m^2/s."""
        return self.omega * self.moments

    @property
    def momentum_inertial(self) -> np.ndarray:
        """``L`` in inertial components, (T, 3), kg m^2/s."""
        return quat.rotate(self.quaternion, self.momentum_body)

    def slice(self, sl: slice) -> PrincipalSeries:
        return PrincipalSeries(self.time[sl], self.quaternion[sl], self.omega[sl],
                               self.moments, self.body)


def _nan_result(template):
    """The diagnostics of a body without motion (an ensemble's invalid input): NaN with
    the shapes of ``template``, no periods."""
    ref, series, scalars, _, _ = template
    return (ref, {k: np.full_like(np.asarray(v, dtype=float), np.nan)
                  for k, v in series.items()},
            {k: np.nan for k in scalars}, {}, "")


def principal_series(eph: Ephemeris, body_index: int | None = None) -> PrincipalSeries:
    """The ephemeris of one body mapped to its principal frame.

    Parameters
    ----------
    eph : Ephemeris
        Needs ``quaternion``, ``angular_velocity`` and the body's inertia (attribute
        ``inertia``, or the per-body variable of a batch).
    body_index : int, optional
        Which body of a batch (required for a batch).

    Raises
    ------
    DiagnosticsError
        On a batch without ``body_index``, non-finite samples, or times that do not
        increase strictly.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> series = principal_series(eph)
    >>> series.omega[0].tolist()           # identity body -> principal frame here
    [0.02, 0.0, 0.1]
    >>> float(series.time[-1])
    3000.0
    """
    ds = eph.dataset
    if eph.is_batch:
        if body_index is None:
            raise DiagnosticsError("a batch ephemeris holds several bodies: give body_index")
        body = eph.body_at(body_index)
        if body is None:
            raise DiagnosticsError(f"body {body_index} has no motion: its input was invalid "
                                   "(status 1 in the ephemeris)")
        q = np.asarray(ds["quaternion"].values[body_index], dtype=float)
        w = np.asarray(ds["angular_velocity"].values[body_index], dtype=float)
    else:
        body = eph.body
        q = np.asarray(ds["quaternion"].values, dtype=float)
        w = np.asarray(ds["angular_velocity"].values, dtype=float)
    t = np.asarray(eph.time, dtype=float)
    if t.ndim != 1 or q.shape != (t.size, 4) or w.shape != (t.size, 3):
        raise DiagnosticsError(f"ephemeris shapes: time {t.shape}, quaternion {q.shape}, "
                               f"angular_velocity {w.shape}; expected (T,), (T, 4), (T, 3)")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(w)) and np.all(np.isfinite(t))):
        raise DiagnosticsError("ephemeris holds non-finite samples (NaN or inf) in time, "
                               "quaternion or angular_velocity: remove them first")
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise DiagnosticsError("time must increase strictly: sort the ephemeris and drop "
                               "duplicate epochs")
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    q_p2i, w_p = to_principal_frame(q, w, body.body_to_principal.as_quat())
    return PrincipalSeries(t, q_p2i, w_p, body.principal_moments.copy(), body)


# ===========================================================================
# invariants (D 5-9)
# ===========================================================================
def invariants(omega: np.ndarray, moments) -> dict[str, np.ndarray]:
    """Instantaneous ("osculating") torque-free invariants from principal rates.

    Parameters
    ----------
    omega : (..., 3) array
        Principal-frame angular velocity, rad/s.
    moments : (3,) array
        ``A <= B <= C``.

    Returns
    -------
    dict of ndarrays (shape ``omega.shape[:-1]``)
        ``L`` (``|L|``, kg m^2/s), ``E`` (J), ``dynamic_inertia`` ``L^2/2E`` (kg m^2),
        ``excitation`` ``(E - E_min)/(E_max - E_min)`` at fixed ``L`` (D 6),
        ``separatrix_distance`` (signed ``m1 = 1 - k^2``: > 0 SAM, < 0 LAM, D 7; NaN for
        an axisymmetric or spherical body), ``nutation_max_C`` and ``nutation_max_A``:
        largest angle (rad) between ``L`` and ``C`` (SAM side) / ``A`` (LAM side) over the
        torque-free nutation cycle through this state (D 8; NaN on the other side).

    Notes
    -----
    The differences that decide the regime are formed from the rate components, so they
    carry full relative precision (no cancellation):
    ``2EC - L^2 = A(C-A) w1^2 + B(C-B) w2^2``, ``L^2 - 2EA = B(B-A) w2^2 + C(C-A) w3^2``,
    ``L^2 - 2EB = C(C-B) w3^2 - A(B-A) w1^2``.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.analysis.diagnostics import invariants
    >>> inv = invariants(np.array([0.02, 0.0, 0.1]), [0.61, 0.965, 1.0])
    >>> round(float(inv["E"]), 15), round(float(inv["L"]) ** 2, 15)   # E, |L|^2 by hand:
    (0.005122, 0.01014884)
    >>> (0.61 * 0.02**2 + 0.1**2) / 2, 0.61**2 * 0.02**2 + 0.1**2  # (A w1^2 + C w3^2)/2, ...
    (0.005122, 0.01014884)
    >>> bool(inv["dynamic_inertia"] > 0.965)       # L^2 / 2E > B: rotation about C
    True
    """
    w = np.asarray(omega, dtype=float)
    A, B, C = (float(x) for x in moments)
    w1, w2, w3 = w[..., 0], w[..., 1], w[..., 2]
    # principal axes are the SAM kernel frame (attitude.freebody):
    # q1c = 2EC - L^2 >= 0, q3a = L^2 - 2EA >= 0, dB = L^2 - 2EB
    sam = fb.invariants(A, B, C, w1, w2, w3)
    _, _, _, q1c, q3a, dB, L2 = sam
    E2 = A * w1 * w1 + B * w2 * w2 + C * w3 * w3                  # 2E
    with np.errstate(invalid="ignore", divide="ignore"):
        L = np.sqrt(L2)
        D = L2 / E2
        exc = A * q1c / (L2 * (C - A)) if C > A else np.full_like(L2, np.nan)
        tri = (B - A) > SYMMETRY_RTOL * C and (C - B) > SYMMETRY_RTOL * C
        if tri:
            m1_sam = fb.jacobi_parameters(A, B, C, *sam[:6])[1]      # (D 7)
            # the LAM kernel frame's m1, negative on the LAM side
            lam = fb.invariants(C, B, A, *fb.kernel_vector(w1, w2, w3, True))
            m1_lam = -fb.jacobi_parameters(C, B, A, *lam[:6])[1]
            m1 = np.where(dB >= 0, m1_sam, m1_lam)
            m1 = np.where(L2 > 0, np.clip(m1, -1.0, 1.0), np.nan)
            s2c = np.clip(B * q1c / ((C - B) * L2), 0.0, 1.0)         # (D 8)
            s2a = np.clip(B * q3a / ((B - A) * L2), 0.0, 1.0)
            nut_c = np.where(dB >= 0, np.arcsin(np.sqrt(s2c)), np.nan)
            nut_a = np.where(dB <= 0, np.arcsin(np.sqrt(s2a)), np.nan)
        else:
            m1 = np.full_like(L2, np.nan)
            nut_c = np.full_like(L2, np.nan)
            nut_a = np.full_like(L2, np.nan)
    return {"L": L, "E": 0.5 * E2, "dynamic_inertia": D, "excitation": exc,
            "separatrix_distance": m1, "nutation_max_C": nut_c, "nutation_max_A": nut_a,
            "L2_minus_2EB": dB}


def osculating_polhode_period(omega: np.ndarray, moments) -> np.ndarray:
    """Polhode period ``4K(k^2)/lambda`` of the torque-free motion through each state (s).

    Vectorised over leading axes of ``omega`` (..., 3).  Triaxial bodies: Landau &
    Lifshitz §37 (TF 4, 6 of ``docs/torquefree.md``), with ``K`` from ``ellipkm1(m1)`` so
    that it stays accurate near the separatrix, where the period diverges
    logarithmically (``inf`` on it).  A principal-axis spin gets the period of small
    nutation about it.  Axisymmetric bodies: ``2 pi / |Omega|`` with
    ``Omega = omega_s (I_t - I_s)/I_t``.  NaN at rest and for a spherical body.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import osculating_polhode_period
    >>> moments, omega = [0.61, 0.965, 1.0], np.array([0.02, 0.0, 0.1])
    >>> P = float(osculating_polhode_period(omega, moments))
    >>> body = att.RigidBody.from_principal_moments(moments)
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), omega)
    >>> bool(abs(P / att.diagnose(body, state).periods["polhode"] - 1) < 1e-12)
    True
    >>> round(P, 3)
    442.451
    """
    w = np.asarray(omega, dtype=float)
    A, B, C = (float(x) for x in moments)
    w1, w2, w3 = w[..., 0], w[..., 1], w[..., 2]
    tol = SYMMETRY_RTOL * C
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        if C - A <= tol:
            return np.full(w.shape[:-1], np.nan)
        if B - A <= tol or C - B <= tol:
            oblate = B - A <= tol
            Is, It, ws = (C, 0.5 * (A + B), w3) if oblate else (A, 0.5 * (B + C), w1)
            Om = np.abs(ws * (It - Is) / It)
            return np.where(Om > 0, _TWO_PI / Om, np.inf)
        # kernel frame (attitude.freebody, TF 3-6): SAM (A, B, C), LAM (C, B, A)
        on_lam = fb.separatrix_gap(A, B, C, w1, w3) < 0
        I1, I2, I3 = fb.kernel_moments(A, B, C, on_lam)
        inv = fb.invariants(I1, I2, I3, *fb.kernel_vector(w1, w2, w3, on_lam))
        _, m1, lam2 = fb.jacobi_parameters(I1, I2, I3, *inv[:6])
        lam = np.sqrt(lam2)
        m1 = np.clip(m1, 0.0, 1.0)
        K = ellipkm1(m1)                                               # K(m), m = 1 - m1
        P = 4.0 * K / lam
        return np.where(np.isfinite(P) | (m1 == 0), P, np.nan)


def reference_axis_for(moments, dynamic_inertia) -> int:
    """Reference axis (1 = A, 3 = C) of the Euler angles for a body and a typical
    ``L^2/2E``: the symmetry axis of an axisymmetric body, else ``C`` on the SAM side
    (``L^2/2E >= B``) and ``A`` on the LAM side.

    Examples
    --------
    >>> from attitude.analysis.diagnostics import reference_axis_for
    >>> reference_axis_for([0.61, 0.965, 1.0], 0.99)   # L^2/2E > B: short-axis mode
    3
    >>> reference_axis_for([0.61, 0.965, 1.0], 0.70)   # L^2/2E < B: long-axis mode
    1
    """
    A, B, C = (float(x) for x in moments)
    tol = SYMMETRY_RTOL * C
    if C - A <= tol or B - A <= tol:
        return 3
    if C - B <= tol:
        return 1
    D = np.atleast_1d(np.asarray(dynamic_inertia, dtype=float))
    D = D[np.isfinite(D)]
    return 3 if not (D.size and float(np.median(D)) < B) else 1


def _adapted(q_p2i: np.ndarray, omega: np.ndarray, reference_axis: int):
    """Quaternion and rates in the frame whose z axis is the reference axis: identity
    for C; ``(C, -B, A)`` for A (the LAM relabelling of :mod:`attitude.propagation.torquefree`)."""
    if reference_axis == 3:
        return q_p2i, omega
    if reference_axis != 1:
        raise DiagnosticsError(f"reference_axis must be 1 (A) or 3 (C), got {reference_axis!r}")
    # adapted -> principal: the LAM kernel frame of attitude.freebody, x' = C axis (e3),
    # y' = -e2, z' = A axis (e1)
    w = np.stack(fb.kernel_vector(omega[..., 0], omega[..., 1], omega[..., 2], True), axis=-1)
    return quat.multiply(q_p2i, np.array(fb.LAM_FRAME)), w


# ===========================================================================
# the angular-momentum frame and the Euler angles (D 1-4)
# ===========================================================================
def _node(z: np.ndarray) -> np.ndarray:
    """Unit vector along ``e_z x z`` (ascending node), or ``e_x`` when ``z`` is along z."""
    x = np.array([-z[1], z[0], 0.0])
    n = np.linalg.norm(x)
    return x / n if n > 1e-12 else np.array([1.0, 0.0, 0.0])


def _transport(x_ref: np.ndarray, z_ref: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Apply to ``x_ref`` (perpendicular to ``z_ref``) the minimal rotation taking
    ``z_ref`` to each ``z`` (Rodrigues): ``x - (x.z)/(1 + z_ref.z) (z_ref + z)``."""
    c = z @ z_ref
    xz = z @ x_ref
    x = x_ref[None, :] - (xz / (1.0 + c))[:, None] * (z_ref[None, :] + z)
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def momentum_frame_x(Lhat: np.ndarray) -> np.ndarray:
    """X axis of the angular-momentum frame for unit ``L`` directions (T, 3) (D 1)."""
    T = Lhat.shape[0]
    X = np.empty_like(Lhat)
    start = 0
    z_ref = Lhat[0]
    x_ref = _node(z_ref)
    while start < T:
        c = Lhat[start:] @ z_ref
        bad = np.flatnonzero(c < 0.0)
        stop = start + int(bad[0]) if bad.size else T
        if stop == start:                 # L flipped by > 90 deg within one sample
            z_new = Lhat[start]
            x_new = x_ref - (x_ref @ z_new) * z_new
            n = np.linalg.norm(x_new)
            x_ref = x_new / n if n > 1e-6 else _node(z_new)
            z_ref = z_new
            continue
        X[start:stop] = _transport(x_ref, z_ref, Lhat[start:stop])
        if stop < T:
            x_ref, z_ref = X[stop - 1], Lhat[stop - 1]
        start = stop
    return X


def momentum_frame_angles(series: PrincipalSeries, reference_axis: int = 3
                          ) -> dict[str, np.ndarray]:
    """3-1-3 Euler angles of the body in the instantaneous angular-momentum frame.

    Parameters
    ----------
    series : PrincipalSeries
    reference_axis : {3, 1}
        Principal axis carried by the third Euler axis: 3 (``C``) or 1 (``A``).

    Returns
    -------
    dict of (T,) ndarrays, rad
        ``precession`` ``phi`` (unwrapped), ``nutation`` ``theta`` in ``[0, pi]``,
        ``rotation`` ``psi`` (unwrapped), ``spin`` ``phi + psi`` (unwrapped: the rotation
        angle about ``L``, the only one defined when ``theta = 0``; ``phi - psi`` when
        the reference axis points mostly against ``L``), and
        ``axis_angles`` (T, 3): angle between ``L`` and ``A``, ``B``, ``C``.

    Notes
    -----
    With ``R = R_z(phi) R_x(theta) R_z(psi)`` the matrix of the body's adapted axes in the
    angular-momentum frame (D 2): ``phi = atan2(R_02, -R_12)``,
    ``psi = atan2(R_20, R_21)``, ``theta = atan2(hypot(R_20, R_21), R_22)``,
    ``phi + psi = atan2(R_10 - R_01, R_00 + R_11)`` and
    ``phi - psi = atan2(R_10 + R_01, R_00 - R_11)`` (D 3).  The bottom row ``R_2j`` is the
    unit angular momentum in body axes, so ``theta`` and ``psi`` depend on the rates
    only; ``phi`` also needs the attitude.  Angles are unwrapped sample to sample, which
    needs less than half a turn of each angle between samples.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series, momentum_frame_angles
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> angles = momentum_frame_angles(principal_series(eph))
    >>> sorted(angles)
    ['axis_angles', 'nutation', 'precession', 'rotation', 'spin']
    >>> bool(np.all((angles["nutation"] > 0) & (angles["nutation"] < np.pi / 2)))
    True
    """
    q, w = _adapted(series.quaternion, series.omega, reference_axis)
    if reference_axis == 3:
        I = series.moments
    else:
        I = series.moments[::-1]
    Lb = w * I                                              # adapted body components
    Ln = np.linalg.norm(Lb, axis=-1)
    rest = Ln == 0
    Lb_safe = np.where(rest[:, None], [0.0, 0.0, 1.0], Lb)
    Li = quat.rotate(q, Lb_safe)
    Z = Li / np.linalg.norm(Li, axis=-1, keepdims=True)
    X = momentum_frame_x(Z)
    Y = np.cross(Z, X)
    b0 = quat.rotate(q, np.array([1.0, 0.0, 0.0]))         # body axes, inertial
    b1 = quat.rotate(q, np.array([0.0, 1.0, 0.0]))
    b2 = quat.rotate(q, np.array([0.0, 0.0, 1.0]))

    def dot(a, b):
        return np.einsum("ij,ij->i", a, b)

    R00, R01, R02 = dot(X, b0), dot(X, b1), dot(X, b2)
    R10, R11, R12 = dot(Y, b0), dot(Y, b1), dot(Y, b2)
    u = Lb_safe / np.linalg.norm(Lb_safe, axis=-1, keepdims=True)   # R_2j, exact in body
    R20, R21, R22 = u[:, 0], u[:, 1], u[:, 2]
    phi = np.arctan2(R02, -R12)
    psi = np.arctan2(R20, R21)
    theta = np.arctan2(np.hypot(R20, R21), R22)
    # rotation angle about L: phi + psi when the reference axis is along +L, phi - psi
    # when it is along -L (theta near pi, where phi + psi is undefined)
    if np.median(R22) >= 0:
        spin = np.arctan2(R10 - R01, R00 + R11)
    else:
        spin = np.arctan2(R10 + R01, R00 - R11)
    if rest.any():
        for x in (phi, psi, theta, spin):
            x[rest] = np.nan
    phi, psi, spin = _unwrap(phi), _unwrap(psi), _unwrap(spin)
    Lp = series.momentum_body
    axis = np.empty_like(Lp)
    for j in range(3):
        others = [k for k in range(3) if k != j]
        axis[:, j] = np.arctan2(np.hypot(Lp[:, others[0]], Lp[:, others[1]]), Lp[:, j])
    if rest.any():
        axis[rest] = np.nan
    return {"precession": phi, "nutation": theta, "rotation": psi, "spin": spin,
            "axis_angles": axis}


def _unwrap(x: np.ndarray) -> np.ndarray:
    """``numpy.unwrap`` over the finite samples (a body at rest has no angles)."""
    ok = np.isfinite(x)
    if ok.all():
        return np.unwrap(x)
    out = x.copy()
    out[ok] = np.unwrap(x[ok])
    return out


# ===========================================================================
# zero crossings with sub-sample interpolation (D 10-12)
# ===========================================================================
def _upward_crossings(x: np.ndarray, h: float) -> np.ndarray:
    """Indices ``i`` of upward zero crossings between samples ``i`` and ``i + 1``, with
    hysteresis ``h``: the last sign change before the signal enters ``x > h`` coming
    from ``x < -h``."""
    n = x.size
    state = np.where(x > h, 1, np.where(x < -h, -1, 0))
    idx = np.where(state != 0, np.arange(n), 0)
    np.maximum.accumulate(idx, out=idx)
    filled = state[idx]
    filled[(idx == 0) & (state[0] == 0)] = 0
    enter = np.flatnonzero((filled[1:] == 1) & (filled[:-1] == -1)) + 1
    up = np.flatnonzero((x[:-1] <= 0) & (x[1:] > 0))
    if enter.size == 0 or up.size == 0:
        return np.empty(0, dtype=int)
    j = np.searchsorted(up, enter, side="left") - 1
    ok = j >= 0
    return up[j[ok]]


def _poly_coeffs(t: np.ndarray, ys: np.ndarray, i: np.ndarray, m: int):
    """Coefficients (n, m, k) of the degree ``m - 1`` polynomials through ``m`` samples
    around each interval ``[t_i, t_i+1]`` in the local abscissa
    ``tau = (t - t_i)/(t_i+1 - t_i)``, for every series in ``ys`` (T, k)."""
    T = t.size
    s = np.clip(i - (m // 2 - 1), 0, T - m)
    j = s[:, None] + np.arange(m)[None, :]
    h = (t[i + 1] - t[i])[:, None]
    tau = (t[j] - t[i][:, None]) / h
    V = tau[:, :, None] ** np.arange(m)[None, None, :]
    return np.linalg.solve(V, ys[j])


def _horner(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Evaluate polynomials ``c`` (n, m, k) at ``tau`` (n,) -> (n, k)."""
    out = c[:, -1, :].copy()
    for k in range(c.shape[1] - 2, -1, -1):
        out = out * tau[:, None] + c[:, k, :]
    return out


def _horner_d(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    m = c.shape[1]
    out = (m - 1) * c[:, -1, :]
    for k in range(m - 2, 0, -1):
        out = out * tau[:, None] + k * c[:, k, :]
    return out


def _refine(t: np.ndarray, x: np.ndarray, others: np.ndarray, i: np.ndarray, m: int):
    """Crossing times of ``x`` in the intervals ``i`` by Newton's method on the local
    interpolating polynomial, the values of ``others`` (T, k) there, and an estimate of
    the interpolation error of each crossing time (difference with a polynomial of
    degree two lower)."""
    ys = np.column_stack([x, others])
    h = t[i + 1] - t[i]

    def root(mm):
        c = _poly_coeffs(t, ys, i, mm)
        cx = c[:, :, :1]
        tau = -x[i] / (x[i + 1] - x[i])                    # linear start
        for _ in range(30):
            f = _horner(cx, tau)[:, 0]
            d = _horner_d(cx, tau)[:, 0]
            with np.errstate(invalid="ignore", divide="ignore"):
                step = np.where(d != 0, f / d, 0.0)
            tau = np.clip(tau - step, -0.5, 1.5)
            if np.all(np.abs(step) < 1e-15):
                break
        return tau, _horner(c, tau)[:, 1:]

    m = min(m, t.size)
    tau, vals = root(m)
    if m >= 4:
        tau_lo, _ = root(m - 2)
        err = np.abs(tau - tau_lo) * h
    else:
        err = np.abs(h) * 0.5
    return t[i] + tau * h, vals, err


# ===========================================================================
# measured periods (D 10-14)
# ===========================================================================
@dataclass(frozen=True)
class MeasuredPeriod:
    """A period measured from an ephemeris.

    Attributes
    ----------
    value : float
        Seconds.
    uncertainty : float
        One-sigma uncertainty, seconds: the standard error of the least-squares fit
        combined with the interpolation error of the crossing times.
    cycles : float
        Number of cycles of the defining signal used.
    method : str
        How it was measured (``"omega_2 zero crossings"``, ...).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import measure_periods
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> p = measure_periods(eph)["polhode"]
    >>> p.method, p.cycles
    ('omega_2 zero crossings', 5.0)
    >>> exact = att.diagnose(body, state).periods["polhode"]
    >>> bool(abs(float(p) - exact) < 5 * p.uncertainty + 1e-9 * exact)
    True
    """

    value: float
    uncertainty: float
    cycles: float
    method: str

    def __float__(self) -> float:
        return float(self.value)


def _linear_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Least-squares slope, its standard error and the intercept of ``y = a + b x``."""
    n = x.size
    xm, ym = x.mean(), y.mean()
    dx = x - xm
    sxx = float(dx @ dx)
    b = float(dx @ (y - ym)) / sxx
    a = ym - b * xm
    if n > 2:
        r = y - a - b * x
        s2 = float(r @ r) / (n - 2)
        se = math.sqrt(s2 / sxx)
    else:
        se = 0.0
    return b, se, a


def _robust_amplitude(x: np.ndarray) -> float:
    lo, hi = np.percentile(x, [2.0, 98.0])
    return 0.5 * float(hi - lo)


def _polhode_crossings(series: PrincipalSeries, angles: dict, stencil: int):
    """Upward zero crossings of ``omega_2`` (the intermediate-axis rate: ``sn`` in SAM and
    LAM, a sinusoid for an axisymmetric body) with ``phi`` and ``psi`` there."""
    w2 = series.omega[:, 1]
    wn = np.linalg.norm(series.omega, axis=-1)
    amp = _robust_amplitude(w2)
    if not amp > MIN_NUTATION * float(np.median(wn)):
        return None
    i = _upward_crossings(w2, HYSTERESIS * amp)
    if i.size == 0:
        return np.empty(0), np.empty((0, 2)), np.empty(0)
    others = np.column_stack([angles["precession"], angles["rotation"]])
    return _refine(series.time, w2, others, i, stencil)


def measure_periods(source, *, body_index: int | None = None, reference_axis: int | None = None,
                    keys=None, stencil: int = STENCIL) -> dict[str, MeasuredPeriod]:
    """Periods measured from the series of an ephemeris (the keys of docs/diagnostics.md,
    "Measured periods").

    Parameters
    ----------
    source : Ephemeris or PrincipalSeries
    body_index : int, optional
        Body of a batch ephemeris.
    reference_axis : {1, 3}, optional
        Axis of the Euler angles (default: :func:`reference_axis_for`).
    keys : iterable of str, optional
        Which periods to measure.  Default: ``polhode``, ``precession``, ``rotation`` if
        the body nutates (``omega_2`` oscillates), else ``spin`` (plus ``precession`` for
        an axisymmetric body spinning about a transverse axis).
    stencil : int
        Points of the local interpolating polynomial (D 11).

    Returns
    -------
    dict
        ``{key: MeasuredPeriod}``.

    Raises
    ------
    InsufficientDataError
        If the series is too short (less than one cycle of the defining signal: two
        upward zero crossings of ``omega_2``, or one turn of the spin angle) or has too
        few samples.

    Notes
    -----
    *Polhode*: upward zero crossings ``t_n`` of ``omega_2`` (with hysteresis), placed
    by Newton's method on a local degree-5 interpolating polynomial; the period is the
    least-squares slope of ``t_n`` against the cycle number ``n`` (D 12).
    *Precession*: ``phi`` interpolated at the same crossing times advances by the same
    amount every polhode cycle in torque-free motion, so the slope of ``phi(t_n)``
    against ``t_n`` is exactly the mean precession rate ``<dphi/dt>`` and
    ``P_phi = 2 pi / |<dphi/dt>|`` (D 13); *rotation* likewise from ``psi(t_n)``.
    *Spin* (principal-axis rotation): ``2 pi`` over the slope of the spin angle
    ``phi + psi`` (D 14).  On torque-free ephemerides sampled 20 times per period or more
    these agree with :func:`attitude.diagnose` to better than 1e-8 relative.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import measure_periods
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> periods = measure_periods(eph)
    >>> sorted(periods)
    ['polhode', 'precession', 'rotation']
    >>> exact = att.diagnose(body, state).periods          # the closed form
    >>> bool(abs(periods["precession"].value / exact["precession"] - 1) < 1e-8)
    True
    """
    series = source if isinstance(source, PrincipalSeries) else principal_series(
        source, body_index)
    t = series.time
    if t.size < max(stencil, 4):
        raise InsufficientDataError(f"{t.size} samples: at least {max(stencil, 4)} are "
                                    "needed to measure a period")
    inv = invariants(series.omega, series.moments)
    if not np.any(inv["L"] > 0):
        raise InsufficientDataError("the body is at rest: no period to measure")
    ref = reference_axis or reference_axis_for(series.moments, inv["dynamic_inertia"])
    angles = momentum_frame_angles(series, ref)
    cross = _polhode_crossings(series, angles, stencil)
    if keys is None:
        if cross is not None:
            keys = ("polhode", "precession", "rotation")
        else:
            keys = ("spin",)
            A, B, C = series.moments
            tol = SYMMETRY_RTOL * C
            axisym = ((B - A) <= tol or (C - B) <= tol) and (C - A) > tol
            nut = angles["nutation"][np.isfinite(angles["nutation"])]
            if axisym and nut.size and float(nut.min()) > 1e-3:
                keys = ("spin", "precession")
    keys = tuple(keys)
    out: dict[str, MeasuredPeriod] = {}
    span = float(t[-1] - t[0])
    need_polhode = any(k in ("polhode", "rotation") for k in keys) or (
        "precession" in keys and cross is not None)
    if need_polhode:
        if cross is None:
            raise InsufficientDataError(
                "the body does not nutate (omega_2 is constant): no polhode period; "
                "ask for keys=('spin',)")
        tc, vals, err = cross
        for key, name in (("precession", "precession"), ("rotation", "rotation")):
            if key in keys:
                _check_sampling(angles[name], name, t)
        if tc.size < 2:
            P_osc = osculating_polhode_period(series.omega, series.moments)
            P_osc = P_osc[~np.isnan(P_osc)]
            P_osc = float(np.median(P_osc)) if P_osc.size else math.inf
            why = ("on the separatrix the polhode period is infinite" if not
                   np.isfinite(P_osc) else f"the expected polhode period is about "
                   f"{P_osc:.6g} s ({span / P_osc:.3g} of it covered)")
            raise InsufficientDataError(
                f"the ephemeris spans {span:.6g} s with {tc.size} upward zero crossing(s) "
                f"of omega_2: at least one full polhode cycle (two crossings) is needed; "
                f"{why}")
        gaps = np.diff(tc)
        n = np.concatenate([[0.0], np.cumsum(np.rint(gaps / np.median(gaps)))])
        P, se, _ = _linear_fit(n, tc)
        ierr = float(np.sqrt(np.mean(err ** 2)))
        unc = math.hypot(se, math.sqrt(2.0) * ierr / n[-1])
        cycles = float(n[-1])
        if "polhode" in keys:
            out["polhode"] = MeasuredPeriod(P, unc, cycles, "omega_2 zero crossings")
        for key, col, name in (("precession", 0, "phi"), ("rotation", 1, "psi")):
            if key not in keys:
                continue
            rate, rse, _ = _linear_fit(tc, vals[:, col])
            if rate == 0.0:
                continue
            Pk = _TWO_PI / abs(rate)
            # the angle's slope error plus the crossing-time errors propagated through it
            rel = math.hypot(rse / abs(rate), math.sqrt(2.0) * ierr / (tc[-1] - tc[0]))
            out[key] = MeasuredPeriod(Pk, Pk * rel, cycles,
                                      f"{name} at omega_2 zero crossings")
    elif "precession" in keys:
        _check_sampling(angles["precession"], "precession", t)
        out["precession"] = _slope_period(t, angles["precession"], "phi slope")
    if "spin" in keys:
        _check_sampling(angles["spin"], "spin", t)
        out["spin"] = _slope_period(t, angles["spin"], "spin-angle slope")
    return out


#: Largest step of an unwrapped angle between samples accepted for a period (rad): beyond
#: it the unwrapping may have aliased (it needs less than pi).
MAX_ANGLE_STEP = 0.75 * math.pi


def _check_sampling(angle: np.ndarray, name: str, t: np.ndarray) -> None:
    steps = np.abs(np.diff(angle))
    steps = steps[np.isfinite(steps)]
    step = float(steps.max()) if steps.size else 0.0
    if step > MAX_ANGLE_STEP:
        raise InsufficientDataError(
            f"the {name} angle turns by up to {math.degrees(step):.0f} deg between samples "
            f"(limit {math.degrees(MAX_ANGLE_STEP):.0f} deg): the ephemeris is sampled too "
            "coarsely to follow it; resample at least 4 times per period of the fastest "
            "angle")


def _slope_period(t: np.ndarray, angle: np.ndarray, method: str) -> MeasuredPeriod:
    turns = abs(float(angle[-1] - angle[0])) / _TWO_PI
    if not turns >= 1.0:
        raise InsufficientDataError(
            f"the ephemeris spans {t[-1] - t[0]:.6g} s, {turns:.3g} turn(s) of the angle "
            "that defines the period: at least one full turn is needed")
    step = max(1, t.size // 200_000)
    rate, se, _ = _linear_fit(t[::step], angle[::step])
    P = _TWO_PI / abs(rate)
    return MeasuredPeriod(P, P * se / abs(rate), turns, method)


# ===========================================================================
# conservation and noise
# ===========================================================================
def conservation_drift(series: PrincipalSeries) -> dict:
    """Drift of ``|L|`` and ``E`` and their rates.

    Returns
    -------
    dict
        Series (T,): ``L`` (kg m^2/s), ``E`` (J), ``L_drift`` ``|L|/|L_0| - 1``,
        ``E_drift`` ``E/E_0 - 1``, ``L_rate`` ``d|L|/dt`` (kg m^2/s^2), ``E_rate``
        ``dE/dt`` (W), ``L_direction_drift`` (rad, angle between ``L(t)`` and
        ``L(t_0)`` in the inertial frame); scalars: ``L_rel_drift``, ``E_rel_drift``
        (largest ``|drift|``), ``L_drift_rate``, ``E_drift_rate`` (least-squares slope of
        the relative drift, 1/s).  Derivatives are second-order finite differences
        (``numpy.gradient``).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series, conservation_drift
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> drift = conservation_drift(principal_series(eph))
    >>> bool(drift["E_rel_drift"] < 1e-14 and drift["L_rel_drift"] < 1e-14)
    True
    >>> drift["E"].shape
    (1501,)
    """
    t = series.time
    inv = invariants(series.omega, series.moments)
    L, E = inv["L"], inv["E"]
    Li = series.momentum_inertial
    with np.errstate(invalid="ignore", divide="ignore"):
        Ld = L / L[0] - 1.0 if L[0] > 0 else np.zeros_like(L)
        Ed = E / E[0] - 1.0 if E[0] > 0 else np.zeros_like(E)
        c = np.cross(Li, Li[0])
        ang = np.arctan2(np.linalg.norm(c, axis=-1), Li @ Li[0])
    if t.size > 1:
        Lr, Er = np.gradient(L, t), np.gradient(E, t)
        Lslope = _linear_fit(t, Ld)[0] if t.size > 2 else float(Ld[-1] / (t[-1] - t[0]))
        Eslope = _linear_fit(t, Ed)[0] if t.size > 2 else float(Ed[-1] / (t[-1] - t[0]))
    else:
        Lr, Er = np.zeros_like(L), np.zeros_like(E)
        Lslope = Eslope = 0.0
    return {"L": L, "E": E, "L_drift": Ld, "E_drift": Ed, "L_rate": Lr, "E_rate": Er,
            "L_direction_drift": ang,
            "L_rel_drift": float(np.max(np.abs(Ld))), "E_rel_drift": float(np.max(np.abs(Ed))),
            "L_drift_rate": float(Lslope), "E_drift_rate": float(Eslope)}


def attitude_noise(series: PrincipalSeries) -> float:
    """Estimate of white attitude noise (rad per axis) from the jitter of the inertial
    direction of ``L``.

    A rigid body's angular momentum turns only under torque, smoothly; sample-to-sample
    jitter of its direction computed from the attitude is measurement noise.  The
    estimate is the median norm of the fourth differences of the unit vector, scaled for
    white noise (``var(Delta^4 x) = 70 sigma^2``; a 2-D Gaussian's median norm is
    ``1.177 sigma``), which removes smooth motion up to cubic in time (D 15).  Zero for an
    exact torque-free ephemeris (to rounding).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.analysis.diagnostics import principal_series, attitude_noise, PrincipalSeries
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> s = principal_series(eph)
    >>> bool(attitude_noise(s) < 1e-12)                    # exact ephemeris
    True
    >>> rng = np.random.default_rng(1)                     # add 1e-4 rad per axis
    >>> kick = Rotation.from_rotvec(rng.normal(0.0, 1e-4, (1501, 3)))
    >>> noisy = (Rotation.from_quat(s.quaternion) * kick).as_quat()
    >>> sigma = attitude_noise(PrincipalSeries(s.time, noisy, s.omega, s.moments, s.body))
    >>> bool(0.8e-4 < sigma < 1.2e-4)
    True
    """
    Li = series.momentum_inertial
    n = np.linalg.norm(Li, axis=-1)
    ok = n > 0
    if ok.sum() < 6:
        return 0.0
    u = Li[ok] / n[ok, None]
    d4 = np.diff(u, n=4, axis=0)
    return float(np.median(np.linalg.norm(d4, axis=-1)) / (1.1774 * math.sqrt(70.0)))


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

