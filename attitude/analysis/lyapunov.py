r"""Finite-time Lyapunov exponents of propagated rotations: the test for chaos.

Two nearby trajectories (Benettin et al. 1980) are propagated with
:func:`attitude.propagate` and renormalised at equal intervals; the exponent is
compared with that of a regular control run (by default the same body and state
without torques, an integrable motion).  :func:`attitude.analysis.classification` calls
:func:`lyapunov_exponent` to call a perturbed run ``chaotic`` (Hyperion, Wisdom, Peale &
Mignard 1984); the thresholds are :class:`attitude.model.regimes.Thresholds`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations.errors import ClassificationError
from ..foundations.quantities import to_si
from ..model import torques as tq
from ..model.body import RigidBody
from ..model.regimes import Thresholds
from ..model.state import AttitudeState
from ..propagation.propagator import propagate
from ..propagation.splitting import choose_step

__all__ = ["LyapunovResult", "lyapunov_exponent"]


@dataclass(frozen=True)
class LyapunovResult:
    """A finite-time Lyapunov exponent and its regular control.

    Attributes
    ----------
    exponent, uncertainty : float
        ``lambda`` (1/s) and its standard error (batch means of the local exponents).
    control_exponent, control_uncertainty : float or None
        The same for the regular control run (default: the same body and state without
        torques, an integrable motion), same duration and intervals.
    excess_efolds : float
        ``(lambda - lambda_control) * duration``: how many e-folds more the displaced
        trajectory separated than in the control.
    significance : float
        ``(lambda - lambda_control) / sqrt(sigma^2 + sigma_control^2)`` (information:
        the local exponents of a chaotic run are intermittent, so their standard error
        converges slowly).
    chaotic : bool
        ``excess_efolds >= lyapunov_efolds`` and ``lambda > lyapunov_ratio *
        lambda_control`` (:class:`Thresholds`).
    duration, interval, separation : float
        Total time (s), renormalisation interval (s), initial separation (dimensionless
        phase-space distance, see :func:`lyapunov_exponent`).
    times, local_exponents : ndarray
        End of each interval (s) and ``ln(d_k / d_0) / interval`` there (1/s).
    control_local_exponents : ndarray or None
    method : str
        Propagator used (``att.propagate`` ``method=``).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.analysis.lyapunov import lyapunov_exponent
    >>> r = lyapunov_exponent(body, state, None, 2000.0, intervals=8)
    >>> r.chaotic                         # a free rigid body is regular
    False
    """

    exponent: float
    uncertainty: float
    control_exponent: float | None
    control_uncertainty: float | None
    excess_efolds: float
    significance: float
    chaotic: bool
    duration: float
    interval: float
    separation: float
    method: str
    times: np.ndarray = field(repr=False)
    local_exponents: np.ndarray = field(repr=False)
    control_local_exponents: np.ndarray | None = field(default=None, repr=False)
    thresholds: Thresholds = field(default_factory=Thresholds, repr=False)

    @property
    def lyapunov_time(self) -> float:
        """``1 / lambda`` (s); ``inf`` when ``lambda <= 0``."""
        return 1.0 / self.exponent if self.exponent > 0 else math.inf

    @property
    def running_exponent(self) -> np.ndarray:
        """Finite-time exponent over ``[0, times[k]]`` (1/s), for convergence plots."""
        return np.cumsum(self.local_exponents) / np.arange(1, self.times.size + 1)


def _shift_torque(torque, t0: float):
    """The same torque for a propagation restarted ``t0`` seconds after the epoch: the
    model's own :meth:`~attitude.torques.TorqueModel.shifted` (a plain function is
    wrapped first), so a user's model is shifted like a built-in one."""
    if t0 == 0.0:
        return torque
    return tq.as_torque_model(torque).shifted(t0)


