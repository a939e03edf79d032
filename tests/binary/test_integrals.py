"""Inertia integrals (attitude.binary.integrals) against references that share no code
with them: exact box moments (products of 1-D integrals, in rational arithmetic), the
double-factorial moments of the ball, the polyhedron's own inertia tensor (Tonon's
closed form in attitude.model.shape), the mesh of an ellipsoid converging to the
ellipsoid, and the invariances a moment must have (translation, rotation).

Round-off bounds.  A polyhedron's integral of degree k is a sum over the N = f q
quadrature points (f faces, q points of the tetrahedron rule) of ``w x^a y^b z^c``;
each term is formed in ~k + 8 roundings (corner minus centroid, the 3-term barycentric
combination, k products, the weight and the density) and the sum adds N - 1 more, so
by Higham (2002, eq. 3.4) the error is at most ``(N + k + 8) u`` times the sum of the
terms' magnitudes, ``<= rho * sum|V_tet| * r_max^k`` (u = eps / 2; we use eps, a factor
two of margin for the centroid's own rounding, which moves every point by a few ulp of
the extent).  Exactness is what is tested: a quadrature rule that is not exact for the
degree asked misses by O(1) relative, twelve orders above these bounds.
"""

from fractions import Fraction

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation
from scipy.special import gammaln

import attitude as att
from attitude.binary.integrals import (
    InertiaIntegrals,
    _simplex_rule,
    inertia_integrals,
    multi_indices,
    rotated,
)
from attitude.foundations.errors import BinarySystemError
from attitude.model.body import MassDistribution, RigidBody
from attitude.model.shape import Polyhedron
from tests.tolerances import EPS, assert_agree

BOX_FACES = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
             [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]


def polyhedral_body(shape: Polyhedron, density: float = 1.0) -> RigidBody:
    """A homogeneous body of ``shape`` (what RigidBody.from_obj makes, without a file)."""
    mass, com, inertia = shape.mass_properties(density)
    return RigidBody(inertia, mass=mass, center_of_mass=com,
                     distribution=MassDistribution("polyhedron", mass, shape=shape))


def box(lo, hi) -> Polyhedron:
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return Polyhedron([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                       [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], BOX_FACES)


def l_prism(height: float) -> Polyhedron:
    """The L of [0,3]x[0,1] and [0,1]x[1,3] in xy, extruded from z = 0 to ``height``:
    non-convex, and its centroid (1.1, 1.1) lies outside it, so the tetrahedra from the
    centroid to the faces come with both signs."""
    ring = [(0, 0), (3, 0), (3, 1), (1, 1), (1, 3), (0, 3)]
    n = len(ring)
    vertices = [(x, y, 0.0) for x, y in ring] + [(x, y, height) for x, y in ring]
    fan = [(3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)]       # from the reflex corner
    faces = [(a, c, b) for a, b, c in fan]                  # bottom: normal -z
    faces += [(a + n, b + n, c + n) for a, b, c in fan]     # top: normal +z
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    return Polyhedron(vertices, faces)


def convex_hull(points) -> Polyhedron:
    """The convex hull of ``points``, faces turned outward (an irregular solid: every
    moment non-zero)."""
    hull = ConvexHull(points)
    faces = hull.simplices.copy()
    v = hull.points
    normal = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    flip = np.einsum("ij,ij->i", normal, hull.equations[:, :3]) < 0
    faces[flip] = faces[flip][:, [0, 2, 1]]
    used = np.unique(faces)
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    return Polyhedron(v[used], remap[faces])


def irregular(seed=3, n=40) -> Polyhedron:
    rng = np.random.default_rng(seed)
    return convex_hull(rng.normal(size=(n, 3)) * [3.0, 2.0, 1.2])


def box_moments(boxes, density, centre, k) -> np.ndarray:
    """Exact ``rho sum_boxes prod_axis integral (x - c)^a dx`` in rational arithmetic."""
    def one_d(lo, hi, p):
        return ((hi - centre_) ** (p + 1) - (lo - centre_) ** (p + 1)) / (p + 1)
    out = []
    for idx in multi_indices(k).tolist():
        total = Fraction(0)
        for lo, hi in boxes:
            term = Fraction(1)
            for axis in range(3):
                centre_ = centre[axis]
                term *= one_d(lo[axis], hi[axis], idx[axis])
            total += term
        out.append(float(density * total))
    return np.array(out)


def roundoff(shape: Polyhedron, density: float, order: int, k: int) -> float:
    """The bound of the module docstring for degree ``k`` of a polyhedron integrated to
    ``order``: ``(N + k + 8) eps rho sum|V_tet| r_max^k``."""
    tri = shape.vertices[shape.faces] - shape.centroid
    volumes = np.abs(np.einsum("fi,fi->f", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))) / 6
    n_points = len(shape.faces) * len(_simplex_rule(max(order, 1))[1])
    r_max = np.linalg.norm(tri, axis=-1).max()
    return (n_points + k + 8) * EPS * density * volumes.sum() * r_max**k


