"""The default step of the splitting integrator (:mod:`attitude.propagation.splitting`):
set by the torques' own time scales and by how fast each torque changes along the
exact free flow (:func:`choose_step`).
"""

from __future__ import annotations

import math

import numpy as np

from ..foundations import quaternion as quat
from ..model.body import as_bodies
from ..model.torques import TorqueModel, as_torque_model
from .freeflow import free_flow_batch
from .kicks import System

__all__ = ["choose_step", "STEPS_PER_PERIOD"]


#: Default number of steps per shortest time scale (``2 pi / rate``) of each order
#: (see :func:`choose_step` and docs/integrators.md for the calibration).
STEPS_PER_PERIOD = {2: 1000, 4: 300, 6: 200}


def own_rates(model, body_arg, n: int, t0: float, q_b, w_b) -> np.ndarray:
    """The model's own rate (``TorqueModel.characteristic_rate``), rad/s, per body, at
    body-frame states ``q_b (n, 4)``, ``w_b (n, 3)`` (``body_arg``: the one body, or
    the batch)."""
    model = as_torque_model(model)
    if n == 1:
        rate = model.characteristic_rate(t0, q_b[0], w_b[0], body_arg)
    else:
        rate = model.characteristic_rate(t0, q_b, w_b, body_arg)
    return np.broadcast_to(np.asarray(rate, dtype=float), (n,))


def _own_rates(model, system: System, t0: float, q_p, w_p) -> np.ndarray:
    """:func:`own_rates` at principal-frame states."""
    q_b, w_b = system.to_body(q_p, w_p)
    return own_rates(model, system.body_arg, system.n, t0, q_b, w_b)


def _inertial_torques(model, system: System, t0: float, q_p, w_p) -> np.ndarray:
    """The model's torque in inertial axes, N m, at principal-frame states ``q_p
    (K, n, 4)``, ``w_p (K, n, 3)``: for one body, a :class:`TorqueModel` (whose
    ``evaluate`` broadcasts over leading axes) is called once on the ``K`` states;
    otherwise once per state, as the integrator calls it."""
    k = q_p.shape[0]
    if system.n == 1 and isinstance(model, TorqueModel):
        q_b, w_b = system.to_body(q_p[:, 0], w_p[:, 0])
        m = model(t0, q_b, w_b, system.body_arg)
        if m.shape == (k, 3):
            if not system.identity:
                m = quat.rotate(system.q_bp, m)
            return quat.rotate(q_p[:, 0], m)[:, None, :]
    return np.stack([quat.rotate(q_p[j], system._torque([model], t0, q_p[j], w_p[j])
                                 * system.moments) for j in range(k)])


def _variation_rates(model, system: System, t0: float, q_p, w_p, order: int
                     ) -> np.ndarray:
    """How fast the model's torque, in inertial axes, varies along the exact free flow
    (time frozen), rad/s, per body: ``max_j (|d^j M / ds^j| / |M|)^(1/j)`` for
    ``j = 1, 2`` and, above order 2, 4, from central differences over the free flow at
    spacing ``0.05 / |omega|``.  Differences at the level of their rounding count as
    zero: a relative variation below ~1e-7 of the torque is not resolved, and need not
    be (sampled at any step it moves the result by about that fraction of the torque's
    effect)."""
    spin = np.sqrt(np.sum(w_p * w_p, axis=1))
    moving = spin > 0
    delta = np.where(moving, 0.05 / np.where(moving, spin, 1.0), 0.0)
    steps = (0, -1, 1, -2, 2)
    flows = [(q_p, w_p)] + [free_flow_batch(system.free, q_p, w_p, k * delta)
                            for k in steps[1:]]
    along = _inertial_torques(model, system, t0, np.stack([f[0] for f in flows]),
                              np.stack([f[1] for f in flows]))
    torque = dict(zip(steps, along))
    scale = np.max([np.sqrt(np.sum(m * m, axis=1)) for m in torque.values()], axis=0)
    ok = moving & (scale > 0)
    d = np.where(ok, delta, 1.0)
    sc = np.where(ok, scale, 1.0)

    def rel(x, weight):
        # above the rounding of the differences (|coefficients| * a generous 64 eps)
        size = np.sqrt(np.sum(x * x, axis=1)) / sc
        return np.maximum(size - 64.0 * np.finfo(float).eps * weight, 0.0)

    nu = np.maximum(rel(torque[1] - torque[-1], 2.0) / (2.0 * d),
                    np.sqrt(rel(torque[1] - 2.0 * torque[0] + torque[-1], 4.0)) / d)
    if order > 2:
        d4 = torque[2] - 4.0 * torque[1] + 6.0 * torque[0] - 4.0 * torque[-1] + torque[-2]
        nu = np.maximum(nu, rel(d4, 16.0) ** 0.25 / d)
    return np.where(ok, np.minimum(nu, spin), 0.0)


