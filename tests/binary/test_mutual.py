"""The mutual potential, force and torques (attitude.binary.mutual) against references
that share no code with the series: a direct double quadrature of
``-G int int dm1 dm2 / |R + r2 - r1|``, MacCullagh's formula, point masses, finite
differences of the potential, the balance of torques, and the trigonometric exactness
of a rotated tensor.

Truncation bound.  With ``d = r2 - r1`` (|d| <= rho = rho1 + rho2, the bodies' largest
radii), ``1/|R + d| = sum_n |d|^n P_n(cos) / R^(n+1)`` and ``|P_n| <= 1``, so the series
stopped at degree N misses at most ``G m1 m2 / R * (rho/R)^(N+1) / (1 - rho/R)``, and the
degree-n part of the potential is at most ``G m1 m2 rho^n / R^(n+1)`` (any attitudes).

Round-off of the series.  Degree n is a sum of ``P_n`` products (``sum n_k n_l`` over
the degree pairs), each within a few ulps; the products are not larger than the
degree's bound by more than ``4^n`` (the multinomial ``2^n`` of splitting a
derivative of 1/R between the bodies and the ``2^n`` of 1/R's Taylor coefficients), so
degree n rounds by at most ``(P_n + n + 4) eps G m1 m2 (4 rho)^n / R^(n+1)``:
:func:`series_roundoff`.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.integrals import inertia_integrals, multi_indices, rotated
from attitude.binary.mutual import MutualGravity, generators
from attitude.model.body import MassDistribution, RigidBody
from attitude.model.shape import Polyhedron
from tests.binary.test_integrals import l_prism
from tests.tolerances import EPS


def ellipsoid(mass, axes):
    return RigidBody.from_mass_properties(att.MassProperties.solid_ellipsoid(mass, axes))


def sphere(mass, radius):
    return RigidBody.from_mass_properties(att.MassProperties.solid_sphere(mass, radius))


def polyhedral_body(shape, density=1.0):
    mass, com, inertia = shape.mass_properties(density)
    return RigidBody(inertia, mass=mass, center_of_mass=com,
                     distribution=MassDistribution("polyhedron", mass, shape=shape))


def n_products(n: int) -> int:
    """Products of integrals in degree n of the series (degree 1 absent)."""
    return sum(len(multi_indices(k)) * len(multi_indices(n - k)) for k in range(n + 1)
               if k != 1 and n - k != 1)


def series_roundoff(order, G, m1, m2, R, rho) -> float:
    return sum((n_products(n) + n + 4) * EPS * G * m1 * m2 * (4 * rho) ** n / R ** (n + 1)
               for n in range(order + 2))


def tail_bound(N, G, m1, m2, R, rho) -> float:
    return G * m1 * m2 / R * (rho / R) ** (N + 1) / (1 - rho / R)


# --- direct quadrature ---------------------------------------------------------------

def ball_rule(n):
    """Points and weights (summing to 1) of the uniform unit ball: Gauss-Legendre in r
    with the r^2 weight, in cos(theta), and n_phi = 2n - 2 uniform azimuths.  Exact for
    polynomials of degree <= D = 2n - 3 (r^(d+2) needs d + 2 <= 2n - 1; the azimuths
    integrate trigonometric degree < n_phi)."""
    x, w = np.polynomial.legendre.leggauss(n)
    r, wr = (x + 1) / 2, 3 * w / 2 * ((x + 1) / 2) ** 2        # int_0^1 3 r^2 dr = 1
    mu, wmu = np.polynomial.legendre.leggauss(n)
    n_phi = 2 * n - 2
    phi = 2 * np.pi * np.arange(n_phi) / n_phi
    Rr, M, P = np.meshgrid(r, mu, phi, indexing="ij")
    W = (wr[:, None, None] * wmu[None, :, None] / 2 / n_phi) * np.ones(n_phi)
    s = np.sqrt(1 - M**2)
    pts = np.stack([Rr * s * np.cos(P), Rr * s * np.sin(P), Rr * M], -1).reshape(-1, 3)
    return pts, W.ravel(), 2 * n - 3


def box_rule(lo, hi, n):
    """Gauss-Legendre product rule over a box, weights summing to its volume; exact to
    degree 2n - 1 in each coordinate."""
    x, w = np.polynomial.legendre.leggauss(n)
    axes = [((a + b) / 2 + (b - a) / 2 * x, (b - a) / 2 * w) for a, b in zip(lo, hi)]
    X, Y, Z = np.meshgrid(*(p for p, _ in axes), indexing="ij")
    W = np.einsum("i,j,k->ijk", *(q for _, q in axes))
    return np.stack([X, Y, Z], -1).reshape(-1, 3), W.ravel()


def direct_potential(R, r1, w1, r2, w2, G, orders=()) -> float:
    """``-G sum_ij w1_i w2_j / |R + r2_j - r1_i|``, in blocks (weights carry the mass);
    with ``orders``, also the averaged Legendre tail bounds ``G sum_ij w1_i w2_j
    (s^(N+1) / (1 - s)) / R`` with ``s = |r2_j - r1_i| / R``: the pointwise bound of the
    series' remainder beyond degree N, integrated (a rigorous bound of the truncation,
    much tighter than the worst pair's)."""
    Rn = np.linalg.norm(R)
    total, tails = 0.0, np.zeros(len(orders))
    for i in range(0, len(r1), 256):
        d = r2[None, :, :] - r1[i:i + 256, None, :]
        full = R + d
        total += w1[i:i + 256] @ (1.0 / np.sqrt(np.einsum("ijk,ijk->ij", full, full))) @ w2
        if len(orders):
            frac = np.sqrt(np.einsum("ijk,ijk->ij", d, d)) / Rn
            term = frac / (1 - frac)                    # s^(N+1) / (1 - s) at N = 0
            for j in range(max(orders) + 1):
                if j in orders:
                    tails[list(orders).index(j)] += w1[i:i + 256] @ term @ w2
                term *= frac
    return (-G * total, G * tails / Rn) if len(orders) else -G * total


