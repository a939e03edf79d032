r"""Splitting integrators: the exact free rigid-body flow composed with torque kicks.

Euler's equations with a torque split into two vector fields,

.. math::

    \underbrace{\dot q = \tfrac12 q\otimes\omega,\;
    I\dot\omega = I\omega\times\omega}_{\text{free rigid body } F}
    \;+\;
    \underbrace{\dot q = 0,\; I\dot\omega = M(t, q, \omega)}_{\text{kick } K} ,

each of which is solved on its own: the free flow :math:`\varphi^F_h` *exactly*
(Jacobi elliptic functions and an elliptic integral of the third kind, see
:func:`free_flow`), the kick with the attitude frozen.  For a torque that depends on
the attitude only (gravity gradient, constant, heavy-top pivot:
``velocity_dependent = False``) the kick is exact, ``omega += h I^-1 M(t, q)``, and is
the flow of the potential energy: every composition of these flows is a Lie–Poisson
(symplectic) map, and a symmetric composition is time-reversible.  Velocity-dependent
torques (eddy currents) are integrated inside the kick by a Runge–Kutta step with the
attitude frozen (explicit midpoint for order 2, classical RK4 otherwise).  Internal
torques (``internal = True``: dissipation) turn ``L`` in the body frame only: their kick
also turns the attitude, at ``(M x L)/L^2``, and ends by restoring the inertial ``L``, so
that it does not drift (``System.internal_kick``).

Compositions (``order=`` / ``scheme=``; ``K(b h) F(a h) K(...) ...``):

=======================  =====  =====================================================
scheme                   order  free flows per step (kicks merge between steps)
=======================  =====  =====================================================
``"strang"``             2      1  (Strang 1968; Touma & Wisdom 1994 for the rigid body)
``"yoshida4"``           4      3  (Yoshida 1990 triple jump: cheap, large error)
``"blanes-moan"``        4      6  (Blanes & Moan 2002, S6: any splitting)
``"blanes-moan-rkn"``    4      6  (Blanes & Moan 2002, SRKN6b: attitude-only torques)
``"yoshida6"``           6      7  (Yoshida 1990, solution A)
=======================  =====  =====================================================

``order=4`` (the default) takes ``"blanes-moan-rkn"`` when every torque depends on the
attitude only (its order conditions use ``[K, [K, [K, F]]] = 0``, true for such kicks
as for ``p^2/2 + V(q)``; ~10x smaller error than S6 at the same cost), else
``"blanes-moan"``.  With velocity-dependent torques the order is ``min(order, 4)`` (the
RK sub-step is of order 2 for Strang, 4 otherwise; the limit shows only when the damping
is fast on the step).  With no torque at all every scheme is the exact solution to
round-off.  The default step is :func:`choose_step`: set by the torques' own time scales
(:meth:`attitude.model.torques.TorqueModel.characteristic_rate`) and by how fast each torque
changes along the free motion, not by the spin.  ``docs/integrators.md`` has the
formulas, the measured orders, accuracy and timings, and which method to use when.

The parts live in modules of their own, each name still importable from here:
:mod:`.freeflow` (the exact free flow, :func:`free_flow`), :mod:`.schemes` (the
compositions and their coefficients), :mod:`.kicks` (bodies, torques and the kick) and
:mod:`.stepsize` (:func:`choose_step`); this module drives them.

Time is carried in the extended phase space: the free flow advances ``t``, the kick is
evaluated at the current ``t`` (so orbit-dependent torques keep the order of the
scheme, and symmetric schemes remain time-reversible).

References
----------
.. [1] Touma, J. & Wisdom, J. (1994). Lie-Poisson integrators for rigid body dynamics
   in the solar system. *Astron. J.* 107, 1189-1202.
.. [2] Celledoni, E., Fassò, F., Säfström, N. & Zanna, A. (2008). The exact
   computation of the free rigid body motion and its use in splitting methods.
   *SIAM J. Sci. Comput.* 30, 2084-2112.
.. [3] McLachlan, R. I. & Quispel, G. R. W. (2002). Splitting methods. *Acta Numerica*
   11, 341-434.
.. [4] Yoshida, H. (1990). Construction of higher order symplectic integrators.
   *Phys. Lett. A* 150, 262-268.
.. [5] Blanes, S. & Moan, P. C. (2002). Practical symplectic partitioned Runge-Kutta and
   Runge-Kutta-Nyström methods. *J. Comput. Appl. Math.* 142, 313-330.
.. [6] Carlson, B. C. (1995). Numerical computation of real or complex elliptic
   integrals. *Numer. Algorithms* 10, 13-26; DLMF §19.25, §22.
"""


