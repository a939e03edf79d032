r"""The exact torque-free flow of rigid bodies over one step: the free part ``F`` of the
splitting integrator (:mod:`attitude.propagation.splitting`).

Jacobi elliptic functions for the rates and an elliptic integral of the third kind for
the precession angle (Celledoni, Fassò, Säfström & Zanna 2008); the formulas, numbered
(S1)-(S5), are in :func:`free_flow`, their code in one place,
:func:`attitude.propagation.compiled.free_step` (compiled for one body, or numpy's on a
batch), which this module applies to batches and single bodies.

References
----------
.. [1] Celledoni, E., Fassò, F., Säfström, N. & Zanna, A. (2008). The exact
   computation of the free rigid body motion and its use in splitting methods.
   *SIAM J. Sci. Comput.* 30, 2084-2112.
.. [2] Carlson, B. C. (1995). Numerical computation of real or complex elliptic
   integrals. *Numer. Algorithms* 10, 13-26; DLMF §19.25, §22.
"""

from __future__ import annotations

import numpy as np

from ..foundations import quaternion as quat
from ..model import freebody as fb
from ..model.freebody import EQUAL_MOMENTS_RTOL
from . import compiled

__all__ = ["free_flow"]


class FreeConstants:
    """Per-body constants of the free flow: principal moments scaled to O(1) by a power
    of two (exact), the symmetry flags and the characteristics ``nu`` of both kernel
    frames; ``rows`` (N, 7) the same as the rows of :meth:`row` (the compiled kernel's
    ``c``)."""

    def __init__(self, moments: np.ndarray):
        moments = np.atleast_2d(np.asarray(moments, dtype=float))
        _, e = np.frexp(moments[:, 2])
        m = moments / np.ldexp(1.0, e)[:, None]            # exact power-of-two scaling
        A, B, C = m[:, 0].copy(), m[:, 1].copy(), m[:, 2].copy()
        self.A, self.B, self.C = A, B, C
        # a spherical body rotates uniformly (attitude.model.freebody.EQUAL_MOMENTS_RTOL)
        self.spherical = (C - A) <= EQUAL_MOMENTS_RTOL * C
        # on the separatrix (L^2 = 2EB exactly) take the kernel frame with the larger
        # gap I3 - I2 (a prolate body spinning in its B-C plane goes to LAM)
        self.lam_on_tie = (C - B) < (B - A)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.nu_sam = fb.characteristic(A, B, C)        # kernel moments (A, B, C)
            self.nu_lam = fb.characteristic(C, B, A)        # kernel moments (C, B, A)
        self.rows = np.ascontiguousarray(np.stack(
            [A, B, C, self.spherical.astype(float), self.lam_on_tie.astype(float),
             self.nu_sam, self.nu_lam], axis=1))

    def row(self, i: int) -> tuple:
        """Plain-float constants of body ``i`` (for the one-body kernel)."""
        return (float(self.A[i]), float(self.B[i]), float(self.C[i]),
                bool(self.spherical[i]), bool(self.lam_on_tie[i]),
                float(self.nu_sam[i]), float(self.nu_lam[i]))


# One source: the formulas are those of attitude.propagation.compiled.free_step, which
# runs compiled on each body when numba is there (free_flow_bodies) and on the arrays
# of all bodies at once when it is not (numpy: a Python loop over the bodies would be
# ~100x slower); see the notes there.
def free_flow_batch(c: FreeConstants, q: np.ndarray, w: np.ndarray, h):
    """Exact free flow of ``N`` bodies over ``h`` (a float, or one per body); see
    :func:`free_flow`.

    ``q`` (N, 4) principal -> inertial, ``w`` (N, 3) principal rates; new arrays out.
    """
    if compiled.NUMBA:
        qn = np.array(q, dtype=float, order="C")
        wn = np.array(w, dtype=float, order="C")
        hh = np.ascontiguousarray(np.broadcast_to(np.asarray(h, dtype=float), (len(qn),)))
        compiled.free_flow_bodies(c.rows, qn, wn, hh)
        return qn, wn
    with np.errstate(all="ignore"):
        gx, gy, gz, gw, p1, p2, p3 = compiled.free_step(
            c.A, c.B, c.C, c.spherical, c.lam_on_tie, c.nu_sam, c.nu_lam,
            w[:, 0], w[:, 1], w[:, 2], h)
    out = quat.multiply(q, np.stack([gx, gy, gz, gw], axis=-1))
    out /= np.sqrt(np.sum(out * out, axis=1, keepdims=True))
    wout = np.empty_like(w)
    wout[:, 0], wout[:, 1], wout[:, 2] = p1, p2, p3
    return out, wout


def free_flow_tuple(k, q: tuple, w: tuple, h: float):
    """The same step for one body on tuples of floats (``k``: :meth:`FreeConstants.row`,
    or that row as an array): :func:`attitude.propagation.compiled.free_flow_one`,
    compiled or plain."""
    qa = np.array(q, dtype=float)
    wa = np.array(w, dtype=float)
    compiled.free_flow_one(np.array(k, dtype=float), qa, wa, float(h))
    return tuple(qa.tolist()), tuple(wa.tolist())