def test_two_ellipsoids_series_converges_to_the_double_quadrature():
    """Ellipsoids of radii 3 and 1.5 at R = 19.4 (rho/R = 0.23), turned arbitrarily.
    The quadrature (n = 10) is exact to degree D = 17 in each body, so it misses the
    true potential by at most twice the tail beyond D (the tail integrated exactly and
    by a positive rule): 1e-11 relative.  The series at order N then misses the
    quadrature by at most the tail beyond N (averaged over the point pairs) plus that;
    and its error must fall as N
    grows: odd degrees vanish for a centrally symmetric body (the potential is the same
    at N and N + 1), each even order gains ~ (size/R)^2 (observed: 5.6e-6, 1.7e-8,
    1.1e-9, 2.6e-11 relative at orders 2, 4, 6, 8)."""
    a1, a2 = np.array([3.0, 2.0, 1.5]), np.array([1.5, 1.0, 0.8])
    m1, m2, G = 2.0, 0.3, 1.0
    A1 = Rotation.from_euler("zyx", [0.3, 0.5, -0.2]).as_matrix()
    A2 = Rotation.from_euler("zyx", [-1.0, 0.4, 0.9]).as_matrix()
    R = np.array([14.0, -9.0, 10.0])
    Rn, rho = np.linalg.norm(R), a1.max() + a2.max()
    pts, w, D = ball_rule(10)
    exact, tails = direct_potential(R, (pts * a1) @ A1.T, m1 * w, (pts * a2) @ A2.T,
                                    m2 * w, G, orders=range(9))
    quad_error = 2 * tail_bound(D, G, m1, m2, Rn, rho) + 4 * len(w) * EPS * abs(exact)
    T1 = rotated(inertia_integrals(ellipsoid(m1, a1), 8), A1)
    T2 = rotated(inertia_integrals(ellipsoid(m2, a2), 8), A2)
    errors = []
    for N in range(9):
        U = MutualGravity(N, G).forces(R, T1, T2).potential
        # the averaged tail bound, itself below the worst-pair bound
        assert tails[N] <= tail_bound(N, G, m1, m2, Rn, rho)
        assert abs(U - exact) <= (tails[N] + quad_error
                                  + series_roundoff(N, G, m1, m2, Rn, rho)), N
        errors.append(abs(U - exact))
    assert errors[1::2] == errors[0::2][:4]         # odd degrees add exactly nothing
    even = errors[0::2]
    # each even order gains ~ (R/rho)^2 = 18.6; at least half of it (measured 330, 15,
    # 42: the gain varies with how the degrees' angular parts happen to align)
    gain = (Rn / rho) ** 2 / 2
    assert all(b < a / gain for a, b in zip(even, even[1:])), even
    # the averaged bound at order 8 (1.2e-8 relative) is far tighter than the
    # worst pair's (2.5e-6); the error measured is 2.6e-11
    assert tails[8] < tail_bound(8, G, m1, m2, Rn, rho) / 100