# --- multi-indices ---------------------------------------------------------------------

@pytest.mark.parametrize("k", range(9))
def test_multi_indices_are_every_monomial_once(k):
    idx = multi_indices(k)
    assert len(idx) == (k + 1) * (k + 2) // 2
    assert (idx.sum(axis=1) == k).all() and (idx >= 0).all()
    assert len({tuple(m) for m in idx.tolist()}) == len(idx)


def test_tetrahedron_rule_is_exact_to_its_degree():
    """The collapsed Gauss-Jacobi rule against the Dirichlet integral over the unit
    tetrahedron, ``u^a v^b w^c t^d -> a! b! c! d! / (a + b + c + d + 3)!``."""
    from math import factorial
    for order in (1, 2, 5, 8):
        points, weights = _simplex_rule(order)
        u, v, w = points.T
        t = 1.0 - u - v - w
        for a, b, c in [(0, 0, 0), (order, 0, 0), (0, order, 0), (1, 1, order - 2),
                        (order // 2, order - order // 2, 0)]:
            if min(a, b, c) < 0:
                continue
            d = order - a - b - c
            exact = (factorial(a) * factorial(b) * factorial(c) * factorial(d)
                     / factorial(order + 3))
            got = np.sum(weights * u**a * v**b * w**c * t**d)
            # terms positive, <= 1/6 in sum: (q + order + 4) roundings of the sum
            assert abs(got - exact) <= (len(weights) + order + 4) * EPS / 6


# --- boxes: exact at every degree -------------------------------------------------------

@pytest.mark.parametrize("lo, hi, density", [
    ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), 1.0),                 # the unit cube
    ((0.25, -1.0, 3.0), (3.25, 1.0, 4.0), 2.5),              # a box off the origin
])
def test_box_is_exact_to_round_off_to_degree_8(lo, hi, density):
    shape = box(lo, hi)
    T = inertia_integrals(polyhedral_body(shape, density), 8)
    lo_q, hi_q = [Fraction(x) for x in lo], [Fraction(x) for x in hi]
    centre = [(a + b) / 2 for a, b in zip(lo_q, hi_q)]
    for k in range(9):
        exact = box_moments([(lo_q, hi_q)], Fraction(density), centre, k)
        bound = roundoff(shape, density, 8, k)
        assert np.abs(T.degrees[k] - exact).max() <= bound, k
    assert T.mass == pytest.approx(density * np.prod(np.subtract(hi, lo)), rel=4 * EPS)


