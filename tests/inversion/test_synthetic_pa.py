"""Synthetic principal-axis rotators (issue 27's first numbers): the cases of
``benchmarks/inversion.py --synthetic-pa`` (Gaussian-random-sphere shapes, the convex
hull; random poles; six apparitions seen from the Earth on (135) Hertha's orbit;
Lommel-Seeliger + 0.1 Lambert; 0.01 mag), inverted by ``att.invert`` from a period range
around the truth.

The bounds are the issue's: the pole within 3 deg of the truth or of its mirror, the
period within 1e-6 (relative).  The inertia ratios of the shape (the issue asks 3 %) are
not asserted: relative photometry from near the ecliptic leaves the extent along the spin
axis weakly determined, and the fit from the true pole itself misses them by ~10 %
(docs/inversion.md, the numbers).
"""

from __future__ import annotations

import numpy as np
import pytest

from . import inversion_benchmark


def test_the_synthetic_shape_is_convex_in_principal_axes():
    """The truth generator: a convex polyhedron of unit volume, moments ascending."""
    bench = inversion_benchmark()
    shape, moments = bench.gaussian_random_sphere(np.random.default_rng(3), rows=6)
    assert shape.is_convex()
    assert abs(shape.volume - 1.0) < 1e-12
    assert moments[0] <= moments[1] <= moments[2]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_synthetic_principal_axis_rotator_is_recovered(seed):
    r = inversion_benchmark().run_pa_case(seed)
    print(f"\nseed {seed}: pole {r['best_to_truth_deg']:.2f} / "
          f"{r['best_to_mirror_of_truth_deg']:.2f} deg, dP/P {r['period_rel_error']:.1e}, "
          f"ratios {r['fitted_ratios']} (truth {r['truth_ratios']}), CPU {r['cpu_s']:.0f} s")
    assert r["pole_ok"], r
    assert r["period_ok"], r
