r"""Spin-orbit resonances p:q: the Cayley coefficients ``H(p/q, e)`` and the widths.

The planar spin-orbit problem (spin axis along the orbit normal; Murray & Dermott 1999,
ch. 5) is, with time in units of ``1/n`` (``n`` the mean motion) and ``theta`` the angle
of the long axis from the periapsis direction,

.. math::

    \ddot\theta + \frac{\omega_0^2}{2}\left(\frac{a}{r}\right)^3 \sin 2(\theta - f) = 0,
    \qquad \omega_0^2 = 3\,\frac{B - A}{C}.

Expanding ``(a/r)^3 exp(-2 i f)`` in the mean anomaly ``M`` (Cayley 1859),

.. math::

    \left(\frac{a}{r}\right)^3 e^{2i(\theta - f)} = \sum_{p} H(p, e)\,e^{2i(\theta - pM)},
    \qquad p = 0, \pm\tfrac12, \pm 1, \ldots

so near ``theta_dot = p`` the averaged motion of ``gamma = theta - p M`` is the pendulum
``gamma'' + (omega0^2 / 2) H(p, e) sin 2 gamma = 0``: a resonance of half-width
``omega0 sqrt(|H(p, e)|)`` in ``theta_dot / n``, centred on ``gamma = 0`` when ``H > 0``
and on ``gamma = pi / 2`` when ``H < 0`` (Murray & Dermott 1999, eqs. 5.76-5.79 and
Table 5.1; Goldreich & Peale 1966).

:func:`cayley_coefficient` computes ``H(p, e)`` by a numerical Fourier transform (the
trapezoidal rule in the eccentric anomaly, exponentially convergent for this periodic
analytic integrand); :func:`cayley_series` gives the tabulated series, for tests and
small ``e``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from ..foundations.errors import SpinOrbitError

__all__ = ["Resonance", "cayley_coefficient", "cayley_series", "resonance_list",
           "overlap_parameter"]


def _check_e(e) -> float:
    e = float(e)
    if not (math.isfinite(e) and 0.0 <= e < 1.0):
        raise SpinOrbitError(f"must be in [0, 1), got {e!r}", key="e")
    return e


def _as_ratio(p) -> Fraction:
    try:
        r = Fraction(p).limit_denominator(1000)
    except (TypeError, ValueError):
        raise SpinOrbitError(f"expected a spin / orbit ratio such as 1.5 or '3/2', got "
                             f"{p!r}", key="p") from None
    if 2 * r != int(2 * r):
        raise SpinOrbitError(f"the gravity-gradient expansion has resonances at half-"
                             f"integer spin rates only (0.5, 1, 1.5, ...), got {p!r}",
                             key="p")
    return r


def cayley_coefficient(p, e, *, samples: int | None = None) -> float:
    r"""``H(p, e)``: the Fourier coefficient of ``(a/r)^3 exp(2 i (f - p M))`` over ``M``.

    .. math::

        H(p, e) = \frac{1}{2\pi}\int_0^{2\pi} \left(\frac{a}{r}\right)^3
                  \cos(2f - 2pM)\,dM
                = \frac{1}{2\pi}\int_0^{2\pi} \left(\frac{a}{r}\right)^2
                  \cos\big(2f - 2p(E - e\sin E)\big)\,dE

    (``dM = (r/a) dE``; the sine part vanishes by symmetry), evaluated by the
    trapezoidal rule in ``E``, which converges exponentially for a periodic analytic
    integrand: the default sample count resolves the periapsis peak of width ``~ 1 - e``.

    Parameters
    ----------
    p : float, str or Fraction
        Spin rate / mean motion: a half-integer (``0.5``, ``1``, ``"3/2"``, ...).
    e : float
        Eccentricity, ``0 <= e < 1``.
    samples : int, optional
        Quadrature nodes.

    Returns
    -------
    float

    Raises
    ------
    SpinOrbitError
        ``p`` not a half-integer, ``e`` outside ``[0, 1)``.

    References
    ----------
    .. [1] Murray, C. D. & Dermott, S. F. (1999). *Solar System Dynamics*, CUP,
       sec. 5.4 and Table 5.1.
    .. [2] Cayley, A. (1859). Tables of the developments of functions in the theory of
       elliptic motion. *Mem. R. Astron. Soc.* 29, 191.

    Examples
    --------
    >>> round(cayley_coefficient(1, 0.0), 12), round(cayley_coefficient("3/2", 0.1), 6)
    (1.0, 0.342351)
    """
    r = _as_ratio(p)
    e = _check_e(e)
    n = samples or int(max(256, 64 * 2 ** math.ceil(math.log2(8.0 / (1.0 - e)))))
    E = 2.0 * np.pi * np.arange(n) / n
    cE = np.cos(E)
    a_over_r = 1.0 / (1.0 - e * cE)
    f = 2.0 * np.arctan2(np.sqrt(1.0 + e) * np.sin(E / 2), np.sqrt(1.0 - e) * np.cos(E / 2))
    M = E - e * np.sin(E)
    return float(np.mean(a_over_r**2 * np.cos(2.0 * f - 2.0 * float(r) * M)))


#: Leading terms of ``H(p, e)`` (Murray & Dermott 1999, Table 5.1; Goldreich & Peale 1966),
#: as ``{2 p: ((coefficient, power), ...)}``.
_SERIES = {
    -1: ((1 / 48, 3),),
    0: (),
    1: ((-1 / 2, 1), (1 / 16, 3)),
    2: ((1.0, 0), (-5 / 2, 2), (13 / 16, 4)),
    3: ((7 / 2, 1), (-123 / 16, 3)),
    4: ((17 / 2, 2), (-115 / 6, 4)),
    5: ((845 / 48, 3), (-32525 / 768, 5)),
    6: ((533 / 16, 4), (-13827 / 160, 6)),
}


def cayley_series(p, e) -> float:
    """``H(p, e)`` from its tabulated power series (leading two terms).

    Valid for small ``e`` (the next term is ``O(e^2)`` relative); ``p`` from ``-1/2`` to
    ``3``.

    Examples
    --------
    >>> cayley_series(1, 0.1)
    0.97508125
    """
    r = _as_ratio(p)
    e = _check_e(e)
    key = int(2 * r)
    if key not in _SERIES:
        raise SpinOrbitError(f"series tabulated for p = -1/2 ... 3, got {r}", key="p")
    return float(sum(c * e**k for c, k in _SERIES[key]))


@dataclass(frozen=True)
class Resonance:
    """One p:q spin-orbit state (spin rate ``p / q`` times the mean motion).

    Attributes
    ----------
    p, q : int
        Spin periods per orbit: ``p`` rotations in ``q`` orbits (``1:1`` synchronous,
        ``3:2`` Mercury).
    H : float
        Cayley coefficient ``H(p/q, e)``.
    half_width : float
        ``omega0 sqrt(|H|)``: half-width of the resonance in spin rate / mean motion.
    centre : float
        Angle (rad) of the long axis from the direction of the primary at periapsis at the
        stable centre: 0 for ``H > 0``, ``pi/2`` for ``H < 0``.

    Examples
    --------
    >>> sync = resonance_list(0.89, 0.1)[1]             # Hyperion: omega0 = 0.89, e = 0.1
    >>> sync.p, sync.q, sync.centre                      # long axis towards the primary
    (1, 1, 0.0)
    >>> bool(math.isclose(sync.half_width, 0.89 * math.sqrt(sync.H)))
    True
    """

    p: int
    q: int
    H: float
    half_width: float
    centre: float

    @property
    def rate(self) -> float:
        """Spin rate of the resonance, in units of the mean motion."""
        return self.p / self.q

    @property
    def name(self) -> str:
        """``"p:q"``."""
        return f"{self.p}:{self.q}"

    @property
    def libration_period(self) -> float:
        """Period of small librations about the centre, in orbital periods:
        ``1 / (omega0 sqrt(2 |H|))`` (the pendulum ``gamma'' = -(omega0^2 H / 2)
        sin 2 gamma``)."""
        return math.inf if self.half_width == 0 else 1.0 / (math.sqrt(2.0) * self.half_width)

    def contains(self, rate, angle=None) -> bool:
        """Whether ``rate`` (units of n) lies within ``half_width`` of the centre rate."""
        return bool(abs(float(rate) - self.rate) < self.half_width)


def resonance_list(omega0: float, e: float, *, max_rate: float = 3.0,
                   min_H: float = 0.0) -> tuple[Resonance, ...]:
    """The p:q resonances ``1:2, 1:1, 3:2, 2:1, ...`` up to ``max_rate``, with widths.

    Parameters
    ----------
    omega0 : float
        ``sqrt(3 (B - A) / C)``.
    e : float
        Eccentricity.
    max_rate : float
        Highest spin rate / mean motion listed.
    min_H : float
        Omit resonances with ``|H| <= min_H`` (``H(p, 0) = 0`` except for ``p = 1``).

    Examples
    --------
    >>> [(r.name, round(r.half_width, 3)) for r in resonance_list(0.89, 0.1)][:4]
    [('1:2', 0.199), ('1:1', 0.879), ('3:2', 0.521), ('2:1', 0.257)]
    """
    e = _check_e(e)
    out = []
    for k in range(1, int(math.floor(2 * max_rate)) + 1):
        r = Fraction(k, 2)
        H = cayley_coefficient(r, e)
        if abs(H) <= min_H:
            continue
        out.append(Resonance(p=r.numerator, q=r.denominator, H=H,
                             half_width=float(omega0) * math.sqrt(abs(H)),
                             centre=0.0 if H > 0 else math.pi / 2))
    return tuple(out)


def overlap_parameter(first: Resonance, second: Resonance) -> float:
    """Chirikov's overlap parameter: (sum of the half-widths) / (distance of the centres).

    Above 1 the two resonances overlap and the zone between them is chaotic (Chirikov
    1979; Wisdom, Peale & Mignard 1984 for the 1:1 and 3:2 states of Hyperion).

    Examples
    --------
    >>> one, three_halves = resonance_list(0.89, 0.1)[1:3]
    >>> overlap_parameter(one, three_halves) > 1
    True
    """
    return (first.half_width + second.half_width) / abs(first.rate - second.rate)
