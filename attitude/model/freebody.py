r"""The algebra of the free rigid body, shared by every kernel that uses it.

The closed-form solution (:mod:`attitude.propagation.torquefree`), both paths of the
splitting integrator's exact free flow (vectorised and one-body,
:mod:`attitude.propagation.splitting`), the analytic diagnosis (``diagnose``) and the
osculating quantities of an ephemeris (:mod:`attitude.analysis.diagnostics`) all use the
definitions of this module, so that each exists once:

- the **kernel frame**: the principal axes ``(A, B, C)`` on the short-axis side of the
  separatrix (SAM, ``L^2 >= 2EB``), the relabelled right-handed frame
  ``(e3, -e2, e1)`` with moments ``(C, B, A)`` on the long-axis side (LAM), so that one
  set of formulas covers both (:func:`kernel_moments`, :func:`kernel_vector`,
  :func:`kernel_attitude`);
- the **invariants** in that frame (:func:`invariants`, :func:`jacobi_parameters`,
  :func:`characteristic`)::

      d21 = I2 - I1, d32 = I3 - I2, d31 = I3 - I1                  (signed)
      Q1 = 2E I3 - L^2 = I1 d31 w1^2 + I2 d32 w2^2
      Q3 = L^2 - 2E I1 = I2 d21 w2^2 + I3 d31 w3^2
      D  = L^2 - 2E I2 = I3 d32 w3^2 - I1 d21 w1^2
      m = k^2 = d21 Q1 / (d32 Q3),  m1 = 1 - k^2 = d31 D / (d32 Q3)
      lambda^2 = d32 Q3 / (I1 I2 I3),  nu = I3 d21 / (I1 d32)

  formed from the rate components, so that the only cancellation is in ``D`` (the
  distance to the separatrix) and none in ``Q1``, ``Q3``, ``m`` or ``m1`` (Landau &
  Lifshitz §37; ``docs/torquefree.md``, TF 3-10);
- the **attitude helpers**: ``cos, sin`` of half the angle between L and the third
  kernel axis without cancellation (:func:`half_theta`), and the quaternion of the 3-1-3
  rotation ``Rz(phi) Rx(theta) Rz(psi)`` from them (:func:`euler313_quaternion`);
- the **tolerances**, one name and one value for each idea (below);
- the per-body constants of the closed form: the branch of each body
  (:func:`branches`) and the elliptic constants of a triaxial body
  (:func:`elliptic_constants`: ``K``, the Landen chain, the precession rates), which
  the closed form evaluates over time (:mod:`attitude.propagation.torquefree`);
- the **analytic diagnosis** from them, without propagating: :func:`diagnose`
  (``att.diagnose``), :func:`diagnose_principal`, :func:`diagnose_many` and
  :func:`branch_of`.

The names live in three modules, one idea each, and are all re-exported here:
:mod:`.freebody_algebra` (the kernel frame, the invariants, the attitude helpers and the
tolerances), :mod:`.freebody_constants` (the inputs, scales, branches and elliptic
constants of the closed form) and :mod:`.freebody_diagnosis` (the analytic diagnosis).

Every helper takes components (plain floats or arrays of one shape) and returns
components: the vectorised kernels pass arrays, the one-body splitting path plain
floats (its scalar fast path).  The invariants are pure arithmetic and run in whatever
precision they are given (the closed form passes ``longdouble``).

Examples
--------
>>> d21, d32, d31, Q1, Q3, D, L2 = invariants(1.0, 2.0, 3.0, 0.3, 0.0, 1.0)
>>> m, m1, lam2 = jacobi_parameters(1.0, 2.0, 3.0, d21, d32, d31, Q1, Q3, D)
>>> round(m + m1, 15), round(lam2, 6)
(1.0, 1.0)
"""

from __future__ import annotations

from .freebody_algebra import (
    EQUAL_MOMENTS_RTOL,
    LAM_FRAME,
    NEAR_SEPARATRIX_WARN,
    PURE_SPIN_TOL,
    PURE_SPIN_TOL_UNSCALED,
    SEPARATRIX_M1_TOL,
    characteristic,
    euler313_quaternion,
    half_angles,
    half_theta,
    half_theta_scalar,
    invariants,
    jacobi_parameters,
    kernel_attitude,
    kernel_moments,
    kernel_vector,
    separatrix_gap,
)
from .freebody_constants import (  # noqa: F401  (the BRANCH_* codes: torquefree uses them)
    BRANCH_LAM,
    BRANCH_PRECESSION,
    BRANCH_SAM,
    BRANCH_SEPARATRIX,
    BRANCHES,
    branches,
    check_inputs,
    discriminant,
    elliptic_constants,
    kernel_invariants,
    unit_scales,
)
from .freebody_diagnosis import (
    Diagnosis,
    branch_of,
    diagnose,
    diagnose_many,
    diagnose_principal,
)

__all__ = [
    "EQUAL_MOMENTS_RTOL",
    "PURE_SPIN_TOL",
    "PURE_SPIN_TOL_UNSCALED",
    "SEPARATRIX_M1_TOL",
    "NEAR_SEPARATRIX_WARN",
    "LAM_FRAME",
    "kernel_moments",
    "kernel_vector",
    "kernel_attitude",
    "invariants",
    "separatrix_gap",
    "jacobi_parameters",
    "characteristic",
    "half_theta",
    "half_theta_scalar",
    "half_angles",
    "euler313_quaternion",
    "check_inputs",
    "unit_scales",
    "discriminant",
    "kernel_invariants",
    "BRANCHES",
    "branches",
    "elliptic_constants",
    "Diagnosis",
    "diagnose",
    "diagnose_principal",
    "diagnose_many",
    "branch_of",
]
