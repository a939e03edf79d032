"""The one quantity reader: to_si and to_time (issue 13 item 5).

Cycles vs radians is decided once (docs/scenarios.md, "Quantities"): Hz counts cycles,
so 1 Hz = 2 pi rad/s like 60 rpm; a bare 1/s where an angular rate is expected is rad/s.
The reference values are independent of astropy's conversion: 2 pi from math, degrees
from their definition, densities and lengths by hand.
"""

import math

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.app.scenario import load_scenario
from attitude.foundations.errors import QuantityError, ScenarioError, TorqueConfigError
from attitude.foundations.quantities import read_unit, to_si, to_time
from attitude.model.torques import from_config
from tests.app.test_scenario import GOOD, write

TWO_PI = 2 * math.pi


@pytest.mark.parametrize("value, unit, expected", [
    ("1 Hz", "rad/s", TWO_PI),
    ("2.5 kHz", "rad/s", 2500 * TWO_PI),
    ("1 mHz", "deg/s", 1e-3 * 360.0),
    ("60 rpm", "rad/s", TWO_PI),
    ("1 rev/day", "rad/s", TWO_PI / 86400),
    ("1 cycle/s", "rad/s", TWO_PI),
    ("2 1/s", "rad/s", 2.0),
    ("2 s-1", "rad/s", 2.0),
    (2.0, "rad/s", 2.0),
    ("1 Hz/s", "rad/s2", TWO_PI),
    ("1 Hz", "1/s", 1.0),                 # no angle wanted: Hz is just 1/s
    ("3 deg", "rad", 3 * math.pi / 180),
    ("30 min", "s", 1800.0),
    ("2.6 g/cm3", "kg/m3", 2600.0),
    ("2.3e7 kg km2", "kg m2", 2.3e13),
    ({"value": 27.38, "unit": "h"}, "s", 27.38 * 3600),
    (3 * u.km, "m", 3000.0),
])
def test_to_si_values(value, unit, expected):
    assert to_si(value, unit) == pytest.approx(expected, rel=4 * np.finfo(float).eps)


def test_hz_is_cycles_and_one_over_second_is_radians_everywhere(tmp_path):
    """'2 1/s' and '1 Hz' mean the same under [state] and under [[torques]]."""
    for text, expected in (("2 1/s", 2.0), ("0.5 Hz", math.pi)):
        sc = load_scenario(write(tmp_path, GOOD.replace(
            'omega_body = { value = [5.0, 0.0, 20.0], unit = "deg/s" }',
            f'omega_body = {{ value = [0.0, 0.0, {text.split()[0]}], '
            f'unit = "{text.split()[1]}" }}')))
        assert sc.state.omega_body[2] == pytest.approx(expected, rel=1e-15)
        torque = from_config({"type": "eddy_current", "magnetic_tensor": 1.0,
                              "orbit": {"a": 7e6},
                              "field": {"model": "dipole", "rotation_rate": text}})
        assert torque.field.rotation_rate == pytest.approx(expected, rel=1e-15)
        state = att.AttitudeState(Time("2030-01-01", scale="tdb"), Rotation.identity(),
                                  u.Quantity([0.0, 0.0, float(text.split()[0])],
                                                         text.split()[1]))
        assert state.omega_body[2] == pytest.approx(expected, rel=1e-15)


def test_arrays_and_tables():
    np.testing.assert_array_equal(to_si({"value": [1, 2, 3], "unit": "km"}, "m", shape=(3,)),
                                  [1000.0, 2000.0, 3000.0])
    out = to_si([[1, 0, 0], [0, 2, 0], [0, 0, 3]], "kg m2", shape=((), (3, 3)))
    assert out.shape == (3, 3)
    assert isinstance(to_si("1 s", "s"), float)


@pytest.mark.parametrize("value, kwargs, match", [
    ([1, 2, 3], {"shape": ()}, r"k: expected a single number .* got 3 numbers"),
    ([], {"shape": ()}, r"k: expected a single number .* got an empty list"),
    ([], {}, r"k: expected at least one number"),
    ([1.0], {"shape": (3,)}, r"k: expected 3 numbers .* got 1 number "),
    ("2 kg", {}, r"k: unit 'kg' cannot be converted to 's' \(not a time unit\)"),
    ("1 Hz", {}, r"k: unit 'Hz' cannot be converted to 's'"),
    ("soon", {}, r"k: cannot parse 'soon' as a quantity"),
    (math.nan, {}, r"k: every value must be finite"),
    ([1.0, math.inf], {}, r"k: every value must be finite"),
    (-1.0, {"positive": True}, r"k: must be positive, got -1 s"),
    (0.0, {"positive": True}, r"k: must be positive"),
    (-1.0, {"nonnegative": True}, r"k: must be non-negative"),
    (5.0, {"bounds": (0, 3)}, r"k: must be within \[0, 3\] s"),
    (True, {}, r"k: expected a quantity"),
    (None, {}, r"k: expected a quantity"),
    ({"value": 1}, {}, r"k: a quantity table needs both 'value' and 'unit'"),
    ({"value": 1, "unit": "s", "tol": 2}, {}, r"k\.tol: unknown key 'tol'"),
    ({"value": "x", "unit": "s"}, {}, r"k: expected a quantity"),
    ({"value": 1, "unit": "parsec per fortnight"}, {}, r"k: unknown unit"),
    ([[1, 2], [3]], {}, r"k: expected numbers"),
    ([1, True], {}, r"k: expected numbers"),
])
def test_to_si_errors_name_the_key(value, kwargs, match):
    with pytest.raises(QuantityError, match=match) as info:
        to_si(value, "s", key="k", **kwargs)
    assert info.value.key and info.value.key.startswith("k")
    assert isinstance(info.value, ValueError) and isinstance(info.value, att.AttitudeError)


