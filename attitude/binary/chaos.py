r"""The chaotic regime of a binary: its finite-time Lyapunov exponent, with a control.

Two trajectories of the same :class:`~attitude.binary.system.BinarySystem`, the
reference and a copy displaced by ``separation`` (Benettin et al. 1980), are propagated
with the run's method and step and renormalised at equal intervals.  The distance is
taken in a scaled state space,

.. math::
    d^2 = \frac{|\delta R|^2}{r_0^2} + \frac{|\delta V|^2}{(n r_0)^2}
        + |\delta\theta_1|^2 + \frac{|\delta\omega_1|^2}{n^2}
        + |\delta\theta_2|^2 + \frac{|\delta\omega_2|^2}{n^2},

``r_0`` the initial separation of the centres, ``n = sqrt(mu / r_0^3)`` the mean motion
of the circular orbit there (both from :func:`attitude.binary.dynamics.system_scales`),
``delta theta_i`` the rotation vector (body frame, rad) from the reference attitude of
body ``i`` to the displaced one.

The control (as in :mod:`attitude.analysis.lyapunov`) is the integrable motion of the
same masses and state with both bodies made spheres (Keplerian orbit, free spins):
its tangent vectors grow only linearly (the orbit's phase shears), so its finite-time
exponent falls like ``ln(t) / t``.  Chaotic when the displaced trajectory separated by
:attr:`~attitude.model.regimes.Thresholds.lyapunov_efolds` e-folds more than in the
control, and its exponent is above ``lyapunov_ratio`` times the control's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from attitude.analysis.lyapunov import batch_means_error
from attitude.binary.dynamics import integrate_dop853, pack, system_scales, unpack
from attitude.binary.lgvi import default_step, integrate_lgvi
from attitude.binary.propagate import initial_vector
from attitude.binary.system import BinaryState, BinarySystem
from attitude.foundations.errors import BinarySystemError
from attitude.foundations.quantities import to_si
from attitude.model.body import MassProperties, RigidBody
from attitude.model.regimes import Thresholds

__all__ = ["BinaryLyapunov", "lyapunov_exponent", "kepler_control"]


@dataclass(frozen=True)
class BinaryLyapunov:
    """A binary's finite-time Lyapunov exponent and its Keplerian control (1/s).

    Attributes
    ----------
    exponent, uncertainty : float
        ``lambda`` (1/s) and its standard error (batch means of the local exponents).
    control_exponent, control_uncertainty : float or None
        The same for the control (both bodies spheres), or None without one.
    excess_efolds : float
        ``(lambda - lambda_control) * duration``.
    chaotic : bool
        ``excess_efolds >= lyapunov_efolds`` and ``lambda > lyapunov_ratio *
        lambda_control`` (:class:`~attitude.model.regimes.Thresholds`).
    duration, interval, separation : float
        s, s, dimensionless (the metric of :mod:`attitude.binary.chaos`).
    method : str
        ``"lgvi"`` or ``"integrator"``.
    times, local_exponents : ndarray
        End of each interval (s) and ``ln(d_k / d_0) / interval`` (1/s).

    Examples
    --------
    >>> r = BinaryLyapunov(2e-5, 1e-6, 1e-7, 1e-7, 19.9, True, 1e6, 1.5e4, 1e-8,
    ...                    "lgvi", np.zeros(0), np.zeros(0))
    >>> r.lyapunov_time
    50000.0
    """

    exponent: float
    uncertainty: float
    control_exponent: float | None
    control_uncertainty: float | None
    excess_efolds: float
    chaotic: bool
    duration: float
    interval: float
    separation: float
    method: str
    times: np.ndarray = field(repr=False)
    local_exponents: np.ndarray = field(repr=False)
    thresholds: Thresholds = field(default_factory=Thresholds, repr=False)

    @property
    def lyapunov_time(self) -> float:
        """``1 / lambda`` (s); ``inf`` when ``lambda <= 0``."""
        return 1.0 / self.exponent if self.exponent > 0 else math.inf


def kepler_control(system: BinarySystem) -> BinarySystem:
    """The integrable control of ``system``: the same masses and moments' traces as two
    homogeneous spheres (a Keplerian orbit, free spins), order 2.

    Examples
    --------
    >>> import attitude as att
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> control = kepler_control(system)
    >>> bool(np.array_equal(control.masses, system.masses)), control.order
    (True, 2)
    """
    bodies = []
    for body, m in zip((system.primary, system.secondary), system.masses):
        radius = math.sqrt(2.5 * float(np.trace(body.inertia)) / 3.0 / m)
        bodies.append(RigidBody.from_mass_properties(MassProperties.solid_sphere(m, radius)))
    return BinarySystem(*bodies, order=2, G=system.G)


def _difference(y, yp, scales) -> np.ndarray:
    """The scaled displacement (18,) from ``y`` to ``yp``."""
    r0, v0, n = scales
    R, V, q1, w1, q2, w2 = unpack(y)
    Rp, Vp, q1p, w1p, q2p, w2p = unpack(yp)
    th1 = (Rotation.from_quat(q1).inv() * Rotation.from_quat(q1p)).as_rotvec()
    th2 = (Rotation.from_quat(q2).inv() * Rotation.from_quat(q2p)).as_rotvec()
    return np.concatenate([(Rp - R) / r0, (Vp - V) / v0, th1, (w1p - w1) / n, th2,
                           (w2p - w2) / n])


def _displaced(y, delta, scales) -> np.ndarray:
    """``y`` displaced by the scaled displacement ``delta`` (18,)."""
    r0, v0, n = scales
    R, V, q1, w1, q2, w2 = unpack(y)
    q1p = (Rotation.from_quat(q1) * Rotation.from_rotvec(delta[6:9])).as_quat()
    q2p = (Rotation.from_quat(q2) * Rotation.from_rotvec(delta[12:15])).as_quat()
    return pack(R + delta[0:3] * r0, V + delta[3:6] * v0, q1p, w1 + delta[9:12] * n, q2p,
                w2 + delta[15:18] * n)


def _ftle(system, y0, knots, bounds, separation, method, step, rtol, seed):
    """Local exponents over the intervals ``knots[bounds[k]] .. knots[bounds[k+1]]``;
    each trajectory is propagated through every knot inside (the run's own grid)."""
    scales = system_scales(system, y0)
    rng = np.random.default_rng(seed)
    u = rng.normal(size=18)
    u *= separation / np.linalg.norm(u)
    y, yp = np.asarray(y0, float), _displaced(y0, u, scales)
    local = np.empty(len(bounds) - 1)
    for k in range(local.size):
        t = knots[bounds[k]:bounds[k + 1] + 1] - knots[bounds[k]]
        ends = []
        for start in (y, yp):
            if method == "lgvi":
                ends.append(integrate_lgvi(system, start, t, step)[-1])
            else:
                ends.append(integrate_dop853(system, start, t, rtol=rtol)[-1])
        delta = _difference(ends[0], ends[1], scales)
        d = float(np.linalg.norm(delta))
        if not d > 0:
            d = separation * 1e-300
        local[k] = math.log(d / separation) / t[-1]
        y, yp = ends[0], _displaced(ends[0], delta * (separation / d), scales)
    return local


def _bounds(size: int, intervals: int) -> np.ndarray:
    """Indices of the renormalisation times among ``size`` knots (equal shares)."""
    m = max(1, min(int(intervals), size - 1))
    return np.unique(np.round(np.linspace(0, size - 1, m + 1)).astype(int))


def lyapunov_exponent(system: BinarySystem, state, times, *, intervals: int = 64,
                      separation: float = 1e-8, method: str = "lgvi", step=None,
                      rtol: float = 1e-10, control: bool = True, seed: int = 0,
                      thresholds: Thresholds | None = None) -> BinaryLyapunov:
    r"""Finite-time maximal Lyapunov exponent of a binary, with its Keplerian control.

    The reference from ``state`` and a copy displaced by ``separation`` (the metric of
    :mod:`attitude.binary.chaos`, a random direction from ``seed``) are propagated
    through ``times`` with ``method`` (the run's: the same step or tolerance) and
    renormalised at ``intervals`` equal shares of the times (Benettin et al. 1980):
    ``lambda = sum_k ln(d_k / d_0) / duration``.  The control is the same state on
    :func:`kepler_control` (``control=False``: none; the test is then ``lambda *
    duration >= lyapunov_efolds`` alone).

    Parameters
    ----------
    system : BinarySystem
    state : BinaryState or ndarray (20,)
        The start (a state vector of :mod:`attitude.binary.dynamics` at time 0).
    times : array-like
        s since the start, sorted, from 0; more than ``intervals`` of them to renormalise
        at each share (the LGVI steps end at each: give the run's output times to follow
        its grid).  A single number ``T``: ``intervals + 1`` equal times over ``[0, T]``.
    intervals : int
        Renormalisations (keep ``lambda * duration / intervals`` below ~10).
    separation : float
        ``d_0``, in (0, 1e-3).
    method : {"lgvi", "integrator"}
    step : float, optional
        The LGVI's longest step, s (default :func:`attitude.binary.lgvi.default_step`).
    rtol : float
        DOP853's tolerance (``"integrator"``): 1e-10 keeps its error well below ``d_0``.

    Returns
    -------
    BinaryLyapunov

    Raises
    ------
    BinarySystemError
        Bad ``times``, ``intervals``, ``separation`` or ``method``.

    References
    ----------
    .. [1] Benettin, G., Galgani, L., Giorgilli, A. & Strelcyn, J.-M. (1980). Lyapunov
       characteristic exponents for smooth dynamical systems. *Meccanica* 15, 9-20.
    .. [2] Wisdom, J., Peale, S. J. & Mignard, F. (1984). The chaotic rotation of
       Hyperion. *Icarus* 58, 137-152.

    Examples
    --------
    A secondary locked in a small libration is regular:

    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ellipsoid = att.MassProperties.solid_ellipsoid
    >>> system = att.BinarySystem(
    ...     att.RigidBody.from_mass_properties(ellipsoid(5.2e11, [400.0, 400.0, 400.0])),
    ...     att.RigidBody.from_mass_properties(ellipsoid(4.3e9, [103.0, 79.0, 66.0])))
    >>> n = np.sqrt(system.mu / 1190.0**3)
    >>> state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
    ...                         Rotation.identity(), [0, 0, 0],
    ...                         Rotation.from_euler("z", 5, degrees=True), [0, 0, n])
    >>> r = lyapunov_exponent(system, state, 4 * 2 * np.pi / n, intervals=8, step=600.0)
    >>> r.chaotic
    False
    """
    th = thresholds or Thresholds()
    if method not in ("lgvi", "integrator"):
        raise BinarySystemError(f"method: expected 'lgvi' or 'integrator', got {method!r}")
    if int(intervals) < 2:
        raise BinarySystemError(f"intervals: must be >= 2, got {intervals!r}")
    if not 0 < separation < 1e-3:
        raise BinarySystemError(f"separation: must be in (0, 1e-3), got {separation!r}")
    if isinstance(state, BinaryState):
        y0 = initial_vector(state)
    else:
        y0 = np.asarray(state, float).reshape(20)
    t = np.atleast_1d(np.asarray(to_si(times, "s", key="times", error=BinarySystemError),
                                 float))
    if t.size == 1:
        t = np.linspace(0.0, float(t[0]), int(intervals) + 1)
    if t[0] != 0 or t.size < 3 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise BinarySystemError("times: sorted, distinct, finite times from 0 s (at least "
                                "three), or one duration")
    bounds = _bounds(t.size, intervals)
    h = None
    if method == "lgvi":
        h = float(to_si(step, "s", key="step", shape=(), positive=True,
                        error=BinarySystemError)) if step is not None else \
            default_step(system, y0)
    local = _ftle(system, y0, t, bounds, separation, method, h, rtol, seed)
    widths = np.diff(t[bounds])
    duration = float(t[bounds[-1]])
    lam = float(np.sum(local * widths) / duration)
    sig = batch_means_error(local)
    lam_c = sig_c = None
    if control:
        c_system = kepler_control(system)
        c_h = default_step(c_system, y0) if h is None else h
        c_local = _ftle(c_system, y0, t, bounds, separation, method, c_h, rtol, seed)
        lam_c = float(np.sum(c_local * widths) / duration)
        sig_c = batch_means_error(c_local)
    excess = (lam - (lam_c or 0.0)) * duration
    chaotic = bool(excess >= th.lyapunov_efolds
                   and lam > th.lyapunov_ratio * max(lam_c or 0.0, 0.0))
    return BinaryLyapunov(
        exponent=lam, uncertainty=sig, control_exponent=lam_c, control_uncertainty=sig_c,
        excess_efolds=float(excess), chaotic=chaotic, duration=duration,
        interval=float(widths.mean()), separation=float(separation), method=method,
        times=t[bounds[1:]], local_exponents=local, thresholds=th)