def batch_means_error(g: np.ndarray) -> float:
    """Standard error of the mean of correlated local exponents (batch means: 2 to 8
    batches); also the binary wing's (:mod:`attitude.binary.chaos`)."""
    n = g.size
    if n < 2:
        return math.inf
    nb = max(2, min(8, n // 4))
    size = n // nb
    means = g[: nb * size].reshape(nb, size).mean(axis=1)
    return float(means.std(ddof=1) / math.sqrt(nb))


def _ftle(body, state, torques, duration, intervals, separation, rate_scale, method,
          rtol, seed, step=None):
    tau = duration / intervals
    rng = np.random.default_rng(seed)
    v = rng.normal(size=6)
    v /= np.linalg.norm(v)
    d0 = separation
    w_ref = np.asarray(state.omega_body, dtype=float)
    ws = rate_scale or float(np.linalg.norm(w_ref)) or 1.0
    R = state.attitude
    q = R.as_quat()
    qp = (R * Rotation.from_rotvec(d0 * v[:3])).as_quat()
    w, wp = w_ref.copy(), w_ref + d0 * v[3:] * ws
    g = np.empty(intervals)
    kwargs = {} if rtol is None else {"rtol": rtol}
    if method is not None:
        kwargs["method"] = method
    # the splitting method: one step for the whole run and both trajectories (computed
    # once, as a single propagation would), each trajectory on the one-body fast path
    apart = bool(torques) and method == "splitting"
    if apart:
        kwargs["step"] = choose_step(body, q, w, torques) if step is None else step
    for k in range(intervals):
        t0 = k * tau
        tq_k = [_shift_torque(x, t0) for x in torques] if torques else None
        s1 = AttitudeState(state.epoch, Rotation.from_quat(q), w, state.frame)
        s2 = AttitudeState(state.epoch, Rotation.from_quat(qp), wp, state.frame)
        if apart:
            ends = [propagate(body, s, [tau], torques=tq_k, **kwargs).dataset
                    for s in (s1, s2)]
            Q = np.stack([e["quaternion"].values.reshape(-1, 4)[-1] for e in ends])
            W = np.stack([e["angular_velocity"].values.reshape(-1, 3)[-1] for e in ends])
        else:
            eph = propagate([body, body], [s1, s2], [tau], torques=tq_k, **kwargs)
            Q = eph.dataset["quaternion"].values[:, -1]
            W = eph.dataset["angular_velocity"].values[:, -1]
        dr = (Rotation.from_quat(Q[0]).inv() * Rotation.from_quat(Q[1])).as_rotvec()
        dw = (W[1] - W[0]) / ws
        d = math.sqrt(float(dr @ dr + dw @ dw))
        if not d > 0:
            d = d0 * 1e-300
        g[k] = math.log(d / d0)
        scale = d0 / d
        q, w = Q[0], W[0]
        qp = (Rotation.from_quat(q) * Rotation.from_rotvec(dr * scale)).as_quat()
        wp = w + dw * scale * ws
    local = g / tau
    return local, tau


def lyapunov_exponent(body: RigidBody, state: AttitudeState, torques: Sequence | None,
                      duration, *, intervals: int = 64, separation: float = 1e-8,
                      rate_scale: float | None = None, method: str | None = None,
                      rtol="auto", control="torque-free", seed: int = 0,
                      thresholds: Thresholds | None = None,
                      step: float | None = None) -> LyapunovResult:
    r"""Finite-time maximal Lyapunov exponent of a propagated rotation, with a control.

    Two nearby trajectories (Benettin et al. 1980): the reference from ``state`` and a
    copy displaced by ``separation`` in the phase-space metric

    .. math::
        d = \sqrt{|\delta\mathbf r|^2 + |\delta\omega|^2 / \omega_s^2}

    (``delta r`` the rotation vector from the reference attitude to the displaced one,
    body frame, rad; ``omega_s = rate_scale``, default ``|omega_0|``) are propagated with
    ``att.propagate`` over ``intervals`` equal intervals; after each, the separation
    ``d_k`` is recorded and the displacement rescaled back to ``separation`` along its
    current direction.  ``lambda = sum_k ln(d_k / d_0) / duration``.

    The regular control (same duration and intervals) is, by default, the same body and
    state without torques (Euler–Poinsot motion is integrable: its finite-time exponent
    only decays like ``ln(t)/t``); ``control=None`` skips it, or give
    ``(body, state, torques)`` for another.  Chaotic when the displaced trajectory
    separated by ``thresholds.lyapunov_efolds`` e-folds more than in the control,
    ``(lambda - lambda_control) * duration >= lyapunov_efolds``, and
    ``lambda > thresholds.lyapunov_ratio * lambda_control``.

    Parameters
    ----------
    body, state : RigidBody, AttitudeState
    torques : sequence of torque models or None
        Time-dependent models are shifted to each interval's start with their
        :meth:`~attitude.torques.TorqueModel.shifted` (Keplerian gravity gradient
        exactly, through the mean anomaly; a user model through its own method or the
        default wrapper).
    duration : float, Quantity or str
        Total time, s.
    intervals : int
        Renormalisations (choose so that ``lambda * duration / intervals`` stays below
        ~10: the separation must stay small).
    separation : float
        Initial and renormalised separation ``d_0``.
    rate_scale : float, optional
        ``omega_s`` of the metric, rad/s.
    method : str, optional
        ``att.propagate`` method.  Default: ``"integrator"`` with torques (the restarts
        favour it: on Hyperion it is several times faster than ``"splitting"`` at
        ``rtol = 1e-10``), ``"exact"`` without.
    rtol : float, None or "auto"
        Relative tolerance of ``method="integrator"``; ``"auto"``: 1e-10 (ample for
        separations of 1e-8, and several times faster than its default 1e-13); None:
        propagate's default.
    control : "torque-free", None or tuple
        The regular control run: ``"torque-free"`` (default), ``None`` (none), or a
        ``(body, state, torques)`` tuple.
    seed : int
        Seed of the random initial displacement direction.
    step : float, optional
        Longest step of ``method="splitting"``, s (the one the run itself used, e.g. a
        scenario's ``integrator_step``); default
        :func:`~attitude.propagation.splitting.choose_step`.  Ignored by the other methods.

    Returns
    -------
    LyapunovResult

    References
    ----------
    .. [1] Benettin, G., Galgani, L., Giorgilli, A. & Strelcyn, J.-M. (1980). Lyapunov
       characteristic exponents for smooth dynamical systems. *Meccanica* 15, 9-20.
    .. [2] Wisdom, J., Peale, S. J. & Mignard, F. (1984). The chaotic rotation of
       Hyperion. *Icarus* 58, 137-152.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> r = lyapunov_exponent(body, state, None, 2000.0, intervals=8)
    >>> bool(abs(r.exponent) < 5 * r.uncertainty + 1e-3)
    True
    """
    th = thresholds or Thresholds()
    duration = to_si(duration, "s", key="duration", shape=(), positive=True,
                     error=ClassificationError)
    if int(intervals) < 2:
        raise ClassificationError(f"intervals must be >= 2, got {intervals!r}")
    if not 0 < separation < 1e-2:
        raise ClassificationError(f"separation must be in (0, 1e-2), got {separation!r}")
    torques = list(torques or [])
    if method is None:
        method = "integrator" if torques else "exact"
    if isinstance(rtol, str):
        if rtol != "auto":
            raise ClassificationError(f"rtol must be a number, None or 'auto', got {rtol!r}")
        rtol = 1e-10 if torques and method == "integrator" else None
    local, tau = _ftle(body, state, torques, duration, int(intervals), separation,
                       rate_scale, method, rtol if torques else None, seed, step)
    lam = float(local.mean())
    sig = batch_means_error(local)
    c_local = None
    lam_c = sig_c = None
    if control is not None:
        if control == "torque-free":
            cb, cs, ct = body, state, []
        else:
            cb, cs, ct = control
            ct = list(ct or [])
        c_local, _ = _ftle(cb, cs, ct, duration, int(intervals), separation, rate_scale,
                           None if not ct else method, rtol if ct else None, seed, step)
        lam_c = float(c_local.mean())
        sig_c = batch_means_error(c_local)
    comb = math.hypot(sig, sig_c or 0.0)
    excess = lam - (lam_c or 0.0)
    significance = excess / comb if comb > 0 else (math.inf if excess > 0 else 0.0)
    efolds = excess * duration
    chaotic = bool(efolds >= th.lyapunov_efolds
                   and lam > th.lyapunov_ratio * max(lam_c or 0.0, 0.0))
    used = method
    return LyapunovResult(
        exponent=lam, uncertainty=sig, control_exponent=lam_c, control_uncertainty=sig_c,
        excess_efolds=float(efolds), significance=float(significance), chaotic=chaotic,
        duration=duration, interval=tau,
        separation=float(separation), method=used,
        times=tau * np.arange(1, local.size + 1), local_exponents=local,
        control_local_exponents=c_local, thresholds=th)
