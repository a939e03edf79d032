"""Ephemeris: schema, netCDF round trip through real netCDF4 files, atomic writes."""

import json

import netCDF4
import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.model.ephemeris import AtomicFiles, write_atomically
from attitude.propagation.reference import DEFAULT_RTOL

from ..tolerances import EPS, INTEGRATOR_PATHS, assert_agree


@pytest.fixture
def eph():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0], mass=12.0, name="probe")
    state = att.AttitudeState(Time("2029-04-13T01:02:03.123456789", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]), [0.3, 0.1, 0.5],
                              frame="EME2000")
    return att.propagate(body, state, np.linspace(0.0, 100.0, 51), method="integrator")


def test_schema_names_dims_units_and_conventions(eph):
    ds = eph.dataset
    assert ds.quaternion.dims == ("time", "quaternion_component")
    assert list(ds.quaternion_component.values) == ["x", "y", "z", "w"]
    assert ds.angular_velocity.dims == ("time", "axis")
    assert ds.angular_momentum.dims == ("time", "axis")
    assert ds.kinetic_energy.dims == ("time",)
    assert ds.time.dtype == np.float64     # seconds since the epoch, a CF time axis
    assert ds.time.attrs["units"] == "seconds since 2029-04-13T01:02:03.123456789"
    assert ds.time.attrs["standard_name"] == "time" and ds.time.attrs["axis"] == "T"
    assert ds.attrs["quaternion_convention"] == "scalar-last, body-to-inertial"
    assert ds.attrs["time_scale"] == "TDB" and ds.attrs["frame"] == "EME2000"
    assert ds.attrs["epoch"] == "2029-04-13T01:02:03.123456789"
    assert ds.attrs["Conventions"] == "CF-1.10"
    np.testing.assert_array_equal(ds.attrs["inertia"], np.diag([1.0, 2.0, 3.0]).ravel())
    for name in ("title", "history", "source"):
        assert ds.attrs[name]
    for name, var in ds.data_vars.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name


def test_derived_variables_are_consistent(eph):
    """L_inertial = R (I omega) and E = omega . I omega / 2, recomputed with scipy."""
    ds = eph.dataset
    w = ds.angular_velocity.values
    L = eph.rotation.apply(w * [1.0, 2.0, 3.0])
    np.testing.assert_allclose(ds.angular_momentum.values, L, rtol=0, atol=1e-15)
    np.testing.assert_allclose(ds.kinetic_energy.values, 0.5 * np.sum(w**2 * [1, 2, 3], 1),
                               rtol=1e-15)
    assert eph.times[-1].isot == "2029-04-13T01:03:43.123456789"
    assert abs((eph.times[-1] - eph.epoch).sec - 100.0) < 1e-9


def test_netcdf_round_trip_is_bit_exact(eph, tmp_path):
    path = eph.to_netcdf(tmp_path / "out.nc")
    back = att.Ephemeris.from_netcdf(path)
    for name in ("time", "quaternion", "angular_velocity", "angular_momentum",
                 "kinetic_energy"):
        np.testing.assert_array_equal(back.dataset[name].values, eph.dataset[name].values)
    for key, value in eph.dataset.attrs.items():
        np.testing.assert_array_equal(back.dataset.attrs[key], value)
    assert back.epoch == eph.epoch and back.frame == "EME2000"
    np.testing.assert_array_equal(back.body.inertia, eph.body.inertia)
    # a real netCDF-4 file, readable by the netCDF4 library itself
    with netCDF4.Dataset(path) as nc:
        assert nc.data_model == "NETCDF4"
        assert nc["quaternion"].dimensions == ("time", "quaternion_component")
        assert nc["time"].units == "seconds since 2029-04-13T01:02:03.123456789"
        np.testing.assert_array_equal(nc["quaternion"][:], eph.dataset.quaternion.values)


def test_atomic_write_leaves_old_file_intact_on_failure(eph, tmp_path):
    path = tmp_path / "eph.nc"
    eph.to_netcdf(path)
    before = path.read_bytes()

    def crash(tmp):
        with open(tmp, "wb") as fh:
            fh.write(b"partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        write_atomically(path, crash)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eph.nc"]


def test_to_netcdf_crash_mid_write_leaves_no_file_and_keeps_the_old_one(eph, tmp_path,
                                                                        monkeypatch):
    """The netCDF writer fails after writing part of the file (the ephemeris writer's
    own path through write_atomically, not a stand-in)."""
    import xarray as xr

    real = xr.Dataset.to_netcdf

    def half_then_crash(self, path, *args, **kwargs):
        real(self.isel(time=slice(0, 2)), path, *args, **kwargs)
        raise KeyboardInterrupt("killed while writing")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", half_then_crash)
    with pytest.raises(KeyboardInterrupt):
        eph.to_netcdf(tmp_path / "new.nc")
    assert list(tmp_path.iterdir()) == []
    old = tmp_path / "old.nc"
    old.write_bytes(b"previous ephemeris")
    with pytest.raises(KeyboardInterrupt):
        eph.to_netcdf(old)
    assert old.read_bytes() == b"previous ephemeris"
    assert list(tmp_path.iterdir()) == [old]


