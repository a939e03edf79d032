"""Observed lightcurves in: ALCDEF (the documented format, v2.2.7) and CSV, with the
light-time and session handling and an error naming the line for each malformation."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from attitude.foundations.errors import LightcurveFormatError
from attitude.photometry import fit_periods, read_lightcurve
from attitude.photometry.readers import read_alcdef

DATA = Path(__file__).resolve().parents[1] / "data" / "photometry"


def test_alcdef_two_sessions_light_time_and_delimiters():
    lc = read_alcdef(DATA / "two_sessions.alcdef")
    ds = lc.dataset
    assert ds.sizes["time"] == 5
    assert ds.session.values.tolist() == [0, 0, 0, 1, 1]
    # session 0: LTCAPP=NONE with LTCDAYS -> moved to the asteroid; session 1: applied
    jd0 = 2456318.5 - 0.000578
    assert lc.epoch.utc.jd == pytest.approx(jd0, abs=1e-9)
    assert lc.epoch.scale == "utc"            # observers' times: the reader says UTC
    expected = (np.array([2456318.5, 2456318.51, 2456318.52, 2456319.5 + 0.000578,
                          2456319.51 + 0.000578]) - 2456318.5) * 86400.0
    np.testing.assert_allclose(lc.time, expected, atol=1e-4)     # 0.1 ms: JD rounding
    np.testing.assert_allclose(ds.magnitude.values, [0.151, 0.182, 0.205, 1.101, 1.122])
    np.testing.assert_allclose(ds.magnitude_error.values, [0.01, 0.01, 0.012, 0.02, 0.02])
    assert ds.attrs["object"] == "99942 Apophis"
    assert "SESSIONDATE=2013-01-26" in ds.attrs["sessions"]
    reduced = read_alcdef(DATA / "two_sessions.alcdef", reduce=True, light_time=False)
    np.testing.assert_allclose(reduced.dataset.magnitude.values[:3],
                               np.array([0.151, 0.182, 0.205]) - 1.234)
    assert reduced.time[0] == 0.0 and reduced.epoch.utc.jd == pytest.approx(2456318.5)


def test_read_lightcurve_dispatches_and_round_trips(tmp_path):
    lc = read_lightcurve(DATA / "two_sessions.alcdef")
    back = read_lightcurve(lc.to_netcdf(tmp_path / "obs.nc"))
    np.testing.assert_array_equal(back.dataset.session.values, lc.dataset.session.values)
    csv = read_lightcurve(DATA / "lightcurve.csv")
    np.testing.assert_allclose(csv.time, [0.0, 600.0, 86400.0], rtol=0, atol=1e-9)
    assert csv.dataset.session.values.tolist() == [0, 0, 1]
    assert csv.epoch.isot == "2029-04-13T00:00:00.000"
    assert csv.epoch.scale == back.epoch.scale == "utc"      # read as UTC, kept in the file


@pytest.mark.parametrize("text, line, match", [
    ("DATA=2456318.5|15.0|0.01\n", 1, "outside a session"),
    ("STARTMETADATA\nOBJECTNAME\nENDMETADATA\n", 2, "KEY=VALUE"),
    ("STARTMETADATA\nDELIMITER=COMMA\nENDMETADATA\n", 3, "PIPE or TAB"),
    ("STARTMETADATA\nENDMETADATA\nDATA=2456318.5|abc|0.01\nENDDATA\n", 3, "not a number"),
    ("STARTMETADATA\nENDMETADATA\nDATA=2456318.5\nENDDATA\n", 3, "expected DATA=JD"),
    ("STARTMETADATA\nENDMETADATA\nDATA=2456318.5|15.0|0.01\n", 3, "not closed"),
    ("STARTMETADATA\nENDMETADATA\nENDDATA\n", 3, "no DATA lines"),
    ("STARTMETADATA\nSTARTMETADATA\n", 2, "inside the block"),
    ("STARTMETADATA\nLTCDAYS=soon\nENDMETADATA\nDATA=2456318.5|2|0.1\nENDDATA\n", 5,
     "LTCDAYS"),
    ("STARTMETADATA\nENDMETADATA\nDATA=1e-320|15.0|0.01\nENDDATA\n", 3,
     "jd 1e-320 is not a date between 1582 and 3000"),          # a damaged JD
])
def test_alcdef_errors_name_the_line(tmp_path, text, line, match):
    path = tmp_path / "bad.alcdef"
    path.write_text(text)
    with pytest.raises(LightcurveFormatError, match=match) as info:
        read_alcdef(path)
    assert info.value.key == f"line {line}" and str(path) in str(info.value)


@pytest.mark.parametrize("text, match", [
    ("when,mag\n1,2\n", "no time column"),
    ("jd,mag\n2460000.5,abc\n", "line 2: not a number"),
    ("jd,mag\n2460000.5,1.0,3\n", "line 2: expected 2 fields"),
    ("jd,mag\n", "no data rows"),
    # damaged times: astropy would take them for year -4712 (and warn) or refuse them
    ("jd,mag\n2460000.5,1.0\n1e-320,1.1\n", "line 3: jd 1e-320 is not a date between"),
    ("mjd,mag\n-1e6,1.0\n", "line 2: mjd -1000000.0 is not a date"),
    ("jd,mag\n1e999,1.0\n", "line 2: non-finite value"),
    ("jd,mag\nnan,1.0\n", "line 2: non-finite value"),
    ("jd,mag\n2460000.5,nan\n", "line 2: non-finite value"),
    ("time,mag\n0001-01-01T00:00:00,1.0\n", "line 2: time '0001-01-01T00:00:00' is not a"),
])
def test_csv_errors(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")            # and no warning of astropy/ERFA first
        with pytest.raises(LightcurveFormatError, match=match):
            read_lightcurve(path)


def test_unknown_format(tmp_path):
    path = tmp_path / "lc.txt"
    path.write_text("hello\n")
    with pytest.raises(LightcurveFormatError, match="cannot tell the format"):
        read_lightcurve(path)
    with pytest.raises(LightcurveFormatError, match="no such file"):
        read_lightcurve(tmp_path / "missing.nc")


def test_period_fit_runs_on_observed_sessions(tmp_path):
    """An ALCDEF file written from a known 6 h double-peaked curve over three sessions
    with different zero points: the period fit with session offsets recovers it."""
    f = 1 / (6 * 3600.0)
    lines = []
    for start, zero in [(0.0, 0.0), (1.0, 2.5), (2.0, -1.0)]:
        lines += ["STARTMETADATA", "OBJECTNAME=Test", "DIFFERMAGS=TRUE", "LTCAPP=AUTO",
                  "DELIMITER=PIPE", "ENDMETADATA"]
        jd = 2460000.5 + start + np.arange(0, 0.3, 0.004)
        t = (jd - 2460000.5) * 86400.0
        mag = zero + 0.3 * np.cos(4 * np.pi * f * t) + 0.05 * np.cos(2 * np.pi * f * t)
        lines += [f"DATA={j:.6f}|{m:.5f}|0.005" for j, m in zip(jd, mag)] + ["ENDDATA"]
    path = tmp_path / "three.alcdef"
    path.write_text("\n".join(lines) + "\n")
    lc = read_lightcurve(path)
    ds = lc.dataset
    fit = fit_periods(lc.time, ds.magnitude.values, ds.magnitude_error.values, n_periods=1,
                      order=2, sessions=ds.session.values, max_period=86400.0)
    assert fit.periods[0] == pytest.approx(6 * 3600.0, rel=1e-4)
