"""The torque of a residual magnetic dipole fixed in the body, ``m x B``."""

from __future__ import annotations

import numpy as np

from ...foundations import quaternion as quat
from ...foundations.errors import TorqueConfigError
from ...foundations.quaternion import cross_parts
from .base import TorqueModel
from .common import dot, moments_of, orbit_rate, parts, si_value, stacked, unit_quaternion
from .fields import UniformField, shifted_field

__all__ = ["MagneticDipole"]


def magnetic_dipole_torque(moment, b) -> tuple:
    """``m x B``, body frame, N m, in component form: the one source of the formula
    (:meth:`MagneticDipole.evaluate`, the compiled kernel of
    :mod:`attitude.propagation.compiled_torques`).

    ``moment`` (A m^2) and ``b`` (T), body axes; floats or arrays that broadcast.
    """
    return cross_parts(moment, b)


class MagneticDipole(TorqueModel):
    """Torque of a residual magnetic dipole fixed in the body: ``M = m x B``.

    .. math::

        M = m \\times B_b, \\qquad V = -\\,m \\cdot B_b

    with ``m`` the body's magnetic moment (A m^2, body frame: the net moment of its
    current loops and magnetised parts, magnetorquers off) and ``B_b`` the field at the
    body in body axes (the inertial field rotated by the attitude,
    ``B_b = q^{-1} B q``).  The torque depends on the attitude and the time only
    (``velocity_dependent = False``: an exact kick in the splitting integrator) and
    turns ``m`` toward ``B`` like a compass needle: in a uniform field it derives from
    the potential ``V`` (:meth:`potential`), and a small swing of ``m`` about ``B``
    about a principal axis of moment ``I`` normal to both oscillates at
    ``sqrt(|m| |B| / I)``.  Satellites carry residual dipoles of order 0.1-1 A m^2
    (an assumption unless measured: Inamori et al. 2011 estimate one in flight), which
    in a LEO field of 2e-5-5.5e-5 T gives torques up to ``|m| |B|`` ~ 2e-6-5e-5 N m.

    Parameters
    ----------
    moment : (3,) array-like, Quantity or ``{value, unit}``
        Magnetic moment, A m^2, body frame.
    field : callable ``t -> (..., 3)`` T, or (3,) array
        Inertial magnetic field at the body: :class:`UniformField`,
        :class:`TiltedDipoleField` along an orbit, :class:`attitude.environment.IGRF`,
        any function, or a constant vector.

    References
    ----------
    .. [1] Wertz, J. R. (ed.) (1978). *Spacecraft Attitude Determination and Control*.
       Reidel (environmental torques: the magnetic disturbance torque).
    .. [2] Inamori, T., Sako, N. & Nakasuka, S. (2011). Magnetic dipole moment
       estimation and compensation for an accurate attitude control in nano-satellite
       missions. *Acta Astronautica* 68, 2038-2046.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import MagneticDipole, UniformField
    >>> body = RigidBody.from_principal_moments([0.02, 0.03, 0.04])
    >>> needle = MagneticDipole({"value": [0.5, 0.0, 0.0], "unit": "A m2"},
    ...                         UniformField([0.0, 3e-5, 0.0]))
    >>> needle(0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body)      # m x B, about +z
    array([0.0e+00, 0.0e+00, 1.5e-05])
    >>> float(needle.potential(0.0, [0, 0, 0, 1], body))      # m normal to B
    0.0
    """

    velocity_dependent = False

    def __init__(self, moment, field):
        self.moment = si_value(moment, "A m2", "moment", shape=(3,))
        if field is None:
            raise TorqueConfigError("a magnetic dipole needs the field: give a "
                                    "UniformField, a TiltedDipoleField, an IGRF, a "
                                    "callable t -> B (T) or a vector", key="field")
        self.field = field if callable(field) else UniformField(field)

    def evaluate(self, t, quaternion, omega_body, body):
        B = quat.rotate(quaternion, np.asarray(self.field(t), dtype=float), inverse=True)
        return stacked(magnetic_dipole_torque(tuple(self.moment.tolist()), parts(B)))

    def potential(self, t, quaternion, body=None) -> np.ndarray:
        """Magnetic potential energy ``V = -m . B_b``, J: lowest with ``m`` along ``B``.
        ``E_kin + V`` is conserved when the field is fixed in inertial space.

        Examples
        --------
        >>> from attitude.model.torques import MagneticDipole
        >>> float(MagneticDipole([1.0, 0.0, 0.0], [2e-5, 0.0, 0.0]).potential(
        ...     0.0, [0, 0, 0, 1]))
        -2e-05
        """
        t = np.asarray(t, dtype=float)
        q = unit_quaternion(quaternion)
        B = quat.rotate(q, np.asarray(self.field(t), dtype=float), inverse=True)
        return -dot(np.broadcast_to(self.moment, B.shape), B)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """``sqrt(|m| |B(t)| / A)``, rad/s: the compass libration rate (``A`` the least
        moment), or the orbital rate of a field along an orbit if faster (the rate at
        which the field turns).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import MagneticDipole
        >>> body = RigidBody.from_principal_moments([1.0, 1.5, 2.0])
        >>> float(MagneticDipole([0.0, 0.0, 2.0], [0.0, 0.0, 4e-5]).characteristic_rate(
        ...     0.0, [0, 0, 0, 1], [0.0, 0.0, 0.0], body))           # sqrt(2 * 4e-5 / 1.0)
        0.008944271909999159
        """
        field = np.asarray(self.field(np.asarray(t, dtype=float)), dtype=float)
        strength = float(np.linalg.norm(self.moment)) * np.sqrt(dot(field, field))
        rate = np.sqrt(strength / moments_of(body)[..., 0])
        orbit = getattr(self.field, "orbit", None)
        if orbit is not None:
            rate = np.maximum(rate, orbit_rate(orbit))
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> TorqueModel:
        """Itself in a uniform field; in a tilted dipole on a Keplerian orbit, the same
        model with the orbit and the Earth rotation angle advanced by ``dt``; else (IGRF,
        a function) the default wrapper.

        Examples
        --------
        >>> from attitude.model.torques import MagneticDipole, UniformField
        >>> m = MagneticDipole([1.0, 0.0, 0.0], UniformField([0.0, 0.0, 3e-5]))
        >>> m.shifted(60.0) is m
        True
        """
        dt = float(dt)
        if dt == 0.0:
            return self
        field = shifted_field(self.field, dt)
        if field is self.field:
            return self
        if field is not None:
            return MagneticDipole(self.moment, field)
        return super().shifted(dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """``[("magnetic_dipole", {moment, field})]``, or None when the field has no
        compiled form (a user's function) (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import MagneticDipole, UniformField
        >>> model = MagneticDipole([0.3, 0.0, 0.0], UniformField([0, 0, 3e-5]))
        >>> [(kind, sorted(v)) for kind, v in model.compiled_parameters(None)]
        [('magnetic_dipole', ['field', 'moment'])]
        """
        if not callable(getattr(self.field, "compiled_parameters", None)):
            return None
        return [("magnetic_dipole", {"moment": self.moment.copy(), "field": self.field})]

    def __repr__(self) -> str:
        return f"MagneticDipole(moment={self.moment.tolist()} A m2, field={self.field!r})"