from __future__ import annotations

import math

import numpy as np

from ..deprecation import moved_attribute
from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError, PropagationError
from ..foundations.progress import Progress, duration_text
from ..model.body import as_bodies, to_body_frame
from . import compiled, compiled_loop
from .compiled_torques import compile_torques_shared

# The splitting in modules of its own: the exact free flow, the compositions, the bodies
# and kicks, the step rule; the public names are importable from here as before.
from .freeflow import FreeConstants, free_flow, free_flow_batch, free_flow_tuple
from .kicks import BatchOps, OneOps, System, torque_kick
from .reference import checked_rtol
from .schemes import (
    DEFAULT_SCHEME,
    EMBEDDED,
    LIE,
    RKN_SCHEMES,
    SCHEMES,
    Scheme,
    controller_exponent,
    resolve_scheme,
)
from .stepsize import STEPS_PER_PERIOD, choose_step, default_step

__all__ = [
    "integrate_splitting",
    "free_flow",
    "choose_step",
    "SCHEMES",
    "DEFAULT_SCHEME",
    "STEPS_PER_PERIOD",
    "step_count",
]


#: The free flow's names that tests and benchmarks import from here (their old homes).
_FreeConstants, _free_flow_vec, _free_flow1 = FreeConstants, free_flow_batch, free_flow_tuple


def __getattr__(name):
    # names that moved to another module: a DeprecationWarning naming the new home
    return moved_attribute(__name__, name)


def _progress(total: float, enabled: bool) -> Progress:
    """The report of a run (:mod:`attitude.foundations.progress`): simulated time."""
    return Progress(total, "propagation", unit="simulated", show=enabled,
                    amount=duration_text)


# ===========================================================================
# stepping
# ===========================================================================
def _segments(t: np.ndarray) -> list[np.ndarray]:
    """Indices of the outputs, per direction (t >= 0, then t < 0), in order of |t|."""
    out = []
    for sign in (1.0, -1.0):
        idx = np.flatnonzero(t >= 0) if sign > 0 else np.flatnonzero(t < 0)
        if idx.size:
            out.append(idx[np.argsort(sign * t[idx], kind="stable")])
    return out


def step_count(dt: float, h_max: float) -> int:
    """Number of equal steps no longer than ``h_max`` that cover ``dt``.

    Examples
    --------
    >>> step_count(10.0, 3.0), step_count(9.0, 3.0), step_count(0.0, 3.0)
    (4, 3, 0)
    """
    if dt == 0.0:
        return 0
    if not math.isfinite(h_max):
        return 1
    return max(1, math.ceil(abs(dt) / h_max * (1.0 - 1e-12)))



#: Relative distance of an output time to a step boundary below which the step is
#: stretched to end on the output (a change of the step at the level of its rounding).
SNAP = 1e-9


