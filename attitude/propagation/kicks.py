"""The bodies, torques and kicks of the splitting integrator
(:mod:`attitude.propagation.splitting`): the torque terms sorted into attitude-only
kicks, velocity-dependent ones and internal ones (:class:`System`), the state
operations of a batch (arrays) and of one body (plain floats), and the kick itself.
"""

from __future__ import annotations

import math

import numpy as np

from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError
from ..model.body import RigidBody, as_bodies, to_body_frame, to_principal_frame
from .freeflow import FreeConstants, free_flow_batch, free_flow_tuple

__all__ = []  # package-internal: the splitting integrator imports these


def qmul_unit(q, g):
    """Normalised product ``q g`` of component quaternions (plain floats)."""
    nx, ny, nz, nw = quat.multiply_parts(q, g)
    r = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    return (nx * r, ny * r, nz * r, nw * r)

def torque_terms(torques) -> list:
    """Flatten torque models (sums included) into their terms."""
    if torques is None:
        return []
    if callable(torques) and not isinstance(torques, (list, tuple)):
        torques = [torques]
    out = []
    for model in torques:
        if not callable(model):
            raise InvalidStateError(f"torques: expected callables torque(t, quaternion, "
                                    f"omega_body, body), got {type(model).__name__}")
        sub = getattr(model, "terms", None)
        out.extend(torque_terms(list(sub)) if isinstance(sub, tuple) else [model])
    return out


def _is_conservative(model) -> bool:
    """Attitude-only torque (declared ``velocity_dependent = False``)?  Plain functions
    without the attribute are treated as velocity-dependent (the safe choice)."""
    return getattr(model, "velocity_dependent", True) is False


def _is_internal(model) -> bool:
    """A torque between parts of the body (``internal = True``): it keeps the inertial
    angular momentum (:attr:`attitude.model.torques.TorqueModel.internal`)."""
    return getattr(model, "internal", False) is True


class System:
    """Everything the stepping loop needs about the bodies and torques."""

    def __init__(self, bodies: list[RigidBody], torques):
        self.bodies = bodies
        self.n = len(bodies)
        batch, _ = as_bodies(bodies)
        self.body_arg = bodies[0] if self.n == 1 else batch
        terms = torque_terms(torques)
        self.terms = terms
        self.internal_terms = [m for m in terms if _is_internal(m)]
        self.kick_terms = [m for m in terms if _is_conservative(m) and not _is_internal(m)]
        self.drag_terms = [m for m in terms
                           if not _is_conservative(m) and not _is_internal(m)]
        self.moments = batch.principal_moments
        self.inv_moments = 1.0 / self.moments
        self.q_bp = batch.body_to_principal
        self.identity = bool(np.all(self.q_bp == np.array([0.0, 0.0, 0.0, 1.0])))
        self.free = FreeConstants(self.moments)

    # --- frames ----------------------------------------------------------------------
    def to_principal(self, q_b: np.ndarray, w_b: np.ndarray):
        """Body-frame quaternions (N, 4) and rates (N, 3) -> principal frame."""
        if self.identity:
            return q_b.copy(), w_b.copy()
        return to_principal_frame(q_b, w_b, self.q_bp)

    def to_body(self, q_p: np.ndarray, w_p: np.ndarray):
        if self.identity:
            return q_p.copy(), w_p.copy()
        return to_body_frame(q_p, w_p, self.q_bp)

    # --- torques -----------------------------------------------------------------------
    def _torque(self, models, t, q_p, w_p):
        """Summed body-frame torque of ``models`` -> principal angular acceleration."""
        q_b, w_b = self.to_body(q_p, w_p)
        total = None
        if self.n == 1:
            for model in models:
                out = np.asarray(model(t, q_b[0], w_b[0], self.body_arg), dtype=float)
                total = out if total is None else total + out
            total = np.reshape(total, (1, 3)) if total.size == 3 else total
        else:
            for model in models:
                out = np.asarray(model(t, q_b, w_b, self.body_arg), dtype=float)
                total = out if total is None else total + out
        if total.shape != (self.n, 3):
            try:
                total = np.broadcast_to(total, (self.n, 3))
            except ValueError:
                raise InvalidStateError(f"a torque model returned shape {total.shape}; "
                                        f"expected ({self.n}, 3) body-frame N m") from None
        if not self.identity:
            total = quat.rotate(self.q_bp, total)
        return total * self.inv_moments

    def accel_kick(self, t, q_p, w_p):
        return self._torque(self.kick_terms, t, q_p, w_p)

    def accel_drag(self, t, q_p, w_p):
        return self._torque(self.drag_terms, t, q_p, w_p)

    def internal_kick(self, t, q, w, tau, rk_order, anchor=None):
        """The kick with internal torques, over ``tau`` at the frozen time ``t``.

        The vector field is ``dL/dt = M_ext(q, w) + M_int(w)`` in the principal frame with
        the attitude moving at the extra rate ``(M_int x L)/L^2`` only (the rigid rotation
        at ``w`` is the free flow's).  Explicit midpoint (``rk_order = 2``) or RK4 on
        ``(w, p, L_ext)``, ``p`` the attitude increment (``q(s) = q p(s)``) and
        ``L_ext`` the inertial angular momentum given by the external torques alone;
        then the new body-frame ``L`` is set to ``q'^-1 (L_inertial(0) + L_ext)``: with
        internal torques only, ``anchor`` is the inertial ``L`` of the start of the run,
        restored to round-off at every kick (no drift accumulates); with external
        torques too, ``L`` changes only by theirs.
        """
        moments = self.moments
        external = self.kick_terms + self.drag_terms
        one = np.zeros_like(q)
        one[:, 3] = 1.0

        def field(wv, p):
            qs = quat.multiply(q, p)
            qs = qs / np.sqrt(np.sum(qs * qs, axis=1, keepdims=True))
            L = wv * moments
            a_int = self._torque(self.internal_terms, t, qs, wv)
            m_int = a_int * moments
            L2 = np.sum(L * L, axis=1, keepdims=True)
            extra = np.where(L2 > 0, _cross(m_int, L) / np.where(L2 > 0, L2, 1.0), 0.0)
            dp = 0.5 * quat.multiply(p, np.concatenate([extra, np.zeros((len(p), 1))], axis=1))
            if external:
                a_ext = self._torque(external, t, qs, wv)
                return a_int + a_ext, dp, quat.rotate(qs, a_ext * moments)
            return a_int, dp, None

        def step(y, k, c):
            wv, p, le = y
            return (wv + c * k[0], p + c * k[1], None if k[2] is None else le + c * k[2])

        y0 = (w, one, np.zeros_like(w))
        k1 = field(w, one)
        if rk_order == 2:
            k2 = field(*step(y0, k1, 0.5 * tau)[:2])
            w1, p1, le1 = step(y0, k2, tau)
        else:
            y = step(y0, k1, 0.5 * tau)
            k2 = field(y[0], y[1])
            y = step(y0, k2, 0.5 * tau)
            k3 = field(y[0], y[1])
            y = step(y0, k3, tau)
            k4 = field(y[0], y[1])
            incr = tuple(None if k1[i] is None else
                         k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i] for i in range(3))
            w1, p1, le1 = step(y0, incr, tau / 6.0)
        q1 = quat.multiply(q, p1)
        q1 = q1 / np.sqrt(np.sum(q1 * q1, axis=1, keepdims=True))
        if anchor is not None and le1 is None:
            L_in = anchor
        else:
            L_in = quat.rotate(q, w * moments)
            if le1 is not None:
                L_in = L_in + le1
        w1 = quat.rotate(quat.conjugate(q1), L_in) / moments
        return q1, w1


