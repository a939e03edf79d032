"""Error of the exact torque-free solution versus distance to the separatrix and time.

Prints a Markdown table (used in docs/torquefree.md): for states at a given signed
complementary parameter ``m1 = 1 - k^2`` (SAM side > 0, LAM side < 0), the largest
attitude error (rad) and relative rate error of
:func:`attitude.propagation.torquefree.free_rotation` over 1, 10 and 50 polhode periods,
against the mpmath closed-form oracle of
``tests/oracle.py`` (60 digits).  For contrast, the last column is the rate error of
a *textbook double-precision* implementation (``k^2`` formed from ``L^2`` and ``2E``,
``scipy.special.ellipj`` / ``ellipkinc``), the approach of most existing tools.
The last row is the separatrix itself (``L^2 = 2EB`` exactly), against the Taylor
oracle over 10 spin periods.

Run from the repository root::

    python benchmarks/separatrix_accuracy.py
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import mpmath as mp
import numpy as np
from scipy import special as sp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from attitude.propagation.torquefree import free_rotation  # noqa: E402
from tests import oracle as O  # noqa: E402

Q0 = np.array([0.3, -0.5, 0.1, 0.8]) / np.linalg.norm([0.3, -0.5, 0.1, 0.8])
BODY = [0.2, 0.6, 1.0]


def state_at(moments, m1, side, ratio=0.5):
    """Rates at complementary parameter m1 on the SAM (+1) / LAM (-1) side."""
    with mp.workdps(60):
        A, B, C = (mp.mpf(x) for x in moments)
        m1 = mp.mpf(m1)
        if side > 0:
            w3, w2 = mp.mpf(1), ratio
            Q3 = B * (B - A) * w2 ** 2 + C * (C - A) * w3 ** 2
            w1sq = (C * (C - B) * w3 ** 2 - m1 * (C - B) * Q3 / (C - A)) / (A * (B - A))
            if w1sq <= 0:  # not reachable with this w2/w3: smaller w2
                return state_at(moments, m1, side, ratio * 0.1)
            return [float(mp.sqrt(w1sq)), float(w2), float(w3)]
        w1, w2 = mp.mpf(1), ratio
        Q1 = A * (C - A) * w1 ** 2 + B * (C - B) * w2 ** 2
        w3sq = (A * (B - A) * w1 ** 2 - m1 * (B - A) * Q1 / (C - A)) / (C * (C - B))
        if w3sq <= 0:
            return state_at(moments, m1, side, ratio * 0.1)
        return [float(w1), float(w2), float(mp.sqrt(w3sq))]


def naive_rates(moments, w, t):
    """Textbook double-precision rates (Landau & Lifshitz §37), k^2 from L^2 and 2E."""
    A, B, C = moments
    w1, w2, w3 = w
    L2 = (A * w1) ** 2 + (B * w2) ** 2 + (C * w3) ** 2
    E2 = A * w1 ** 2 + B * w2 ** 2 + C * w3 ** 2
    if L2 > E2 * B:  # SAM: (cn, sn, dn)
        lam = math.sqrt((C - B) * (L2 - E2 * A) / (A * B * C))
        m = (B - A) * (E2 * C - L2) / ((C - B) * (L2 - E2 * A))
        a = [math.sqrt((E2 * C - L2) / (A * (C - A))), math.sqrt((E2 * C - L2) / (B * (C - B))),
             math.sqrt((L2 - E2 * A) / (C * (C - A)))]
        s = math.copysign(1.0, w3)
        phi0 = math.atan2(s * w2 / a[1], w1 / a[0])
        u0 = sp.ellipkinc(phi0, m)
        sn, cn, dn, _ = sp.ellipj(lam * t + u0, m)
        return np.stack([a[0] * cn, s * a[1] * sn, s * a[2] * dn], axis=-1)
    lam = math.sqrt((B - A) * (E2 * C - L2) / (A * B * C))  # LAM: (dn, sn, cn)
    m = (C - B) * (L2 - E2 * A) / ((B - A) * (E2 * C - L2))
    a = [math.sqrt((E2 * C - L2) / (A * (C - A))), math.sqrt((L2 - E2 * A) / (B * (B - A))),
         math.sqrt((L2 - E2 * A) / (C * (C - A)))]
    s = math.copysign(1.0, w1)
    phi0 = math.atan2(s * w2 / a[1], w3 / a[2])
    u0 = sp.ellipkinc(phi0, m)
    sn, cn, dn, _ = sp.ellipj(lam * t + u0, m)
    return np.stack([s * a[0] * dn, s * a[1] * sn, a[2] * cn], axis=-1)


def errors(moments, w, periods, dps):
    with mp.workdps(dps):
        P = O.polhode_period(moments, w, dps=dps)
    out = []
    rng = np.random.default_rng(0)
    for n in periods:
        t = np.concatenate([[0.0], np.sort(rng.uniform(0, n * P, 6)), [n * P]])
        qc, wc = O.closed_form_solution(moments, w, Q0, t, dps=dps)
        qf, wf = free_rotation(moments, Q0, w, t)
        out.append((O.attitude_error(qf, qc).max(), O.rate_error(wf, wc)))
    with np.errstate(invalid="ignore"):
        naive = O.rate_error(naive_rates(moments, w, t), wc)
    return out, naive


def main():
    t0 = time.perf_counter()
    periods = (1, 10, 50)
    print(f"Body A:B:C = {BODY[0]}:{BODY[1]}:{BODY[2]}; errors = max over epochs in the span "
          "(attitude rad / rate relative)")
    print()
    head = " | ".join(f"{n} period{'s' if n > 1 else ''}" for n in periods)
    print(f"| m1 = 1 - k^2 | {head} | textbook double, 50 periods (rate) |")
    print("|---:|" + "---|" * len(periods) + "---|")
    for d in (1e-1, 1e-3, 1e-6, 1e-9, 1e-12, 1e-15):
        for side in (1, -1):
            w = state_at(BODY, d, side)
            m1 = O.separatrix_m1(BODY, w)
            errs, naive = errors(BODY, w, periods, 60 if d < 1e-6 else 40)
            cells = " | ".join(f"{a:.1e} / {r:.1e}" for a, r in errs)
            print(f"| {m1:+.1e} | {cells} | {naive:.1e} |")
    # exactly on the separatrix: A=1, B=2.5, C=4, w1 = 2 w3 makes L^2 = 2EB in floats
    I, w = [1.0, 2.5, 4.0], [2.0, 0.5, 1.0]
    T = 10 * 2 * math.pi / np.linalg.norm(w)
    t = np.linspace(0.0, T, 9)
    qt, wt, _ = O.taylor_solution(I, w, Q0, t, dps=32, order=40)
    qf, wf = free_rotation(I, Q0, w, t)
    print(f"| 0 (exact; A:B:C = 1:2.5:4, 10 spin periods, Taylor oracle) | "
          f"{O.attitude_error(qf, qt).max():.1e} / {O.rate_error(wf, wt):.1e} | | | n/a |")
    print()
    shape_sweep()
    print()
    print(f"({time.perf_counter() - t0:.0f} s)")


def shape_sweep():
    """Worst errors over 50 polhode periods for bodies from needle-like to nearly
    spherical, B at 5 %, 50 %, 95 % of the way from A to C, m1 in {1e-3, 0.3, 0.99}
    on both sides (the grid of tests/propagation/test_torquefree.py)."""
    print("| A/C | worst attitude error (rad) | worst rate error (rel.) | "
          "longest span (rad of rotation) |")
    print("|---:|---:|---:|---:|")
    rng = np.random.default_rng(0)
    for AC in (0.01, 0.1, 0.5, 0.9, 0.999):
        wa = wr = span = 0.0
        for bf in (0.05, 0.5, 0.95):
            I = [AC, AC + bf * (1 - AC), 1.0]
            for side in (1, -1):
                for m1 in (1e-3, 0.3, 0.99):
                    w = state_at(I, m1, side)
                    P = O.polhode_period(I, w)
                    t = np.concatenate([[0.0], np.sort(rng.uniform(0, 50 * P, 6)), [50 * P]])
                    qc, wc = O.closed_form_solution(I, w, Q0, t)
                    qf, wf = free_rotation(I, Q0, w, t)
                    wa = max(wa, O.attitude_error(qf, qc).max())
                    wr = max(wr, O.rate_error(wf, wc))
                    span = max(span, 50 * P * np.linalg.norm(w))
        print(f"| {AC} | {wa:.1e} | {wr:.1e} | {span:.1e} |")


if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__,   # --help: what it measures, then exit
                            formatter_class=argparse.RawDescriptionHelpFormatter
                            ).parse_args()
    main()
