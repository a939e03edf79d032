"""The compiled one-body kernels (attitude/propagation/compiled.py), each run twice: as
numba compiled it (when numba is installed) and as plain Python (the same source loaded
with ``ATTITUDE_NO_NUMBA=1``), against scipy.special, mpmath and the numpy/scipy free
flow of attitude/propagation/splitting.py.

Tolerances are ulps of a stated magnitude, with the reason next to each number
(tests/tolerances.py).  Where an argument is large the magnitude includes the condition
of the function in it: ``|f| + |u f'(u)|`` for ``f(u)``, since rounding ``u`` (or a phase
built from it, ``phi = 2^n a_n u`` in the AGM) moves ``f`` by ``|u f'| eps``.
"""

import importlib.util
import math
import os
import sys

import mpmath
import numpy as np
import pytest
from scipy import special as sp
from scipy.spatial.transform import Rotation

from attitude.foundations import quaternion as quat
from attitude.model import freebody as fb
from attitude.propagation import compiled, splitting
from attitude.propagation.torquefree import free_rotation

from ..tolerances import EPS, EXACT_SOLUTION, FEW_OPS, assert_agree


def _plain_module():
    """compiled.py loaded afresh with ATTITUDE_NO_NUMBA=1, on a fresh numba machinery
    (jit.py) that reads it: every kernel as plain Python."""
    def fresh(name, file):
        spec = importlib.util.spec_from_file_location(name, file)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    old = os.environ.get("ATTITUDE_NO_NUMBA")
    os.environ["ATTITUDE_NO_NUMBA"] = "1"
    machinery = sys.modules["attitude.propagation.jit"]
    try:
        sys.modules["attitude.propagation.jit"] = fresh("attitude.propagation.jit_plain",
                                                        machinery.__file__)
        return fresh("attitude.propagation.compiled_plain", compiled.__file__)
    finally:
        sys.modules["attitude.propagation.jit"] = machinery
        if old is None:
            del os.environ["ATTITUDE_NO_NUMBA"]
        else:
            os.environ["ATTITUDE_NO_NUMBA"] = old


PLAIN = _plain_module()


@pytest.fixture(params=["compiled", "plain"], scope="module")
def k(request):
    """The kernels as numba compiled them (plain Python too when numba is absent), and
    as plain Python."""
    return compiled if request.param == "compiled" else PLAIN


def test_numba_flag_and_plain_fallback():
    try:
        import numba  # noqa: F401   (optional: the compiled path is tested when present)
        importable = True
    except ImportError:
        importable = False
    assert compiled.NUMBA is (importable and os.environ.get("ATTITUDE_NO_NUMBA") != "1")
    assert PLAIN.NUMBA is False
    f = PLAIN.jit(math.sin)
    assert f is math.sin                                 # the identity without numba
    if compiled.NUMBA:
        assert compiled.free_flow_one.py_func.__code__ is not None


# --- Jacobi elliptic functions -----------------------------------------------------------

#: ``ellipj`` against scipy where both run Cephes' algorithm: the same IEEE operations in
#: the same order, so the only differences can come from the maths library (sin, asin,
#: cos, sqrt: within 1 ulp each).  The amplitude ``phi`` passes through at most 9 levels
#: of ``phi <- (asin(t) + phi) / 2`` (2 library calls each), then sin/cos: ~20 calls of
#: 1 ulp of |phi| ~ |u|, rounded up to 32 ulp of ``1 + |u|`` (the condition of sn, cn,
#: dn in u: their derivatives are at most 1).
ELLIPJ_SAME_ALGORITHM = 32
#: ``ellipj`` near m = 1 (our Landen path) against mpmath: the reduction
#: ``x = u - 2nK`` rounds x by ``(|u| + 2|n| K) eps / 2`` (<= ~1.5 |u| ulp) and the
#: Landen levels (<= 8, each a division and a product of terms without cancellation,
#: A&S 16.12) add ~2 ulp of the value each; relative to ``|f| + |u f'|``: 16 + 8 * 2,
#: rounded to 32.
ELLIPJ_NEAR1 = 32