def test_l_prisms_every_degree_against_the_box_quadrature():
    """Two non-convex L prisms (no centre of symmetry: every odd degree present).
    Degree n of the series is ``-G int int |d|^n P_n(-d.R/|d|R) / R^(n+1)``, a polynomial
    of degree n in each body's coordinates: a Gauss-Legendre product rule over the two
    boxes of each L with 6 points per axis (exact to degree 11 per coordinate) gives it
    exactly, up to the round-off of its two sums of 432 terms (plus ~3n for |d|^n and
    the Legendre recurrence).  The whole potential against the rule with 10 points
    (exact to degree 19) bounds the truncation at order 8.  (The error of the series is
    not monotone in N here: degrees 3 to 5 happen to nearly cancel.)"""
    from scipy.special import eval_legendre
    h = 0.75
    shape = l_prism(h)
    c = shape.centroid
    boxes = [((0, 0, 0), (3, 1, h)), ((0, 1, 0), (1, 3, h))]
    A1 = Rotation.from_euler("xyz", [0.4, -0.8, 1.3]).as_matrix()
    A2 = Rotation.from_euler("xyz", [2.0, 0.1, -0.6]).as_matrix()
    R = np.array([-6.0, 17.0, 9.0])
    G, d1, d2 = 1.0, 1.0, 0.5
    T = inertia_integrals(polyhedral_body(shape), 8)
    T1 = rotated(InertiaScaled(T, d1), A1)
    T2 = rotated(InertiaScaled(T, d2), A2)
    m1, m2 = d1 * shape.volume, d2 * shape.volume
    Rn = np.linalg.norm(R)
    rho = 2 * np.linalg.norm(shape.vertices - c, axis=1).max()
    terms = MutualGravity(8, G).terms(R, T1, T2)

    def rule(n):
        parts = [box_rule(np.subtract(lo, c), np.subtract(hi, c), n) for lo, hi in boxes]
        return (np.concatenate([p for p, _ in parts]),
                np.concatenate([q for _, q in parts]))

    pts, w = rule(6)
    d = (pts @ A2.T)[None, :, :] - (pts @ A1.T)[:, None, :]
    dist = np.linalg.norm(d, axis=-1)
    cos = -(d @ R) / (np.where(dist == 0, 1.0, dist) * Rn)
    W = (d1 * w)[:, None] * (d2 * w)[None, :]
    for n in range(9):
        pair = W * dist**n * eval_legendre(n, cos) / Rn ** (n + 1)
        direct = -G * pair.sum(axis=1).sum()
        bound = (2 * len(w) + 3 * n + 8) * EPS * G * np.abs(pair).sum() + \
            (n_products(n) + n + 4) * EPS * G * m1 * m2 * (4 * rho) ** n / Rn ** (n + 1)
        assert abs(terms[n] - direct) <= bound, (n, terms[n], direct)
    # every odd degree is far above these bounds: a wrong one would show
    assert (np.abs(terms[[3, 5, 7]]) > 1e-13 * abs(terms[0])).all(), terms

    pts, w = rule(10)
    exact = direct_potential(R, pts @ A1.T, d1 * w, pts @ A2.T, d2 * w, G)
    quad_error = 2 * tail_bound(19, G, m1, m2, Rn, rho) + 4 * len(w) * EPS * abs(exact)
    for N in range(9):
        U = MutualGravity(N, G).forces(R, T1, T2).potential
        assert abs(U - exact) <= (tail_bound(N, G, m1, m2, Rn, rho) + quad_error
                                  + series_roundoff(N, G, m1, m2, Rn, rho)), N
    assert abs(U - exact) <= 1e-9 * abs(exact)       # measured 2.1e-10 at order 8


def InertiaScaled(T, factor):
    """The integrals of the same shape at ``factor`` times the density."""
    return type(T)(tuple(factor * t for t in T.degrees))


# --- exact special cases --------------------------------------------------------------

