"""CF compliance of the ephemeris netCDF file: the rules tested directly, then two real
checkers (the CF checker ``cfchecker`` and IOOS ``compliance-checker``) when installed,
each asked for every message at every priority, on the four writers' outputs (one body,
a batch, an ensemble written from dask chunks, the streaming writer).

``time`` is a CF time axis (``standard_name = "time"``, ``axis = "T"``, ``units =
"seconds since <epoch>"``, ``calendar``), so plain ``xarray.open_dataset`` shows dates, while
:meth:`attitude.Ephemeris.from_netcdf` reads the float seconds as they are, and still reads
the files of attitude 0.1.0 (``units = "s"``, tests/data/netcdf_v0_1_0_*.nc).

cfchecker 4.1.0 (the newest on PyPI) knows CF versions up to 1.8 only: for a file declared
``CF-1.10`` it reports that the file "does not appear to contain CF Convention data".  The
same file declared ``CF-1.8`` (the newest version it knows; nothing in the file needs 1.9 or
1.10) is then checked, and the CF-1.10 check is skipped with that reason until a cfchecker
knows CF-1.10.
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.ephemeris import TIME_CALENDAR, time_attributes, time_from_file

DATA = Path(__file__).parents[1] / "data"


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
        time = nc["time"]                                   # a CF time axis (CF 4.4)
        assert time.dtype == np.float64
        assert time.standard_name == "time" and time.axis == "T"
        assert time.units == f"seconds since {nc.epoch}" and time.calendar == TIME_CALENDAR
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
    assert ds.time.dtype == np.float64
    assert ds.time.attrs == time_attributes(eph.epoch)
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
    """``{level: [(variable or "global", message), ...]}`` for every level cfchecker
    reports (FATAL, ERROR, WARN, INFO, ...)."""
    from cfchecker.cfchecks import CFChecker, CFVersion

    std, area, region = tables
    checker = CFChecker(cfStandardNamesXML=std, cfAreaTypesXML=area, cfRegionNamesXML=region,
                        version=CFVersion(), silent=True)  # auto
    results = checker.checker(str(path))
    found = {"FATAL": [], "ERROR": [], "WARN": []}
    scopes = {"global": results["global"], **results["variables"]}
    for where, scope in scopes.items():
        for level, messages in scope.items():
            if level != "VERSION":
                found.setdefault(level, []).extend((where, m) for m in messages)
    return found


def _cfchecker():
    try:
        from cfchecker import cfchecks
    except ModuleNotFoundError:
        pytest.skip("cfchecker not installed (pip install cfchecker)")
    except (ImportError, OSError, AttributeError) as exc:
        pytest.skip(f"cfchecker does not import ({exc}): it needs the udunits2 C library "
                    "(apt-get install libudunits2-0)")
    return cfchecks


#: cfchecker's one warning: a string-valued coordinate variable (API.md's x y z w labels, a
#: char array named like its dimension, CF 6.1) is a "possible incorrect declaration".  Not
#: an error, and it cannot go: listing the variable in ``coordinates`` (an auxiliary label
#: variable) makes compliance-checker fail CF 5 (an auxiliary coordinate named like its
#: dimension); naming it ``<dim>_label`` drops the labels from the dimension for readers.
STRING_COORDINATE = "(5): Possible incorrect declaration of a coordinate variable."
LABELS = {"quaternion_component", "axis"}


def _assert_no_cfchecker_error(found):
    """No FATAL and no ERROR; WARN and INFO only the note on each string coordinate."""
    assert found["FATAL"] == [] and found["ERROR"] == [], found
    notes = [m for level in found if level not in ("FATAL", "ERROR") for m in found[level]]
    assert set(notes) == {(name, STRING_COORDINATE) for name in LABELS}, notes


def test_cfchecker_cf_1_10(ncfile, tmp_path):
    cfchecks = _cfchecker()
    newest = str(cfchecks.newest_version)                      # "CF-1.8" in cfchecker 4.1.0
    if "CF-1.10" not in map(str, cfchecks.cfVersions):
        pytest.skip(f"cfchecker {cfchecks.__version__} knows CF versions up to {newest} only, "
                    f"not CF-1.10: the file is checked declared as {newest} "
                    "(test_cfchecker_newest_known_cf_version)")
    _assert_no_cfchecker_error(_cfchecker_messages(ncfile, _cf_tables(tmp_path)))


def test_cfchecker_newest_known_cf_version(ncfile, tmp_path):
    cfchecks = _cfchecker()
    newest = str(cfchecks.newest_version)
    tables = _cf_tables(tmp_path)
    copy = tmp_path / f"{newest}.nc"
    shutil.copy(ncfile, copy)
    with netCDF4.Dataset(copy, "a") as nc:
        nc.Conventions = newest
    _assert_no_cfchecker_error(_cfchecker_messages(copy, tables))


def test_compliance_checker_cf_1_10_all_priorities(ncfile, tmp_path):
    pytest.importorskip("compliance_checker", reason="compliance-checker not installed "
                        "(pip install compliance-checker)")
    report = tmp_path / "report.json"
    exe = Path(sys.executable).with_name("compliance-checker")
    if not exe.exists():
        pytest.skip(f"{exe} not found")
    subprocess.run([str(exe), "--test=cf:1.10", "-f", "json", "-o", str(report), str(ncfile)],
                   capture_output=True, text=True, timeout=300)
    results = json.loads(report.read_text())["cf:1.10"]
    failures, checked = {}, 0
    for priority in ("high_priorities", "medium_priorities", "low_priorities"):
        for item in results[priority]:
            checked += 1
            if item["value"][0] != item["value"][1] or item["msgs"]:
                failures[(priority, item["name"])] = item["msgs"]
    assert failures == {}
    assert checked > 10 and results["scored_points"] == results["possible_points"] > 0


def test_plain_xarray_and_cftime_show_dates(ncfile):
    """A CF reader decodes ``time`` to dates: xarray's default ``decode_times`` (to the
    nanosecond) and cftime, which udunits-based viewers resemble (to the microsecond)."""
    with netCDF4.Dataset(ncfile) as nc:
        nc.set_auto_mask(False)
        seconds, units, calendar = nc["time"][:], nc["time"].units, nc["time"].calendar
        epoch = np.datetime64(nc.epoch, "ns")
    with xr.open_dataset(ncfile) as ds:
        dates = ds.time.values
    assert dates.dtype == np.dtype("datetime64[ns]")
    expected = epoch + np.round(seconds * 1e9).astype("timedelta64[ns]")
    assert np.max(np.abs(dates - expected)) <= np.timedelta64(1, "ns")
    import cftime

    shown = cftime.num2date(seconds, units, calendar, only_use_cftime_datetimes=False,
                            only_use_python_datetimes=True)
    ns = np.array([np.datetime64(d, "ns") for d in shown])
    assert np.max(np.abs(ns - expected)) <= np.timedelta64(1, "us")


def test_seconds_keep_full_precision(tmp_path):
    """Seconds finer than the nanosecond of a datetime64 survive the round trip to the
    ulp, so the reader does not go through dates."""
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState(Time("2029-04-13T01:02:03.123456789", scale="tdb"),
                              Rotation.identity(), [0.01, 0.02, 0.03])
    t = np.array([0.0, 1e-12, 1e-6 / 3, 0.1, 1 / 3, 86400.0 + 1 / 7, 1.0e9 + 0.1])
    eph = att.propagate(body, state, t)
    back = att.Ephemeris.from_netcdf(eph.to_netcdf(tmp_path / "fine.nc"))
    np.testing.assert_array_max_ulp(back.time, t, maxulp=1)
    assert back.epoch == state.epoch and back.time_scale == "TDB"
    assert back.dataset.time.attrs == time_attributes(state.epoch)


@pytest.mark.parametrize("kind", ["single", "batch"])
def test_files_of_attitude_0_1_0_read_back(kind, tmp_path):
    """tests/data/netcdf_v0_1_0_*.nc (``units = "s"``, written by attitude 0.1.0; see
    tests/data/README.md) read with the CF time axis in memory, values unchanged, and
    written again in the CF form."""
    path = DATA / f"netcdf_v0_1_0_{kind}.nc"
    with netCDF4.Dataset(path) as nc:
        assert nc["time"].units == "s"                    # the old form
        nc.set_auto_mask(False)
        raw = {name: nc[name][:] for name in ("time", "quaternion", "angular_velocity",
                                              "angular_momentum", "kinetic_energy")}
    eph = att.Ephemeris.from_netcdf(path)
    if kind == "single":
        t = 1.0e9 + np.array([0.0, 0.1, 0.2, 0.3, 1.7, 2.9, 10.0 / 3.0, 12.5])
        epoch = Time("2029-04-13T01:02:03.123456789", scale="tdb")
        assert eph.body.name == "probe" and not eph.is_batch
    else:
        t = np.array([0.0, 0.25, 1.0 / 3.0, 7.5, 86400.125])
        epoch = Time("2024-03-01T12:00:00.5", scale="utc")
        assert list(eph.dataset.body_name.values) == ["a", "bb"]
    np.testing.assert_array_max_ulp(eph.time, t, maxulp=1)
    assert eph.epoch == epoch and eph.time_scale == epoch.scale.upper()
    assert eph.dataset.time.attrs == time_attributes(epoch)
    for name, values in raw.items():              # read as stored: no arithmetic on them
        np.testing.assert_array_equal(eph.dataset[name].values, values, err_msg=name)
    again = eph.to_netcdf(tmp_path / "again.nc")
    with netCDF4.Dataset(again) as nc:
        assert nc["time"].units == f"seconds since {nc.epoch}" and nc["time"].axis == "T"
    np.testing.assert_array_max_ulp(att.Ephemeris.from_netcdf(again).time, t, maxulp=1)


def test_other_cf_time_units_are_converted_to_seconds_since_the_epoch():
    """``hours since`` another reference: scaled and shifted onto the epoch attribute."""
    ds = xr.Dataset(coords={"time": ("time", np.array([0.0, 1.5]), {
        "units": "hours since 2030-01-01 01:00:00", "calendar": "standard"})},
        attrs={"time_scale": "TT", "epoch": "2030-01-01T00:00:00"})
    out = time_from_file(ds)
    # the shift is an astropy Time difference: two doubles in days, so the fraction of a day
    # carries 2**-53 day (1e-11 s) of rounding, a few times over
    day_ulp = 86400.0 * np.finfo(float).eps
    np.testing.assert_allclose(out.time.values, [3600.0, 9000.0], rtol=0, atol=4 * day_ulp)
    assert out.time.attrs["units"] == "seconds since 2030-01-01T00:00:00.000000000"
    # no epoch attribute: the reference time of the units is the epoch
    bare = xr.Dataset(coords={"time": ("time", np.array([2.0]), {
        "units": "seconds since 2030-01-01T00:00:00.25"})}, attrs={"time_scale": "TDB"})
    out = time_from_file(bare)
    assert out.attrs["epoch"] == "2030-01-01T00:00:00.250000000"
    assert out.time.values.tolist() == [2.0]


@pytest.mark.parametrize(("attrs", "units", "key", "match"), [
    ({"time_scale": "TDB", "epoch": "2030-01-01"}, "furlongs", "time.units",
     "not a time since a reference epoch"),
    ({"time_scale": "TDB", "epoch": "2030-01-01"}, "seconds since yesterday", "time.units",
     "not an epoch in the TDB time scale"),
    ({"epoch": "2030-01-01"}, "s", "time_scale", "time_scale is missing"),
])
def test_unreadable_time_names_the_attribute(attrs, units, key, match):
    ds = xr.Dataset(coords={"time": ("time", np.array([0.0]), {"units": units})},
                    attrs=attrs)
    with pytest.raises(att.EphemerisFormatError, match=match) as err:
        time_from_file(ds)
    assert err.value.key == key


def test_from_netcdf_error_names_file_and_attribute(tmp_path, ncfile):
    with netCDF4.Dataset(ncfile, "a") as nc:
        nc["time"].units = "seconds since the beginning"
    with pytest.raises(att.EphemerisFormatError) as err:
        att.Ephemeris.from_netcdf(ncfile)
    assert str(err.value).startswith(f"{ncfile}: time.units: ")


def test_dates_decoded_by_xarray_are_refused_with_the_fix(ncfile):
    with xr.open_dataset(ncfile) as ds:
        with pytest.raises(att.EphemerisFormatError, match="Ephemeris.from_netcdf") as err:
            att.Ephemeris(ds.load())
    assert err.value.key == "time"
