"""Tolerances for results computed along two code paths.

A batch and a single run, a vector and a scalar, chunks and the whole, dask and local:
two paths that compute the same number round differently.  OpenBLAS picks its kernel
per CPU at run time (``OPENBLAS_CORETYPE``), numpy dispatches its loops (``sin``,
``exp``, ``sqrt``, sums) to SIMD variants per CPU and per array length, and the order
of a sum or the use of fused multiply-add changes with both.  Each rounding is at most
half an ulp of the number it produces, so the difference of the two paths is bounded by
the *magnitude* of the values times the number of roundings the error can pass through,
times whatever the computation amplifies it by (the angle turned, the number of steps).
It is never bounded by zero: a comparison with ``==`` or ``atol=0`` only records what
one CPU happened to give (issue 14: ``test_batch_equals_single_runs`` failed by
1.36e-15 under another OpenBLAS kernel).

The helpers state the bound as ``n`` ulps of the magnitude, ``n`` named below with where
it comes from.  ``.ci/other_numerics.py`` reruns the numerical tests under another BLAS
kernel and without numpy's widest SIMD targets, so that a bound that holds on one CPU
only fails there first.

Exact equality stays right where no arithmetic happens on either side: a pure storage
round trip (netCDF, Parquet, CSV written with ``repr``) returns the same bits, and the
same code on the same inputs in the same process is deterministic.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EPS", "ulps", "assert_agree", "agree", "STORAGE", "FEW_OPS", "EXACT_SOLUTION",
           "SPLITTING_STEP", "TORQUE_EVAL", "INTEGRATOR_PATHS", "attitude_angle"]

#: Machine epsilon of float64 (the spacing of 1.0, 2 u).
EPS = float(np.finfo(float).eps)

#: A pure storage round trip: the same bits come back (no arithmetic on either side).
STORAGE = 0

#: A few elementary operations on each side (a 3x3 rotation applied to a vector, a dot
#: product, a norm): Higham (2002) eq. 3.4 bounds a dot product of three terms by
#: ``gamma_3 |x||y|`` (3 u = 1.5 ulp) per side; a rotation matrix built from a
#: quaternion and then applied is two such products; two paths, each side: 2 x 2 x 1.5
#: = 6, rounded up to 8.
FEW_OPS = 8

#: The exact torque-free solution (``free_rotation``), one path against another: each is
#: within 5.1e-15 (23 ulp of 1) in attitude and 3.5e-15 (16 ulp) relative in rate of the
#: 30-digit mpmath references (``docs/torquefree.md`` section 8, worst of the table);
#: two paths each within that differ by at most the sum, 46 ulp, plus the body-to-
#: principal rotation on both sides (:data:`FEW_OPS`): 54, rounded up to 64.
EXACT_SOLUTION = 64

#: One step of the splitting integrator: the exact free flow (:data:`EXACT_SOLUTION`)
#: composed with the torque kicks (a few products each, :data:`FEW_OPS`).  Over ``n``
#: steps of a non-chaotic run the differences add (at most linearly), so ``n`` steps get
#: ``n * SPLITTING_STEP`` ulp.
SPLITTING_STEP = EXACT_SOLUTION + FEW_OPS

#: One evaluation of a torque model, vectorised against per element: the primary's
#: position (a Kepler solve, 4 ulp), the attitude applied to it and to the field
#: (:data:`FEW_OPS` each) and a cross product of terms, ~32 ulp of the scale of the terms
#: per side, 64 for two.  The magnitude to use is the scale of the terms (the largest
#: torque over random attitudes), not one component: a cross product of nearly parallel
#: vectors is small while its rounding errors are not.
TORQUE_EVAL = 64

#: DOP853 along two paths (a batch and a single run, chunks): an ulp of difference in
#: the right-hand side (BLAS, SIMD) can flip one step's acceptance, after which the two
#: adaptive runs follow different step sequences and differ by up to the integrator's
#: tolerance, not by ulps.  Tests allow ``INTEGRATOR_PATHS * rtol`` relative: the global
#: error of an rtol-controlled run over a few hundred steps of a non-chaotic problem
#: stays below ~10 rtol (Hairer, Norsett & Wanner 1993, section II.4).
INTEGRATOR_PATHS = 10.0


def ulps(magnitude, n) -> np.ndarray:
    """``n`` units in the last place of ``magnitude`` (elementwise): ``n * spacing(|m|)``.

    >>> float(ulps(1.0, 4)) == 4 * EPS
    True
    """
    return n * np.spacing(np.abs(np.asarray(magnitude, dtype=float)))


_n_ulps = ulps   # the parameter ``ulps`` of the functions below shadows the name


def _magnitude(desired: np.ndarray, axis) -> np.ndarray:
    """The magnitude the rounding errors scale with: the largest |value| along ``axis``
    (the components of a vector, a quaternion) or of the whole array (``axis=None``)."""
    a = np.abs(desired)
    if axis is None:
        return np.full(desired.shape, np.nanmax(a) if a.size else 0.0)
    return np.broadcast_to(np.nanmax(a, axis=axis, keepdims=True), desired.shape)


def agree(actual, desired, *, ulps: float, axis=-1, magnitude=None) -> np.ndarray:
    """The elementwise test of :func:`assert_agree`, as a boolean array."""
    actual, desired = np.asarray(actual, dtype=float), np.asarray(desired, dtype=float)
    mag = _magnitude(desired, axis) if magnitude is None else np.asarray(magnitude)
    tol = _n_ulps(mag, ulps)
    same_nan = np.isnan(actual) & np.isnan(desired)
    return same_nan | (np.abs(actual - desired) <= tol)


def assert_agree(actual, desired, *, ulps: float, axis=-1, magnitude=None, what: str = ""):
    """Assert that two computations of the same values agree to ``ulps`` units in the
    last place of their magnitude.

    ``magnitude``: what the rounding errors scale with; by default the largest |value|
    along ``axis`` (-1: per vector or quaternion; ``None``: the whole array).  NaN must
    match NaN.

    >>> assert_agree([1.0, 2.0 + 4e-16], [1.0, 2.0], ulps=2)
    >>> assert_agree([1.0], [1.0 + 1e-14], ulps=8)
    Traceback (most recent call last):
    ...
    AssertionError: ...
    """
    actual, desired = np.asarray(actual, dtype=float), np.asarray(desired, dtype=float)
    assert actual.shape == desired.shape, f"{what}: shapes {actual.shape} != {desired.shape}"
    ok = agree(actual, desired, ulps=ulps, axis=axis, magnitude=magnitude)
    if not ok.all():
        mag = _magnitude(desired, axis) if magnitude is None else np.broadcast_to(
            np.asarray(magnitude, dtype=float), desired.shape)
        with np.errstate(invalid="ignore", divide="ignore"):
            in_ulps = np.abs(actual - desired) / np.spacing(np.abs(mag))
        worst = np.unravel_index(np.nanargmax(np.where(ok, -np.inf, in_ulps)), ok.shape)
        raise AssertionError(
            f"{what or 'values'}: {int((~ok).sum())} of {ok.size} differ by more than "
            f"{ulps} ulp of their magnitude; worst at {tuple(int(i) for i in worst)}: "
            f"{actual[worst]!r} vs {desired[worst]!r}, {in_ulps[worst]:.1f} ulp of "
            f"{float(mag[worst]):.3g}")


def attitude_angle(q1, q2) -> np.ndarray:
    """Angle (rad) of the rotation between two quaternion arrays ``(..., 4)``, sign-blind:
    compare it with ``ulps(1.0, n)`` (a quaternion has unit magnitude).

    >>> float(attitude_angle([0, 0, 0, 1.0], [0, 0, 0, -1.0]))
    0.0
    """
    q1, q2 = np.asarray(q1, dtype=float), np.asarray(q2, dtype=float)
    # the chord |q1 -+ q2| = 2 sin(angle / 4) keeps angles of a few ulps (arccos of a dot
    # product near 1 would lose half the digits)
    s = np.where(np.sum(q1 * q2, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    chord = np.linalg.norm(q1 - s * q2, axis=-1)
    return 4.0 * np.arcsin(np.minimum(0.5 * chord, 1.0))