@pytest.mark.parametrize("order", range(9))
def test_two_spheres_are_point_masses_at_every_order(order):
    G, m1, m2, r1, r2 = 6.674e-11, 5e11, 4e9, 400.0, 80.0
    R = np.array([3000.0, -2400.0, 1800.0])
    Rn, rho = np.linalg.norm(R), r1 + r2            # rho / R = 0.11
    A1, A2 = Rotation.random(2, random_state=order).as_matrix()
    T1 = rotated(inertia_integrals(sphere(m1, r1), order), A1)
    T2 = rotated(inertia_integrals(sphere(m2, r2), order), A2)
    f = MutualGravity(order, G).forces(R, T1, T2)
    tol = series_roundoff(order, G, m1, m2, Rn, rho)
    assert abs(f.potential + G * m1 * m2 / Rn) <= tol
    np.testing.assert_allclose(f.force, -G * m1 * m2 * R / Rn**3, rtol=0, atol=tol / Rn * 8)
    for tau in (f.torque_primary, f.torque_secondary):
        assert np.abs(tau).max() <= 8 * tol


@pytest.mark.parametrize("secondary_radius", [1e-3, 20.0])
def test_point_mass_near_an_ellipsoid_is_maccullagh(secondary_radius):
    """Order 2 with a sphere as secondary: ``-G m2 (M/R + (A + B + C - 3 I)/(2 R^3))``,
    I the primary's moment about R's direction: the sphere's own degree 2 drops (the
    trace of the second derivatives of 1/R vanishes), whatever its radius."""
    G, M, m2 = 6.674e-11, 5.2e11, 4.3e9
    axes = np.array([425.0, 410.0, 390.0])
    A1 = Rotation.from_euler("zxz", [0.3, 1.1, -0.4]).as_matrix()
    R = np.array([900.0, -500.0, 700.0])
    Rn = np.linalg.norm(R)
    primary = ellipsoid(M, axes)
    T1 = rotated(inertia_integrals(primary, 2), A1)
    T2 = inertia_integrals(sphere(m2, secondary_radius), 2)
    f = MutualGravity(2, G).forces(R, T1, T2)
    I_inertial = A1 @ primary.inertia @ A1.T
    e = R / Rn
    I_R = e @ I_inertial @ e
    mac = -G * m2 * (M / Rn + (np.trace(primary.inertia) - 3 * I_R) / (2 * Rn**3))
    rho = axes.max() + secondary_radius
    assert abs(f.potential - mac) <= series_roundoff(2, G, M, m2, Rn, rho) + 8 * EPS * abs(mac)
    # the same from a body known only by its moments (no distribution)
    bare = RigidBody(primary.inertia, mass=M)
    g = MutualGravity(2, G).forces(R, rotated(inertia_integrals(bare, 2), A1), T2)
    assert abs(g.potential - mac) <= series_roundoff(2, G, M, m2, Rn, rho) + 8 * EPS * abs(mac)
    # MacCullagh's torque on the primary: 3 G m2 / R^5 (R x I R)
    tau = 3 * G * m2 / Rn**5 * np.cross(R, I_inertial @ R)
    scale = 3 * G * m2 / Rn**3 * np.abs(I_inertial).max()
    np.testing.assert_allclose(f.torque_primary, tau, rtol=0,
                               atol=series_roundoff(2, G, M, m2, Rn, rho) / Rn * 16
                               + 32 * EPS * scale)


# --- derivatives ---------------------------------------------------------------------

def _setup(order=6):
    a1 = np.array([3.0, 2.0, 1.5])
    m1, m2, G = 2.0, 0.3, 1.0
    shape = l_prism(0.75)                                 # odd degrees present
    T1 = rotated(inertia_integrals(ellipsoid(m1, a1), order),
                 Rotation.from_euler("zyx", [0.3, 0.5, -0.2]).as_matrix())
    T2 = inertia_integrals(polyhedral_body(shape, m2 / shape.volume), order)
    T2 = rotated(T2, Rotation.from_euler("zyx", [-1.0, 0.4, 0.9]).as_matrix())
    rho2 = np.linalg.norm(shape.vertices - shape.centroid, axis=1).max()
    R = np.array([9.0, -6.0, 7.0])
    return MutualGravity(order, G), R, T1, T2, G, m1, m2, a1.max() + rho2


def five_point(f, h):
    """``f'(0)`` by the 5-point stencil; its truncation is ``h^4/30 max|f^(5)|``."""
    return (8 * (f(h) - f(-h)) - (f(2 * h) - f(-2 * h))) / (12 * h)


