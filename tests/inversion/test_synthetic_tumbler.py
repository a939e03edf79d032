"""A synthetic tumbler found from the data alone (issue 27): the issue's first paragraph,
a SAM of A/C 0.55, B/C 0.9, E/E0 1.027 (P_phi 10 h) seen 40 days at 30 min with 0.01 mag
of noise, its shape a lumpy convex body (``benchmarks/inversion.py``'s
``tumbler_case``), no start given: ``search_tumbler`` from the two periods of
``fit_periods`` to the refined state (the search itself: ``benchmarks/inversion.py
--issue-case``, minutes of CPU).
"""

from __future__ import annotations

import numpy as np

from attitude.inversion import ConvexModel, GaussianImage
from attitude.inversion import tumbler as tb
from attitude.model.freebody import diagnose_many
from attitude.model.sampling import tumbling_state
from attitude.photometry.periods import fit_periods

from . import inversion_benchmark


def test_the_synthetic_tumbler_has_the_asked_state():
    """The generator: the state has the issue's energy and the shape's moment ratios
    near the asked ones (lumps move them by a few per cent)."""
    case = inversion_benchmark().tumbler_case("issue SAM", 0, days=2.0)
    truth = case["truth"]
    assert truth[2] == 1.027 and case["regime"] == "SAM"
    assert abs(truth[3] - 0.55) < 0.1 and abs(truth[4] - 0.9) < 0.05
    assert truth[2] < 1.0 / truth[4]                      # below the separatrix: a SAM


def test_the_period_pairs_of_the_data_hold_the_issue_state():
    """From the data alone: the two fundamentals of fit_periods on the issue's 40 days
    are P_psi and 1/(1/P_phi - 1/P_psi) (not P_phi itself), and period_pairs, reading one
    of them as P_psi, offers the true (P_phi, P_psi) within the frequency resolution of
    the span (a period P is resolved to about P / T)."""
    bench = inversion_benchmark()
    case = bench.tumbler_case("issue SAM", 0)
    model = ConvexModel(case["observations"], GaussianImage(3, 2))
    magnitudes = -2.5 * np.log10(model.data)
    sigma = 2.5 / np.log(10.0) * model.sigma / model.data
    found = fit_periods(model.time, magnitudes, sigma, n_periods=2,
                        sessions=model.block).periods
    moments, _, w, _ = tumbling_state(*case["truth"])
    d = diagnose_many(moments, w)
    p_phi, p_psi = float(d["precession"][0]), float(d["rotation"][0])
    span = float(np.ptp(model.time))
    assert any(abs(a / p_phi - 1) < p_phi / span and abs(b / p_psi - 1) < p_psi / span
               for a, b in tb.period_pairs(found))
