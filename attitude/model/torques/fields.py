"""Magnetic field models for the magnetic torques: a uniform field, and the Earth's
tilted dipole along an orbit (IGRF-14 lives in :mod:`attitude.environment.igrf`)."""

from __future__ import annotations

import numpy as np

from ...foundations.constants import (
    EARTH_DIPOLE_MOMENT,
    EARTH_DIPOLE_POLE_LONGITUDE,
    EARTH_DIPOLE_TILT,
    EARTH_ROTATION_RATE,
    MU0_OVER_4PI,
)
from ..orbit import KeplerOrbit, as_path
from .common import advance, parts, si_positive, si_value, stacked

__all__ = ["UniformField", "TiltedDipoleField", "shifted_field"]


def dipole_direction(sin_tilt, cos_tilt, longitude) -> tuple:
    """The unit dipole moment (pointing south) whose northern pole is at colatitude
    ``tilt`` and inertial longitude ``longitude`` (rad), component form: the one source
    (:meth:`TiltedDipoleField.dipole_direction`, the compiled kernel of
    :mod:`attitude.propagation.compiled_torques`); floats or arrays."""
    return (-(sin_tilt * np.cos(longitude)), -(sin_tilt * np.sin(longitude)),
            -cos_tilt)


def dipole_field(coefficient, m_hat, r) -> tuple:
    """``mu0 m / (4 pi r^3) (3 (m_hat . r_hat) r_hat - m_hat)``, T, component form
    (``coefficient = mu0 m / 4 pi``, ``m_hat`` the unit moment, ``r`` the position, m):
    the one source (:class:`TiltedDipoleField`, the compiled kernel of
    :mod:`attitude.propagation.compiled_torques`); floats or arrays that broadcast."""
    x, y, z = r
    mx, my, mz = m_hat
    r2 = x * x + y * y + z * z
    rn = np.sqrt(r2)
    hx, hy, hz = x / rn, y / rn, z / rn
    scale = coefficient / (r2 * rn)
    d3 = 3.0 * (mx * hx + my * hy + mz * hz)
    return scale * (d3 * hx - mx), scale * (d3 * hy - my), scale * (d3 * hz - mz)