def test_force_is_minus_the_gradient_of_the_potential():
    """5-point differences in R.  The full potential's 5th directional derivative is at
    most ``5! G m1 m2 / (R - rho)^6`` (Legendre's bound on 1/|x| at every point pair);
    the truncated series differs from it by the tail, taken as at most as much again.
    Round-off: the series' bound on each side, times 18/12 / h."""
    gravity, R, T1, T2, G, m1, m2, rho = _setup()
    Rn = np.linalg.norm(R)
    F = gravity.forces(R, T1, T2).force
    h = 0.02
    trunc = h**4 / 30 * 2 * 120 * G * m1 * m2 / (Rn - rho) ** 6
    rnd = 3 * series_roundoff(gravity.order, G, m1, m2, Rn, rho) / h
    for i in range(3):
        e = np.eye(3)[i]
        dU = five_point(lambda s, e=e: gravity.forces(R + s * e, T1, T2).potential, h)
        assert abs(F[i] + dU) <= trunc + rnd, (i, F[i], -dU)
    assert trunc + rnd < 1e-6 * np.linalg.norm(F)        # the test has teeth


@pytest.mark.parametrize("body", ["primary", "secondary"])
def test_torque_is_minus_the_derivative_along_a_small_rotation(body):
    """Turn one body by theta about an inertial axis; U(theta) of the series to order N
    is a trigonometric polynomial of degree <= N (each integral of degree l is degree l
    in the attitude matrix), and its degree-n part is at most G m1 m2 rho^n/R^(n+1), so
    Bernstein's inequality bounds its 5th derivative by ``sum_n n^5`` of those.  Only
    the degrees >= 2 turn (the monopole is constant), so those terms are differenced."""
    gravity, R, T1, T2, G, m1, m2, rho = _setup()
    Rn = np.linalg.norm(R)
    f = gravity.forces(R, T1, T2)
    tau = f.torque_primary if body == "primary" else f.torque_secondary
    h = 0.005

    def U(axis, s):
        turn = Rotation.from_rotvec(s * np.eye(3)[axis]).as_matrix()
        A = rotated(T1, turn) if body == "primary" else T1
        B = rotated(T2, turn) if body == "secondary" else T2
        return gravity.terms(R, A, B)[2:].sum()

    trunc = h**4 / 30 * sum(n**5 * G * m1 * m2 * rho**n / Rn ** (n + 1)
                            for n in range(2, gravity.order + 1))
    rnd = 3 * series_roundoff(gravity.order, G, m1, m2, Rn, rho) / h
    for i in range(3):
        dU = five_point(lambda s, i=i: U(i, s), h)
        assert abs(tau[i] + dU) <= trunc + rnd, (i, tau[i], -dU)
    assert trunc + rnd < 1e-4 * np.linalg.norm(tau)


@pytest.mark.parametrize("order", [2, 3, 4, 6, 8])
def test_torques_and_orbit_balance_to_round_off(order):
    """``tau1 + tau2 + R x F = 0``: each degree pair is invariant under a rotation of
    the whole system, so the truncated series conserves angular momentum exactly; what
    remains is the round-off of the three terms (bounded by the series' round-off
    scaled by the lever arm and the degree)."""
    gravity, R, T1, T2, G, m1, m2, rho = _setup(order)
    Rn = np.linalg.norm(R)
    for Rs in (R, R * 1.7, np.array([-3.0, 11.0, 2.0])):
        f = gravity.forces(Rs, T1, T2)
        total = f.torque_primary + f.torque_secondary + np.cross(Rs, f.force)
        Rn = np.linalg.norm(Rs)
        tol = (order + 2) * 3 * series_roundoff(order, G, m1, m2, Rn, rho)
        assert np.abs(total).max() <= tol, (total, tol)
        assert np.linalg.norm(f.torque_primary) > 1e4 * tol     # not zero trivially


def test_batch_of_separations_equals_single_calls():
    gravity, R, T1, T2, *_ = _setup(4)
    Rs = R * np.array([[1.0], [1.3], [2.0]])
    batch = gravity.forces(Rs, T1, T2)
    for j, Rj in enumerate(Rs):
        one = gravity.forces(Rj, T1, T2)
        for a, b in zip(batch, one):
            # the same operations, the sum over the batch axis aside: a few ulps
            np.testing.assert_allclose(np.asarray(a)[j], b, rtol=16 * EPS,
                                       atol=16 * EPS * np.abs(b).max())


