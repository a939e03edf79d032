r"""An ephemeris in the body's principal frame, its torque-free invariants, and the 3-1-3
Euler angles of the principal frame relative to the angular-momentum frame
(precession ``phi``, nutation ``theta``, rotation ``psi``).

Part of :mod:`attitude.analysis.diagnostics`, which re-exports every name and states the
conventions (the angular-momentum frame, the reference axis); ``(D n)`` are the
equations of ``docs/diagnostics.md``.  Nothing here propagates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ellipkm1

from ..foundations import quaternion as quat
from ..foundations.errors import DiagnosticsError
from ..model import freebody as fb
from ..model.body import SYMMETRY_RTOL, RigidBody, to_principal_frame
from ..model.ephemeris import Ephemeris

__all__ = [
    "PrincipalSeries",
    "principal_series",
    "invariants",
    "osculating_polhode_period",
    "reference_axis_for",
    "momentum_frame_x",
    "momentum_frame_angles",
]

_TWO_PI = 2.0 * math.pi


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
    """X axis of the angular-momentum frame for unit ``L`` directions (T, 3) (D 1).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.analysis.angles import momentum_frame_x
    >>> L = np.array([[0.0, 0.0, 1.0], [0.0, 0.1, 1.0], [0.1, 0.1, 1.0]])
    >>> L /= np.linalg.norm(L, axis=1, keepdims=True)
    >>> X = momentum_frame_x(L)               # unit vectors normal to L
    >>> bool(np.allclose(np.einsum("ij,ij->i", X, L), 0.0, atol=1e-15))
    True
    >>> bool(np.allclose(np.linalg.norm(X, axis=1), 1.0))
    True
    """
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