def _ellipj_condition(u, sn, cn, dn, m):
    """|f| + |u f'| for f = sn, cn, dn (sn' = cn dn, cn' = -sn dn, dn' = -m sn cn)."""
    u = np.abs(u)
    return (np.abs(sn) + u * np.abs(cn * dn), np.abs(cn) + u * np.abs(sn * dn),
            np.abs(dn) + u * m * np.abs(sn * cn))


def _ellipj_many(k, u, m):
    return np.array([k.ellipj(float(a), float(b)) for a, b in zip(u, m)]).T


def test_ellipj_equals_scipy_over_the_cephes_domain(k):
    """0 <= m < 1 - 1e-10 (and the expansion about m = 1 where it holds), |u| <= 100."""
    rng = np.random.default_rng(11)
    n = 3000
    m = np.concatenate([rng.uniform(0, 1, n), 10.0 ** rng.uniform(-16, -9, 200),
                        1 - 10.0 ** rng.uniform(-10, -1, 300),
                        [0.0, 1e-9, 1e-9 * (1 - EPS), 0.5, 1 - 1e-10 - 1e-16]])
    u = rng.uniform(-100, 100, m.size)
    u[:50] = rng.uniform(-1e-3, 1e-3, 50)
    # the expansion about m = 1 (|u| small): scipy's values are right there
    m_hi = 1 - 10.0 ** rng.uniform(-16, -10, 200)
    u_hi = rng.uniform(-1, 1, 200) * np.arccosh(np.sqrt(1e-8 / (1 - m_hi)))
    m = np.concatenate([m, m_hi, [1.0, 1 - 1e-10, 1 - 1e-10 + 1e-17]])
    u = np.concatenate([u, u_hi, [3.0, 0.5, -0.7]])
    ours = _ellipj_many(k, u, m)
    ref = np.array(sp.ellipj(u, m)[:3])
    tol = ELLIPJ_SAME_ALGORITHM * EPS * (1 + np.abs(u))
    assert np.all(np.abs(ours - ref) <= tol), np.max(np.abs(ours - ref) / tol)


def test_ellipj_near_m_1_against_mpmath(k):
    """1 - 1e-10 < m < 1 and |u| up to 100 (several quarter periods: K = 12.5 - 19.8),
    where Cephes' expansion about m = 1 (so scipy) fails beyond the first quarter
    period: our values against 30-digit mpmath, and the identities."""
    rng = np.random.default_rng(12)
    n = 60
    m1 = np.concatenate([10.0 ** rng.uniform(-16, -10, n), [1e-12, 1e-12, 2.0 ** -53]])
    m = 1 - m1
    m1 = 1 - m                                        # the complement m really has
    u = np.concatenate([rng.uniform(-100, 100, n), [40.0, -17.3, 30.0]])
    sn, cn, dn = _ellipj_many(k, u, m)
    with mpmath.workdps(30):
        ref = np.array([[float(mpmath.ellipfun(f, mpmath.mpf(a), m=mpmath.mpf(b)))
                         for a, b in zip(u, m)] for f in ("sn", "cn", "dn")])
    cond = _ellipj_condition(u, *ref, m)
    for got, want, c, name in zip((sn, cn, dn), ref, cond, ("sn", "cn", "dn")):
        assert np.all(np.abs(got - want) <= ELLIPJ_NEAR1 * EPS * c), name
    # sn^2 + cn^2 = 1, dn^2 = m1 + m cn^2: the Landen levels with g ~ 1 (up to 4 for
    # m1 >= 1.1e-16) double the relative error of cn and dn each (dn' ~ 2 cn dcn): 2^4
    # x 2 roundings, for each of the two squares: 64
    assert np.all(np.abs(sn * sn + cn * cn - 1) <= 64 * EPS)
    assert np.all(np.abs(dn * dn - (m1 + m * cn * cn)) <= 64 * EPS)