class UniformField:
    """A magnetic field constant in inertial space, T (callable ``t -> (..., 3)``).

    Examples
    --------
    >>> from attitude.model.torques import UniformField
    >>> UniformField([0.0, 0.0, 3e-5])([0.0, 60.0])
    array([[0.e+00, 0.e+00, 3.e-05],
           [0.e+00, 0.e+00, 3.e-05]])
    """

    def __init__(self, field):
        self.vector = si_value(field, "T", "field", shape=(3,))

    def __call__(self, t) -> np.ndarray:
        return np.broadcast_to(self.vector, np.shape(t) + (3,)).copy()

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("uniform", {vector})``: the field as numbers for a compiled kernel
        (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude.model.torques import UniformField
        >>> UniformField([0.0, 0.0, 3e-5]).compiled_parameters()
        ('uniform', {'vector': array([0.e+00, 0.e+00, 3.e-05])})
        """
        return ("uniform", {"vector": self.vector.copy()})

    def __repr__(self) -> str:
        return f"UniformField({self.vector.tolist()} T)"


class TiltedDipoleField:
    """The Earth's field as a tilted dipole rotating with the Earth, along an orbit.

    .. math::

        B(r) = \\frac{\\mu_0}{4\\pi}\\,\\frac{m}{r^3}\\left(3 (\\hat m\\cdot\\hat r)\\hat r
               - \\hat m\\right)

    with ``hat m`` pointing from the northern geomagnetic pole to the southern one (the
    Earth's moment points roughly south).  In Earth-fixed axes the northern geomagnetic
    pole is at colatitude ``tilt`` and east longitude ``pole_longitude``; Earth-fixed
    axes turn about the inertial ``z`` axis by ``theta(t) = rotation_angle + rate t``
    (the Earth rotation angle).  The inertial frame is taken as equatorial (GCRF,
    EME2000; precession and nutation ignored) and ``r`` comes from the path.

    Parameters
    ----------
    orbit : KeplerOrbit, path, callable or (3,) array
        Position of the body relative to the Earth's centre, inertial, m.
    moment : float (A m^2), Quantity or str
        Dipole moment; default :data:`EARTH_DIPOLE_MOMENT` (7.94e22 A m^2: 3.07e-5 T at
        the magnetic equator on a 6371.2 km sphere).
    tilt, pole_longitude : float (rad), Quantity or str
        Colatitude and east longitude of the northern geomagnetic pole; defaults 9.4 deg
        and -72.7 deg (IGRF-13, 2020).
    rotation_angle : float (rad), Quantity or str
        Earth rotation angle (Greenwich sidereal angle) at ``t = 0``
        (:func:`attitude.foundations.earth_rotation.earth_rotation_angle` of the epoch).
    rotation_rate : float (rad/s)
        Default :data:`EARTH_ROTATION_RATE`.

    References
    ----------
    .. [1] Wertz, J. R. (ed.) (1978). *Spacecraft Attitude Determination and Control*.
       Reidel. Sec. 5.1 and App. H (dipole model of the geomagnetic field).
    .. [2] Alken, P. et al. (2021). International Geomagnetic Reference Field: the
       thirteenth generation. *Earth Planets Space* 73, 49.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.orbit import KeplerOrbit
    >>> from attitude.model.torques import TiltedDipoleField
    >>> leo = KeplerOrbit.from_elements(mu=3.986004418e14, a="6871 km", i="51.6 deg")
    >>> b = TiltedDipoleField(leo)(np.linspace(0.0, leo.period, 7))
    >>> bool(np.all((np.linalg.norm(b, axis=-1) > 1.5e-5) & (np.linalg.norm(b, axis=-1) < 6e-5)))
    True
    """

    def __init__(self, orbit, *, moment=EARTH_DIPOLE_MOMENT, tilt=EARTH_DIPOLE_TILT,
                 pole_longitude=EARTH_DIPOLE_POLE_LONGITUDE, rotation_angle=0.0,
                 rotation_rate=EARTH_ROTATION_RATE):
        self.orbit = as_path(orbit)
        self.moment = si_positive(moment, "A m2", "moment")
        self.tilt = si_value(tilt, "rad", "tilt")
        self.pole_longitude = si_value(pole_longitude, "rad", "pole_longitude")
        self.rotation_angle = si_value(rotation_angle, "rad", "rotation_angle")
        self.rotation_rate = si_value(rotation_rate, "rad/s", "rotation_rate")

    def dipole_direction(self, t) -> np.ndarray:
        """Unit vector of the dipole moment (pointing south), inertial, ``S + (3,)``."""
        return stacked(self._direction(np.asarray(t, dtype=float)))

    def _direction(self, t) -> tuple:
        lam = (self.rotation_angle + self.rotation_rate * t) + self.pole_longitude
        return dipole_direction(float(np.sin(self.tilt)), float(np.cos(self.tilt)), lam)

    def __call__(self, t) -> np.ndarray:
        """Field at the body, inertial components, T, shape ``S + (3,)``."""
        t = np.asarray(t, dtype=float)
        r = np.asarray(self.orbit.position(t), dtype=float)
        m_hat = self._direction(float(t) if t.ndim == 0 else t)
        return stacked(dipole_field(MU0_OVER_4PI * self.moment, m_hat, parts(r)))

    def compiled_parameters(self, t_span=None) -> tuple[str, dict]:
        """``("tilted_dipole", {...})``: the field as numbers for a compiled kernel, the
        same terms as :meth:`__call__` (``coefficient = mu0 / 4 pi * moment``, the sine
        and cosine of the tilt, the rotation angle, rate and pole longitude, the orbit).

        Examples
        --------
        >>> from attitude.model.torques import TiltedDipoleField
        >>> kind, values = TiltedDipoleField([7e6, 0.0, 0.0]).compiled_parameters()
        >>> kind, float(values["coefficient"])
        ('tilted_dipole', 7940000000000000.0)
        """
        return ("tilted_dipole", {
            "coefficient": MU0_OVER_4PI * self.moment,
            "sin_tilt": float(np.sin(self.tilt)), "cos_tilt": float(np.cos(self.tilt)),
            "rotation_angle": float(self.rotation_angle),
            "rotation_rate": float(self.rotation_rate),
            "pole_longitude": float(self.pole_longitude), "orbit": self.orbit})

    def __repr__(self) -> str:
        return (f"TiltedDipoleField(moment={self.moment:.4g} A m2, tilt="
                f"{np.degrees(self.tilt):.4g} deg, orbit={self.orbit!r})")


def shifted_field(field, dt: float):
    """``field`` with its time origin moved ``dt`` s later, as a field of its own class
    (uniform: itself; tilted dipole on a Keplerian orbit: the orbit and the Earth
    rotation angle advanced), or None when it has no such form.

    Examples
    --------
    >>> from attitude.model.orbit import KeplerOrbit
    >>> from attitude.model.torques.fields import TiltedDipoleField, shifted_field
    >>> field = TiltedDipoleField(KeplerOrbit(mu=3.986004418e14, a=7.0e6, e=0.001))
    >>> later = shifted_field(field, 600.0)
    >>> bool(abs(later(0.0) - field(600.0)).max() <= 1e-12 * abs(field(600.0)).max())
    True
    """
    if isinstance(field, UniformField):
        return field
    if isinstance(field, TiltedDipoleField) and isinstance(field.orbit, KeplerOrbit):
        return TiltedDipoleField(advance(field.orbit, dt), moment=field.moment,
                                 tilt=field.tilt, pole_longitude=field.pole_longitude,
                                 rotation_angle=field.rotation_angle
                                 + field.rotation_rate * dt,
                                 rotation_rate=field.rotation_rate)
    return None
