r"""The geometry of Poinsot's construction, as small pure functions (numpy only).

A torque-free rigid body with inertia tensor ``I`` (body frame), kinetic energy ``E`` and
angular momentum ``L`` moves so that its angular velocity ``omega``

* lies, in the body frame, on the **energy (inertia) ellipsoid** ``omega . I omega = 2E``
  and on the **momentum ellipsoid** ``|I omega|^2 = L^2``: their intersection is the
  **polhode**, the curve ``omega`` traces on the body;
* lies, in the inertial frame, on the **invariable plane**, normal to the fixed ``L`` at
  the distance ``omega . L / |L| = 2E / |L|`` from the origin: the curve it traces there
  is the **herpolhode**.

The energy ellipsoid carried by the body touches the invariable plane at ``omega`` (its
normal there is ``I omega``, parallel to ``L``) and, since the contact point is on the
instantaneous axis of rotation, rolls on it without slipping.

Quaternions are scalar-last, body -> inertial; rates in rad/s; every function broadcasts
over leading (time) dimensions.
"""

from __future__ import annotations

import numpy as np

from ..foundations import quaternion as quat

__all__ = ["energy_ellipsoid_surface", "equivalent_ellipsoid_axes", "solid_semi_axes",
           "ellipsoid_surface",
           "energy_residual", "momentum_residual", "on_polhode", "herpolhode_point",
           "invariable_plane", "plane_patch", "body_axes", "surface_quads"]

#: Iterations of the Gauss-Newton projection onto the polhode (quadratic convergence:
#: six reach round-off from a start within 1e-2 relative).
_NEWTON_STEPS = 12


def ellipsoid_surface(semi_axes, rotation=None, *, n_lat: int = 12, n_lon: int = 24):
    """A latitude-longitude grid on the ellipsoid with ``semi_axes`` along the frame's axes
    (optionally rotated by the (3, 3) matrix ``rotation``, columns = the ellipsoid's axes).

    Returns
    -------
    x, y, z : (n_lat + 1, n_lon + 1) ndarrays

    Examples
    --------
    >>> x, y, z = ellipsoid_surface([1.0, 2.0, 3.0])
    >>> float(np.max(np.abs((x / 1) ** 2 + (y / 2) ** 2 + (z / 3) ** 2 - 1))) < 1e-15
    True
    """
    a = np.asarray(semi_axes, dtype=float)
    lat = np.linspace(-np.pi / 2, np.pi / 2, n_lat + 1)[:, None]
    lon = np.linspace(0.0, 2 * np.pi, n_lon + 1)[None, :]
    pts = np.stack([a[0] * np.cos(lat) * np.cos(lon), a[1] * np.cos(lat) * np.sin(lon),
                    a[2] * np.sin(lat) * np.ones_like(lon)], axis=-1)
    if rotation is not None:
        pts = pts @ np.asarray(rotation, dtype=float).T
    return pts[..., 0], pts[..., 1], pts[..., 2]


def energy_ellipsoid_surface(inertia, energy, *, n_lat: int = 12, n_lon: int = 24):
    """The energy ellipsoid ``x . I x = 2E`` in the body frame (Poinsot's inertia
    ellipsoid scaled to the motion): semi-axes ``sqrt(2E / I_k)`` along the principal axes.

    Parameters
    ----------
    inertia : (3, 3) array_like
        Inertia tensor, body frame, kg m^2.
    energy : float
        Kinetic energy, J.

    Returns
    -------
    x, y, z : (n_lat + 1, n_lon + 1) ndarrays, rad/s

    Examples
    --------
    >>> I = np.diag([1.0, 2.0, 3.0])
    >>> x, y, z = energy_ellipsoid_surface(I, 0.5)
    >>> pts = np.stack([x, y, z], -1)
    >>> float(np.max(np.abs(energy_residual(pts, I, 0.5)))) < 1e-14
    True
    """
    moments, axes = np.linalg.eigh(np.asarray(inertia, dtype=float))
    return ellipsoid_surface(np.sqrt(2.0 * energy / moments), axes, n_lat=n_lat, n_lon=n_lon)