def test_ellipj_limits(k):
    """m = 0: sin, cos, 1; m = 1: tanh, sech, sech (also where cosh overflows); NaN
    outside 0 <= m <= 1."""
    for u in (0.0, 0.3, -2.0, 90.0):
        sn, cn, dn = k.ellipj(u, 0.0)
        assert (sn, cn, dn) == (math.sin(u), math.cos(u), 1.0)
    for u in (0.0, 0.3, -2.0, 30.0, 800.0):
        sn, cn, dn = k.ellipj(u, 1.0)
        assert sn == math.tanh(u) and cn == dn
        assert abs(cn - (1 / math.cosh(u) if u < 700 else 0.0)) <= 4 * EPS * cn
    assert all(math.isnan(x) for x in k.ellipj(0.5, 1.5) + k.ellipj(0.5, -0.1)
               + k.ellipj(0.5, math.nan) + k.ellipj(math.inf, 0.5)
               + k.ellipj(-math.inf, 1 - 1e-12) + k.ellipj(math.nan, 0.0))


# --- Carlson's integrals -----------------------------------------------------------------

#: R_F by duplication (Carlson 1995): the final series (8 terms, |E2|, |E3| <= r^(1/3)
#: so the terms past 1 are small) and sqrt(A) divide in ~3 roundings; each duplication
#: rounds x, y, z, A by ~3 roundings of positive terms, and an error made at step j
#: shrinks by 4^-(n-j) relative to A... so at most ~4 u per implementation (2 ulp of the
#: value), measured <= 2.5 eps against mpmath.  Two implementations: 4 + 4 ulp.
RF_ULPS = 8
#: R_J adds 6 sum_j 4^-j R_C(1, 1 + e_j) / d_j: positive terms each of ~6 roundings
#: (atan or atanh, sqrt, a quotient): ~8 ulp per implementation, 16 for two.
RJ_ULPS = 16
#: Against scipy's R_J: ours (RJ_ULPS / 2 of mpmath, below) and scipy's own error, which
#: at ``x = 0, y << z`` (R_J(0, m1, 1, 1 + nu) near the separatrix) is up to 16 ulp of
#: mpmath (measured at the arguments of this test; ours 1-2 there): 8 + 16, rounded up.
RJ_VS_SCIPY = 32


def _rel_ulps(got, want):
    return np.abs(got - want) / np.spacing(np.abs(want))


def _free_flow_carlson_arguments(rng, n, nu_max=1e12):
    """The arguments the free flow passes: R_F(cn^2, dn^2, 1), R_F(0, m1, 1),
    R_J(cn^2, dn^2, 1, 1 + nu sn^2), R_J(0, m1, 1, 1 + nu), with dn^2 >= m1 >= 1e-16
    and nu from 0 to 1e12 (a body with I3 close to I2)."""
    m1 = 10.0 ** rng.uniform(-16, 0, n)
    m = 1 - m1
    sn = rng.uniform(-1, 1, n)
    cn2 = 1 - sn * sn
    dn2 = m1 + m * cn2
    nu = np.concatenate([10.0 ** rng.uniform(-3, math.log10(nu_max), n - 20), np.zeros(20)])
    rf = [(cn2, dn2, np.ones(n)), (np.zeros(n), m1, np.ones(n))]
    rj = [(cn2, dn2, np.ones(n), 1 + nu * sn * sn), (np.zeros(n), m1, np.ones(n), 1 + nu)]
    return rf, rj


def test_carlson_integrals_equal_scipy(k):
    """At the free flow's arguments with nu <= 1e3 (scipy's R_J loses up to ~60 ulp for
    p > 1e9, where ours stays within RJ_ULPS / 2 of mpmath: the next test) and at
    general ones."""
    rng = np.random.default_rng(21)
    rf, rj = _free_flow_carlson_arguments(rng, 1500, nu_max=1e3)
    # and general arguments
    x, y, z = rng.uniform(0, 10, (3, 1500)) ** 2
    rf.append((x, y, z))
    rj.append((x, y, z, rng.uniform(1e-3, 10, 1500)))
    for args in rf:
        got = np.array([k.elliprf(*map(float, a)) for a in zip(*args)])
        assert np.max(_rel_ulps(got, sp.elliprf(*args))) <= RF_ULPS
    for args in rj:
        got = np.array([k.elliprj(*map(float, a)) for a in zip(*args)])
        assert np.max(_rel_ulps(got, sp.elliprj(*args))) <= RJ_VS_SCIPY