def torque_rates(system: System, q_p, w_p, order: int = 4, t0: float = 0.0,
                 variation: bool = True):
    """``(omega_M, nu, rate)`` per body, each the largest over the models: the torques'
    own rate, how fast they turn along the free flow, and the step rule's
    ``max(omega_M, (nu^2 omega_M)^(1/3))`` (see :func:`choose_step`).  With
    ``variation=False`` ``nu`` is taken as 0 (not measured: the cheap part alone)."""
    own_max, nu_max, rate = np.zeros(system.n), np.zeros(system.n), np.zeros(system.n)
    for model in system.terms:
        own = _own_rates(model, system, t0, q_p, w_p)
        nu = (_variation_rates(model, system, t0, q_p, w_p, order) if variation
              else np.zeros(system.n))
        own_max, nu_max = np.maximum(own_max, own), np.maximum(nu_max, nu)
        rate = np.maximum(rate, np.maximum(own, np.cbrt(nu * nu * own)))
    return own_max, nu_max, rate


def _step_rates(system: System, q_p, w_p, order: int = 4, t0: float = 0.0
                ) -> np.ndarray:
    """``max over models of max(omega_M, (nu^2 omega_M)^(1/3))`` per body (see
    :func:`choose_step`)."""
    return torque_rates(system, q_p, w_p, order, t0)[2]


def choose_step(bodies, quat0, omega0, torques=(), *, order: int = 4,
                steps_per_period: float | None = None, t0: float = 0.0) -> float:
    r"""The default step of :func:`integrate_splitting`, s: set by the torques' own time
    scales, not by the spin, which the exact free flow carries.

    ``h = 2 pi / (N * rate)``, ``N = STEPS_PER_PERIOD[order]`` (1000, 300, 200 for
    orders 2, 4, 6), with, over the torque models and the bodies of a batch,

    .. math::

        \mathrm{rate} = \max\big(\omega_M,\ (\nu^2 \omega_M)^{1/3}\big)

    * ``omega_M`` is the model's own rate, :meth:`~attitude.torques.TorqueModel.characteristic_rate`
      at ``(t0, quat0, omega0)`` (gravity gradient: ``sqrt(3 mu / r_p^3)`` or the
      orbital rate at periapsis; dissipation: ``1 / time_constant``; eddy currents: the
      damping rate; heavy top: the pendulum frequency; a user model: from its torque);
    * ``nu`` is how fast the model's torque, seen in inertial axes, changes along the
      exact free flow itself: measured by the integrator from central differences of
      the torque over the free flow (``j = 1, 2, 4``-th derivatives,
      ``max_j (|M^(j)| / |M|)^(1/j)``), at most the spin rate ``|omega0|``.

    A splitting with the exact free flow makes errors only through the commutators of
    the kick with the free flow, which grow with the torque's rate of change *along* the
    free motion, not with the spin: a spin about the axis of a symmetric top, or about
    a principal axis under eddy currents in a uniform field, leaves the inertial torque
    (nearly) unchanged, and the step is that of the torque alone.  For a triaxial
    tumbler under gravity gradient (the inertial torque turns at up to twice the spin)
    ``nu`` reaches the spin and the rule is the previous one, ``(Omega^2
    omega_M)^(1/3)``, for which ``N`` was calibrated (~1e-10 relative accuracy over a
    few orbits at order 4 and 6, ~1e-6 at order 2; docs/integrators.md has the
    measurements).  Only the protocol of :class:`~attitude.model.torques.TorqueModel` is used
    (``characteristic_rate`` and the call), so a user's model is treated like the
    built-in ones.  Returns ``inf`` without torques (the free flow is exact in one
    step).

    Examples
    --------
    >>> import math
    >>> from attitude.propagation.splitting import choose_step, STEPS_PER_PERIOD
    >>> from attitude.model.torques import EnergyDissipation
    >>> h = choose_step([1.0, 2.0, 3.0], [0, 0, 0, 1], [0.0, 0.0, 5.0],  # pure spin about C
    ...                 [EnergyDissipation(600.0)])
    >>> bool(math.isclose(h, 2 * math.pi * 600.0 / STEPS_PER_PERIOD[4]))
    True
    >>> choose_step([1.0, 2.0, 3.0], [0, 0, 0, 1], [0.1, 0.2, 0.3])   # no torque
    inf
    """
    body_list, _ = as_bodies(bodies)
    system = System(body_list, torques)
    q0 = np.atleast_2d(np.asarray(quat0, dtype=float))
    w0 = np.atleast_2d(np.asarray(omega0, dtype=float))
    q_p, w_p = system.to_principal(np.broadcast_to(q0, (system.n, 4)).copy(),
                                   np.broadcast_to(w0, (system.n, 3)).copy())
    return default_step(system, q_p, w_p, order, steps_per_period, float(t0))


def default_step(system, q_p, w_p, order, steps_per_period, t0: float = 0.0) -> float:
    per = STEPS_PER_PERIOD[order] if steps_per_period is None else float(steps_per_period)
    if not system.terms:
        return math.inf
    rate = float(np.max(_step_rates(system, q_p, w_p, order, t0)))
    if not rate > 0 or not math.isfinite(rate):
        return math.inf
    return 2.0 * math.pi / (per * rate)

