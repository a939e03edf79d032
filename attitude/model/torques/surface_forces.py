"""The formulas of the surface torques on a faceted body (solar radiation pressure,
free-molecular drag), in component form: their one source.

:class:`attitude.environment.SolarRadiationPressure` and
:class:`attitude.environment.AerodynamicDrag` (the environment wing, which holds the
models, their paths and their tables) evaluate them on ``(time, facet)`` arrays; the
compiled kernel of :mod:`attitude.propagation.compiled_torques` (which may import the
model layer, not a wing) compiles the same functions with numba and runs them on floats,
facet by facet.  Each function takes components (floats, or arrays that broadcast) and
returns a tuple; the sums over facets are the callers' (a matrix product in numpy, a loop
in the kernel): the only place where the two paths round differently.

Radiation pressure (Montenbruck & Gill 2000, Sec. 3.4; the environment's module notes):
``M = -P [(sum_k w_k r_k) x s + 2 sum_k u_k (r_k x n_k)]`` with ``w_k = A_k c_k (1 -
rho_s)``, ``u_k = A_k c_k (rho_s c_k + rho_d / 3)``, ``c_k = max(n_k . s, 0)``.  Drag
(Vallado 2013, Sec. 8.6.2): ``M = -1/2 rho v^2 C_D (sum_k c_k A_k r_k) x v_hat``,
``c_k = max(n_k . v_hat, 0)``, the air co-rotating with the Earth.
"""

from __future__ import annotations

import numpy as np

from ...foundations.quaternion import cross_parts

#: Nothing public: the formulas serve the environment's models and the compiled kernels.
__all__ = []


def facing(normal, direction):
    """``max(n . d, 0)``: the cosine of the angle between a facet's outward normal and
    the direction of the light or the flow, zero for a facet facing away."""
    return np.maximum(normal[0] * direction[0] + normal[1] * direction[1]
                      + normal[2] * direction[2], 0.0)


def sunlight(pressure, astronomical_unit, sun, body) -> tuple:
    """``(p, s)``: the radiation pressure at the body (``pressure`` at 1 au, N/m^2,
    scaled by ``(1 au / d)^2``) and the unit vector from the body toward the Sun, from
    the two positions (m, same frame)."""
    dx, dy, dz = sun[0] - body[0], sun[1] - body[1], sun[2] - body[2]
    dist = np.sqrt(dx * dx + dy * dy + dz * dz)
    ratio = astronomical_unit / dist
    return pressure * (ratio * ratio), (dx / dist, dy / dist, dz / dist)


def radiation_weights(c, one_minus_s, spec, diff) -> tuple:
    """``(w, u)`` of facets at cosine ``c`` (:func:`facing`): ``w = c A (1 - rho_s)``,
    ``u = c (c A rho_s + A rho_d / 3)`` from ``one_minus_s = A (1 - rho_s)``,
    ``spec = A rho_s``, ``diff = A rho_d / 3``."""
    return c * one_minus_s, c * (c * spec + diff)


def radiation_torque(p, W, U, s) -> tuple:
    """``-p (W x s + 2 U)``: the torque (N m) from the facet sums ``W = sum_k w_k r_k``
    and ``U = sum_k u_k (r_k x n_k)`` (m^3), the pressure ``p`` and the Sun's direction
    ``s`` in body axes."""
    c0, c1, c2 = cross_parts(W, s)
    return -p * (c0 + 2.0 * U[0]), -p * (c1 + 2.0 * U[1]), -p * (c2 + 2.0 * U[2])


def corotating_air(rate, r, v) -> tuple:
    """The velocity relative to air turning with the Earth at ``rate`` (rad/s) about the
    inertial ``z`` axis: ``v - omega x r``, m/s."""
    return v[0] + rate * r[1], v[1] - rate * r[0], v[2]


def exponential_density(h, base, density, scale_height):
    """``rho_0 exp(-(h - h_0) / H)``, kg/m^3: one layer of the piecewise-exponential
    atmosphere at altitude ``h`` (m)."""
    return density * np.exp(-(h - base) / scale_height)


def drag_pressure(rho, v2, cd):
    """``1/2 rho v^2 C_D``, N/m^2 (``v2`` the squared speed relative to the air)."""
    return 0.5 * rho * v2 * cd


def drag_torque(q, S, v_hat) -> tuple:
    """``-q S x v_hat``: the torque (N m) from the facet sum ``S = sum_k c_k A_k r_k``
    (m^3), the pressure ``q`` (:func:`drag_pressure`) and the flow's direction in body
    axes."""
    c0, c1, c2 = cross_parts(S, v_hat)
    return -q * c0, -q * c1, -q * c2
