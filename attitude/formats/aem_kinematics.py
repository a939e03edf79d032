"""Attitude and rates at the AEM file boundary: from each ``ATTITUDE_TYPE`` (quaternion,
Euler angles, spin; with angular velocity, derivatives or nutation) to body -> inertial
quaternions (scalar last) and body rates in rad/s (:func:`rotation_and_rates`), back
(:func:`state_values`), and rates estimated from attitudes alone
(:func:`estimate_omega`).  The conventions are CCSDS 504.0-B-2 annex F (see
:mod:`attitude.formats.aem`).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import EphemerisFormatError
from .aem_message import (
    AEM_QUATERNION_NORM_TOL,
    ANGDOT_ITEMS,
    ANGLE_ITEMS,
    ANGVEL_ITEMS,
    FIELDS,
    Q_ITEMS,
    QDOT_ITEMS,
    Segment,
    error_at,
)

#: Nothing public: these functions serve aem_read and aem_write; the public names are
#: those of :mod:`attitude.formats.aem`.
__all__ = []

_AXIS = {"X": np.array([1.0, 0.0, 0.0]), "Y": np.array([0.0, 1.0, 0.0]),
         "Z": np.array([0.0, 0.0, 1.0])}


def rotation_and_rates(seg: Segment, where: str) -> tuple[np.ndarray, np.ndarray, bool]:
    """Body -> inertial quaternions (scalar last) and body rates (rad/s, NaN if the file
    has none) of one segment, and whether the file gave rates."""
    spec, values, lines = seg.spec, seg.values, seg.lines
    col = {name: values[:, j] for j, name in enumerate(FIELDS[spec.attitude_type])}
    n = len(values)
    kind = spec.attitude_type
    w = np.full((n, 3), np.nan)
    has_rates = True

    # "Start" frame S and "end" frame E of the data: X_S = R X_E; w = omega of E
    # relative to S in E components (annex F).  S = A, E = B unless version 1 says B2A.
    if kind.startswith("QUATERNION"):
        q = np.stack([col[k] for k in Q_ITEMS], axis=1)
        norm = np.linalg.norm(q, axis=1)
        bad = np.flatnonzero(~(np.abs(norm - 1.0) <= AEM_QUATERNION_NORM_TOL))
        if bad.size:
            i = bad[0]
            raise error_at(where, lines[i], "Q1 Q2 Q3 QC",
                         f"quaternion ({', '.join(f'{x:.9g}' for x in q[i])}) has norm "
                         f"{norm[i]:.9g}, not 1 within {AEM_QUATERNION_NORM_TOL:g}: corrupt "
                         "data or wrong columns (is the scalar QC first?)")
        q = q / norm[:, None]
        rot = Rotation.from_quat(q)
        if kind == "QUATERNION/DERIVATIVE":
            qdot = np.stack([col[k] for k in QDOT_ITEMS], axis=1)
            # q_dot = q (x) (omega_E, 0) / 2  =>  omega_E = 2 vec(conj(q) (x) q_dot)
            w = 2.0 * quat.multiply(quat.conjugate(q), qdot)[:, :3]
    elif kind.startswith("EULER"):
        angles = np.stack([col[k] for k in ANGLE_ITEMS], axis=1)
        rot = Rotation.from_euler(spec.euler_seq, angles, degrees=True)
        if kind == "EULER_ANGLE/DERIVATIVE":
            rates = np.radians(np.stack([col[k] for k in ANGDOT_ITEMS], axis=1))
            w = _euler_rates_to_omega(spec.euler_seq, np.radians(angles), rates)
    else:
        # Spin (annex F5): attitude = rotations Z(alpha + 90), X(90 - delta), Z(spin angle)
        # from A; body rate = spin rate about body Z plus the nutation rate about the
        # angular momentum L (F5.3: omega = phi_dot L + psi_dot z_B).
        angles = np.stack([col["SPIN_ALPHA"] + 90.0, 90.0 - col["SPIN_DELTA"],
                           col["SPIN_ANGLE"]], axis=1)
        rot = Rotation.from_euler("ZXZ", angles, degrees=True)
        w = np.zeros((n, 3))
        w[:, 2] = np.radians(col["SPIN_ANGLE_VEL"])
        if kind == "SPIN/NUTATION_MOM":
            a, d = np.radians(col["MOMENTUM_ALPHA"]), np.radians(col["MOMENTUM_DELTA"])
            L_a = np.stack([np.cos(d) * np.cos(a), np.cos(d) * np.sin(a), np.sin(d)], axis=1)
            w += np.radians(col["NUTATION_VEL"])[:, None] * rot.inv().apply(L_a)
        elif kind == "SPIN/NUTATION":
            per = col["NUTATION_PER"]
            if np.any(per == 0):
                i = int(np.flatnonzero(per == 0)[0])
                raise error_at(where, lines[i], "NUTATION_PER", "a nutation period of 0 s")
            nu, ph = np.radians(col["NUTATION"]), np.radians(col["NUTATION_PHASE"])
            L_b = np.stack([np.sin(nu) * np.cos(ph), -np.sin(nu) * np.sin(ph), np.cos(nu)],
                           axis=1)
            w += np.radians(360.0 / per)[:, None] * L_b
    if kind.endswith("/ANGVEL"):
        w = np.radians(np.stack([col[k] for k in ANGVEL_ITEMS], axis=1))
        if spec.angvel_in_a:
            w = rot.inv().apply(w)             # X_B = R^T X_A
    if kind.endswith("/RATE") or kind in ("QUATERNION", "EULER_ANGLE"):
        has_rates = False
        w = np.full((n, 3), np.nan)
    if not spec.a2b:                          # data were B -> A: flip to A -> B
        rot, w = rot.inv(), -rot.apply(w)
    if not spec.inertial_is_a:                # A is the body: flip to inertial -> body
        rot, w = rot.inv(), -rot.apply(w)
    return rot.as_quat(), w, has_rates


def _euler_rates_to_omega(seq: str, angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Body rate from intrinsic Euler angles and their rates (rad, rad/s).

    With ``R = R1(t1) R2(t2) R3(t3)``: ``omega_B = R3^T R2^T a1 t1' + R3^T a2 t2' + a3 t3'``.
    """
    M = _euler_rate_matrix(seq, angles)
    return np.einsum("nij,nj->ni", M, rates)


