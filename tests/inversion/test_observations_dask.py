"""The period scan on a dask cluster, one task per chunk of trial periods, equals the
scan in one process."""

from __future__ import annotations

import numpy as np
import pytest

from attitude.inversion.invert import _example_observations, period_scan

distributed = pytest.importorskip("distributed")


@pytest.mark.slow          # a two-worker LocalCluster: 5 to 20 s to start on a busy machine
def test_the_period_scan_on_dask_equals_the_sequential_scan():
    from attitude.propagation.cluster import local_cluster

    obs = _example_observations()
    periods = np.linspace(7150.0, 7250.0, 5)
    options = {"poles": 2, "rows": 3, "degree": 2, "max_iterations": 5}
    alone = period_scan(obs, periods, **options)
    with local_cluster(2) as client:
        spread = period_scan(obs, periods, client=client, chunks=3, **options)
    np.testing.assert_array_equal(spread.periods, alone.periods)
    # the same fits, each in one single-threaded process: the same floating-point
    # operations in the same order, so the same numbers
    np.testing.assert_array_equal(spread.chi2, alone.chi2)
    np.testing.assert_array_equal(spread.fitted_periods, alone.fitted_periods)
    assert spread.best == alone.best