def free_flow(moments, quat, omega, h):
    r"""Exact torque-free motion of rigid bodies over one interval ``h``.

    Parameters
    ----------
    moments : (N, 3) or (3,) array
        Principal moments, sorted ``A <= B <= C`` (any unit).
    quat : (N, 4) or (4,) array
        Principal -> inertial quaternions, scalar-last, unit.
    omega : (N, 3) or (3,) array
        Principal-frame rates, rad/s.
    h : float
        Interval, s (any sign).

    Returns
    -------
    quat, omega : arrays of the input shapes, at ``t + h``.

    Notes
    -----
    (S1) Kernel frame: the principal axes ``(A, B, C)`` when ``L^2 >= 2EB`` (SAM), else
    ``(C, B, A)`` along ``(e3, -e2, e1)`` (LAM, right-handed), with moments
    ``I1, I2, I3`` and signed differences ``d_ij = I_i - I_j``.  There
    ``omega = (a1 cn u, a2 sn u, a3 dn u)`` with ``u = u0 + lambda t``,
    ``m = d21 (2E I3 - L^2) / (d32 (L^2 - 2E I1))``,
    ``lambda^2 = d32 (L^2 - 2E I1) / (I1 I2 I3)``.

    (S2) The addition theorems of ``sn, cn, dn`` with ``v = lambda h`` give the new
    rates without dividing by an amplitude::

        D   = 1 - I2 d21 / (L^2 - 2E I1) * w2^2 sn^2 v
        w1' = (w1 cn v - d32/I1 w2 w3 sn v/lambda dn v) / D
        w2' = (w2 cn v dn v + d31/I2 w1 w3 sn v/lambda) / D
        w3' = (w3 dn v - d21/I3 w1 w2 sn v/lambda cn v) / D

    (S3) With the 3-1-3 angles ``(phi, theta, psi)`` of the body relative to a frame
    whose z axis is L, ``theta`` and ``psi`` are algebraic in the body components of L
    and ``phi' = L/I3 + c1 / (1 + nu sn^2 u)``, ``c1 = L d31 / (I1 I3)``,
    ``nu = I3 d21 / (I1 d32)``, so

    .. math::

        \Delta\phi = h\,(L/I_3 + c_1) - \frac{c_1}{\lambda}\,[J(u_0 + v) - J(u_0)],
        \qquad J(u) = \int_0^u \frac{\nu\,\mathrm{sn}^2}{1 + \nu\,\mathrm{sn}^2}\,du ,

    with ``J(u) = (nu/3) sn^3 R_J(cn^2, dn^2, 1, 1 + nu sn^2)`` for ``|u| <= K``
    (DLMF 19.25.14) and ``J(u + 2K) = J(u) + 2 J(K)``: the half-period window of ``u``
    has the parity of the sign of ``cn``, so a step with ``|v| < 2K`` crosses a window
    boundary exactly when ``cn`` changes sign; longer steps locate ``u0`` with
    ``R_F`` (DLMF 19.25.5).

    (S4) ``q(t+h) = q(t) E(t)^-1 E(t+h)`` with ``E = Rz(phi) Rx(theta) Rz(psi)``.

    (S5) Spherical bodies, pure principal-axis spins (transverse L below 1e-100
    relative) and bodies at rest rotate uniformly about ``omega``.

    Accuracy: a few ulp per step (tested against
    :func:`attitude.propagation.torquefree.free_rotation` in ``tests/test_splitting.py``);
    near the separatrix the motion itself is ill-conditioned and ``sn, cn, dn`` lose
    ~``eps / m1`` relative.

    The formulas are computed by :func:`attitude.propagation.compiled.free_step`, their
    one source: compiled body by body when numba is installed, else by numpy on all the
    bodies at once.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.propagation.splitting import free_flow
    >>> from attitude.propagation.torquefree import free_rotation
    >>> I, q0, w0 = np.array([1.0, 2.0, 3.0]), np.array([0, 0, 0, 1.0]), np.array([0.1, 0.2, 1.0])
    >>> q1, w1 = free_flow(I, q0, w0, 2.5)
    >>> q2, w2 = free_rotation(I, q0, w0, [2.5])
    >>> bool(np.allclose(w1, w2[0], rtol=0, atol=1e-14) and abs(abs(q1 @ q2[0]) - 1) < 1e-14)
    True
    """
    moments = np.asarray(moments, dtype=float)
    quat = np.asarray(quat, dtype=float)
    omega = np.asarray(omega, dtype=float)
    single = quat.ndim == 1
    q, w = free_flow_batch(FreeConstants(moments), np.atleast_2d(quat),
                          np.atleast_2d(omega), float(h))
    return (q[0], w[0]) if single else (q, w)