class _Stepper:
    """One composition step of the splitting over ``h``, and the state between steps.

    The loop keeps the state just after the last free flow, ``(q, w)`` at time ``t``,
    and the *pending* kick ``tau`` that closes the step (the last kick of a step and
    the first of the next act at the same time and attitude, so they merge).  The state
    at the step boundary, needed only for outputs and the error estimate, is that state
    with the pending kick applied (:meth:`boundary`).
    """

    def __init__(self, ops, scheme: Scheme, has_kick, has_drag, has_internal, rk_order,
                 anchor):
        self.ops = ops
        self.scheme = scheme
        self.has_kick, self.has_drag = has_kick, has_drag
        self.has_internal = has_internal
        self.rk_order = rk_order
        self.anchor = anchor
        self.free_flows = 0

    def kick(self, t, q, w, tau, cached):
        if tau == 0.0:
            return q, w, cached
        if self.has_internal:
            q, w = self.ops.internal(t, q, w, tau, self.rk_order, self.anchor)
            return q, w, None
        w, cached = torque_kick(self.ops, t, q, w, tau, cached, self.has_kick,
                                self.has_drag, self.rk_order)
        return q, w, cached

    def boundary(self, t, q, w, pending, cached):
        """The state at the step boundary ``t``: the pending kick applied."""
        q, w, cached = self.kick(t, q, w, pending, cached)
        return q, w, cached

    def step(self, t, q, w, pending, h, cached, scheme: Scheme | None = None):
        """One step of ``scheme`` (default the run's) over ``h`` from the state after the
        last free flow with its pending kick: ``(q, w, new pending)`` at ``t + h``."""
        scheme = self.scheme if scheme is None else scheme
        acc = 0.0
        b, a = scheme.b, scheme.a
        for i in range(len(a)):
            q, w, cached = self.kick(t + acc * h, q, w, (pending if i == 0 else 0.0)
                                     + b[i] * h, cached)
            q, w = self.ops.free(q, w, a[i] * h)
            self.free_flows += 1
            cached = None
            acc += a[i]
        return q, w, b[-1] * h


def _rtol_error(w0, q_hi, w_hi, q_lo, w_lo, rtol, w_floor) -> float:
    """Error of a trial step relative to ``rtol``: the larger of ``|dq|`` (the
    quaternion has norm 1; the nearer of ``q`` and ``-q``) and
    ``|dw| / max(|w|, |w'|, w_floor)``, over the bodies."""
    q_hi, q_lo = np.asarray(q_hi, dtype=float), np.asarray(q_lo, dtype=float)
    # q and -q are one attitude: the nearer of the two
    dq = np.minimum(np.sqrt(np.sum((q_hi - q_lo) ** 2, axis=-1)),
                    np.sqrt(np.sum((q_hi + q_lo) ** 2, axis=-1)))
    dw = np.asarray(w_hi, dtype=float) - np.asarray(w_lo, dtype=float)
    w0 = np.asarray(w0, dtype=float)
    w1 = np.asarray(w_hi, dtype=float)
    scale = np.maximum(np.maximum(np.sqrt(np.sum(w0 * w0, axis=-1)),
                                  np.sqrt(np.sum(w1 * w1, axis=-1))), w_floor)
    err = np.maximum(dq, np.sqrt(np.sum(dw * dw, axis=-1)) / scale)
    return float(np.max(err)) / rtol