def test_carlson_integrals_against_mpmath(k):
    """One implementation's share of the bounds above, at the free flow's arguments."""
    rng = np.random.default_rng(22)
    rf, rj = _free_flow_carlson_arguments(rng, 40)
    with mpmath.workdps(30):
        for args in rf:
            for a in zip(*args):
                want = float(mpmath.elliprf(*map(mpmath.mpf, map(float, a))))
                assert _rel_ulps(k.elliprf(*map(float, a)), want) <= RF_ULPS / 2
        for args in rj:
            for a in zip(*args):
                want = float(mpmath.elliprj(*map(mpmath.mpf, map(float, a))))
                assert _rel_ulps(k.elliprj(*map(float, a)), want) <= RJ_ULPS / 2


def test_carlson_special_values(k):
    # R_F(0, 1, 1) = pi/2, R_J(0, 1, 1, 1) = 3 pi / 4 (DLMF 19.20.1, 19.20.5 with R_J = R_D)
    assert abs(k.elliprf(0.0, 1.0, 1.0) - math.pi / 2) <= 2 * EPS
    assert abs(k.elliprj(0.0, 1.0, 1.0, 1.0) - 3 * math.pi / 4) <= 4 * EPS
    # R_F(x, x, x) = x^-1/2, R_J(x, x, x, x) = x^-3/2
    assert k.elliprf(4.0, 4.0, 4.0) == 0.5 and k.elliprj(4.0, 4.0, 4.0, 4.0) == 0.125
    assert k.elliprf(0.0, 0.0, 1.0) == math.inf == k.elliprj(0.0, 0.0, 1.0, 2.0)
    assert k.elliprj(0.2, 0.5, 1.0, math.inf) == 0.0
    assert math.isnan(k.elliprf(-1.0, 1.0, 1.0)) and math.isnan(k.elliprj(1.0, 1.0, 1.0, 0.0))


# --- the twins of the freebody helpers ------------------------------------------------

def test_twins_equal_the_freebody_helpers(k):
    """The scalar twins perform the operations of attitude.freebody in the same order;
    ``x ** 2`` is the C library's ``pow`` in Python (within 1 ulp, not always correctly
    rounded) and ``x * x`` compiled: a sum of three such squares then differs by up to
    2 ulp, within FEW_OPS of each value."""
    rng = np.random.default_rng(31)
    for _ in range(200):
        I = tuple(np.sort(rng.uniform(0.5, 2.0, 3)).tolist())
        w = tuple(rng.normal(size=3).tolist())
        lam = bool(rng.integers(2))
        want = np.array(fb.invariants(*I, *w))
        assert_agree(k._invariants(*I, *w), want, ulps=FEW_OPS, magnitude=np.abs(want))
        assert k._kernel_moments(*I, lam) == fb.kernel_moments(*I, lam)
        assert k._kernel_vector(*w, lam) == fb.kernel_vector(*w, lam)
        assert k._half_theta(*w) == fb.half_theta(*w)
        args = (*rng.uniform(0, 1, 2).tolist(), *rng.uniform(-7, 7, 2).tolist())
        assert k._euler313_quaternion(*args) == fb.euler313_quaternion(*args)
        a, b = tuple(rng.normal(size=4).tolist()), tuple(rng.normal(size=4).tolist())
        assert k._multiply_parts(a, b) == quat.multiply_parts(a, b)
    for x in (0.5, 1.5, 2.5, -0.5, -1.5, 2.4999999999999996, 0.49999999999999994, -3.7):
        assert k._round_half_even(x) == round(x)


# --- the free flow -------------------------------------------------------------------------

