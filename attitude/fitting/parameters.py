"""The parameters of a free rotation in the form observers use, and the forward model.

A torque-free rotation is fixed by eight numbers in the parameterisation of Pravec et
al. (2005, 2014), the one :meth:`attitude.Ensemble.sample` uses:

======================== ==============================================================
``angular_momentum_ra``  right ascension of L, inertial frame (rad)
``angular_momentum_dec`` declination of L (rad)
``energy_ratio``         E/E0, E0 = L^2/(2C) the energy of a spin about C with the same L
``ratio_a``, ``ratio_b`` A/C and B/C
``precession_period``    P_phi, the mean period of the reference axis about L (s)
``phi0``, ``psi0``       precession and rotation angles of the reference axis at the epoch
======================== ==============================================================

The reference axis is C in SAM (E/E0 < C/B) and A in LAM.  :func:`free_parameters` reads
them off a body and a state; :class:`RotationModel` goes back, for many parameter
vectors at once, to the body-frame attitudes and rates at the observation times, with the
exact solution (:func:`attitude.propagation.torquefree.free_rotation`).

Like every parameterisation by the direction of L, this one is singular where L points to
a pole of the inertial frame: there the right ascension of L and ``phi0`` turn about the
same axis, the Jacobian loses a rank and a fit crawls.  Express the observations in a
frame whose pole is away from L (an ecliptic frame for an asteroid whose L is near the
celestial pole, say).

The absolute size of the moments (``C``) is not observable from attitude or light: it is
kept from the first guess.  So is the orientation of the principal axes in the body frame
(the guess body's ``body_to_principal``), with the half-turn about a principal axis that
makes the reference axis's component of L positive (the parameterisation covers those
states only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..model.body import RigidBody
from ..model.freebody import diagnose_many
from ..model.sampling import TUMBLING_PARAMETERS, tumbling_parameters, tumbling_state
from ..model.state import AttitudeState
from ..propagation.torquefree import free_rotation

__all__ = ["PARAMETERS", "ANGLES", "RotationModel", "free_parameters"]

#: The parameter names, in the order of the parameter vectors.
PARAMETERS = TUMBLING_PARAMETERS
#: The parameters that are angles (wrapped, and reported in degrees by the CLI).
ANGLES = ("angular_momentum_ra", "angular_momentum_dec", "phi0", "psi0")



@dataclass(frozen=True)
class RotationModel:
    """The forward model: parameter vectors -> attitudes and rates at given times.

    Parameters
    ----------
    epoch : astropy Time
        Epoch of the parameters (``phi0``, ``psi0`` are the angles at this time).
    body_to_principal : (4,) array
        Quaternion, body -> principal frame of the fitted bodies, scalar-last.
    moment_c : float
        The largest moment C, kg m^2 (not observable; kept from the guess).
    frame : str
        Inertial frame label of the attitudes.

    Examples
    --------
    >>> import numpy as np
    >>> from astropy.time import Time
    >>> model = RotationModel(Time("2029-04-13", scale="tdb"), np.array([0, 0, 0, 1.0]), 1.0)
    >>> x = [0.5, 0.2, 1.02, 0.6, 0.9, 86400.0, 0.0, 0.0]
    >>> q, w = model.evaluate(np.array([x]), np.array([0.0, 3600.0]))
    >>> q.shape, w.shape
    ((1, 2, 4), (1, 2, 3))
    """

    epoch: object
    body_to_principal: np.ndarray
    moment_c: float
    frame: str = "ICRF"

    def principal_states(self, values: np.ndarray):
        """Moments (N, 3), principal -> inertial quaternions (N, 4), principal rates
        (N, 3) and ``{row: reason}`` of invalid rows, for parameter vectors (N, 8)."""
        v = np.atleast_2d(np.asarray(values, dtype=float))
        ra, dec, er, ra_, rb, pphi, phi, psi = v.T
        return tumbling_state(ra, dec, er, ra_, rb, pphi, phi, psi, self.moment_c)

    def evaluate(self, values: np.ndarray, t: np.ndarray):
        """Body -> inertial quaternions (N, T, 4) and body rates (N, T, 3) at ``t`` (s
        since the epoch) for parameter vectors (N, 8); NaN rows where the parameters
        describe no state (see :meth:`principal_states`)."""
        moments, q_p2i, w_p, bad = self.principal_states(values)
        n = moments.shape[0]
        t = np.asarray(t, dtype=float)
        q = np.full((n, t.size, 4), np.nan)
        w = np.full((n, t.size, 3), np.nan)
        ok = np.setdiff1d(np.arange(n), list(bad))
        if ok.size:
            qp, wp = free_rotation(moments[ok], q_p2i[ok], w_p[ok], t)
            b2p = self.body_to_principal
            q[ok] = quat.multiply(qp, b2p[None, None, :])
            w[ok] = quat.rotate(quat.conjugate(b2p)[None, None, :], wp)
        return q, w

    def periods(self, values: np.ndarray) -> dict:
        """:func:`attitude.model.freebody.diagnose_many` of each parameter vector."""
        moments, _, w_p, bad = self.principal_states(values)
        good = np.isfinite(moments).all(axis=1)
        safe_m = np.where(good[:, None], moments, [1.0, 2.0, 2.5])
        safe_w = np.where(good[:, None], w_p, [0.0, 0.0, 1.0])
        out = diagnose_many(safe_m, safe_w)
        for value in out.values():
            if value.dtype.kind == "f":
                value[~good] = np.nan
        return out

    def body_and_state(self, values) -> tuple[RigidBody, AttitudeState]:
        """The :class:`~attitude.RigidBody` (principal moments in the guess body's axes)
        and the :class:`~attitude.AttitudeState` of one parameter vector."""
        moments, q_p2i, w_p, bad = self.principal_states(values)
        if bad:
            raise ValueError(next(iter(bad.values())))
        b2p = Rotation.from_quat(self.body_to_principal)
        axes = b2p.inv().as_matrix()                 # columns: principal axes, body frame
        inertia = axes @ np.diag(moments[0]) @ axes.T
        body = RigidBody(0.5 * (inertia + inertia.T))
        # the body built from the tensor may order its own principal axes differently;
        # the attitude is body -> inertial, independent of that choice
        attitude = Rotation.from_quat(q_p2i[0]) * b2p
        omega = b2p.inv().apply(w_p[0])
        return body, AttitudeState(self.epoch, attitude, omega, frame=self.frame)


def free_parameters(body: RigidBody, state: AttitudeState) -> tuple[dict, RotationModel]:
    """The eight parameters of a torque-free state, and the model that maps them back.

    Raises ``ValueError`` for a state the parameterisation cannot hold: at rest, a
    principal-axis spin or on the separatrix (no precession period), or an axisymmetric
    body.

    Examples
    --------
    >>> import numpy as np
    >>> import attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
    ...                           [0.05, 0.1, 1.0])
    >>> p, model = free_parameters(body, state)
    >>> round(p["energy_ratio"], 6), round(p["ratio_a"], 6)
    (1.001487, 0.6)
    >>> b2, s2 = model.body_and_state([p[k] for k in PARAMETERS])
    >>> bool(np.allclose(s2.omega_body, state.omega_body, rtol=1e-12, atol=1e-14))
    True
    """
    params, b2p = tumbling_parameters(body, state)
    C = float(np.max(body.principal_moments))
    model = RotationModel(state.epoch, b2p.as_quat(), C, state.frame)
    return params, model