def _march(stepper: _Stepper, q, w, t0: float, times, store, h: float, *, mode: str,
           rtol: float | None = None, embedded: Scheme | None = None, expo: float = 0.0,
           w_floor: float = 0.0, h_limit: float = math.inf, bar=None) -> None:
    """Advance one direction of a run and hand every output to ``store(j, q, w)``.

    ``times``: ``(index, time relative to t0)`` pairs in order of increasing ``|time|``,
    all of one sign.  Modes: ``"dense"`` (steps of ``h`` from ``t0``, outputs inside a
    step by a partial step from its start), ``"cut"`` (each interval between outputs
    cut into equal steps no longer than ``h``) and ``"rtol"`` (steps chosen by the
    error estimate, outputs as in ``"dense"``; ``expo`` is the controller's exponent,
    :func:`controller_exponent`).
    """
    if not times:
        return
    sign = 1.0 if times[-1][1] >= 0 else -1.0
    pending, cached, t_now, k = 0.0, None, 0.0, 0
    tol = SNAP * (abs(h) if math.isfinite(h) else abs(times[-1][1]))
    j = 0
    while j < len(times):
        idx, tj = times[j]
        if abs(tj - t_now) <= tol or tj == t_now:
            qb, wb, cached = stepper.boundary(t0 + t_now, q, w, pending, cached)
            store(idx, qb, wb)
            j += 1
            continue
        if mode == "cut":
            n = step_count(tj - t_now, h)
            hh = (tj - t_now) / n
            for i in range(n):
                q, w, pending = stepper.step(t0 + t_now + i * hh, q, w, pending, hh, cached)
                cached = None
            if bar is not None:
                bar.update(abs(tj - t_now))
            t_now = tj
            continue
        if mode == "dense":
            t_next = sign * (k + 1) * h if math.isfinite(h) else times[-1][1]
            if abs(t_next - times[-1][1]) <= tol:
                t_next = times[-1][1]
        else:                                            # rtol: a trial step
            hh = sign * min(h, h_limit)
            t_next = t_now + hh
            last = times[-1][1]
            if sign * (t_next - last) > -tol:             # do not step past the last output
                t_next = last
            # the embedded step starts from the state at the step boundary (one per step)
            q_b, w_b, cached = stepper.boundary(t0 + t_now, q, w, pending, cached)
            while True:
                hh = t_next - t_now
                q_pre, w_pre, pend_new = stepper.step(t0 + t_now, q, w, pending, hh, cached)
                q_hi, w_hi, c_hi = stepper.boundary(t0 + t_next, q_pre, w_pre, pend_new, None)
                ql, wl, pl = stepper.step(t0 + t_now, q_b, w_b, 0.0, hh, cached, embedded)
                q_lo, w_lo, _ = stepper.boundary(t0 + t_next, ql, wl, pl, None)
                err = _rtol_error(w_b, q_hi, w_hi, q_lo, w_lo, rtol, w_floor)
                if err <= 1.0:
                    break
                factor = max(0.2, 0.9 * err ** -expo) if math.isfinite(err) else 0.2
                h = abs(hh) * factor
                if h <= 1e-12 * max(abs(t_now), abs(hh)):
                    raise PropagationError(f"splitting with rtol={rtol:g}: the step fell "
                                           f"below round-off at t = {t0 + t_now:.9g} s; "
                                           "loosen rtol or use method='integrator'",
                                           key="rtol")
                t_next = t_now + sign * h
            grow = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** -expo))
            h = abs(hh) * grow
        # outputs strictly inside (t_now, t_next): partial steps from the step's start
        while j < len(times) and sign * (times[j][1] - t_next) < -tol:
            idx, tj = times[j]
            if abs(tj - t_now) <= tol:
                qb, wb, cached = stepper.boundary(t0 + t_now, q, w, pending, cached)
            else:
                qp, wp, pp = stepper.step(t0 + t_now, q, w, pending, tj - t_now, cached)
                qb, wb, _ = stepper.boundary(t0 + tj, qp, wp, pp, None)
            store(idx, qb, wb)
            j += 1
        if j == len(times):
            break
        if mode == "rtol":
            q, w, pending, cached = q_pre, w_pre, pend_new, c_hi
        else:
            q, w, pending = stepper.step(t0 + t_now, q, w, pending, t_next - t_now, cached)
            cached = None
            k += 1
        if bar is not None:
            bar.update(abs(t_next - t_now))
        t_now = t_next


def _compiled_specs(system: System, body_list, t0: float, t: np.ndarray, supported: bool):
    """Per body, the compiled forms of the kick, drag and internal torques, or ``None``
    if a model has none (or internal torques act together with external ones).  The
    bodies share one ``params`` array: a path or field (a TLE orbit's, the Sun's, IGRF's
    tables) is laid out once for the whole batch."""
    if not supported or not system.terms:
        return None
    span = (t0 + float(min(0.0, np.min(t))), t0 + float(max(0.0, np.max(t))))
    groups = (system.kick_terms, system.drag_terms, system.internal_terms)
    shared = compile_torques_shared(groups, body_list, t_span=span)
    if shared is None:
        return None
    return [[(c.kinds, c.offsets, c.params) for c in row] for row in shared]


