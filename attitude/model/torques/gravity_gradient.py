"""The gravity-gradient torque of a point-mass primary."""

from __future__ import annotations

import math

import numpy as np

from ...foundations import quaternion as quat
from ...foundations.errors import TorqueConfigError
from ...foundations.quaternion import cross_parts
from ..orbit import KeplerOrbit, as_path
from .base import TorqueModel
from .common import (
    advance,
    dot,
    entries,
    inertia_of,
    matvec,
    matvec_parts,
    min_radius,
    orbit_rate,
    parts,
    si_positive,
    stacked,
    unit_quaternion,
)

__all__ = ["GravityGradient"]


def gravity_gradient_torque(mu, inertia, r) -> tuple:
    """``3 mu / r^5 (r x I r)``, body frame, N m, in component form: the one source of
    the formula (:meth:`GravityGradient.evaluate` on arrays over time, the compiled
    kernel of :mod:`attitude.propagation.compiled_torques` on floats).

    ``mu`` (m^3/s^2), ``inertia`` the nine entries of ``I`` row-major (kg m^2), ``r`` the
    position ``(x, y, z)`` in body axes (m); floats or arrays that broadcast.
    """
    x, y, z = r
    r2 = x * x + y * y + z * z
    f = 3.0 * mu / (r2 * r2 * np.sqrt(r2))
    m0, m1, m2 = cross_parts(r, matvec_parts(inertia, r))
    return f * m0, f * m1, f * m2