def test_error_class_is_the_callers():
    with pytest.raises(TorqueConfigError, match="^mu: must be positive"):
        to_si(-1.0, "m3/s2", key="mu", positive=True, error=TorqueConfigError)


def test_read_unit():
    assert read_unit("deg/h", like="rad/s") == u.deg / u.h
    assert read_unit("Hz", like="rad/s") == u.Hz
    with pytest.raises(QuantityError, match="cannot be converted to 's'"):
        read_unit("kg", like="s")
    with pytest.raises(QuantityError, match="expected a unit string"):
        read_unit(3, key="unit")


@pytest.mark.parametrize("text, scale, iso", [
    ("2029-04-13T00:00:00", "tdb", "2029-04-13T00:00:00.000000000"),
    ("2024-02-29T12:00:00", "utc", "2024-02-29T12:00:00.000000000"),     # a leap day
    ("2016-12-31T23:59:60", "utc", "2016-12-31T23:59:60.000000000"),     # a leap second
    ("2030-01-01", "TT", "2030-01-01T00:00:00.000000000"),
])
def test_to_time(text, scale, iso):
    t = to_time(text, scale=scale)
    assert t.isot == iso and t.scale == scale.lower()
    assert to_time({"value": text, "scale": scale}).isot == iso
    assert to_time(t) is t


@pytest.mark.parametrize("value, scale, match", [
    ("2023-02-30T00:00:00", "tdb", "day 30 does not exist: February 2023 has 28 days"),
    ("2023-02-29", "tdb", "day 29 does not exist: February 2023 has 28 days"),
    ("2023-04-31T00:00:00", "utc", "April 2023 has 30 days"),
    ("2023-13-01T00:00:00", "tdb", "month 13 does not exist"),
    ("2023-01-01T24:30:00", "tdb", "hour 24 does not exist"),
    ("2023-01-01T12:60:00", "tdb", "minute 60 does not exist"),
    ("2023-01-01T23:59:60", "utc", "a second 60 only exists in a UTC leap second"),
    ("2016-12-31T23:59:60", "tdb", "a second 60 only exists in a UTC leap second"),
    ("soon", "tdb", "cannot parse 'soon' as a time"),
    (2030, "tdb", "expected an ISO 8601 date string"),
    ("2030-01-01", "gps-ish", "'gps-ish' is not a time scale"),
    (Time(["2030-01-01", "2030-01-02"]), "tdb", "expected one epoch"),
])
def test_to_time_errors_name_the_key(value, scale, match):
    with pytest.raises(QuantityError, match=match) as info:
        to_time(value, scale=scale, key="state.epoch")
    assert str(info.value).startswith("state.epoch")


def test_nonexistent_dates_in_a_scenario_name_file_and_key(tmp_path):
    path = write(tmp_path, GOOD.replace("2030-01-01T00:00:00", "2031-02-29T00:00:00"))
    with pytest.raises(ScenarioError, match="February 2031 has 28 days") as info:
        load_scenario(path)
    assert str(info.value).startswith(f"{path}: state.epoch: ")


def test_propagate_reads_times_and_step_with_to_si():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(Time("2030-01-01", scale="tdb"), Rotation.identity(),
                              [0.1, 0.0, 0.2])
    a = att.propagate(body, state, [0.0, 60.0, 120.0])
    b = att.propagate(body, state, {"value": [0.0, 1.0, 2.0], "unit": "min"})
    np.testing.assert_array_equal(a.dataset["time"].values, b.dataset["time"].values)
    with pytest.raises(att.InvalidStateError, match="times: unit 'kg' cannot be converted"):
        att.propagate(body, state, [0.0, 1.0] * u.kg)
    with pytest.raises(att.InvalidStateError, match="step: must be positive"):
        att.propagate(body, state, [0.0, 1.0], torques=[att.torques.ConstantTorque(
            [0, 0, 0])], step="-1 s")
