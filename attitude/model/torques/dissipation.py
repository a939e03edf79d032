"""Internal energy dissipation (a damper, an inelastic asteroid) and the damping time
scale of a tumbling asteroid."""

from __future__ import annotations

import math

import numpy as np
from astropy import units as u

from ...foundations.errors import TorqueConfigError
from ..body import SYMMETRY_RTOL, RigidBody
from .base import TorqueModel
from .common import (
    dot_parts,
    entries,
    inertia_of,
    matvec_parts,
    moments_of,
    parts,
    si_positive,
    stacked,
)

__all__ = ["EnergyDissipation", "damping_timescale"]


def dissipation_torque(k, inertia, w) -> tuple:
    """``-k w_perp``, body frame, N m, in component form: ``w_perp`` the part of the
    rate ``w`` normal to ``L = I w``, projected out twice (the second pass removes the
    rounding error of the first, so that ``L . M`` vanishes to the last bit).  The one
    source of the formula (:meth:`EnergyDissipation.evaluate`, the compiled kernel of
    :mod:`attitude.propagation.compiled_torques`).

    ``k`` (kg m^2/s), ``inertia`` the nine entries of ``I`` row-major, ``w`` (rad/s);
    floats or arrays that broadcast.  A body at rest (``L^2 = 0``) gets ``-k w``, zero.
    """
    L = matvec_parts(inertia, w)
    L2 = dot_parts(L, L)
    safe = L2 + (L2 == 0.0)             # 1 where L = 0 (floats and arrays alike)
    c = dot_parts(w, L) / safe
    p0, p1, p2 = w[0] - c * L[0], w[1] - c * L[1], w[2] - c * L[2]
    c = dot_parts((p0, p1, p2), L) / safe
    nk = -k
    return nk * (p0 - c * L[0]), nk * (p1 - c * L[1]), nk * (p2 - c * L[2])