# --- generators of rotation ------------------------------------------------------------

@pytest.mark.parametrize("k", range(2, 9))
def test_generators_are_the_derivative_of_rotated(k):
    """``rotated(T, exp(theta e_i))`` is exactly a trigonometric polynomial of degree k
    in theta, so 2k + 1 equally spaced samples give its derivative at 0 exactly (the
    discrete Fourier derivative, weights ``(2/M) sum_m m sin(m theta_j)``); the
    generators must match it to round-off."""
    T = inertia_integrals(polyhedral_body(l_prism(0.75)), k)
    M = 2 * k + 1
    theta = 2 * np.pi * np.arange(M) / M
    weights = 2 / M * sum(m * np.sin(m * theta) for m in range(1, k + 1))
    scale = np.abs(T.degrees[k]).max() * 3 ** (k / 2)     # entries of the turned tensor
    for axis in range(3):
        samples = np.stack([rotated(T, Rotation.from_rotvec(t * np.eye(3)[axis])
                                    .as_matrix()).degrees[k] for t in theta])
        exact = weights @ samples
        got = generators(k)[axis] @ T.degrees[k]
        # each sample within 3k ulps of its scale (k passes of 3-term sums); the
        # weighted sum multiplies that by sum|w|; the generators' sum is 2k terms
        tol = (np.abs(weights).sum() * 3 * k + 2 * k) * EPS * scale * 2
        assert np.abs(got - exact).max() <= tol, axis
        assert np.abs(exact).max() > 1e3 * tol


def test_cube_degree_4_by_hand():
    """A unit cube and a small sphere at order 4: degree 2 of a cube is isotropic (it
    drops), degree 4 is the cube's own harmonic, computed by hand."""
    cube = Polyhedron([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                       [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
                      [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                       [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    T1 = inertia_integrals(polyhedral_body(cube), 4)
    T2 = inertia_integrals(sphere(1.0, 0.1), 4)
    R = np.array([5.0, 0.0, 0.0])
    t = MutualGravity(4, 1.0).terms(R, T1, T2)
    rho = np.sqrt(3) / 2 + 0.1
    tol = series_roundoff(4, 1.0, 1.0, 1.0, 5.0, rho)
    assert abs(t[0] + 1.0 / 5.0) <= tol and abs(t[2]) <= tol
    # degree 4 along a face normal, by hand: -G m M / R^5 * mean(r^4 P_4(x/r)) over the
    # unit cube, with mean x^4 = 1/80, x^2 y^2 = 1/144: (35 - 30 + 9)/80 + (-60 + 18)/144
    # = -7/60, over 8: U_4 = +7 G m M / (480 R^5)
    assert abs(t[4] - 7.0 / (480 * 5.0**5)) <= tol
    assert abs(t[3]) <= tol                        # the cube is centrally symmetric


# --- bad input ----------------------------------------------------------------------

@pytest.mark.parametrize("field, kwargs", [
    ("order", dict(order=-1)), ("order", dict(order=2.0)), ("order", dict(order=True)),
    ("order", dict(order="4")), ("G", dict(order=2, G=-1.0)), ("G", dict(order=2, G=0.0)),
    ("G", dict(order=2, G=float("nan"))), ("G", dict(order=2, G="6.7e-11")),
])
def test_mutual_gravity_rejects_a_bad_order_or_g(field, kwargs):
    """An order of -1 used to give a potential of exactly 0 without a word."""
    with pytest.raises(att.BinarySystemError) as err:
        MutualGravity(**kwargs)
    assert str(err.value).startswith(field)


def test_integrals_below_the_order_are_named():
    """They used to raise IndexError from inside the series."""
    T4 = inertia_integrals(ellipsoid(1.0, [3.0, 2.0, 1.0]), 4)
    T2 = inertia_integrals(ellipsoid(1.0, [3.0, 2.0, 1.0]), 2)
    with pytest.raises(att.BinarySystemError, match="^secondary: .*order 4"):
        MutualGravity(4).forces([10.0, 0, 0], T4, T2)
    with pytest.raises(att.BinarySystemError, match="^primary: .*order 4"):
        MutualGravity(4).terms([10.0, 0, 0], T2, T4)
    # more than enough is fine: order 2 of order-4 integrals is order 2
    a = MutualGravity(2).forces([10.0, 0, 0], T4, T4)
    b = MutualGravity(2).forces([10.0, 0, 0], T2, T2)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