def _cases(rng, n):
    """Random triaxial bodies and states on both sides of the separatrix, and the
    special ones: near the separatrix, on it, axisymmetric (oblate, prolate), spherical,
    pure spins, rest, a slow spin."""
    moments = np.sort(rng.uniform(1.0, 2.0, (n, 3)), axis=1)
    omega = rng.normal(size=(n, 3))
    special = [
        ([1.0, 1.0, 2.0], [0.3, 0.1, 0.5]),          # oblate (m = 0)
        ([0.5, 2.0, 2.0], [0.4, 0.2, -0.1]),         # prolate (LAM, m = 0)
        ([1.0, 2.0, 2.0], [0.0, 1.0, 0.5]),          # prolate spinning in its B-C plane
        ([2.0, 2.0, 2.0], [0.2, -0.1, 0.3]),         # spherical
        ([1.0, 2.0, 3.0], [0.0, 0.0, -1.5]),         # pure spin about C
        ([1.0, 2.0, 3.0], [0.7, 0.0, 0.0]),          # pure spin about A
        ([1.0, 2.0, 3.0], [0.0, 0.9, 0.0]),          # intermediate-axis equilibrium
        ([1.0, 2.0, 3.0], [1e-40, 0.0, 1.0]),        # all but pure spin
        ([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]),          # rest
        ([1.0, 2.0, 4.0], [0.5, 0.3, -0.5 / math.sqrt(8)]),   # on the separatrix (rounded)
        ([1.0, 2.0, 3.0], [math.sqrt(3) * (1 - 1e-7), 0.3, 1.0]),   # m1 ~ 2e-7, SAM
        ([1.0, 2.0, 3.0], [math.sqrt(3) * (1 + 1e-7), 0.3, 1.0]),   # m1 ~ 2e-7, LAM
        ([1.0, 1.5, 1.5 * (1 + 1e-9)], [0.2, 0.5, 0.1]),     # nearly prolate (nu ~ 1e9)
        ([1e3, 2e3, 2.5e3], [1e-8, -3e-9, 2e-8]),     # slow spin, large moments
    ]
    moments = np.concatenate([moments, [s[0] for s in special]])
    omega = np.concatenate([omega, [s[1] for s in special]])
    quat0 = Rotation.random(len(moments), random_state=rng).as_quat()
    return moments, omega, quat0


def _run_one(k, consts, i, q, w, h):
    qq, ww = np.array(q, dtype=float), np.array(w, dtype=float)
    out = k.free_flow_one(np.array(consts.row(i), dtype=float), qq, ww, h)
    assert out is None                                # in place
    return qq, ww


#: The compiled free flow against splitting._free_flow1 and free_flow: the same formulas
#: in the same order; only the special functions differ (R_F, R_J by <= RJ_ULPS,
#: ellipj by ELLIPJ_SAME_ALGORITHM ulps of the argument), and enter the attitude through
#: the precession angle and the rates through the addition theorems: the bound of two
#: paths of the exact free flow (EXACT_SOLUTION, 64 ulp), of the magnitude of the angle
#: turned, ``max(1, |omega h|)`` (a phase of 100 rad carries ulps of 100).
FLOW_ULPS = EXACT_SOLUTION


def _assert_flow_agrees(q, w, q_ref, w_ref, omega, h, what):
    turn = max(1.0, float(np.linalg.norm(omega)) * abs(h))
    s = 1.0 if np.dot(q, q_ref) >= 0 else -1.0
    assert_agree(q, s * np.asarray(q_ref), ulps=FLOW_ULPS, magnitude=turn, what=f"q {what}")
    assert_agree(w, w_ref, ulps=FLOW_ULPS,
                 magnitude=max(float(np.linalg.norm(omega)), 1e-300) * turn, what=f"w {what}")


@pytest.mark.parametrize("h", [0.0, 1e-3, 0.37, -2.5, 30.0, -61.0])
def test_free_flow_one_equals_the_numpy_paths(k, h):
    """SAM, LAM, near the separatrix, symmetric, spherical, pure spin, rest, negative
    steps and steps of several polhode periods (|lambda h| up to ~100 >> 4K)."""
    rng = np.random.default_rng(41)
    moments, omega, quat0 = _cases(rng, 120 if k is compiled else 40)
    consts = splitting._FreeConstants(moments)
    q_vec, w_vec = splitting.free_flow(moments, quat0, omega, h)
    for i in range(len(moments)):
        q, w = _run_one(k, consts, i, quat0[i], omega[i], h)
        q1, w1 = splitting._free_flow1(consts.row(i), tuple(quat0[i]), tuple(omega[i]), h)
        _assert_flow_agrees(q, w, q1, w1, omega[i], h, f"of body {i} vs _free_flow1")
        _assert_flow_agrees(q, w, q_vec[i], w_vec[i], omega[i], h, f"of body {i} vs free_flow")


