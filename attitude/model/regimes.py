"""Names of rotation regimes and periods, and the thresholds that separate the regimes:
the shared vocabulary of ``diagnose``, ``classify``, the Lyapunov test, scenario
expectations and reports (docs/diagnostics.md)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..foundations.errors import ClassificationError
from .body import SYMMETRY_RTOL

__all__ = ["REGIMES", "PERIOD_KEYS", "Thresholds"]

#: Regime (class) names.  ``PA-short``: principal-axis spin about C (short axis);
#: ``PA-long``: about A (long axis); ``SAM``/``LAM``: short-/long-axis mode
#: (L^2 > 2EB / L^2 < 2EB); ``separatrix``: L^2 = 2EB within tolerance (including spin
#: about the intermediate axis); ``axisymmetric``: regular precession (A = B or B = C);
#: ``spherical``: A = B = C; ``at-rest``: omega = 0; ``chaotic``: perturbed runs with a
#: significantly positive finite-time Lyapunov exponent.
REGIMES = ("PA-short", "PA-long", "SAM", "LAM", "separatrix", "axisymmetric", "spherical",
           "at-rest", "chaotic")

#: Period keys, seconds.  ``polhode``: period of omega in the body frame; ``precession``:
#: mean period P_phi of the long/short axis about L; ``rotation``: P_psi; ``spin``:
#: ``2 pi / |omega|`` for principal-axis spin.
PERIOD_KEYS = ("polhode", "precession", "rotation", "spin")


@dataclass(frozen=True)
class Thresholds:
    """Named thresholds of the classification (all documented in docs/diagnostics.md).

    Attributes
    ----------
    rest_rate : float
        ``at-rest`` when ``|omega| <=`` this in every sample of a window, rad/s.
    symmetry_rtol : float
        Moments equal within ``symmetry_rtol * C``: ``axisymmetric`` / ``spherical``
        bodies (default :data:`attitude.model.body.SYMMETRY_RTOL`, as ``att.diagnose``).
    principal_axis_angle : float
        Principal-axis spin (``PA-short``/``PA-long``) when the largest angle between
        ``L`` and the axis over the osculating nutation cycle is at most this, rad.
    separatrix : float
        ``separatrix`` when the separatrix distance ``|m1| = |1 - k^2|`` is at most this
        (dimensionless; ``m1`` is 0 on the separatrix and +-1 for principal-axis spin), or
        when ``m1`` changes sign within the window (a crossing).
    softness : float
        Width of each boundary for the confidence, as a fraction of its threshold: the
        margin enters the confidence as ``Phi(margin / width)`` (normal CDF), so a state
        at the boundary gets 0.5, one a threshold's width inside gets ``Phi(1/softness)``.
    noise_angle : float
        Attitude-noise scale, rad: the confidence is multiplied by
        ``exp(-noise / noise_angle)`` with ``noise`` from
        :func:`attitude.analysis.diagnostics.attitude_noise`.
    window_cycles : float
        Default window length in osculating polhode periods (median over the run).
    window_overlap : float
        Fraction of a window shared with the next one (step = length * (1 - overlap)).
    min_window_samples : int
        Fewest samples in a window (the window is lengthened to hold them).
    lyapunov_efolds : float
        ``chaotic`` needs the displaced trajectory to separate by at least this many
        e-folds more than in the regular control run of the same duration,
        ``(lambda - lambda_control) * duration >= lyapunov_efolds`` (5: a separation
        150 times that of the control) ...
    lyapunov_ratio : float
        ... and ``lambda`` above this multiple of the control's exponent.

    Examples
    --------
    >>> from attitude.model.regimes import Thresholds
    >>> t = Thresholds()
    >>> Thresholds(separatrix=2 * t.separatrix).separatrix == 2 * t.separatrix
    True
    """

    rest_rate: float = 1e-12
    symmetry_rtol: float = SYMMETRY_RTOL
    principal_axis_angle: float = 1e-2
    separatrix: float = 1e-4
    softness: float = 0.25
    noise_angle: float = 1e-2
    window_cycles: float = 4.0
    window_overlap: float = 0.5
    min_window_samples: int = 16
    lyapunov_efolds: float = 5.0
    lyapunov_ratio: float = 2.0

    def __post_init__(self):
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ClassificationError(f"thresholds.{f.name} must be a finite number "
                                          f">= 0, got {v!r}")
        if not 0 <= self.window_overlap < 1:
            raise ClassificationError("thresholds.window_overlap must be in [0, 1), got "
                                      f"{self.window_overlap!r}")
        if self.softness <= 0:
            raise ClassificationError("thresholds.softness must be > 0")


# ===========================================================================
# results
