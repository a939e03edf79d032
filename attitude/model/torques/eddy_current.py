"""The eddy-current torque on a spinning conductor in a magnetic field."""

from __future__ import annotations

import numpy as np

from ...foundations import quaternion as quat
from ...foundations.errors import TorqueConfigError
from ...foundations.quaternion import cross_parts
from .base import TorqueModel
from .common import (
    dot,
    matvec_parts,
    moments_of,
    orbit_rate,
    parts,
    si_positive,
    si_value,
    stacked,
)
from .fields import UniformField, shifted_field

__all__ = ["EddyCurrentDamping"]


def eddy_current_torque(tensor, w, b) -> tuple:
    """``(M (w x B)) x B``, body frame, N m, in component form: the one source of the
    formula (:meth:`EddyCurrentDamping.evaluate`, the compiled kernel of
    :mod:`attitude.propagation.compiled_torques`).

    ``tensor`` the nine entries of the magnetic tensor row-major (S m^4; an isotropic
    one is its scalar times the identity), ``w`` the rate (rad/s) and ``b`` the field
    (T), body axes; floats or arrays that broadcast.
    """
    return cross_parts(matvec_parts(tensor, cross_parts(w, b)), b)


class EddyCurrentDamping(TorqueModel):
    """Eddy-current torque on a spinning conducting body in a slowly varying field.

    .. math::

        M = \\big(\\mathbf{M}\\,(\\omega \\times B)\\big) \\times B

    with ``B`` the field in body axes (the inertial field rotated by the attitude) and
    ``bold M`` the symmetric positive semi-definite *magnetic tensor* of the body (body
    frame, S m^4), which depends only on its shape and conductivity (Ortiz Gomez &
    Walker 2015).  It is always dissipative:
    ``ω . M = -(ω x B) . bold M (ω x B) <= 0``.  For an isotropic tensor ``m 1``,
    ``M = -m B^2 ω_perp`` (``ω_perp`` the component of ``ω`` normal to ``B``); a sphere
    of moment ``I`` in a uniform field keeps ``ω_parallel`` and loses ``ω_perp`` as
    ``exp(-m B^2 t / I)``.

    Valid at low spin rates, when the induced field is negligible (skin depth much
    larger than the wall thickness; Praly et al. 2012).

    Parameters
    ----------
    magnetic_tensor : float or (3, 3) array-like, Quantity or str
        S m^4, body frame.  A thin spherical shell (radius ``R``, thickness ``h``,
        conductivity ``sigma``) has ``(2 pi / 3) sigma R^4 h`` times the identity, a solid
        sphere ``(2 pi / 15) sigma R^5``: see :meth:`spherical_shell`,
        :meth:`solid_sphere`.
    field : callable ``t -> (..., 3)`` T, or (3,) array
        Inertial magnetic field at the body: :class:`TiltedDipoleField` along an orbit,
        :class:`UniformField`, any function, or a constant vector.

    Notes
    -----
    Derivation for a sphere: in body axes the field changes as ``dB/dt = -ω x B``; the
    induced electric field ``E = -(1/2) dB/dt x r`` is tangential and divergence-free,
    so ``J = sigma E`` needs no surface charge; its moment ``m = (1/2) ∫ r x J dV =
    -(sigma/4) ∫ r^2 (1 - r_hat r_hat) dV dB/dt`` gives ``(2 pi/3) sigma R^4 h`` for a
    thin shell, and ``M = m x B``.

    References
    ----------
    .. [1] Ortiz Gomez, N. & Walker, S. J. I. (2015). Eddy currents applied to
       de-tumbling of space debris: analysis and validation of approximate proposed
       methods. *Acta Astronautica* 114, 34-53.
    .. [2] Praly, N., Hillion, M., Bonnal, C., Laurent-Varin, J. & Petit, N. (2012).
       Study on the eddy current damping of the spin dynamics of space debris from the
       Ariane upper stage. *Acta Astronautica* 76, 145-153.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import EddyCurrentDamping, UniformField
    >>> body = RigidBody.from_principal_moments([10.0, 10.0, 10.0])
    >>> damper = EddyCurrentDamping.solid_sphere("0.5 m", "3.5e7 S/m", UniformField([0, 0, 3e-5]))
    >>> m = damper(0.0, [0, 0, 0, 1], [0.1, 0.0, 0.1], body)
    >>> bool(m[0] < 0 and abs(m[2]) < 1e-20)      # brakes the spin across B, not along it
    True
    """

    velocity_dependent = True

    def __init__(self, magnetic_tensor, field):
        tensor = np.asarray(si_value(magnetic_tensor, "S m4", "magnetic_tensor",
                                      shape=None), dtype=float)
        if tensor.shape == ():
            if tensor < 0:
                raise TorqueConfigError(f"must be >= 0, got {tensor}", key="magnetic_tensor")
            self.isotropic = True
        elif tensor.shape == (3, 3):
            scale = np.max(np.abs(tensor))
            if np.any(np.abs(tensor - tensor.T) > 1e-10 * scale):
                raise TorqueConfigError("must be symmetric", key="magnetic_tensor")
            tensor = 0.5 * (tensor + tensor.T)
            if np.linalg.eigvalsh(tensor)[0] < -1e-12 * scale:
                raise TorqueConfigError("must be positive semi-definite "
                                        "(a negative eigenvalue would pump energy in)",
                                        key="magnetic_tensor")
            self.isotropic = False
        else:
            raise TorqueConfigError(f"expected a scalar or a 3x3 tensor, "
                                    f"got shape {tensor.shape}", key="magnetic_tensor")
        self.magnetic_tensor = tensor
        full = float(tensor) * np.eye(3) if self.isotropic else tensor
        self._entries = tuple(full.ravel().tolist())        # row-major, for the formula
        if callable(field):
            self.field = field
        else:
            self.field = UniformField(field)

    @classmethod
    def spherical_shell(cls, radius, thickness, conductivity, field) -> EddyCurrentDamping:
        """Thin spherical shell: ``bold M = (2 pi / 3) sigma R^4 h`` (isotropic)."""
        R = si_positive(radius, "m", "radius")
        h = si_positive(thickness, "m", "thickness")
        sigma = si_positive(conductivity, "S/m", "conductivity")
        return cls(2.0 * np.pi / 3.0 * sigma * R**4 * h, field)

    @classmethod
    def solid_sphere(cls, radius, conductivity, field) -> EddyCurrentDamping:
        """Solid sphere: ``bold M = (2 pi / 15) sigma R^5`` (isotropic)."""
        R = si_positive(radius, "m", "radius")
        sigma = si_positive(conductivity, "S/m", "conductivity")
        return cls(2.0 * np.pi / 15.0 * sigma * R**5, field)

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """``lambda_max(bold M) |B(t)|^2 / A``, rad/s: the fastest damping rate of the
        spin (``A`` the least moment), or the orbital rate of a field along an orbit if
        larger."""
        tensor = np.atleast_2d(self.magnetic_tensor)
        strength = (float(abs(self.magnetic_tensor)) if self.isotropic
                    else float(np.max(np.abs(np.linalg.eigvalsh(tensor)))))
        field = np.asarray(self.field(np.asarray(t, dtype=float)), dtype=float)
        rate = strength * dot(field, field) / moments_of(body)[..., 0]
        orbit = getattr(self.field, "orbit", None)
        if orbit is not None:
            rate = np.maximum(rate, orbit_rate(orbit))
        return float(rate) if np.ndim(rate) == 0 else rate

    def shifted(self, dt: float) -> TorqueModel:
        """Itself in a uniform field; in a tilted dipole on a Keplerian orbit, the same
        model with the orbit and the Earth rotation angle advanced by ``dt``; else the
        default wrapper."""
        dt = float(dt)
        if dt == 0.0:
            return self
        field = shifted_field(self.field, dt)
        if field is self.field:
            return self
        if field is not None:
            return EddyCurrentDamping(self.magnetic_tensor, field)
        return super().shifted(dt)

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]] | None:
        """``[("eddy_current", {isotropic, scalar, tensor, field})]`` (``tensor`` 3 x 3,
        the isotropic ``scalar`` times the identity when ``isotropic``), or None when the
        field has no compiled form (a user's function)
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import EddyCurrentDamping, UniformField
        >>> damper = EddyCurrentDamping(2.0, UniformField([0, 0, 3e-5]))
        >>> damper.compiled_parameters(None)[0][1]["isotropic"]
        True
        """
        if not callable(getattr(self.field, "compiled_parameters", None)):
            return None
        tensor = (float(self.magnetic_tensor) * np.eye(3) if self.isotropic
                  else np.array(self.magnetic_tensor, dtype=float))
        return [("eddy_current", {"tensor": tensor, "isotropic": self.isotropic,
                                  "scalar": float(self.magnetic_tensor[()]) if
                                  self.isotropic else 0.0, "field": self.field})]

    def evaluate(self, t, quaternion, omega_body, body):
        B = quat.rotate(quaternion, np.asarray(self.field(t), dtype=float), inverse=True)
        return stacked(eddy_current_torque(self._entries, parts(omega_body), parts(B)))

    def __repr__(self) -> str:
        m = (f"{float(self.magnetic_tensor):.6g}" if self.isotropic
             else str(self.magnetic_tensor.tolist()))
        return f"EddyCurrentDamping(magnetic_tensor={m} S m4, field={self.field!r})"