def _run_compiled(system, specs, q_p0, w_p0, t, t0, segments, h, h_limit, expo, mode,
                  rtol, scheme, embedded, rk_order, w_floor, anchor, out_q, out_w, bar):
    """Each body through :func:`attitude.propagation.compiled_loop.march_one`, the
    bodies of a batch on a thread per core (the compiled loop releases the GIL); the
    progress bar moves body by body."""
    flags = (bool(system.kick_terms), bool(system.drag_terms), bool(system.internal_terms))
    coeffs = (np.array(scheme.b), np.array(scheme.a))
    emb = embedded if embedded is not None else scheme
    ecoeffs = (np.array(emb.b), np.array(emb.a))

    def run(i, groups):
        fc = np.array(system.free.row(i), dtype=float)
        frame = (np.ascontiguousarray(system.q_bp[i], dtype=float), system.identity,
                 np.ascontiguousarray(system.inv_moments[i], dtype=float))
        torq = (tuple(groups[0]), tuple(groups[1]), tuple(groups[2]), flags)
        moments = np.ascontiguousarray(system.moments[i], dtype=float)
        anc = (np.ascontiguousarray(anchor[i], dtype=float) if anchor is not None
               else np.zeros(3))
        for idx in segments:
            times = np.ascontiguousarray(t[idx], dtype=float)
            oq = np.empty((idx.size, 4))
            ow = np.empty((idx.size, 3))
            code = compiled_loop.march_one(
                fc, torq, frame, moments, anc, coeffs, ecoeffs,
                np.ascontiguousarray(q_p0[i]), np.ascontiguousarray(w_p0[i]), t0, times,
                float(h), compiled_loop.MODES[mode], float(rtol or 0.0), expo, w_floor,
                h_limit, SNAP, rk_order, oq, ow)
            if code < 0:
                raise PropagationError(
                    f"splitting with rtol={rtol:g}: the step fell below round-off before "
                    f"t = {t0 + times[-code - 1]:.9g} s; loosen rtol or use "
                    "method='integrator'", key="rtol")
            out_q[i, idx] = oq
            out_w[i, idx] = ow
        return sum(abs(float(t[idx][-1])) for idx in segments) / len(specs)

    with bar.ticking():          # one body is one call: the elapsed time moves meanwhile
        for done in compiled.each_on_cores(lambda i: run(i, specs[i]), len(specs)):
            bar.update(done)