def test_non_convex_l_prism_equals_its_two_boxes():
    """A non-convex solid whose centroid lies outside it (tetrahedra of both signs)."""
    h, density = 0.75, 1.5
    shape = l_prism(h)
    T = inertia_integrals(polyhedral_body(shape, density), 7)
    boxes = [((0, 0, 0), (3, 1, h)), ((0, 1, 0), (1, 3, h))]
    boxes = [([Fraction(x) for x in lo], [Fraction(x) for x in hi]) for lo, hi in boxes]
    centre = [Fraction(11, 10), Fraction(11, 10), Fraction(h) / 2]
    assert shape.centroid == pytest.approx([1.1, 1.1, h / 2], abs=8 * EPS * 3)
    for k in range(8):
        exact = box_moments(boxes, Fraction(density), centre, k)
        assert np.abs(T.degrees[k] - exact).max() <= roundoff(shape, density, 7, k), k
    # odd degrees do not vanish: the L has no centre of symmetry (a real test of them)
    assert np.abs(box_moments(boxes, Fraction(density), centre, 3)).max() > 0.1


# --- ellipsoids: closed form, and the mesh converging to it ------------------------------

def double_factorial(n: int) -> int:
    return 1 if n <= 0 else n * double_factorial(n - 2)


@pytest.mark.parametrize("k", range(9))
def test_ellipsoid_closed_form_is_the_double_factorial_moments_of_the_ball(k):
    """Mean of ``x^a y^b z^c`` over the unit ball: ``3 (a-1)!! (b-1)!! (c-1)!! /
    ((k + 3) (k + 1)!!)`` for even exponents (the Gamma-function form in the code,
    derived differently), scaled by the semi-axes."""
    mass, axes = 7.0, np.array([3.0, 2.0, 1.25])
    T = inertia_integrals(att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(mass, axes)), k).degrees[k]
    idx = multi_indices(k)
    exact = np.array([0.0 if any(e % 2 for e in m) else
                      3 * np.prod([double_factorial(e - 1) for e in m])
                      / ((k + 3) * double_factorial(k + 1)) for m in idx.tolist()])
    exact = mass * exact * np.prod(axes**idx, axis=1)
    # the code's exp(log-gamma sum): the absolute error of the log (each gammaln within
    # an ulp or two of its value) becomes a relative error of the result, plus the
    # k products of the semi-axes and a few more
    h = (idx + 1) / 2.0
    log_size = np.abs(gammaln(h)).sum(axis=1) + np.abs(gammaln(h.sum(axis=1))) + 2 + k
    bound = (2 * log_size + k + 6) * EPS * np.abs(exact)
    assert (np.abs(T - exact) <= bound).all()


def test_sphere_is_the_ellipsoid_of_equal_axes():
    ball = inertia_integrals(att.RigidBody.from_mass_properties(
        att.MassProperties.solid_sphere(3.0, 2.0)), 6)
    egg = inertia_integrals(att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(3.0, [2.0, 2.0, 2.0])), 6)
    for a, b in zip(ball.degrees, egg.degrees):
        np.testing.assert_array_equal(a, b)       # the same formula on the same numbers


def test_polyhedral_ellipsoid_converges_to_the_ellipsoid_as_h_squared():
    """An icosphere mesh inscribed in the ellipsoid misses it by a shell of thickness
    ~ curvature x h^2 (h the edge length), so the moments (at a fixed mass) converge
    as h^2: each subdivision halves h and must divide the error by 4 (1 + O(h^2)).
    Observed: 3.78, 3.94, 3.98 from subdivisions 1-2, 2-3, 3-4 at degrees 2, 4, 6
    (slightly less at the coarsest mesh, where the O(h^4) term still shows): bounded
    by [3.4, 4.3] for the first pair and [3.8, 4.1] for the next two.  Odd degrees
    vanish to round-off: the icosphere is centrally symmetric."""
    axes = np.array([3.0, 2.0, 1.5])
    exact = inertia_integrals(att.RigidBody.from_mass_properties(
        att.MassProperties.solid_ellipsoid(1.0, axes)), 6)
    errors = []
    for s in (1, 2, 3, 4):
        mesh = Polyhedron.ellipsoid(*axes, subdivisions=s)
        T = inertia_integrals(polyhedral_body(mesh, 1.0 / mesh.volume), 6)
        errors.append([np.abs(T.degrees[k] - exact.degrees[k]).max() / axes.max()**k
                       for k in (2, 4, 6)])
        for k in (3, 5):
            assert np.abs(T.degrees[k]).max() <= roundoff(mesh, 1.0 / mesh.volume, 6, k)
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert ((ratios[0] > 3.4) & (ratios[0] < 4.3)).all(), ratios
    assert ((ratios[1:] > 3.8) & (ratios[1:] < 4.1)).all(), ratios
    assert max(errors[-1]) < 4e-4          # 0.017 / 4^3 at the coarsest, as observed