def _cross(a, b):
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)



class BatchOps:
    """State operations on (N, 4) / (N, 3) principal-frame arrays."""

    def __init__(self, system: System):
        self.s = system

    def free(self, q, w, h):
        return free_flow_batch(self.s.free, q, w, h)

    def acc_kick(self, t, q, w):
        return self.s.accel_kick(t, q, w)

    def acc_drag(self, t, q, w):
        return self.s.accel_drag(t, q, w)

    def internal(self, t, q, w, tau, rk_order, anchor):
        return self.s.internal_kick(t, q, w, tau, rk_order, anchor)

    @staticmethod
    def axpy(w, tau, a):
        return w + tau * a

    @staticmethod
    def add(a, b):
        return a + b

    def store(self, out_q, out_w, j, q, w):
        out_q[:, j] = q
        out_w[:, j] = w


class OneOps:
    """The same operations for one body on tuples of floats (numpy costs ~1 us per call
    on one element: the one-body path would otherwise be dominated by call overhead)."""

    def __init__(self, system: System):
        self.s = system
        self.k = system.free.rows[0].copy()
        self.inv = tuple(float(x) for x in system.inv_moments[0])
        self.identity = system.identity
        self.q_bp_t = tuple(system.q_bp[0].tolist())
        self.body = system.body_arg

    def free(self, q, w, h):
        return free_flow_tuple(self.k, q, w, h)

    def _acc(self, models, t, q, w):
        if self.identity:
            q_b, w_b = np.array(q), np.array(w)
        else:
            q_b = np.array(qmul_unit(q, self.q_bp_t))
            w_b = np.array(quat.rotate_parts(self.q_bp_t, w, inverse=True))
        total = None
        for model in models:
            out = np.asarray(model(t, q_b, w_b, self.body), dtype=float)
            total = out if total is None else total + out
        if total.size != 3:
            raise InvalidStateError(f"a torque model returned shape {total.shape}; "
                                    "expected (3,) body-frame N m")
        m = total.ravel().tolist()
        if not self.identity:
            m = quat.rotate_parts(self.q_bp_t, m)
        i1, i2, i3 = self.inv
        return (m[0] * i1, m[1] * i2, m[2] * i3)

    def acc_kick(self, t, q, w):
        return self._acc(self.s.kick_terms, t, q, w)

    def acc_drag(self, t, q, w):
        return self._acc(self.s.drag_terms, t, q, w)

    def internal(self, t, q, w, tau, rk_order, anchor):
        """:meth:`System.internal_kick` in plain floats (see there)."""
        external = self.s.kick_terms + self.s.drag_terms
        if external:                      # rare: the array version is good enough
            q1, w1 = self.s.internal_kick(t, np.array([q]), np.array([w]), tau, rk_order,
                                          anchor)
            return tuple(q1[0].tolist()), tuple(w1[0].tolist())
        I1, I2, I3 = (float(x) for x in self.s.moments[0])

        def field(wv, p):
            qs = qmul_unit(q, p)
            a = self._acc(self.s.internal_terms, t, qs, wv)
            m0, m1, m2 = a[0] * I1, a[1] * I2, a[2] * I3
            L0, L1, L2 = wv[0] * I1, wv[1] * I2, wv[2] * I3
            LL = L0 * L0 + L1 * L1 + L2 * L2
            if LL > 0:
                ex = (m1 * L2 - m2 * L1) / LL
                ey = (m2 * L0 - m0 * L2) / LL
                ez = (m0 * L1 - m1 * L0) / LL
            else:
                ex = ey = ez = 0.0
            px, py, pz, pw = p                         # dp = p (extra, 0) / 2
            dp = (0.5 * (pw * ex + py * ez - pz * ey), 0.5 * (pw * ey - px * ez + pz * ex),
                  0.5 * (pw * ez + px * ey - py * ex), -0.5 * (px * ex + py * ey + pz * ez))
            return a, dp

        def ax(y, c, k):
            return tuple(yi + c * ki for yi, ki in zip(y, k))

        one = (0.0, 0.0, 0.0, 1.0)
        k1 = field(w, one)
        if rk_order == 2:
            k2 = field(ax(w, 0.5 * tau, k1[0]), ax(one, 0.5 * tau, k1[1]))
            w1, p1 = ax(w, tau, k2[0]), ax(one, tau, k2[1])
        else:
            k2 = field(ax(w, 0.5 * tau, k1[0]), ax(one, 0.5 * tau, k1[1]))
            k3 = field(ax(w, 0.5 * tau, k2[0]), ax(one, 0.5 * tau, k2[1]))
            k4 = field(ax(w, tau, k3[0]), ax(one, tau, k3[1]))
            p1 = tuple(o + tau / 6.0 * (a + 2.0 * b + 2.0 * c + d)
                       for o, a, b, c, d in zip(one, k1[1], k2[1], k3[1], k4[1]))
            w1 = tuple(o + tau / 6.0 * (a + 2.0 * b + 2.0 * c + d)
                       for o, a, b, c, d in zip(w, k1[0], k2[0], k3[0], k4[0]))
        q1 = qmul_unit(q, p1)                                   # normalised
        del w1                                   # superseded by the restored L
        L_in = (anchor[0] if anchor is not None
                else quat.rotate(np.array(q), np.array(w) * self.s.moments[0]))
        Lb = quat.rotate(quat.conjugate(np.array(q1)), L_in).tolist()
        return q1, (Lb[0] / I1, Lb[1] / I2, Lb[2] / I3)

    @staticmethod
    def axpy(w, tau, a):
        return (w[0] + tau * a[0], w[1] + tau * a[1], w[2] + tau * a[2])

    @staticmethod
    def add(a, b):
        return (a[0] + b[0], a[1] + b[1], a[2] + b[2])

    def store(self, out_q, out_w, j, q, w):
        out_q[0, j] = q
        out_w[0, j] = w


