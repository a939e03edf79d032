"""Uniform gravity about a fixed pivot: the heavy top."""

from __future__ import annotations

import numpy as np

from ...foundations import quaternion as quat
from ...foundations.constants import STANDARD_GRAVITY
from ...foundations.errors import TorqueConfigError
from ...foundations.quaternion import cross_parts
from .base import TorqueModel
from .common import inertia_of, mass_of, parts, si_positive, si_value, stacked

__all__ = ["HeavyTopPivot"]


def heavy_top_torque(mg, up, lever) -> tuple:
    """``m g (u_b x l)``, body frame, N m, in component form: the one source of the
    formula (:meth:`HeavyTopPivot.evaluate`, the compiled kernel of
    :mod:`attitude.propagation.compiled_torques`).

    ``mg`` the weight (N), ``up`` the inertial up direction in body axes, ``lever`` the
    pivot -> centre of mass vector (body, m); floats or arrays that broadcast.
    """
    m0, m1, m2 = cross_parts(up, lever)
    return mg * m0, mg * m1, mg * m2


class HeavyTopPivot(TorqueModel):
    """Uniform gravity acting on a body that turns about a fixed pivot (the heavy top).

    .. math::

        M = l \\times (-m g\\, \\hat u_b) = m g\\, \\hat u_b \\times l

    with ``l`` the body-frame vector from the pivot to the centre of mass and ``hat u_b``
    the inertial "up" direction in body axes.  **The body's inertia must be the inertia
    about the pivot** (``I_pivot = I_cm + m (|l|^2 1 - l l^T)``, e.g.
    ``MassProperties.inertia_about(pivot)``), since Euler's equations are then written
    about the fixed point.

    For a symmetric top (``I1`` about the pivot, ``I3`` about the axis ``l``), steady
    precession at rate ``Omega`` with the axis at angle ``theta`` from up and spin
    component ``ω3`` requires ``m g l = Omega (I3 ω3 - I1 Omega cos theta)``; for a fast
    top ``Omega ~= m g l / (I3 ω3)`` (Goldstein, Poole & Safko 2002, Sec. 5.7).

    Parameters
    ----------
    mass : float (kg), Quantity or str, optional
        Default: ``body.mass``.
    pivot_to_com : (3,) array-like, Quantity or ``{value, unit}``
        Pivot -> centre of mass, body frame, m.
    g : float (m/s^2)
        Default :data:`STANDARD_GRAVITY`.
    up : (3,) array-like
        Inertial direction opposite to gravity (normalised).

    References
    ----------
    .. [1] Goldstein, H., Poole, C. & Safko, J. (2002). *Classical Mechanics*, 3rd ed.
       Addison-Wesley. Sec. 5.7 (heavy symmetrical top).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import HeavyTopPivot
    >>> top = HeavyTopPivot(mass=1.0, pivot_to_com=[0.0, 0.0, 0.1])   # 10 cm up the axis
    >>> body = RigidBody.from_principal_moments([0.02, 0.02, 0.01])
    >>> tilted = [np.sin(0.25), 0.0, 0.0, np.cos(0.25)]               # axis 0.5 rad from up
    >>> round(float(np.linalg.norm(top(0.0, tilted, [0, 0, 50.0], body))), 6)   # m g l sin
    0.47016
    """

    velocity_dependent = False

    def __init__(self, mass=None, pivot_to_com=None, g=STANDARD_GRAVITY, up=(0.0, 0.0, 1.0)):
        self.mass = None if mass is None else si_positive(mass, "kg", "mass")
        if pivot_to_com is None:
            raise TorqueConfigError("give the vector from the pivot to the "
                                    "centre of mass (body frame, m)", key="pivot_to_com")
        self.pivot_to_com = si_value(pivot_to_com, "m", "pivot_to_com", shape=(3,))
        self.g = si_positive(g, "m/s2", "g")
        up = si_value(up, "", "up", shape=(3,))
        norm = float(np.linalg.norm(up))
        if norm == 0:
            raise TorqueConfigError("must be a non-zero vector", key="up")
        self.up = up / norm

    def evaluate(self, t, quaternion, omega_body, body):
        mass = self.mass if self.mass is not None else mass_of(body)
        if mass is None:
            raise TorqueConfigError("the body has no mass: give HeavyTopPivot a "
                                    "mass, or build the body with one", key="mass")
        up_b = quat.rotate(quaternion, self.up, inverse=True)
        mg = np.asarray(mass, dtype=float) * self.g                 # (n,) for n bodies
        mg = float(mg) if mg.ndim == 0 else mg
        return stacked(heavy_top_torque(mg, parts(up_b), tuple(self.pivot_to_com.tolist())))

    def characteristic_rate(self, t, quaternion, omega_body, body):
        """``sqrt(m g |l| / I_swing)``, rad/s: the small-swing pendulum frequency
        (``I_swing`` the least moment about an axis normal to ``l``: the torque is always
        normal to ``l``), the time scale of a slow top; a fast top precesses more slowly,
        at about ``m g l / |L|``, and the splitting step adds how fast the torque changes
        along its nutation.

        Examples
        --------
        >>> import numpy as np
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import HeavyTopPivot
        >>> top = RigidBody(np.diag([9.5e-4, 9.5e-4, 2.0e-4]), mass=0.5)
        >>> pivot = HeavyTopPivot(pivot_to_com=[0.0, 0.0, 0.04])
        >>> round(pivot.characteristic_rate(0.0, [0, 0, 0, 1], [0, 0, 0.0], top), 3)
        14.369
        """
        mass = self.mass if self.mass is not None else mass_of(body)
        if mass is None:
            raise TorqueConfigError("the body has no mass: give HeavyTopPivot a "
                                    "mass, or build the body with one", key="mass")
        length = float(np.linalg.norm(self.pivot_to_com))
        mgl = np.asarray(mass, dtype=float) * self.g * length
        inertia = inertia_of(body)
        axis = self.pivot_to_com / length
        normal = np.eye(3) - np.outer(axis, axis)            # directions of the torque
        A = 1.0 / np.linalg.norm(np.linalg.inv(inertia) @ normal, ord=2, axis=(-2, -1))
        rate = np.sqrt(mgl / A)
        return float(rate) if np.ndim(rate) == 0 else rate

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("heavy_top", {mass_g, up, pivot_to_com})]`` (``mass_g = m g``, the mass
        from the body when not given) (:meth:`TorqueModel.compiled_parameters`).

        Raises
        ------
        TorqueConfigError
            If neither the model nor the body has a mass.

        Examples
        --------
        >>> from attitude.model.torques import HeavyTopPivot
        >>> top = HeavyTopPivot(mass=2.0, pivot_to_com=[0.0, 0.0, 0.1], g=10.0)
        >>> top.compiled_parameters(None)[0][1]["mass_g"]
        20.0
        """
        mass = self.mass if self.mass is not None else mass_of(body)
        if mass is None or np.ndim(mass) != 0:
            raise TorqueConfigError("the body has no mass: give HeavyTopPivot a "
                                    "mass, or build the body with one", key="mass")
        return [("heavy_top", {"mass_g": float(mass) * self.g,
                               "up": self.up.copy(),
                               "pivot_to_com": self.pivot_to_com.copy()})]

    def shifted(self, dt: float) -> HeavyTopPivot:
        """Itself (no time dependence)."""
        return self

    def __repr__(self) -> str:
        mass = "body.mass" if self.mass is None else f"{self.mass:.6g} kg"
        return (f"HeavyTopPivot(mass={mass}, pivot_to_com={self.pivot_to_com.tolist()} m, "
                f"g={self.g:.6g})")