# --- degree 2 is the inertia tensor ---------------------------------------------------

@pytest.mark.parametrize("make", ["rocket_body.obj", "irregular"])
def test_degree_2_is_the_inertia_tensor(make):
    """``T_ij = tr(I)/2 delta_ij - I_ij`` with I from the polyhedron's closed-form
    inertia (Tonon 2004; a different formula and code path)."""
    from pathlib import Path
    if make == "irregular":
        shape = irregular()
        body = polyhedral_body(shape, 1800.0)
    else:
        path = Path(__file__).resolve().parents[2] / "scenarios" / make
        body = att.RigidBody.from_obj(path, density=2700.0)
        shape = body.distribution.shape
    T = inertia_integrals(body, 2)
    I = body.inertia
    expected = 0.5 * np.trace(I) * np.eye(3) - I
    got = np.zeros((3, 3))
    for (a, b, c), value in zip(multi_indices(2).tolist(), T.degrees[2]):
        i, j = [axis for axis, e in enumerate((a, b, c)) for _ in range(e)]
        got[i, j] = got[j, i] = value
    density = body.mass / shape.volume
    # both sides round: the quadrature's bound, and Tonon's sum over f faces (~f + 20
    # roundings of terms bounded the same way)
    bound = roundoff(shape, density, 2, 2) * (1 + (len(shape.faces) + 20)
                                              / (len(shape.faces) * 8 + 10))
    assert np.abs(got - expected).max() <= bound
    assert T.mass == body.mass
    np.testing.assert_array_equal(T.degrees[1], np.zeros(3))


def test_a_body_known_by_its_moments_has_degree_2_only():
    body = RigidBody(np.array([[2.0, 0.1, 0.0], [0.1, 3.0, 0.2], [0.0, 0.2, 4.0]]),
                     mass=5.0)
    T = inertia_integrals(body, 2)
    assert T.order == 2 and T.mass == 5.0
    # tr(I)/2 - I_xx = 2.5, -I_xy = -0.1, -I_xz = 0, 1.5, -0.2, 0.5
    np.testing.assert_allclose(T.degrees[2], [2.5, -0.1, 0.0, 1.5, -0.2, 0.5],
                               rtol=0, atol=4 * EPS * 4.5)
    with pytest.raises(BinarySystemError, match="order 2"):
        inertia_integrals(body, 3, name="secondary")
    with pytest.raises(BinarySystemError, match="no mass"):
        inertia_integrals(RigidBody(np.eye(3)), 2)


# --- invariances ----------------------------------------------------------------------

def test_translated_polyhedron_has_the_same_integrals():
    """About the centre of mass, moving the vertices changes nothing: each side within
    its round-off bound, plus the rounding of the shifted vertices (each coordinate by
    half an ulp of |v + d|, moving degree k by k of those relative to r_max)."""
    shape = irregular(seed=5)
    shift = np.array([7.5, -3.25, 11.0])
    moved = Polyhedron(shape.vertices + shift, shape.faces)
    order = 6
    T = inertia_integrals(polyhedral_body(shape, 2.0), order)
    U = inertia_integrals(polyhedral_body(moved, 2.0), order)
    r_max = np.linalg.norm(shape.vertices - shape.centroid, axis=1).max()
    for k in range(order + 1):
        shifted = k * EPS * (r_max + np.linalg.norm(shift)) / r_max * (
            2.0 * shape.volume * r_max**k) * 4
        bound = roundoff(shape, 2.0, order, k) + roundoff(moved, 2.0, order, k) + shifted
        assert np.abs(T.degrees[k] - U.degrees[k]).max() <= bound, k


