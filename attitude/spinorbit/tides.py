r"""Tidal despinning: how long a moon takes to reach the synchronous state.

Gladman, Quinn, Nicholson & Rand (1996, Icarus 122, 166, eq. 9): a satellite of mass
``m``, radius ``R`` and moment of inertia ``I = alpha m R^2`` spinning at ``omega`` on an
orbit of semi-major axis ``a`` about a primary of mass ``m_p`` is despun by the tide the
primary raises in it in

.. math::

    \tau_{despin} = \frac{\omega\,a^6\,I\,Q}{3\,G\,m_p^2\,k_2\,R^5},

with ``Q`` the tidal dissipation factor and ``k_2`` the potential Love number.  For a
homogeneous elastic body of rigidity ``mu_r``, density ``rho`` and surface gravity
``g = G m / R^2`` (Love 1944; Gladman et al. eq. 10)

.. math::

    k_2 = \frac{3/2}{1 + \dfrac{19\,\mu_r}{2\,\rho\,g\,R}},

so small, rigid bodies (``19 mu_r / (2 rho g R) >> 1``) have ``k_2 ~ 3 rho g R / (19
mu_r)``, tiny.  Gladman et al. use ``Q = 100`` and ``mu_r = 3e10 N/m^2`` (rock) or
``4e9 N/m^2`` (ice).  Compare the result with the age of the system and with the
damping time of the free wobble to say which state a moon should have reached.
"""

from __future__ import annotations

import math

from ..foundations.constants import G
from ..foundations.errors import SpinOrbitError
from ..foundations.quantities import to_si

__all__ = ["G", "love_number_k2", "despinning_time"]



def _positive(value, unit: str, key: str) -> float:
    try:
        x = float(to_si(value, unit, name=key))
    except Exception as exc:  # noqa: BLE001  (re-raised as our error, naming the key)
        raise SpinOrbitError(f"expected a quantity in {unit!r}, got {value!r} ({exc})",
                             key=key) from None
    if not (math.isfinite(x) and x > 0):
        raise SpinOrbitError(f"must be a finite, positive quantity ({unit}), got "
                             f"{value!r}", key=key)
    return x


def love_number_k2(*, mass, radius, rigidity=3e10) -> float:
    """``k2 = 1.5 / (1 + 19 mu_r / (2 rho g R))`` of a homogeneous elastic sphere.

    Parameters
    ----------
    mass : float (kg), Quantity or str
    radius : float (m), Quantity or str
    rigidity : float (Pa), Quantity or str
        ``3e10`` rock, ``4e9`` ice (Gladman et al. 1996).

    Examples
    --------
    >>> round(love_number_k2(mass=1.0659e16, radius="11.1 km"), 9)     # Phobos, rock
    6.28e-07
    """
    m = _positive(mass, "kg", "mass")
    R = _positive(radius, "m", "radius")
    mu_r = _positive(rigidity, "Pa", "rigidity")
    rho = m / (4.0 / 3.0 * math.pi * R**3)
    g = G * m / R**2
    return 1.5 / (1.0 + 19.0 * mu_r / (2.0 * rho * g * R))


def despinning_time(*, spin_rate, semi_major_axis, primary_mass, mass, radius,
                    Q: float = 100.0, rigidity=3e10, k2: float | None = None,
                    moment_factor: float = 0.4) -> float:
    """Tidal despinning time (s) of Gladman et al. (1996, eq. 9).

    Parameters
    ----------
    spin_rate : float (rad/s), Quantity or str
        Initial spin rate ``omega`` (e.g. ``"2 rev/d"`` or ``"1e-4 rad/s"``).
    semi_major_axis : float (m), Quantity or str
    primary_mass, mass : float (kg), Quantity or str
        Mass of the primary and of the satellite.
    radius : float (m), Quantity or str
        Mean radius of the satellite.
    Q : float
        Tidal dissipation factor (100 in Gladman et al.).
    rigidity : float (Pa), Quantity or str
        For ``k2`` when it is not given.
    k2 : float, optional
        Love number; default :func:`love_number_k2`.
    moment_factor : float
        ``alpha = I / (m R^2)`` (0.4 homogeneous sphere).

    Returns
    -------
    float
        Seconds.

    References
    ----------
    .. [1] Gladman, B., Quinn, D. D., Nicholson, P. & Rand, R. (1996). Synchronous
       locking of tidally evolving satellites. *Icarus* 122, 166-192.

    Examples
    --------
    >>> t = despinning_time(spin_rate="2 rev/d", semi_major_axis="9376 km",
    ...                     primary_mass=6.417e23, mass=1.0659e16, radius="11.1 km")
    >>> 1e3 < t / 3.15576e7 < 1e6      # Phobos from a 12 h spin: ~ 1e4 years
    True
    """
    w = _positive(spin_rate, "rad/s", "spin_rate")
    a = _positive(semi_major_axis, "m", "semi_major_axis")
    mp = _positive(primary_mass, "kg", "primary_mass")
    m = _positive(mass, "kg", "mass")
    R = _positive(radius, "m", "radius")
    if not (math.isfinite(Q) and Q > 0):
        raise SpinOrbitError(f"must be > 0, got {Q!r}", key="Q")
    if not 0 < moment_factor <= 2.0 / 3.0:
        raise SpinOrbitError(f"must be in (0, 2/3], got {moment_factor!r}",
                             key="moment_factor")
    if k2 is None:
        k2 = love_number_k2(mass=m, radius=R, rigidity=rigidity)
    elif not (math.isfinite(k2) and k2 > 0):
        raise SpinOrbitError(f"must be > 0, got {k2!r}", key="k2")
    inertia = moment_factor * m * R**2
    return w * a**6 * inertia * Q / (3.0 * G * mp**2 * k2 * R**5)