class EnergyDissipation(TorqueModel):
    r"""Internal energy dissipation with the inertial angular momentum fixed: the
    quasi-rigid relaxation of a tumbling asteroid, or of a spacecraft with a nutation
    damper, fuel slosh or flexible antennas (Explorer 1).

    A body that dissipates energy inside itself keeps its total angular momentum: in
    inertial space ``L`` does not move, while in the body frame it drifts toward the
    axis of the largest moment, where the kinetic energy ``E = L.I^-1 L / 2`` is least
    for the given ``|L|`` (the quasi-rigid picture of Sharma, Burns & Hui 2005 and
    Breiter, Rozek & Vokrouhlicky 2012: the body is rigid to first order, the small
    anelastic strains only drain energy).  With ``omega = I^-1 L`` the rigid-body rate,
    the body-frame angular momentum obeys

    .. math::

        \frac{dL}{dt} = L\times\omega + M, \qquad
        M = \frac{k}{L^2}\, L\times(L\times\omega) = -k\,\omega_\perp ,

    ``omega_perp = omega - (omega.L) L / L^2`` the part of ``omega`` normal to ``L``.
    ``M`` is the internal torque this class returns: ``L.M = 0`` (``|L|`` kept) and

    .. math::

        \frac{dE}{dt} = \omega\cdot M = -k\,|\omega_\perp|^2 \le 0 ,

    zero only for a principal-axis spin; among the torques that keep ``|L|`` it is the
    one that removes energy fastest for its size (the "double bracket" dissipation of
    Bloch et al. 1996).  Stable end state: spin about the major axis, ``E = L^2/2C``.

    **The attitude.**  ``L_inertial = R L`` is fixed, so the body frame cannot turn at
    ``omega`` alone: with ``dR/dt = R [Omega x]``, ``d(R L)/dt = R (Omega x L + L x
    omega + M) = 0`` holds for

    .. math::

        \Omega = \omega + \frac{M\times L}{L^2}

    (``(M x L) x L = -L^2 M`` since ``L.M = 0``).  The extra rate is normal to ``L``; a
    rate along ``L`` would only re-label the rotation phase about ``L``, which the free
    motion carries, and is taken zero.  The model is therefore *internal*
    (:attr:`TorqueModel.internal`): the integrators apply ``M`` to ``L`` in the body
    frame and ``Omega`` to the attitude, the splitting integrator in a kick that ends
    by re-imposing the inertial ``L`` exactly (:mod:`attitude.propagation.splitting`),
    the DOP853 reference in its right-hand side.  The body-frame motion of ``L`` (and
    so ``E``, the regime, the nutation angles) is the same as with an external torque
    ``M``; only the attitude differs: an external ``M`` would turn the inertial ``L``
    (by per cents over a long-axis to flat-spin relaxation), a drift of the pole that no
    internal mechanism can cause.

    **The time constant.**  ``k`` is set from ``time_constant`` ``tau`` so that near
    the final state the excess energy ``E - L^2/(2C)`` decays as ``exp(-t / tau)`` (and
    the nutation angle between ``L`` and the major axis, ``~ sqrt(E - L^2/2C)``, as
    ``exp(-t / 2 tau)``).  Near spin about ``C``, ``omega_perp ~= ((C-A) w1, (C-B) w2,
    0) / C``, so ``dE/dt = -k ((C-A)^2 w1^2 + (C-B)^2 w2^2) / C^2``, while the free
    nutation keeps ``A (C-A) w1^2 + B (C-B) w2^2 = 2 C (E - L^2/2C)`` and shares it
    equally between the two terms on average; hence

    .. math::

        \frac{1}{\tau} = \frac{k}{C}\left(\frac{C-A}{A} + \frac{C-B}{B}\right),
        \qquad k = \frac{C}{\tau\,[(C-A)/A + (C-B)/B]} .

    For a prolate body (``B = C``) only the ``w1`` term is excited and
    ``k = A C / (2 tau (C - A))`` gives the same e-folding exactly.  (For a nearly
    prolate triaxial body the nutation period near the final state,
    ``2 pi / (omega sqrt((C-A)(C-B)/(AB)))``, becomes long and the averaged rate
    applies only once it is short compared with ``tau``.)  A spherical body has
    ``omega_perp = 0``: no torque.  For an asteroid, ``tau`` follows from its size,
    density, spin and ``mu Q`` (:func:`damping_timescale`).

    Parameters
    ----------
    time_constant : float (s), Quantity or str (``"30 min"``)
        e-folding time of the excess kinetic energy near the final (major-axis) spin.

    Notes
    -----
    The rate of a real body depends on its rheology and on the nutation angle (the
    dissipation happens at the nutation frequency and its harmonics; Efroimsky &
    Lazarian 2000, Breiter et al. 2012, Frouard & Efroimsky 2018); this model fixes the
    e-folding time near the end state and keeps the qualitative path (LAM ->
    separatrix -> SAM -> principal-axis spin).

    References
    ----------
    .. [1] Sharma, I., Burns, J. A. & Hui, C.-Y. (2005). Nutational damping times in
       solids of revolution. *MNRAS* 359, 79-92.
    .. [2] Breiter, S., Rozek, A. & Vokrouhlicky, D. (2012). Stress field and spin axis
       relaxation for inelastic triaxial ellipsoids. *MNRAS* 427, 755.
    .. [3] Bloch, A. M., Krishnaprasad, P. S., Marsden, J. E. & Ratiu, T. S. (1996).
       The Euler-Poincare equations and double bracket dissipation. *Commun. Math.
       Phys.* 175, 1-42.
    .. [4] Hughes, P. C. (1986). *Spacecraft Attitude Dynamics*. Wiley. Ch. 5 (energy
       sink, major-axis rule).
    .. [5] Bracewell, R. N. & Garriott, O. K. (1958). Rotation of artificial Earth
       satellites. *Nature* 182, 760-762 (Explorer 1).

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> from attitude.model.torques import EnergyDissipation
    >>> body = RigidBody.from_principal_moments([1.0, 1.5, 2.0])
    >>> damper = EnergyDissipation("10 min")
    >>> damper.internal
    True
    >>> w = np.array([0.3, 0.1, 0.2])
    >>> M = damper(0.0, [0, 0, 0, 1], w, body)
    >>> L = body.inertia @ w
    >>> float(abs(L @ M)) < 1e-16, bool(w @ M < 0)
    (True, True)
    """

    velocity_dependent = True
    internal = True

    def __init__(self, time_constant):
        self.time_constant = si_positive(time_constant, "s", "time_constant")
        self._cache = None

    def coefficient(self, body) -> np.ndarray | float:
        """Damping coefficient ``k`` (kg m^2/s) for ``body`` (see the class notes).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import EnergyDissipation
        >>> body = RigidBody.from_principal_moments([2.0, 4.0, 4.0])   # prolate
        >>> EnergyDissipation(10.0).coefficient(body)     # A C / (2 tau (C - A))
        0.2
        """
        cached = self._cache
        if cached is not None and cached[0] is body:   # bodies are immutable values
            return cached[1]
        k = self._coefficient(moments_of(body))
        if isinstance(body, RigidBody):
            self._cache = (body, k)
        return k

    def _coefficient(self, m: np.ndarray) -> np.ndarray | float:
        A, B, C = m[..., 0], m[..., 1], m[..., 2]
        tol = SYMMETRY_RTOL * C
        prolate = (C - B) <= tol
        sigma = np.where(prolate, 2.0 * (C - A) / A, (C - A) / A + (C - B) / B)
        spherical = (C - A) <= tol
        k = np.where(spherical, 0.0, C / (self.time_constant * np.where(spherical, 1.0,
                                                                             sigma)))
        return float(k) if np.ndim(k) == 0 else k

    def evaluate(self, t, quaternion, omega_body, body):
        k = self.coefficient(body)
        return stacked(dissipation_torque(k, entries(inertia_of(body)), parts(omega_body)))

    def characteristic_rate(self, t, quaternion, omega_body, body) -> float:
        """``1 / time_constant``, rad/s."""
        return 1.0 / self.time_constant

    def compiled_parameters(self, body, t_span=None) -> list[tuple[str, dict]]:
        """``[("dissipation", {k, inertia})]``, ``k`` the :meth:`coefficient` for
        ``body`` (:meth:`TorqueModel.compiled_parameters`).

        Examples
        --------
        >>> from attitude import RigidBody
        >>> from attitude.model.torques import EnergyDissipation
        >>> body = RigidBody.from_principal_moments([2.0, 4.0, 4.0])
        >>> EnergyDissipation(10.0).compiled_parameters(body)[0][1]["k"]
        0.2
        """
        return [("dissipation", {"k": float(self.coefficient(body)),
                                 "inertia": inertia_of(body)})]

    def shifted(self, dt: float) -> EnergyDissipation:
        """Itself (no time dependence)."""
        return self

    def __repr__(self) -> str:
        return f"EnergyDissipation(time_constant={self.time_constant:.6g} s)"