def torque_kick(ops, t, q, w, tau, cached, has_kick: bool, has_drag: bool, rk_order: int):
    """Advance ``w`` by the torques over ``tau`` with the attitude and time frozen.

    Attitude-only torques: the exact flow ``w += tau a``; with velocity-dependent
    torques: explicit midpoint (``rk_order = 2``) or classical RK4 on
    ``dw/dt = a + a_drag(w)``.  Returns ``(w, cached)``, ``cached`` the attitude-only
    acceleration at ``(t, q)`` for reuse.
    """
    a = None
    if has_kick:
        a = cached if cached is not None else ops.acc_kick(t, q, w)
        cached = a
        if not has_drag:
            return ops.axpy(w, tau, a), cached

    def f(wv):
        d = ops.acc_drag(t, q, wv)
        return d if a is None else ops.add(a, d)

    k1 = f(w)
    if rk_order == 2:
        return ops.axpy(w, tau, f(ops.axpy(w, 0.5 * tau, k1))), cached
    k2 = f(ops.axpy(w, 0.5 * tau, k1))
    k3 = f(ops.axpy(w, 0.5 * tau, k2))
    k4 = f(ops.axpy(w, tau, k3))
    incr = ops.add(ops.add(k1, k4), ops.axpy(k2, 1.0, k3))
    incr = ops.axpy(incr, 1.0, ops.axpy(k2, 1.0, k3))     # k1 + 2 k2 + 2 k3 + k4
    return ops.axpy(w, tau / 6.0, incr), cached