def test_free_flow_one_near_the_separatrix_with_long_steps(k):
    """1 - m down to 2e-13 and steps past the quarter period K (12 - 16 here), where
    scipy's ellipj leaves the elliptic functions (the numpy paths of splitting take
    compiled.ellipj there): against the closed form.  The motion there is ill-
    conditioned: a relative change eps of the state changes m1 by ~eps and the period
    4K/lambda by ~eps/(2 m1) relative (K ~ ln(4/sqrt m1)), so after |v|/(4K) periods the
    phase is off by ~|v| eps/(2 m1), and the rates and attitude by up to that, relative:
    bound (1 + |v|) eps / m1."""
    I = np.array([1.0, 2.0, 3.0])
    consts = splitting._FreeConstants(I)
    q0 = np.array([0.1, 0.2, 0.3, 0.9]) / math.sqrt(0.95)
    for gap in (1e-6, 1e-9, 1e-11, 1e-13):
        w0 = np.array([math.sqrt(3.0) * (1 - gap), 0.3, 1.0])
        d21, d32, d31, Q1, Q3, D, _ = fb.invariants(*I, *w0)
        _, m1, lam2 = fb.jacobi_parameters(*I, d21, d32, d31, Q1, Q3, D)
        for h in (5.0, 20.0, -60.0):
            q_ref, w_ref = free_rotation(I, q0, w0, [h])
            bound = (1 + abs(h) * math.sqrt(lam2)) * EPS / m1
            q1, w1 = splitting._free_flow1(consts.row(0), tuple(q0), tuple(w0), h)
            for q, w in (_run_one(k, consts, 0, q0, w0, h),         # and the numpy paths
                         splitting.free_flow(I, q0, w0, h), (np.array(q1), np.array(w1))):
                assert np.max(np.abs(w - w_ref[0])) <= bound * np.linalg.norm(w0), (gap, h)
                s = 1.0 if q @ q_ref[0] >= 0 else -1.0
                assert np.max(np.abs(q - s * q_ref[0])) <= bound, (gap, h)


def test_free_flow_one_conserves_and_returns(k):
    """|q| = 1 and L conserved over many steps, and h then -h returns (to round-off
    growing with the number of steps), away from the separatrix (there the motion
    amplifies round-off by ~1/m1: the test above)."""
    rng = np.random.default_rng(51)
    moments, omega, quat0 = _cases(rng, 10)
    consts = splitting._FreeConstants(moments)
    for i in range(len(moments)):
        L2 = np.sum((moments[i] * omega[i]) ** 2)
        twoE_B = np.sum(moments[i] * omega[i] ** 2) * moments[i, 1]
        if 0 < L2 and abs(L2 - twoE_B) < 1e-3 * L2 and moments[i, 0] < moments[i, 2]:
            continue
        c = np.array(consts.row(i), dtype=float)
        q, w = quat0[i].copy(), omega[i].copy()
        for _ in range(20):
            k.free_flow_one(c, q, w, 0.9)
        L0 = quat.rotate(quat0[i], moments[i] * omega[i])
        L1 = quat.rotate(q, moments[i] * w)
        scale = max(float(np.linalg.norm(L0)), 1e-300)
        assert abs(np.linalg.norm(q) - 1) <= 4 * EPS
        # 20 steps of the exact flow: 20 x FLOW_ULPS of the angle turned
        turn = max(1.0, 18.0 * float(np.linalg.norm(omega[i])))
        assert np.max(np.abs(L1 - L0)) <= 20 * FLOW_ULPS * EPS * scale * turn, i
        for _ in range(20):
            k.free_flow_one(c, q, w, -0.9)
        np.testing.assert_allclose(w, omega[i], rtol=0,
                                   atol=40 * FLOW_ULPS * EPS * turn * np.linalg.norm(omega[i]))
