"""CF compliance of the ephemeris netCDF file: the rules tested directly, then two real
checkers (the CF checker ``cfchecker`` and IOOS ``compliance-checker``) when installed.

The schema of API.md gives ``time`` the units ``"s"`` (seconds since the ``epoch`` global
attribute), a duration rather than a CF reference time (``s since ...``).  The variable is
therefore not declared a CF time axis (no ``axis = "T"``, no ``standard_name = "time"``);
see docs/formats.md.  Known checker reports, asserted below so that any new one fails:

* cfchecker 4.1.0 (the newest on PyPI) knows CF versions up to 1.8 only, so it reports
  ``(2.6.1) This netCDF file does not appear to contain CF Convention data`` for
  ``Conventions = "CF-1.10"``; a copy declared ``CF-1.8`` passes with no error or warning.
* compliance-checker (cf:1.10) reports one §5.1 error: a dimension *named* ``time`` should
  have ``standard_name = "time"``, which CF §4.4 only allows with a reference-time unit.
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import netCDF4
import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att


def _single():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0], mass=12.0, name="probe")
    state = att.AttitudeState(Time("2029-04-13T01:02:03.123456789", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]), [0.3, 0.1, 0.5],
                              frame="EME2000")
    return att.propagate(body, state, np.linspace(0.0, 100.0, 51))


def _batch():
    bodies = [att.RigidBody.from_principal_moments(m, name=n)
              for m, n in (([1, 2, 3], "a"), ([2, 2, 3], "bb"))]
    states = [att.AttitudeState("2030-01-01", Rotation.identity(), w)
              for w in ([0.1, 0.2, 0.3], [0.0, 0.1, 0.4])]
    return att.propagate(bodies, states, np.arange(5.0))


def _ensemble():
    """Sampled bodies, one of them invalid, written from dask chunks (status flags and
    sampled-parameter variables)."""
    with pytest.warns(att.ensemble.InvalidBodiesWarning):
        ens = att.Ensemble.from_arrays(principal_moments=[[1, 2, 3], [1, 1, 3], [2, 2, 3]],
                                       omega_body=[[0.1, 0.2, 0.3]] * 3, epoch="2030-01-01",
                                       names=["a", "bad", "bb"])
    return att.propagate(ens, np.arange(5.0), chunks=2)


@pytest.fixture(params=["single", "batch", "streamed", "ensemble"])
def ncfile(request, tmp_path):
    if request.param == "streamed":
        from attitude.formats.streaming import UniformTimes, propagate_to_netcdf

        eph = _single()
        return propagate_to_netcdf(eph.body, att.AttitudeState(
            eph.epoch, eph.rotation[0], eph.dataset.angular_velocity.values[0],
            frame=eph.frame), UniformTimes(0.0, 2.0, 51), tmp_path / "streamed.nc", block=20)
    eph = {"single": _single, "batch": _batch, "ensemble": _ensemble}[request.param]()
    return eph.to_netcdf(tmp_path / f"{request.param}.nc")


def test_cf_rules_directly(ncfile):
    with netCDF4.Dataset(ncfile) as nc:
        assert nc.Conventions == "CF-1.10"
        for name in ("title", "history", "source", "epoch", "time_scale", "frame"):
            assert getattr(nc, name), name
        for name, var in nc.variables.items():
            assert getattr(var, "long_name", "") or getattr(var, "standard_name", ""), name
            if "flag_values" in var.ncattrs():               # CF 3.5 flags: no units
                assert len(var.flag_values) == len(var.flag_meanings.split()), name
            elif var.dtype != str and var.dtype.kind != "S":
                assert hasattr(var, "units"), f"{name} has no units"
            if name in nc.dimensions and var.dtype.kind == "S":
                # a string-valued coordinate variable: a char array (CF 6.1)
                assert var.dimensions[0] == name and var.ndim == 2, name
            elif name in nc.dimensions:                     # a coordinate variable (CF 1.3)
                assert var.ndim == 1 and var.dtype.kind in "fiu", name
                values = var[:]
                assert np.all(np.diff(values) > 0), f"{name} is not strictly monotonic"
                assert "_FillValue" not in var.ncattrs(), name
            else:
                assert var.dtype != str, f"{name}: vlen strings; use char arrays"
        time = nc["time"]
        assert time.units == "s" and time.dtype == np.float64
        assert "axis" not in time.ncattrs() and "standard_name" not in time.ncattrs()
        assert time.reference_epoch == nc.epoch and time.time_scale == nc.time_scale
        assert nc.dimensions["time"].isunlimited()
        # string labels: string-valued coordinate variables stored as char arrays, so any
        # reader finds the x y z w labels of API.md
        labels = nc["quaternion_component"]
        assert labels.dtype.kind == "S" and labels.dimensions[0] == "quaternion_component"
        assert list(labels[:]) == ["x", "y", "z", "w"]     # decoded by netCDF4 (_Encoding)
        assert list(nc["axis"][:]) == ["x", "y", "z"]
        # large-file layout: chunked, shuffled, zlib-compressed float variables
        for name in ("time", "quaternion", "angular_velocity", "angular_momentum",
                     "kinetic_energy"):
            filters = nc[name].filters()
            assert filters["zlib"] and filters["shuffle"], name
            assert nc[name].chunking() != "contiguous", name


def test_file_reads_back_with_the_in_memory_schema(ncfile):
    eph = att.Ephemeris.from_netcdf(ncfile)
    ds = eph.dataset
    assert list(ds.quaternion_component.values) == ["x", "y", "z", "w"]
    assert list(ds.axis.values) == ["x", "y", "z"]
    assert "quaternion_component_label" not in ds.variables
    assert ds.time.attrs["units"] == "s"
    if eph.is_batch and "status" in ds:
        assert list(ds.body_name.values) == ["a", "bad", "bb"]
        assert ds.status.values.tolist() == [0, 1, 0]
        assert np.isnan(ds.quaternion.values[1]).all()
    elif eph.is_batch:
        assert list(ds.body_name.values) == ["a", "bb"]


def _cf_tables(tmp_path):
    """Standard-name table bundled with compliance-checker (cfchecker downloads it
    otherwise); area-type and region tables empty: the ephemeris uses neither."""
    pytest.importorskip("compliance_checker", reason="compliance-checker not installed: "
                        "its bundled CF standard-name table is used offline")
    import compliance_checker

    table = Path(compliance_checker.__file__).parent / "data" / "cf-standard-name-table.xml"
    if not table.is_file():
        pytest.skip(f"{table} not found")
    area = tmp_path / "area-type-table.xml"
    area.write_text('<?xml version="1.0"?>\n<area_type_table><version_number>0'
                    "</version_number><date>none</date></area_type_table>\n")
    region = tmp_path / "region-list.xml"
    region.write_text('<?xml version="1.0"?>\n<standardized_region_list><version_number>0'
                      "</version_number><date>none</date></standardized_region_list>\n")
    return str(table), str(area), str(region)


def _cfchecker_messages(path, tables):
    from cfchecker.cfchecks import CFChecker, CFVersion

    std, area, region = tables
    checker = CFChecker(cfStandardNamesXML=std, cfAreaTypesXML=area, cfRegionNamesXML=region,
                        version=CFVersion(), silent=True)  # auto
    results = checker.checker(str(path))
    found = {"ERROR": [], "WARN": [], "FATAL": []}
    for scope in [results["global"], *results["variables"].values()]:
        for category in found:
            found[category] += scope.get(category, [])
    return found


def test_cfchecker_reports_no_errors(ncfile, tmp_path):
    try:
        import cfchecker.cfchecks  # noqa: F401  (cfunits loads libudunits2 with ctypes)
    except ModuleNotFoundError:
        pytest.skip("cfchecker not installed (pip install cfchecker)")
    except (ImportError, OSError, AttributeError) as exc:
        pytest.skip(f"cfchecker does not import ({exc}): it needs the udunits2 C library "
                    "(apt-get install libudunits2-0)")
    tables = _cf_tables(tmp_path)
    found = _cfchecker_messages(ncfile, tables)
    # cfchecker 4.1.0 does not know CF-1.10 yet: its only complaints are about the version,
    # and a warning (not an error) for each string-valued coordinate variable (char array)
    string_coordinate = "(5): Possible incorrect declaration of a coordinate variable."
    version_only = ("does not appear to contain CF Convention data",
                    "Cannot determine CF version from the Conventions attribute",
                    string_coordinate)
    assert not found["FATAL"], found
    for message in found["ERROR"] + found["WARN"]:
        assert any(v in message for v in version_only), message
    copy = tmp_path / "cf18.nc"
    shutil.copy(ncfile, copy)
    with netCDF4.Dataset(copy, "a") as nc:
        nc.Conventions = "CF-1.8"
    found = _cfchecker_messages(copy, tables)
    assert found["ERROR"] == [] and found["FATAL"] == []
    assert set(found["WARN"]) <= {string_coordinate}, found["WARN"]


def test_compliance_checker_cf_suite(ncfile, tmp_path):
    pytest.importorskip("compliance_checker", reason="compliance-checker not installed "
                        "(pip install compliance-checker)")
    report = tmp_path / "report.json"
    exe = Path(sys.executable).with_name("compliance-checker")
    if not exe.exists():
        pytest.skip(f"{exe} not found")
    subprocess.run([str(exe), "--test=cf:1.10", "-f", "json", "-o", str(report), str(ncfile)],
                   capture_output=True, text=True, timeout=300)
    results = json.loads(report.read_text())["cf:1.10"]
    failures = {}
    for priority in ("high_priorities", "medium_priorities", "low_priorities"):
        for item in results[priority]:
            if item["value"][0] != item["value"][1]:
                failures[(priority, item["name"])] = set(item["msgs"])
    expected = {("high_priorities", "§5.1 Independent Latitude, Longitude, Vertical, and "
                 "Time Axes"): {"Coordinate variable 'time' should have standard_name="
                                "'time', found: 'None'"}}
    assert failures == expected
