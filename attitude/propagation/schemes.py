"""The compositions of the splitting integrator (:mod:`attitude.propagation.splitting`):
each scheme's kick and free-flow coefficients, its order, the embedded scheme of the
error estimate and the step controller's exponent.

References
----------
.. [1] Yoshida, H. (1990). Construction of higher order symplectic integrators.
   *Phys. Lett. A* 150, 262-268.
.. [2] Blanes, S. & Moan, P. C. (2002). Practical symplectic partitioned Runge-Kutta and
   Runge-Kutta-Nyström methods. *J. Comput. Appl. Math.* 142, 313-330.
.. [3] McLachlan, R. I. & Quispel, G. R. W. (2002). Splitting methods. *Acta Numerica*
   11, 341-434.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..foundations.errors import InvalidStateError

__all__ = ["SCHEMES", "DEFAULT_SCHEME", "RKN_SCHEMES", "EMBEDDED"]


def _strang_chain(w: Sequence[float]) -> tuple:
    """Kick/free coefficients of a composition of Strang steps ``S(w_i h)``."""
    ops = []
    for wi in w:
        ops += [("K", wi / 2), ("F", wi), ("K", wi / 2)]
    return tuple(ops)


def _alternating(first: str, coefficients: Sequence[float]) -> tuple:
    other = "F" if first == "K" else "K"
    return tuple((first if i % 2 == 0 else other, c) for i, c in enumerate(coefficients))


_CBRT2 = 2.0 ** (1.0 / 3.0)
_Y1 = 1.0 / (2.0 - _CBRT2)
_Y0 = -_CBRT2 / (2.0 - _CBRT2)
# Yoshida (1990), Table 1, solution A
_W6 = (0.784513610477560, 0.235573213359357, -1.17767998417887)
_W6_0 = 1.0 - 2.0 * sum(_W6)
# Blanes & Moan (2002), Table 2, S6 (order 4, 6 stages): a_1..a_4 and b_1..b_3
_BM_A = (0.0792036964311957, 0.353172906049774, -0.0420650803577195)
_BM_B = (0.209515106613362, -0.143851773179818)
_BM_A4 = 1.0 - 2.0 * sum(_BM_A)
_BM_B3 = 0.5 - sum(_BM_B)
_BM = (_BM_A[0], _BM_B[0], _BM_A[1], _BM_B[1], _BM_A[2], _BM_B3, _BM_A4, _BM_B3,
       _BM_A[2], _BM_B[1], _BM_A[1], _BM_B[0], _BM_A[0])
# Blanes & Moan (2002), Table 3, SRKN_6^b (order 4, 6 stages) for splittings whose kick
# part B satisfies [B, [B, [B, A]]] = 0: true here for attitude-only torques (the kick
# is a momentum translation by a function of the attitude and time, the free part a
# kinetic energy quadratic in the momenta, as in H = p^2/2 + V(q)).
_RKN_B = (0.0829844064174052, 0.396309801498368, -0.0390563049223486)
_RKN_A = (0.245298957184271, 0.604872665711080)
_RKN_B4 = 1.0 - 2.0 * sum(_RKN_B)
_RKN_A3 = 0.5 - sum(_RKN_A)
_RKN = (_RKN_B[0], _RKN_A[0], _RKN_B[1], _RKN_A[1], _RKN_B[2], _RKN_A3, _RKN_B4, _RKN_A3,
        _RKN_B[2], _RKN_A[1], _RKN_B[1], _RKN_A[0], _RKN_B[0])

#: Compositions: name -> (order, ops), ops a tuple of ``("K" | "F", coefficient)``
#: applied left to right (kick = torque, free = exact free flow; ``sum`` of each kind
#: is 1).  All are symmetric.
SCHEMES: dict[str, tuple[int, tuple]] = {
    "strang": (2, _strang_chain([1.0])),
    "yoshida4": (4, _strang_chain([_Y1, _Y0, _Y1])),
    "blanes-moan": (4, _alternating("K", _BM)),
    "blanes-moan-rkn": (4, _alternating("K", _RKN)),
    "yoshida6": (6, _strang_chain([_W6[0], _W6[1], _W6[2], _W6_0, _W6[2], _W6[1],
                                   _W6[0]])),
}
#: Default scheme of each order (order 4 uses ``"blanes-moan-rkn"`` instead when every
#: torque depends on the attitude only).
DEFAULT_SCHEME = {2: "strang", 4: "blanes-moan", 6: "yoshida6"}
#: Schemes that need attitude-only kicks (their order conditions assume
#: ``[B, [B, [B, A]]] = 0``).
RKN_SCHEMES = ("blanes-moan-rkn",)


def _merge(ops) -> list:
    out = []
    for kind, cc in ops:
        if out and out[-1][0] == kind:
            out[-1] = (kind, out[-1][1] + cc)
        else:
            out.append((kind, cc))
    return out


def resolve_scheme(order, scheme, attitude_only: bool = False) -> tuple[str, int, tuple]:
    if scheme is None and order is None:
        order = 4
    if scheme is None:
        if order not in DEFAULT_SCHEME:
            raise InvalidStateError(f"order={order!r} is not available; choose one of "
                                    f"{sorted(DEFAULT_SCHEME)}")
        scheme = DEFAULT_SCHEME[order]
        if order == 4 and attitude_only:
            scheme = "blanes-moan-rkn"
    if scheme not in SCHEMES:
        raise InvalidStateError(f"scheme {scheme!r} is unknown; choose one of "
                                f"{tuple(SCHEMES)}")
    sorder, ops = SCHEMES[scheme]
    if order is not None and order != sorder:
        raise InvalidStateError(f"scheme {scheme!r} is of order {sorder}, not {order}")
    return scheme, sorder, ops



#: Embedded composition of each scheme for the error estimate of ``rtol=`` (see
#: :func:`~attitude.propagation.splitting.integrate_splitting`): a cheaper scheme of the
#: same or lower order whose difference from the step estimates the local error.
EMBEDDED = {"strang": "lie", "yoshida4": "strang", "blanes-moan": "yoshida4",
            "blanes-moan-rkn": "yoshida4", "yoshida6": "blanes-moan"}
LIE = (1, (("K", 1.0), ("F", 1.0), ("K", 0.0)))      # Lie-Trotter, order 1


class Scheme:
    """A symmetric composition as kick coefficients ``b[0..m]`` and free-flow
    coefficients ``a[0..m-1]``: ``K(b0 h) F(a0 h) K(b1 h) ... F(a_{m-1} h) K(b_m h)``."""

    def __init__(self, order: int, ops):
        merged = _merge(ops)
        if merged[0][0] != "K":
            merged = [("K", 0.0)] + merged
        if merged[-1][0] != "K":
            merged = merged + [("K", 0.0)]
        self.order = order
        self.b = tuple(c for kind, c in merged if kind == "K")
        self.a = tuple(c for kind, c in merged if kind == "F")



def controller_exponent(scheme: Scheme, embedded: Scheme) -> float:
    """Exponent of the step controller ``h (1/err)^expo``: ``1/(p+1)`` with ``p`` the
    lower order of the pair, whose error the estimate measures; ``1/5`` for two order-4
    compositions (the difference is then of order 5)."""
    if embedded.order == scheme.order:
        return 0.2
    return 1.0 / (min(scheme.order, embedded.order) + 1.0)

