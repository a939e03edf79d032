"""The analytic torque-free diagnosis, without propagating: the regime, the periods,
the nutation range and the distance to the separatrix of a body in a state
(:func:`diagnose`, which is ``att.diagnose``), from principal moments and rates
(:func:`diagnose_principal`), for a batch (:func:`diagnose_many`), and the propagation
branch the closed form would take (:func:`branch_of`).

Part of :mod:`attitude.model.freebody` (which re-exports every name); built on the
per-body constants of :mod:`.freebody_constants` (Landau & Lifshitz §37; Samarasinha &
A'Hearn 1991; Kaasalainen 2001; ``docs/torquefree.md``, TF 31-34).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..foundations import elliptic as el
from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError, NearSeparatrixWarning
from .body import SYMMETRY_RTOL, to_principal_frame
from .freebody_algebra import (
    EQUAL_MOMENTS_RTOL,
    NEAR_SEPARATRIX_WARN,
    PURE_SPIN_TOL,
    invariants,
)
from .freebody_constants import (
    BRANCH_LAM,
    BRANCH_PRECESSION,
    BRANCH_SAM,
    BRANCH_SEPARATRIX,
    BRANCHES,
    branches,
    check_inputs,
    elliptic_constants,
    kernel_invariants,
    unit_scales,
)
from .regimes import PERIOD_KEYS, REGIMES

__all__ = ["Diagnosis", "diagnose", "diagnose_principal", "diagnose_many", "branch_of"]

_LD = el.LD
_TWO_PI = 2.0 * math.pi


# ===========================================================================
# analytic diagnostics
# ===========================================================================
@dataclass(frozen=True)
class Diagnosis:
    """Analytic torque-free quantities of one body and state (no propagation).

    Attributes
    ----------
    regime : str
        One of ``"PA-short"``, ``"PA-long"``, ``"SAM"``, ``"LAM"``, ``"separatrix"``,
        ``"axisymmetric"``, ``"spherical"``, ``"at-rest"`` (:data:`attitude.model.regimes.REGIMES`).
    periods : dict
        Seconds, keys from :data:`attitude.model.regimes.PERIOD_KEYS`.  ``polhode`` (period of
        omega in the body frame, ``4K/lambda``), ``precession`` (mean period ``P_phi`` of
        the reference axis about L), ``rotation`` (``P_psi``, period of the rotation
        angle about the reference axis; equal to the polhode period), ``spin``
        (``2 pi/|omega|``, principal-axis spin).  Keys whose period does not exist for
        the regime are absent.
    angular_momentum : float
        ``|L|`` (kg m^2/s).
    kinetic_energy : float
        ``E`` (J).
    dynamic_inertia : float
        ``L^2 / 2E`` (kg m^2); NaN at rest.
    separatrix_distance : float
        Signed complementary Jacobi parameter ``m1 = 1 - k^2`` (dimensionless, in
        [-1, 1]): ``(C-A)(L^2-2EB) / ((C-B)(L^2-2EA))`` > 0 on the SAM side,
        ``-(C-A)(2EB-L^2) / ((B-A)(2EC-L^2))`` < 0 on the LAM side; 0 on the
        separatrix, +-1 for principal-axis spin about C / A.  NaN when undefined
        (spherical body, rest).
    nutation_range : tuple of float or None
        ``(theta_min, theta_max)`` (rad): range of the angle between L and the
        reference axis (:attr:`reference_axis`); ``None`` at rest.
    stable : bool or None
        Lyapunov stability of a principal-axis spin (False for the intermediate axis
        and for transverse spin of an axisymmetric body); ``None`` otherwise.
    reference_axis : int or None
        Principal axis (1 = A, 3 = C, ...) of the Euler angles: C for SAM and the
        separatrix, A for LAM, the symmetry axis of an axisymmetric body, the spin axis.
    k2 : float or None
        Jacobi parameter ``m = k^2`` (SAM/LAM; 1 on the separatrix).
    lam : float or None
        Jacobi frequency ``lambda`` (rad/s); rates are functions of ``lambda t``.
    mean_precession_rate : float or None
        ``<d phi/dt>`` (rad/s).
    excitation : float
        ``(E - E_min)/(E_max - E_min)`` at fixed L, with ``E_min = L^2/2C`` and
        ``E_max = L^2/2A`` (0: spin about C, 1: spin about A); NaN if undefined.
    energy_ratio : float
        ``E / E0`` with ``E0 = L^2/2C`` (Pravec et al. 2014); NaN at rest.
    branch : str
        Propagation branch used by :func:`free_rotation` (``"elliptic"``,
        ``"separatrix"``, ``"precession"``); can differ from the label because the
        label uses the looser ``rtol_symmetry``.
    omega_principal, angular_momentum_principal : ndarray (3,)
        Rates and L in principal components.
    angular_momentum_inertial : ndarray (3,) or None
        L in the inertial frame (from :func:`diagnose`).

    Examples
    --------
    >>> d = diagnose_principal([0.61, 0.965, 1.0], [0.02, 0.0, 0.1])
    >>> d.regime, round(d.separatrix_distance, 6)         # short-axis mode, m1 > 0
    ('SAM', 0.752514)
    >>> bool(0.965 < d.dynamic_inertia < 1.0)             # B < L^2/2E < C
    True
    >>> diagnose_principal([0.61, 0.965, 1.0], [0.0, 0.0, 1.0]).regime
    'PA-short'
    """

    regime: str
    periods: dict
    angular_momentum: float
    kinetic_energy: float
    dynamic_inertia: float
    separatrix_distance: float
    nutation_range: tuple | None
    stable: bool | None
    reference_axis: int | None = None
    k2: float | None = None
    lam: float | None = None
    mean_precession_rate: float | None = None
    excitation: float = math.nan
    energy_ratio: float = math.nan
    branch: str = ""
    omega_principal: np.ndarray = field(default=None, repr=False)
    angular_momentum_principal: np.ndarray = field(default=None, repr=False)
    angular_momentum_inertial: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self):
        if self.regime not in REGIMES:  # pragma: no cover - internal consistency
            raise ValueError(f"unknown regime {self.regime!r}")
        if not set(self.periods) <= set(PERIOD_KEYS):  # pragma: no cover
            raise ValueError(f"unknown period keys {sorted(self.periods)}")


def branch_of(moments, omega0):
    """Propagation branch names (``"precession"``, ``"separatrix"``, ``"SAM"``,
    ``"LAM"``) that :func:`free_rotation` uses, for (..., 3) inputs.

    Examples
    --------
    >>> import numpy as np
    >>> omega = np.array([[0.02, 0.0, 0.1], [0.1, 0.0, 0.02], [0.0, 0.0, 1.0]])
    >>> branch_of(np.array([0.61, 0.965, 1.0]), omega).tolist()
    ['SAM', 'LAM', 'precession']
    """
    moments = np.asarray(moments, dtype=float)
    omega0 = np.asarray(omega0, dtype=float)
    batch, I, w, _, _ = check_inputs(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    sI, sw = unit_scales(I, w)
    br, _, _ = branches(I / sI[:, None], w / sw[:, None])
    out = np.array(BRANCHES)[br]
    return out.reshape(batch) if batch else str(out[0])


def _atan2_sqrt(s2, c2):
    return float(np.arctan2(np.sqrt(np.float64(s2)), np.sqrt(np.float64(c2))))


def diagnose_principal(moments, omega0, *, rtol_symmetry=None, rtol_spin=None,
                       quat0=None) -> Diagnosis:
    """Analytic diagnosis from principal moments and principal-frame rates.

    Parameters
    ----------
    moments : (3,) array_like
        ``A <= B <= C`` (kg m^2).
    omega0 : (3,) array_like
        Principal-frame angular velocity (rad/s).
    rtol_symmetry : float, optional
        Moments within ``rtol_symmetry * C`` are equal for the *label* (default
        ``attitude.model.body.SYMMETRY_RTOL``, 1e-12, the tolerance of
        ``RigidBody.symmetry``).  Propagation itself uses :data:`EQUAL_MOMENTS_RTOL`.
    rtol_spin : float, optional
        The state is labelled principal-axis spin (``PA-short``, ``PA-long``, or
        ``separatrix`` for the intermediate axis) when the two smaller body components
        of L are at most ``rtol_spin * |L|`` (default: ``rtol_symmetry``), so that the
        1e-16 wobble left by rotating a spin into the principal frame does not turn it
        into SAM/LAM.  Propagation itself uses :data:`PURE_SPIN_TOL`.
    quat0 : (4,) array_like, optional
        Principal -> inertial quaternion; gives ``angular_momentum_inertial``.

    Returns
    -------
    Diagnosis

    Notes
    -----
    Periods (Landau & Lifshitz §37; Samarasinha & A'Hearn 1991; Kaasalainen 2001):
    ``P_polhode = P_psi = 4 K(m) / lambda`` and ``P_phi = 2 pi / <phi'>`` with, for SAM,
    ``<phi'> = L/C + L (C-A)/(A C) * Pi(-nu | m) / K(m)``, ``nu = C(B-A)/(A(C-B))``,
    and for LAM the same with A and C exchanged (docs/torquefree.md, TF 31-33).

    Examples
    --------
    >>> import math
    >>> d = diagnose_principal([1.0, 1.0, 2.0], [0.1, 0.0, 1.0])    # axisymmetric
    >>> d.regime
    'axisymmetric'
    >>> L = math.hypot(0.1, 2.0)                # precession period 2 pi A / |L|
    >>> bool(math.isclose(d.periods["precession"], 2 * math.pi / L, rel_tol=1e-14))
    True
    >>> d = diagnose_principal([0.61, 0.965, 1.0], [0.1, 0.0, 0.02])
    >>> d.regime, d.separatrix_distance < 0     # long-axis mode: m1 < 0
    ('LAM', True)
    """
    if rtol_symmetry is None:
        rtol_symmetry = SYMMETRY_RTOL
    rtol_symmetry = max(float(rtol_symmetry), EQUAL_MOMENTS_RTOL)  # never finer than the solver
    rtol_spin = max(float(rtol_symmetry if rtol_spin is None else rtol_spin), PURE_SPIN_TOL)
    _, I, w, _, _ = check_inputs(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    if I.shape[0] != 1:
        raise InvalidStateError("diagnose_principal takes one body; use branch_of for batches")
    A, B, C = (float(x) for x in I[0])
    wv = w[0].copy()
    Lp = I[0] * wv
    L = float(np.sqrt(np.sum(Lp.astype(_LD) ** 2)))
    E2 = float(np.sum(I[0].astype(_LD) * wv.astype(_LD) ** 2))
    E = 0.5 * E2
    Lin = None
    if quat0 is not None:
        q = np.asarray(quat0, dtype=float)
        Lin = quat.rotate(q / np.linalg.norm(q), Lp)
    base = dict(angular_momentum=L, kinetic_energy=E, omega_principal=wv,
                angular_momentum_principal=Lp, angular_momentum_inertial=Lin)
    if L == 0.0:
        return Diagnosis(regime="at-rest", periods={}, dynamic_inertia=math.nan,
                         separatrix_distance=math.nan, nutation_range=None, stable=None,
                         branch="precession", **base)
    wn = float(np.linalg.norm(wv))
    D = L * L / E2
    sI, sw = unit_scales(I, w)
    Is, ws = I / sI[:, None], w / sw[:, None]
    br, dhi, dlo = branches(Is, ws)
    bname = {BRANCH_PRECESSION: "precession", BRANCH_SEPARATRIX: "separatrix"}.get(
        int(br[0]), "elliptic")
    # excitation (E - E_min)/(E_max - E_min) from 2EC - L^2 = A(C-A)w1^2 + B(C-B)w2^2
    q1c = float(invariants(A, B, C, *(float(x) for x in wv))[3])      # 2EC - L^2
    exc = min(1.0, float(A * q1c / (L * L * (C - A)))) if C > A else math.nan
    base.update(dynamic_inertia=D, excitation=exc, energy_ratio=float(1.0 + q1c / (L * L)),
                branch=bname)
    tol = rtol_symmetry * C
    spin = {"spin": _TWO_PI / wn}
    Labs = np.abs(Lp)
    k = int(np.argmax(Labs))
    pure = np.sort(Labs)[1] <= rtol_spin * L

    def theta_of(axis):
        c = Lp[axis] / L
        s = math.sqrt(max(0.0, float(np.sum(np.delete(Lp, axis) ** 2)))) / L
        return math.atan2(s, c)

    if C - A <= tol:
        th = theta_of(2)
        return Diagnosis(regime="spherical", periods=dict(spin), separatrix_distance=math.nan,
                         nutation_range=(th, th), stable=None, reference_axis=3, **base)
    oblate = B - A <= tol
    prolate = C - B <= tol
    if pure:
        sign = 1.0 if Lp[k] > 0 else -1.0
        nut = (0.0, 0.0) if sign > 0 else (math.pi, math.pi)
        if oblate or prolate:
            sym = 2 if oblate else 0
            if k == sym:
                regime = "PA-short" if oblate else "PA-long"
                return Diagnosis(regime=regime, periods=dict(spin), separatrix_distance=(
                    1.0 if oblate else -1.0), nutation_range=nut, stable=True,
                    reference_axis=k + 1, **base)
            th = theta_of(sym)
            return Diagnosis(regime="axisymmetric", periods=dict(spin, precession=spin["spin"]),
                             separatrix_distance=0.0, nutation_range=(th, th), stable=False,
                             reference_axis=sym + 1, **base)
        regime = {2: "PA-short", 0: "PA-long", 1: "separatrix"}[k]
        dist = {2: 1.0, 0: -1.0, 1: 0.0}[k]
        return Diagnosis(regime=regime, periods=dict(spin), separatrix_distance=dist,
                         nutation_range=nut, stable=(k != 1), reference_axis=k + 1, **base)
    if oblate or prolate:
        sym = 2 if oblate else 0
        Is_ = C if oblate else A
        It = 0.5 * (A + B) if oblate else 0.5 * (B + C)
        Om = float(wv[sym] * (It - Is_) / It)
        th = theta_of(sym)
        periods = {"precession": _TWO_PI * It / L}
        if Om != 0.0:
            periods["polhode"] = periods["rotation"] = _TWO_PI / abs(Om)
            dist = 1.0 if oblate else -1.0
        else:
            periods["spin"] = _TWO_PI / wn
            dist = 0.0
        return Diagnosis(regime="axisymmetric", periods=periods, separatrix_distance=dist,
                         nutation_range=(th, th), stable=None if Om != 0.0 else False,
                         reference_axis=sym + 1, mean_precession_rate=L / It, **base)
    # triaxial
    if int(br[0]) in (BRANCH_SEPARATRIX, BRANCH_PRECESSION):
        # separatrix closed form, SAM labels: theta from theta_min to pi/2 (asymptote)
        v = kernel_invariants(Is, ws)
        s2 = v["I1"] * v["Q1"] / (v["d31"] * v["L2"])
        c2 = v["I3"] * v["Q3"] / (v["d31"] * v["L2"])
        th = _atan2_sqrt(s2[0], c2[0])
        nut = (th, 0.5 * math.pi) if wv[2] >= 0 else (0.5 * math.pi, math.pi - th)
        lamb = float(np.sqrt(v["d32"] * v["Q3"] / (v["I1"] * v["I2"] * v["I3"]))[0]) * sw[0]
        return Diagnosis(regime="separatrix", periods={}, separatrix_distance=0.0,
                         nutation_range=nut, stable=None, reference_axis=3, k2=1.0,
                         lam=float(lamb), **base)
    lam_side = int(br[0]) == BRANCH_LAM
    x = elliptic_constants(Is, ws, dhi, dlo, lam_side)
    m1 = float(x["m1"][0])
    if m1 < NEAR_SEPARATRIX_WARN:
        warnings.warn(f"state is {m1:.1e} from the separatrix (1 - k^2): periods and regime "
                      "are ill-conditioned; the motion itself is still computed exactly",
                      NearSeparatrixWarning, stacklevel=2)
    lamb = x["lamb"][0] * _LD(sw[0])
    K = x["K"][0]
    P_pol = float(4 * K / lamb)
    # mean precession rate (TF 31): linear rate + kappa_j * (dj/dt)
    phidot = (x["w_lin"][0] + x["kappa_j"][0] * x["sigma"] * x["lamb"][0] / (2 * K)) * _LD(sw[0])
    L2 = x["L"][0] ** 2
    s2min = x["I1"][0] * x["Q1"][0] / (x["d31"][0] * L2)  # nutation extremes (TF 34)
    c2min = x["I3"][0] * x["Q3"][0] / (x["d31"][0] * L2)
    s2max = x["I2"][0] * x["Q1"][0] / (x["d32"][0] * L2)
    c2max = x["I3"][0] * x["Dl"][0] / (x["d32"][0] * L2)
    tmin, tmax = _atan2_sqrt(s2min, c2min), _atan2_sqrt(s2max, c2max)
    if x["s"][0] < 0:
        tmin, tmax = math.pi - tmax, math.pi - tmin
    return Diagnosis(
        regime="LAM" if lam_side else "SAM",
        periods={"polhode": P_pol, "precession": float(_TWO_PI / abs(phidot)),
                 "rotation": P_pol},
        separatrix_distance=-m1 if lam_side else m1,
        nutation_range=(tmin, tmax), stable=None, reference_axis=1 if lam_side else 3,
        k2=float(x["m"][0]), lam=float(lamb), mean_precession_rate=float(phidot), **base)


def diagnose(body, state, *, rtol_symmetry=None, rtol_spin=None) -> Diagnosis:
    """Analytic torque-free diagnosis of a body in a state (``att.diagnose``).

    Parameters
    ----------
    body : attitude.RigidBody
        Uses ``principal_moments`` and ``body_to_principal``.
    state : attitude.AttitudeState
        Uses ``omega_body`` (rad/s, body frame) and ``attitude`` (body -> inertial).
    rtol_symmetry, rtol_spin : float, optional
        Label tolerances, see :func:`diagnose_principal`.

    Returns
    -------
    Diagnosis

    Examples
    --------
    >>> import attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.2, 0.0, 3.0])
    >>> d = att.diagnose(body, state)
    >>> d.regime, sorted(d.periods)
    ('SAM', ['polhode', 'precession', 'rotation'])
    """
    q_p2i, w_p = to_principal_frame(state.attitude.as_quat(), state.omega_body,
                                    body.body_to_principal.as_quat())
    return diagnose_principal(body.principal_moments, w_p, rtol_symmetry=rtol_symmetry,
                              rtol_spin=rtol_spin, quat0=q_p2i)


def diagnose_many(moments, omega0, *, rtol_symmetry=None, rtol_spin=None) -> dict:
    """:func:`diagnose_principal` for a batch, vectorised over bodies.

    Parameters
    ----------
    moments : (N, 3) array_like
        Principal moments ``A <= B <= C`` (kg m^2) of each body.
    omega0 : (N, 3) array_like
        Principal-frame angular velocities (rad/s).
    rtol_symmetry, rtol_spin : float, optional
        Label tolerances, as in :func:`diagnose_principal`.

    Returns
    -------
    dict of (N,) arrays
        ``regime`` (str), ``polhode``, ``precession``, ``rotation``, ``spin`` (s; NaN
        where the period does not exist for the regime), ``energy_ratio`` (E/E0),
        ``separatrix_distance``, ``nutation_min`` and ``nutation_max`` (rad).

    Notes
    -----
    Triaxial SAM and LAM states (the bulk of any sampled population) are evaluated
    together with the same formulas as :func:`diagnose_principal`; the rare special
    cases (rest, principal-axis spin, axisymmetric or spherical bodies, the separatrix and
    states within :data:`NEAR_SEPARATRIX_WARN` of it) are delegated to it one by one, so
    the two agree (tested to 1e-13 relative).

    Examples
    --------
    >>> d = diagnose_many([[0.61, 0.965, 1.0], [1.0, 2.0, 3.0]], [[0.2, 0.0, 3.0], [0, 0, 1]])
    >>> d["regime"].tolist()
    ['SAM', 'PA-short']
    """
    if rtol_symmetry is None:
        rtol_symmetry = SYMMETRY_RTOL
    rtol_symmetry = max(float(rtol_symmetry), EQUAL_MOMENTS_RTOL)
    rtol_spin_ = max(float(rtol_symmetry if rtol_spin is None else rtol_spin), PURE_SPIN_TOL)
    moments = np.atleast_2d(np.asarray(moments, dtype=float))
    omega0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    _, I, w, _, _ = check_inputs(moments, [0.0, 0.0, 0.0, 1.0], omega0, [0.0])
    n = I.shape[0]
    keys = ("polhode", "precession", "rotation", "spin", "energy_ratio",
            "separatrix_distance", "nutation_min", "nutation_max")
    out = {k: np.full(n, np.nan) for k in keys}
    regime = np.empty(n, dtype=object)
    A, B, C = I[:, 0], I[:, 1], I[:, 2]
    Lp = I * w
    L = np.sqrt(np.sum(Lp * Lp, axis=1))
    tol = rtol_symmetry * C
    pure = np.sort(np.abs(Lp), axis=1)[:, 1] <= rtol_spin_ * L
    generic = (L > 0) & ((B - A) > tol) & ((C - B) > tol) & ~pure
    sI, sw = unit_scales(I, w)
    Is, ws = I / sI[:, None], w / sw[:, None]
    br, dhi, dlo = branches(Is, ws)
    generic &= (br == BRANCH_SAM) | (br == BRANCH_LAM)
    for lam_side, code in ((False, BRANCH_SAM), (True, BRANCH_LAM)):
        idx = np.nonzero(generic & (br == code))[0]
        if idx.size == 0:
            continue
        x = elliptic_constants(Is[idx], ws[idx], dhi[idx], dlo[idx], lam_side)
        m1 = x["m1"].astype(np.float64)
        far = m1 >= NEAR_SEPARATRIX_WARN
        generic[idx[~far]] = False
        # per-body arrays along the last axis (the Landen chain has its level axis first)
        idx, x = idx[far], {k: (v[..., far] if np.ndim(v) else v) for k, v in x.items()}
        s_w = sw[idx].astype(_LD)
        lamb = x["lamb"] * s_w
        K = x["K"]
        P_pol = (4 * K / lamb).astype(np.float64)
        phidot = ((x["w_lin"] + x["kappa_j"] * x["sigma"] * x["lamb"] / (2 * K)) * s_w)
        L2 = x["L"] ** 2
        tmin = np.arctan2(np.sqrt((x["I1"] * x["Q1"] / (x["d31"] * L2)).astype(np.float64)),
                          np.sqrt((x["I3"] * x["Q3"] / (x["d31"] * L2)).astype(np.float64)))
        tmax = np.arctan2(np.sqrt((x["I2"] * x["Q1"] / (x["d32"] * L2)).astype(np.float64)),
                          np.sqrt((x["I3"] * x["Dl"] / (x["d32"] * L2)).astype(np.float64)))
        flip = x["s"] < 0
        tmin, tmax = np.where(flip, np.pi - tmax, tmin), np.where(flip, np.pi - tmin, tmax)
        regime[idx] = "LAM" if lam_side else "SAM"
        out["polhode"][idx] = out["rotation"][idx] = P_pol
        out["precession"][idx] = (_TWO_PI / np.abs(phidot)).astype(np.float64)
        out["separatrix_distance"][idx] = -m1[far] if lam_side else m1[far]
        out["nutation_min"][idx], out["nutation_max"][idx] = tmin, tmax
        q1c = invariants(A[idx], B[idx], C[idx], *w[idx].T)[3]            # 2EC - L^2
        out["energy_ratio"][idx] = 1.0 + q1c / L[idx] ** 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearSeparatrixWarning)
        for i in np.nonzero(~generic)[0]:
            d = diagnose_principal(I[i], w[i], rtol_symmetry=rtol_symmetry,
                                   rtol_spin=rtol_spin)
            regime[i] = d.regime
            for k, v in d.periods.items():
                out[k][i] = v
            out["energy_ratio"][i] = d.energy_ratio
            out["separatrix_distance"][i] = d.separatrix_distance
            if d.nutation_range is not None:
                out["nutation_min"][i], out["nutation_max"][i] = d.nutation_range
    out["regime"] = regime.astype(str)
    return out