class GravityGradient(TorqueModel):
    """Gravity-gradient torque of a point-mass primary.

    .. math::

        M = \\frac{3\\mu}{r^3}\\,\\hat r \\times (I \\hat r)
          = \\frac{3\\mu}{r^5}\\, r \\times (I r)

    with ``r`` the position of the body relative to the primary (the torque is even in
    ``r``, so the sign convention does not matter) expressed in body axes through the
    attitude, ``r_b = q^{-1} r q``, and ``I`` the body-frame inertia tensor about the
    centre of mass.  The lowest order of the expansion of the primary's potential over
    the body (Hughes 1986, Ch. 8): valid while the body is small compared with ``r``.
    Conservative: it derives from the potential ``V = mu/(2 r^3) (3 r_hat . I r_hat -
    tr I)`` (MacCullagh's formula), see :meth:`potential`.

    Parameters
    ----------
    mu : float, Quantity or str, optional
        Gravitational parameter of the primary, m^3/s^2.  Default: ``orbit.mu`` when the
        orbit is a :class:`~attitude.model.orbit.KeplerOrbit`.
    orbit : KeplerOrbit, path, callable or (3,) array
        Where the body is: anything with ``position(t)`` (inertial, m; e.g.
        :class:`~attitude.model.orbit.TabulatedPath` for a real ephemeris), a callable
        ``t -> position`` or a fixed position vector.

    Notes
    -----
    A body pitched by ``theta`` about an axis ``k`` normal to ``r`` with the two other
    principal moments ``I_i, I_j`` (``r`` in their plane) feels
    ``3 mu / (2 r^3) (I_j - I_i) sin 2 theta`` about ``k``; the torque vanishes when a
    principal axis points at the primary.  In a circular orbit of mean motion ``n`` the
    small pitch libration of an Earth-pointing body has frequency
    ``n sqrt(3 (I_along - I_radial) / I_normal)``.

    References
    ----------
    .. [1] Hughes, P. C. (1986). *Spacecraft Attitude Dynamics*. Wiley. Ch. 8.
    .. [2] Touma, J. & Wisdom, J. (1994). Lie-Poisson integrators for rigid body
       dynamics in the solar system. *Astron. J.* 107, 1189.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import GravityGradient
    >>> body = RigidBody.from_principal_moments([100.0, 200.0, 250.0])
    >>> gg = GravityGradient(3.986004418e14, [7.0e6, 0.0, 0.0])   # primary along -x
    >>> theta = np.radians(10.0)                                   # pitch about z
    >>> q = [0.0, 0.0, np.sin(theta / 2), np.cos(theta / 2)]
    >>> torque = gg(0.0, q, [0.0, 0.0, 0.0], body)
    >>> expected = 1.5 * 3.986004418e14 / 7.0e6**3 * (200.0 - 100.0) * np.sin(2 * theta)
    >>> bool(np.isclose(torque[2], -expected, rtol=1e-14))
    True
    """

    velocity_dependent = False

    def __init__(self, mu=None, orbit=None):
        if orbit is None:
            raise TorqueConfigError("a gravity-gradient torque needs the body's "
                                    "position: give a KeplerOrbit, a path, a "
                                    "callable or a position vector", key="orbit")
        self.orbit = as_path(orbit)
        if mu is None:
            if not isinstance(self.orbit, KeplerOrbit):
                raise TorqueConfigError("give the gravitational parameter of the "
                                        "primary (only a KeplerOrbit carries one)", key="mu")
            mu = self.orbit.mu
        self.mu = si_positive(mu, "m3/s2", "mu")

    def evaluate(self, t, quaternion, omega_body, body):
        r_b = quat.rotate(quaternion, self.orbit.position(t), inverse=True)
        return stacked(gravity_gradient_torque(self.mu, entries(inertia_of(body)),
                                               parts(r_b)))

    def characteristic_rate(self, t, quaternion, omega_body, body) -> float:
        """``max(sqrt(3 mu / r_p^3), orbital rate at periapsis)``, rad/s: the libration
        rate of a body with ``(C - A)/B = 1`` (``r_p`` the periapsis distance, or
        ``|r(0)|``), or the rate at which the direction to the primary turns."""
        r = min_radius(self.orbit)
        return max(math.sqrt(3.0 * self.mu / r**3), orbit_rate(self.orbit))

    def shifted(self, dt: float) -> TorqueModel:
        """On a Keplerian orbit: the same model with the mean anomaly advanced by
        ``n dt``; other paths: the default wrapper."""
        dt = float(dt)
        if dt == 0.0:
            return self
        if isinstance(self.orbit, KeplerOrbit):
            return GravityGradient(self.mu, advance(self.orbit, dt))
        return super().shifted(dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("gravity_gradient", {mu, inertia, orbit})]``
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import GravityGradient
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> [(kind, sorted(v)) for kind, v in GravityGradient(
        ...     3.986e14, [7e6, 0, 0]).compiled_parameters(body)]
        [('gravity_gradient', ['inertia', 'mu', 'orbit'])]
        """
        return [("gravity_gradient", {"mu": self.mu, "inertia": inertia_of(body),
                                      "orbit": self.orbit})]

    def potential(self, t, quaternion, body) -> np.ndarray:
        """Gravity-gradient potential energy ``V = mu/(2 r^3)(3 r_hat.I r_hat - tr I)``, J.

        The second-order term of MacCullagh's formula for the potential energy of an
        extended body, ``U = -mu m / r - mu/(2 r^3)(tr I - 3 r_hat.I r_hat)``: the part that
        depends on the attitude (lowest when the axis of least inertia points at the
        primary).  ``E_kin + V`` is conserved when the primary is fixed.
        """
        t = np.asarray(t, dtype=float)
        q = unit_quaternion(quaternion)
        r_b = quat.rotate(q, self.orbit.position(t), inverse=True)
        r2 = dot(r_b, r_b)
        inertia = inertia_of(body)
        trace = np.trace(inertia, axis1=-2, axis2=-1)
        return self.mu / (2.0 * r2 * np.sqrt(r2)) * (3.0 * dot(r_b, matvec(
            inertia, r_b)) / r2 - trace)

    def __repr__(self) -> str:
        return f"GravityGradient(mu={self.mu:.10g}, orbit={self.orbit!r})"