def integrate_splitting(bodies, quat0, omega0, t, *, torques=(), step: float | None = None,
                        order: int | None = None, scheme: str | None = None,
                        progress: bool = False, steps_per_period: float | None = None,
                        t0: float = 0.0, rtol: float | None = None,
                        dense: bool = True, compiled: bool | None = None
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Propagate rigid bodies under torques with a splitting method.

    The exact free rigid-body flow alternates with torque kicks (see the module
    docstring); all bodies of a batch advance together, vectorised, with one common
    step.

    Parameters
    ----------
    bodies : RigidBody, sequence of RigidBody, or principal moments (3,) / (N, 3)
        Moments mean bodies whose frame is their principal frame.
    quat0 : (4,) or (N, 4) array
        Body -> inertial quaternions at ``t = 0``, scalar-last.
    omega0 : (3,) or (N, 3) array
        Body-frame rates at ``t = 0``, rad/s.
    t : (T,) array
        Output times, s since the epoch, any order, may be negative (integrated
        backwards from 0).
    torques : sequence of torque models (or one model)
        ``torque(t, quaternion, omega_body, body) -> body-frame N m``
        (:mod:`attitude.model.torques`).  Models with ``velocity_dependent = False`` are
        exact kicks; the others are integrated inside the kick.  In a batch a model is
        called once per kick with arrays ``(N, 4)``, ``(N, 3)`` and a
        :class:`attitude.model.body.BodyBatch`; for one body with ``(4,)``, ``(3,)`` and the
        :class:`~attitude.model.body.RigidBody` (like the reference integrator).
    step : float, optional
        Step, s (with ``rtol``: the longest step).  Default: :func:`choose_step`.
    order : {2, 4, 6}, optional
        Order of the composition (default 4, or that of ``scheme``; if both are given
        they must agree).
    scheme : str, optional
        One of :data:`SCHEMES` (default :data:`DEFAULT_SCHEME` of the order).
    progress : bool
        Report the progress on stderr (:mod:`attitude.foundations.progress`: a bar on
        a terminal, occasional lines otherwise).
    steps_per_period : float, optional
        ``N`` of the default step rule (:func:`choose_step`).
    t0 : float
        Time of ``quat0`` / ``omega0``, s since the epoch (default 0); ``t`` stays in
        seconds since the epoch (used to restart from an intermediate state).
    rtol : float, optional
        Error control: each step is accepted when the estimated local error is at most
        ``rtol`` (relative to the unit quaternion and to ``|omega|``), the estimate
        being the difference from a cheaper composition on the same step
        (:data:`EMBEDDED`: Yoshida's triple jump for the order-4 schemes), and the next
        step follows the usual controller ``h (1/err)^(1/(p+1))`` (factor 0.9, between
        0.2 and 5).  Like DOP853's ``rtol``, it bounds the local error estimate per
        step; the propagated solution is the more accurate one.  Variable steps are
        not symplectic: for long conservative runs prefer the fixed default step.
    dense : bool
        Outputs do not set the steps (default): the steps run on the grid
        ``t0 + k h`` and an output inside a step is one partial step of the same
        composition from the step's start (its error is that of one step).  With
        ``False`` each interval between outputs is cut into equal steps no longer than
        ``step`` (every output then lies on a step boundary).
    compiled : bool, optional
        Run the compiled loop (:mod:`attitude.propagation.compiled_loop`, numba): each
        body on its own, a few microseconds per step.  Default: when numba is installed
        and every torque model has a compiled form
        (:func:`attitude.propagation.compiled_torques.compile_torques`; a user's Python
        torque has none).  ``False`` forces the numpy path (bodies of a batch
        vectorised, one common step), which gives the same results to round-off;
        ``True`` raises if a torque has no compiled form (without numba it runs the
        same scalar loop as Python: slow, for tests).  With ``rtol`` the compiled loop
        controls the error of each body separately (the numpy path: the worst body).

    Returns
    -------
    quaternion : (N, T, 4) array, or (T, 4) for one body
        Body -> inertial, scalar-last, unit norm.
    omega : (N, T, 3) array, or (T, 3) for one body
        Body-frame rates, rad/s.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.splitting import integrate_splitting
    >>> from attitude.model.torques import GravityGradient
    >>> gg = GravityGradient(3.986004418e14, [7.0e6, 0.0, 0.0])
    >>> q, w = integrate_splitting([1.0, 2.0, 3.0], [0, 0, 0, 1], [1e-3, 2e-3, 3e-3],
    ...                            np.linspace(0.0, 600.0, 7), torques=[gg], step=10.0)
    >>> q.shape, w.shape
    ((7, 4), (7, 3))
    """
    body_list, single = as_bodies(bodies)
    system = System(body_list, torques)
    n = system.n
    attitude_only = not (system.drag_terms or system.internal_terms)
    name, sorder, ops_step = resolve_scheme(order, scheme, attitude_only)
    if name in RKN_SCHEMES and not attitude_only:
        raise InvalidStateError(f"scheme {name!r} needs attitude-only torques (its order "
                                "conditions assume them); with velocity-dependent torques "
                                "use 'blanes-moan', 'strang', 'yoshida4' or 'yoshida6'")
    q0 = np.asarray(quat0, dtype=float)
    w0 = np.asarray(omega0, dtype=float)
    if q0.shape[-1:] != (4,) or w0.shape[-1:] != (3,) or q0.ndim > 2 or w0.ndim > 2:
        raise InvalidStateError(f"quat0 / omega0: expected (N, 4) / (N, 3) (or (4,) / (3,)),"
                                f" got {q0.shape} / {w0.shape}")
    try:
        q0 = np.broadcast_to(q0, (n, 4)).astype(float)
        w0 = np.broadcast_to(w0, (n, 3)).astype(float)
    except ValueError:
        raise InvalidStateError(f"quat0 / omega0: {q0.shape} / {w0.shape} do not match "
                                f"{n} bodies") from None
    if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(w0))):
        raise InvalidStateError("quat0 and omega0 must be finite")
    norm = np.linalg.norm(q0, axis=1, keepdims=True)
    if np.any(norm == 0):
        raise InvalidStateError("quat0 must be a non-zero quaternion")
    q0 = q0 / norm
    t = np.atleast_1d(np.asarray(t, dtype=float))
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise InvalidStateError("t: expected a 1-D array of finite times (s)")
    if rtol is not None:
        checked_rtol(rtol)
    t0 = float(t0)
    t = t - t0
    q_p0, w_p0 = system.to_principal(q0, w0)

    if step is None:
        h_max = h_rule = default_step(system, q_p0, w_p0, sorder, steps_per_period, t0)
    else:
        h_max = float(step)
        if not (h_max > 0 and math.isfinite(h_max)):
            raise InvalidStateError(f"step: expected a positive number of seconds, got "
                                    f"{step!r}")
        h_rule = h_max
    has_kick = bool(system.kick_terms)
    has_drag = bool(system.drag_terms)
    has_internal = bool(system.internal_terms)
    run_scheme = Scheme(sorder, ops_step)
    mode = "dense" if dense else "cut"
    if not (has_kick or has_drag or has_internal):
        run_scheme = Scheme(sorder, (("F", 1.0),))   # no torque: the free flow is exact
        h_max, mode = math.inf, "dense"
    elif rtol is not None:
        mode = "rtol"
    rk_order = 2 if sorder == 2 else 4
    embedded = None
    if mode == "rtol":
        emb = EMBEDDED[name]
        if emb == "blanes-moan" and attitude_only:
            emb = "blanes-moan-rkn"
        embedded = Scheme(*LIE) if emb == "lie" else Scheme(*SCHEMES[emb])
    # the loop's settings, the same for the numpy and the compiled loop: the first step
    # (with rtol: the rule's, at most step=), the longest step, the controller's exponent
    h_start = h_max if mode != "rtol" else min(h_rule, h_max)
    h_limit = math.inf if step is None else h_max
    expo = controller_exponent(run_scheme, embedded) if mode == "rtol" else 0.0

    out_q = np.empty((n, t.size, 4))
    out_w = np.empty((n, t.size, 3))
    ops = OneOps(system) if n == 1 else BatchOps(system)
    # internal torques alone keep the inertial L: every kick restores the initial one
    anchor = (quat.rotate(q_p0, w_p0 * system.moments)
              if has_internal and not (has_kick or has_drag) else None)
    stepper = _Stepper(ops, run_scheme, has_kick, has_drag, has_internal, rk_order, anchor)
    spin0 = float(np.max(np.sqrt(np.sum(w_p0 * w_p0, axis=1))))
    w_floor = 1e-3 * max(spin0, 1.0 / h_rule if math.isfinite(h_rule) else 0.0)
    w_floor = w_floor if w_floor > 0 else np.finfo(float).tiny
    specs = None
    torqued = has_kick or has_drag or has_internal
    if torqued and (compiled or (compiled is None and compiled_loop.NUMBA)):
        specs = _compiled_specs(system, body_list, t0, t, anchor is not None or not has_internal)
        if compiled and specs is None:
            raise InvalidStateError("compiled=True: a torque model has no compiled form (a "
                                    "Python function or model), or internal torques act "
                                    "together with external ones; use compiled=None",
                                    key="compiled")
    segments = _segments(t)
    bar = _progress(sum(float(np.max(np.abs(t[idx]))) for idx in segments), progress)

    def store(j, q, w):
        ops.store(out_q, out_w, j, q, w)

    try:
        if specs is not None:
            _run_compiled(system, specs, q_p0, w_p0, t, t0, segments, h_start, h_limit,
                          expo, mode, rtol, run_scheme, embedded, rk_order, w_floor, anchor,
                          out_q, out_w, bar)
            segments = []
        for idx in segments:
            if n == 1:
                q, w = tuple(q_p0[0].tolist()), tuple(w_p0[0].tolist())
            else:
                q, w = q_p0.copy(), w_p0.copy()
            _march(stepper, q, w, t0, [(int(j), float(t[j])) for j in idx], store, h_start,
                   mode=mode, rtol=rtol, embedded=embedded, expo=expo, w_floor=w_floor,
                   h_limit=h_limit, bar=bar)
    finally:
        bar.close()
    if system.identity:
        qb, wb = out_q, out_w
    else:
        qb, wb = to_body_frame(out_q, out_w, system.q_bp[:, None, :])
    if single:
        return qb[0], wb[0]
    return qb, wb