def solid_semi_axes(moments, mass: float) -> np.ndarray:
    """Semi-axes (m) of the uniform solid ellipsoid of principal moments ``A <= B <= C``
    (kg m^2) and ``mass`` (kg): ``a^2 = 5 (B + C - A) / (2 m)``, ...

    Examples
    --------
    >>> m, a, b, c = 10.0, 3.0, 2.0, 1.0
    >>> moments = [m * (b**2 + c**2) / 5, m * (a**2 + c**2) / 5, m * (a**2 + b**2) / 5]
    >>> solid_semi_axes(moments, m).round(12).tolist()
    [3.0, 2.0, 1.0]
    """
    A, B, C = np.asarray(moments, dtype=float)
    squares = 2.5 / mass * np.array([B + C - A, A + C - B, A + B - C])
    return np.sqrt(np.maximum(squares, 0.0))


def equivalent_ellipsoid_axes(moments) -> np.ndarray:
    """Semi-axes of the uniform solid ellipsoid with the principal moments ``moments``
    (:func:`solid_semi_axes`), scaled so that the largest is 1: the shape drawn for a
    body known only by its inertia.

    Examples
    --------
    >>> equivalent_ellipsoid_axes([0.4 * 5, 0.4 * 5, 0.4 * 5]).tolist()     # a sphere
    [1.0, 1.0, 1.0]
    >>> equivalent_ellipsoid_axes([(4 + 9), (1 + 9), (1 + 4)]).round(12).tolist()
    [0.333333333333, 0.666666666667, 1.0]
    """
    axes = solid_semi_axes(moments, 1.0)
    return axes / axes.max()


def energy_residual(omega, inertia, energy):
    """``omega . I omega / 2E - 1``: 0 on the energy ellipsoid.

    Examples
    --------
    >>> float(energy_residual([1.0, 0.0, 0.0], np.diag([2.0, 3.0, 4.0]), 1.0))
    0.0
    """
    w = np.asarray(omega, dtype=float)
    Iw = w @ np.asarray(inertia, dtype=float).T
    return np.sum(w * Iw, axis=-1) / (2.0 * np.asarray(energy, dtype=float)) - 1.0


def momentum_residual(omega, inertia, momentum):
    """``|I omega|^2 / L^2 - 1``: 0 on the momentum ellipsoid.

    Examples
    --------
    >>> float(momentum_residual([1.0, 0.0, 0.0], np.diag([2.0, 3.0, 4.0]), 2.0))
    0.0
    """
    Iw = np.asarray(omega, dtype=float) @ np.asarray(inertia, dtype=float).T
    return np.sum(Iw * Iw, axis=-1) / np.asarray(momentum, dtype=float) ** 2 - 1.0


def on_polhode(omega, inertia, energy, momentum) -> np.ndarray:
    """``omega`` moved to the nearest point of the polhode of ``(E, |L|)``: on both the
    energy ellipsoid ``omega . I omega = 2E`` and the momentum ellipsoid
    ``|I omega|^2 = L^2`` (Gauss-Newton, minimal-norm steps on the two constraints).

    Used on rates interpolated between samples: a sample of a torque-free ephemeris is on
    its polhode already, to round-off, and moves by that much.  Where the two constraints
    are tangent (spin about a principal axis, a spherical body) the rate is scaled onto
    the energy ellipsoid, which then satisfies both.

    Parameters
    ----------
    omega : (..., 3) array_like
        Body-frame rates, rad/s.
    inertia : (3, 3) array_like
    energy, momentum : float or (...) array_like
        ``E`` (J) and ``|L|`` (kg m^2/s).

    Examples
    --------
    >>> I = np.diag([0.61, 0.965, 1.0])
    >>> w = np.array([0.02, 0.001, 0.1])
    >>> E, L = 0.5 * w @ I @ w, np.linalg.norm(I @ w)
    >>> p = on_polhode(w * [1.01, 1.2, 0.99], I, E, L)
    >>> bool(abs(energy_residual(p, I, E)) < 1e-15 and abs(momentum_residual(p, I, L)) < 1e-15)
    True
    """
    I = np.asarray(inertia, dtype=float)
    I2 = I @ I
    w = np.array(omega, dtype=float, copy=True)
    two_e = 2.0 * np.asarray(energy, dtype=float)[..., None]
    l2 = np.asarray(momentum, dtype=float)[..., None] ** 2
    for _ in range(_NEWTON_STEPS):
        g1, g2 = w @ I.T, w @ I2.T                     # half-gradients of the constraints
        f1 = np.sum(w * g1, -1, keepdims=True) - two_e
        f2 = np.sum(w * g2, -1, keepdims=True) - l2
        a = 4 * np.sum(g1 * g1, -1, keepdims=True)
        b = 4 * np.sum(g1 * g2, -1, keepdims=True)
        c = 4 * np.sum(g2 * g2, -1, keepdims=True)
        det = a * c - b * b
        good = det > 1e-10 * a * c
        safe = np.where(good, det, 1.0)
        lam1 = (c * f1 - b * f2) / safe
        lam2 = (a * f2 - b * f1) / safe
        step = -2 * (lam1 * g1 + lam2 * g2)
        scaled = w * np.sqrt(two_e / np.sum(w * g1, -1, keepdims=True))
        w = np.where(good, w + step, scaled)
    return w