def _euler_rate_matrix(seq: str, angles: np.ndarray) -> np.ndarray:
    """(n, 3, 3) matrix whose columns map the three Euler angle rates to body rates."""
    a1, a2, a3 = (_AXIS[c] for c in seq)
    n = len(angles)
    R2 = Rotation.from_rotvec(a2 * angles[:, 1:2])
    R3 = Rotation.from_rotvec(a3 * angles[:, 2:3])
    c1 = R3.inv().apply(R2.inv().apply(np.tile(a1, (n, 1))))
    c2 = R3.inv().apply(np.tile(a2, (n, 1)))
    c3 = np.tile(a3, (n, 1))
    return np.stack([c1, c2, c3], axis=2)


def estimate_omega(q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Body rates from a quaternion sequence: relative rotations between neighbours
    (``rotvec(R_i^-1 R_i+1) / dt``), averaged with weights that make the estimate
    second-order accurate at interior points."""
    n = len(t)
    w = np.full((n, 3), np.nan)
    if n < 2:
        return w
    rot = Rotation.from_quat(q)
    d = (rot[:-1].inv() * rot[1:]).as_rotvec() / np.diff(t)[:, None]
    h = np.diff(t)[:, None]
    w[0], w[-1] = d[0], d[-1]
    w[1:-1] = (h[1:] * d[:-1] + h[:-1] * d[1:]) / (h[:-1] + h[1:])
    return w


def state_values(kind: str, q: np.ndarray, w: np.ndarray, seq: str | None,
                  angvel_in_a: bool) -> np.ndarray:
    """Data items (without the epoch) of ``kind`` for quaternions body -> inertial and
    body rates (rad/s): REF_FRAME_A is the inertial frame, REF_FRAME_B the body."""
    parts = []
    rot = Rotation.from_quat(q)
    if kind.startswith("QUATERNION"):
        parts.append(q)
        if kind == "QUATERNION/DERIVATIVE":
            parts.append(0.5 * quat.multiply(q, np.concatenate([w, np.zeros((len(w), 1))],
                                                               axis=1)))
    else:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*[Gg]imbal lock.*")
            angles = rot.as_euler(seq, degrees=True)
        parts.append(angles)
        if kind == "EULER_ANGLE/DERIVATIVE":
            M = _euler_rate_matrix(seq, np.radians(angles))
            det = np.linalg.det(M)
            bad = np.flatnonzero(~(np.abs(det) > 1e-9))
            if bad.size:
                raise EphemerisFormatError(
                    f"EULER_ANGLE/DERIVATIVE: the {seq} sequence is in gimbal lock at sample "
                    f"{bad[0]} (angles {np.round(angles[bad[0]], 6).tolist()} deg): the angle "
                    "rates are undefined there; write EULER_ANGLE/ANGVEL or choose another "
                    "EULER_ROT_SEQ")
            parts.append(np.degrees(np.linalg.solve(M, w[..., None])[..., 0]))
    if kind.endswith("/ANGVEL"):
        parts.append(np.degrees(rot.apply(w) if angvel_in_a else w))
    return np.concatenate(parts, axis=1)