def test_rotated_equals_the_integrals_of_the_rotated_polyhedron():
    """``rotated`` (the tensor turned index by index) against integrating the turned
    mesh: exact to round-off on both sides (the vertices turned by a 3-term dot product
    each, 3 ulp of r_max, moving degree k by 3k; the tensor turned k times, each a
    3-term sum of entries bounded by m r_max^k)."""
    shape = irregular(seed=11)
    A = Rotation.from_euler("zyx", [0.7, -1.1, 2.3]).as_matrix()
    turned = Polyhedron(shape.vertices @ A.T, shape.faces)
    order = 8
    T = inertia_integrals(polyhedral_body(shape, 1.0), order)
    direct = inertia_integrals(polyhedral_body(turned, 1.0), order)
    via = rotated(T, A)
    r_max = np.linalg.norm(shape.vertices - shape.centroid, axis=1).max()
    for k in range(order + 1):
        scale = shape.volume * r_max**k
        bound = (roundoff(shape, 1.0, order, k) + roundoff(turned, 1.0, order, k)
                 + (3 * k + 3 * k * 3) * EPS * scale * 3 ** (k / 2))
        assert np.abs(via.degrees[k] - direct.degrees[k]).max() <= bound, k
    # and the rotation is not trivial: degree 3 changed by far more than the bound
    assert np.abs(via.degrees[3] - T.degrees[3]).max() > 1e-3 * shape.volume * r_max**3


def test_rotated_composes_and_broadcasts():
    T = inertia_integrals(polyhedral_body(irregular(seed=2), 1.0), 5)
    A, B = Rotation.random(2, random_state=4).as_matrix()
    once = rotated(T, B @ A)
    twice = rotated(rotated(T, A), B)
    batch = rotated(T, np.stack([A, B, B @ A]))
    scale = [np.abs(t).max() for t in T.degrees]
    for k in range(6):
        # each rotation of degree k: k passes of 3-term sums, ~3k ulp of the tensor's
        # largest entry times its norm growth (<= 3^(k/2) for entries of a unit tensor)
        bound = 2 * 3 * k * 3 ** (k / 2) * EPS * scale[k] * 4
        assert np.abs(once.degrees[k] - twice.degrees[k]).max() <= bound
        assert_agree(batch.degrees[k][2], once.degrees[k], ulps=8 * k + 1, axis=None)
        assert_agree(batch.degrees[k][0], rotated(T, A).degrees[k], ulps=8 * k + 1,
                     axis=None)
    assert isinstance(once, InertiaIntegrals) and once.mass == T.mass


def test_rotated_broadcasts_a_batch_of_bodies_against_one_or_many_attitudes():
    """A batch of integrals (bodies) turned by one matrix, or each by its own: each the
    same as the single rotation (it used to fail for a batch of bodies and one matrix)."""
    bodies = [inertia_integrals(polyhedral_body(irregular(seed=s), 1.0), 4) for s in (1, 2)]
    batch = InertiaIntegrals(tuple(np.stack([b.degrees[k] for b in bodies])
                                   for k in range(5)))
    A, B = Rotation.random(2, random_state=7).as_matrix()
    one = rotated(batch, A)
    each = rotated(batch, np.stack([A, B]))
    for k in range(5):
        assert one.degrees[k].shape == (2, len(multi_indices(k)))
        # the same k passes of 3-term sums, perhaps grouped differently over a batch
        assert_agree(one.degrees[k][1], rotated(bodies[1], A).degrees[k], ulps=8 * k + 1,
                     axis=None)
        assert_agree(each.degrees[k][1], rotated(bodies[1], B).degrees[k], ulps=8 * k + 1,
                     axis=None)