def damping_timescale(diameter, density, *, period=None, spin_rate=None,
                      rigidity_q="5e11 Pa", k3_squared: float = 0.1) -> u.Quantity:
    r"""Damping time scale of a tumbling asteroid (Burns & Safronov 1973; Harris 1994).

    .. math::

        \tau \simeq \frac{\mu Q}{\rho\, K_3^2\, R^2\, \omega^3}

    with ``mu`` the rigidity, ``Q`` the quality factor (they enter only as the product
    ``mu Q``), ``rho`` the bulk density, ``R = D/2`` the mean radius, ``omega`` the spin
    rate and ``K_3^2`` a shape factor (about 0.1 for a nearly spherical body, smaller
    for elongated ones).  An order-of-magnitude estimate: published coefficients of
    this form differ by factors of ~10 between authors (Sharma, Burns & Hui 2005 derive
    ``T_d = D(h) mu Q / (rho a^2 Omega^3)`` with ``D(h)`` a few hundred, shape
    dependent).  Use it as the ``time_constant`` of :class:`EnergyDissipation` (order
    of magnitude; docs/torques.md has a worked Apophis example).

    Parameters
    ----------
    diameter : float (m), Quantity or str
        Mean (volume-equivalent) diameter.
    density : float (kg/m^3), Quantity or str
    period : float (s), Quantity or str, optional
        Spin period (give this or ``spin_rate``).
    spin_rate : float (rad/s), Quantity or str, optional
    rigidity_q : float (Pa), Quantity or str
        ``mu Q``; default 5e11 Pa (Harris 1994's value for rock-like asteroids, as used
        by Pravec et al. 2005, 2014).
    k3_squared : float
        Shape factor ``K_3^2`` (default 0.1).

    Returns
    -------
    Quantity
        The time scale, in years.

    Raises
    ------
    TorqueConfigError
        A non-positive or non-finite input, a unit of the wrong dimension, or both (or
        neither) of ``period`` and ``spin_rate``.

    References
    ----------
    .. [1] Burns, J. A. & Safronov, V. S. (1973). Asteroid nutation angles. *MNRAS* 165,
       403-411.
    .. [2] Harris, A. W. (1994). Tumbling asteroids. *Icarus* 107, 209-211.
    .. [3] Pravec, P. et al. (2005). Tumbling asteroids. *Icarus* 173, 108-131.
    .. [4] Pravec, P. et al. (2014). The tumbling spin state of (99942) Apophis.
       *Icarus* 233, 48-60.
    .. [5] Sharma, I., Burns, J. A. & Hui, C.-Y. (2005). *MNRAS* 359, 79-92.

    Examples
    --------
    Apophis (D = 0.34 km, 2.5 g/cm^3, P = 30.56 h, mu Q = 5e11 Pa):

    >>> from attitude.model.torques import damping_timescale
    >>> tau = damping_timescale("0.34 km", "2.5 g/cm3", period="30.56 h")
    >>> print(f"{tau.to_value('Gyr'):.1f} Gyr")
    11.8 Gyr
    """
    D = si_positive(diameter, "m", "diameter")
    rho = si_positive(density, "kg/m3", "density")
    muq = si_positive(rigidity_q, "Pa", "rigidity_q")
    k3 = si_positive(k3_squared, "", "k3_squared")
    if (period is None) == (spin_rate is None):
        raise TorqueConfigError("give exactly one of 'period' and 'spin_rate'", key="period")
    omega = (2.0 * math.pi / si_positive(period, "s", "period") if spin_rate is None
             else si_positive(spin_rate, "rad/s", "spin_rate"))
    R = 0.5 * D
    tau = muq / (rho * k3 * R * R * omega**3)
    return (tau * u.s).to(u.yr)