def herpolhode_point(quaternion, omega) -> np.ndarray:
    """The angular velocity in the inertial frame, ``R omega``: the point of the
    herpolhode (on the invariable plane).

    Examples
    --------
    >>> herpolhode_point([0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)], [1.0, 0.0, 0.0]).round(15)
    array([0., 1., 0.])
    """
    return quat.rotate(np.asarray(quaternion, dtype=float), np.asarray(omega, dtype=float))


def invariable_plane(quaternion, omega, inertia):
    """The invariable plane of the motion: its unit normal ``L / |L|`` (inertial) and its
    distance ``2E / |L|`` from the origin, from the attitude and the body-frame rate
    (``L = R I omega``, ``2E = omega . I omega``).

    Returns
    -------
    normal : (..., 3) ndarray
    distance : (...) ndarray, rad/s

    Examples
    --------
    >>> n, d = invariable_plane([0, 0, 0, 1.0], [1.0, 0.0, 1.0], np.diag([1.0, 2.0, 3.0]))
    >>> (n * np.sqrt(10)).round(12).tolist(), round(float(d * np.sqrt(10)), 12)
    ([1.0, 0.0, 3.0], 4.0)
    """
    w = np.asarray(omega, dtype=float)
    Iw = w @ np.asarray(inertia, dtype=float).T
    L = quat.rotate(np.asarray(quaternion, dtype=float), Iw)
    size = np.linalg.norm(L, axis=-1)
    return L / size[..., None], np.sum(w * Iw, axis=-1) / size


def plane_patch(normal, distance, centre, half_width):
    """The four corners of a square of the plane ``x . normal = distance`` (one normal),
    centred on the projection of ``centre``: the invariable plane as drawn.

    Returns
    -------
    (4, 3) ndarray

    Examples
    --------
    >>> c = plane_patch([0.0, 0.0, 1.0], 2.0, [0.0, 0.0, 0.0], 1.0)
    >>> c[:, 2].tolist(), float(np.abs(c[:, :2]).max())
    ([2.0, 2.0, 2.0, 2.0], 1.0)
    """
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    helper = np.eye(3)[int(np.argmin(np.abs(n)))]
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    c = np.asarray(centre, dtype=float)
    c = c + (distance - c @ n) * n
    signs = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float) * half_width
    return c + signs[:, :1] * u + signs[:, 1:] * v


def body_axes(quaternion) -> np.ndarray:
    """The body frame's unit axes in the inertial frame: ``out[..., k, :] = R e_k``.

    Examples
    --------
    >>> body_axes([0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)]).round(15).tolist()
    [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    q = np.asarray(quaternion, dtype=float)[..., None, :]
    return quat.rotate(q, np.broadcast_to(np.eye(3), q.shape[:-2] + (3, 3)))


def surface_quads(x, y, z) -> np.ndarray:
    """The quadrilaterals (n, 4, 3) of a surface grid (as :func:`ellipsoid_surface` gives).

    Examples
    --------
    >>> surface_quads(*ellipsoid_surface([1.0, 1.0, 1.0], n_lat=4, n_lon=6)).shape
    (24, 4, 3)
    """
    p = np.stack([x, y, z], -1)
    return np.stack([p[:-1, :-1], p[1:, :-1], p[1:, 1:], p[:-1, 1:]], axis=-2).reshape(-1, 4, 3)