def test_atomic_files_all_or_each_untouched(tmp_path):
    """Several files: all renamed on success; on a crash after some are written, none is
    replaced and no temporary file or folder is left."""
    a, b = tmp_path / "a.txt", tmp_path / "sub" / "b.txt"
    with AtomicFiles(a, b) as files:
        files[a].write_text("A1")
        files[b].write_text("B1")
        assert not a.exists() and files[a].parent.parent == tmp_path
    assert (a.read_text(), b.read_text()) == ("A1", "B1")
    with pytest.raises(KeyboardInterrupt), AtomicFiles(a, b) as files:
        files[a].write_text("A2")
        raise KeyboardInterrupt
    assert (a.read_text(), b.read_text()) == ("A1", "B1")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "sub"]
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["b.txt"]
    with pytest.raises(att.WriterError, match="nothing was written"), \
            AtomicFiles(a, b) as files:
        files[a].write_text("A3")                     # b never written: nothing renamed
    assert a.read_text() == "A1" and sorted(p.name for p in tmp_path.iterdir()) == [
        "a.txt", "sub"]
    with pytest.raises(att.WriterError, match="not a destination"), AtomicFiles(a) as files:
        files[tmp_path / "c.txt"]
    with pytest.raises(att.WriterError, match="not open"):
        AtomicFiles(a)[a]


def test_batch_dataset_has_a_body_dimension(tmp_path):
    bodies = [att.RigidBody.from_principal_moments(m) for m in ([1, 2, 3], [2, 2, 3])]
    states = [att.AttitudeState("2030-01-01", Rotation.identity(), w)
              for w in ([0.1, 0.2, 0.3], [0.0, 0.1, 0.4])]
    eph = att.propagate(bodies, states, np.arange(5.0), method="integrator")
    assert eph.dataset.quaternion.dims == ("body", "time", "quaternion_component")
    assert eph.rotation.shape == (2, 5)
    back = att.Ephemeris.from_netcdf(eph.to_netcdf(tmp_path / "b.nc"))
    np.testing.assert_array_equal(back.dataset.quaternion.values, eph.dataset.quaternion.values)
    np.testing.assert_array_equal(back.bodies[1].inertia, np.diag([2.0, 2.0, 3.0]))
    single = att.propagate(bodies[1], states[1], np.arange(5.0), method="integrator")
    # DOP853 in a batch against a single run (tests/tolerances.py: INTEGRATOR_PATHS)
    assert_agree(eph.dataset.quaternion.values[1], single.dataset.quaternion.values,
                 ulps=INTEGRATOR_PATHS * DEFAULT_RTOL / EPS, magnitude=1.0)


def test_reading_bad_files_gives_clear_errors(tmp_path):
    with pytest.raises(att.EphemerisFormatError, match="no such file"):
        att.Ephemeris.from_netcdf(tmp_path / "missing.nc")
    junk = tmp_path / "junk.nc"
    junk.write_text(json.dumps({"not": "netcdf"}))
    with pytest.raises(att.EphemerisFormatError, match="not a readable netCDF file"):
        att.Ephemeris.from_netcdf(junk)
    other = tmp_path / "other.nc"
    with netCDF4.Dataset(other, "w") as nc:
        nc.createDimension("time", 2)
        nc.createVariable("time", "f8", ("time",))[:] = [0.0, 1.0]
    with pytest.raises(att.EphemerisFormatError, match="missing quaternion, angular_velocity"):
        att.Ephemeris.from_netcdf(other)


def test_input_arrays_are_not_modified():
    w = np.array([0.1, 0.2, 0.3])
    state = att.AttitudeState("2030-01-01", Rotation.identity(), w)
    assert w.flags.writeable and state.omega_body is not w


def test_a_damaged_netcdf_file_is_a_format_error(eph, tmp_path):
    """Each 512-byte block of a written ephemeris zeroed in turn: reading gives the
    ephemeris or an EphemerisFormatError naming the file, never netCDF4's bare
    RuntimeError ("NetCDF: HDF error", raised when a damaged chunk is decompressed)."""
    path = tmp_path / "eph.nc"
    eph.to_netcdf(path)
    data = path.read_bytes()
    damaged, refused = tmp_path / "damaged.nc", 0
    for start in range(0, len(data), 512):
        damaged.write_bytes(data[:start] + bytes(min(512, len(data) - start))
                            + data[start + 512:])
        try:
            att.Ephemeris.from_netcdf(damaged)
        except att.EphemerisFormatError as err:
            assert str(damaged) in str(err)
            refused += 1
    assert refused > 0
