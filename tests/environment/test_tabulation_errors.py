"""``TimeTable`` refuses bad input with the project's error naming the field (issue 26:
it raised a bare ValueError)."""

import numpy as np
import pytest

from attitude.environment.tabulation import TimeTable
from attitude.foundations.errors import AttitudeError, QuantityError


def _line(t):
    return np.stack([t, 2.0 * t], axis=-1)


@pytest.mark.parametrize("spacing, segment, key", [
    (0.0, 100.0, "spacing"),
    (-1.0, 100.0, "spacing"),
    (float("nan"), 100.0, "spacing"),
    (10.0, 30.0, "segment"),            # 3 spacings: fewer than 4
    (10.0, 105.0, "segment"),           # not a whole number of spacings
    (10.0, float("inf"), "segment"),
])
def test_bad_grids_name_the_field(spacing, segment, key):
    with pytest.raises(QuantityError) as err:
        TimeTable(_line, spacing=spacing, segment=segment)
    assert err.value.key == key and str(err.value).startswith(f"{key}: ")
    assert isinstance(err.value, AttitudeError) and isinstance(err.value, ValueError)


def test_bad_times_name_the_field():
    table = TimeTable(_line, spacing=10.0, segment=40.0)
    for bad in (float("nan"), np.array([0.0, np.inf])):
        with pytest.raises(QuantityError) as err:
            table(bad)
        assert err.value.key == "t" and "finite" in err.value.reason
    with pytest.raises(QuantityError) as err:
        table.piecewise(50.0, 5.0)
    assert err.value.key == "t_span"
    np.testing.assert_allclose(table(np.array([5.0, 45.0])), [[5.0, 10.0], [45.0, 90.0]],
                               rtol=1e-14)
