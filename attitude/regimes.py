"""Names of rotation regimes and periods (API.md): the shared vocabulary of
``diagnose``, ``classify``, scenario expectations and reports."""

from __future__ import annotations

__all__ = ["REGIMES", "PERIOD_KEYS"]

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
