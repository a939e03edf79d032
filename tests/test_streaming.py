"""Streaming netCDF writer: same data as a one-shot file, bounded blocks, atomic on crash."""

import sys

import netCDF4
import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
import attitude.formats.streaming as streaming
from attitude.formats.streaming import EphemerisWriter, UniformTimes, propagate_to_netcdf

from .tolerances import EXACT_SOLUTION, FEW_OPS, assert_agree

VARIABLES = ("time", "quaternion", "angular_velocity", "angular_momentum", "kinetic_energy")


@pytest.fixture
def case():
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0], name="tumbler")
    state = att.AttitudeState(Time("2029-04-13T01:02:03.123456789", scale="tdb"),
                              Rotation.from_euler("ZXZ", [0.3, 1.1, -0.7]),
                              [0.02, 0.003, 0.05], frame="EME2000")
    return body, state


def _read(path):
    with netCDF4.Dataset(path) as nc:
        data = {name: nc[name][:].data for name in VARIABLES}
        attrs = {k: nc.getncattr(k) for k in nc.ncattrs()}
        var_attrs = {name: {k: nc[name].getncattr(k) for k in nc[name].ncattrs()}
                     for name in nc.variables}
        dims = {name: (len(d), d.isunlimited()) for name, d in nc.dimensions.items()}
    return data, attrs, var_attrs, dims


def test_streamed_file_equals_one_shot_file(case, tmp_path):
    body, state = case
    times = UniformTimes(-30.0, 7.5, 1003)
    t = -30.0 + 7.5 * np.arange(1003)
    np.testing.assert_array_equal(times[0:1003], t)
    one = att.propagate(body, state, t).to_netcdf(tmp_path / "one.nc")
    streamed = propagate_to_netcdf(body, state, times, tmp_path / "streamed.nc", block=100,
                                   chunk=64)
    a, b = _read(one), _read(streamed)
    # the same layout, attributes and times bit for bit; the numbers of blocks of 100
    # epochs against one run of 1003 are two paths of the exact solution (numpy's SIMD
    # loops take other branches for other lengths): a few ulps of their magnitude
    np.testing.assert_array_equal(a[0]["time"], b[0]["time"])      # exact: -30 + 7.5 k
    for name in VARIABLES:
        assert a[0][name].dtype == b[0][name].dtype == np.float64
        vector = a[0][name].ndim == 2
        magnitude = (1.0 if name == "quaternion" else
                     np.linalg.norm(a[0][name], axis=-1, keepdims=True) if vector else
                     np.abs(a[0][name]))
        assert_agree(b[0][name], a[0][name], ulps=EXACT_SOLUTION + FEW_OPS,
                     magnitude=magnitude, what=name)
    a[1].pop("history"), b[1].pop("history")
    assert a[1].keys() == b[1].keys()
    for key in a[1]:
        np.testing.assert_array_equal(a[1][key], b[1][key], err_msg=key)
    assert a[2] == b[2] and a[3] == b[3]
    back = att.Ephemeris.from_netcdf(streamed)
    assert back.epoch == state.epoch and back.frame == "EME2000" and len(back) == 1003
    with netCDF4.Dataset(streamed) as nc:
        assert nc["quaternion"].chunking() == [64, 4]
        assert nc["quaternion"].filters()["zlib"]


def test_blocks_are_bounded(case, tmp_path, monkeypatch):
    """propagate is called on at most `block` samples at a time, covering every sample."""
    body, state = case
    calls = []
    real = att.propagate

    def spy(body, state, times, **kwargs):
        calls.append(np.array(times))
        return real(body, state, times, **kwargs)

    monkeypatch.setattr(sys.modules["attitude.formats.streaming"], "propagate", spy)
    path = propagate_to_netcdf(body, state, UniformTimes(0.0, 1.0, 2501), tmp_path / "b.nc",
                               block=1000)
    assert [len(c) for c in calls] == [1000, 1000, 501]
    np.testing.assert_array_equal(np.concatenate(calls), np.arange(2501.0))
    assert len(att.Ephemeris.from_netcdf(path)) == 2501


def test_crash_in_the_middle_leaves_no_file(case, tmp_path, monkeypatch):
    body, state = case
    real = att.propagate
    count = {"n": 0}

    def failing(*args, **kwargs):
        count["n"] += 1
        if count["n"] == 3:
            raise RuntimeError("simulated crash")
        return real(*args, **kwargs)

    monkeypatch.setattr(sys.modules["attitude.formats.streaming"], "propagate", failing)
    with pytest.raises(RuntimeError, match="simulated crash"):
        propagate_to_netcdf(body, state, np.arange(500.0), tmp_path / "c.nc", block=100)
    assert list(tmp_path.iterdir()) == []
    # an existing file is left as it was
    previous = tmp_path / "c.nc"
    previous.write_bytes(b"old")
    count["n"] = 0
    with pytest.raises(RuntimeError):
        propagate_to_netcdf(body, state, np.arange(500.0), previous, block=100)
    assert previous.read_bytes() == b"old" and list(tmp_path.iterdir()) == [previous]


def test_writer_context_manager(case, tmp_path):
    body, state = case
    eph = att.propagate(body, state, np.arange(20.0))
    ds = eph.dataset
    path = tmp_path / "w.nc"
    with EphemerisWriter(path, body=body, epoch=state.epoch, frame="EME2000") as w:
        w.append(eph.__class__(ds.isel(time=slice(0, 8))))
        w.append_arrays(ds.time.values[8:], ds.quaternion.values[8:],
                        ds.angular_velocity.values[8:])
        assert len(w) == 20 and not path.exists()
    back = att.Ephemeris.from_netcdf(path)
    for name in VARIABLES:      # append_arrays renormalises the quaternions: 1 ulp
        np.testing.assert_allclose(back.dataset[name].values, ds[name].values, rtol=1e-15,
                                   atol=1e-15)
        np.testing.assert_array_equal(back.dataset[name].values[:8], ds[name].values[:8])
    with pytest.raises(ValueError), EphemerisWriter(tmp_path / "x.nc", body=body,
                                                    epoch=state.epoch) as w:
        w.append_arrays([0.0], [[0, 0, 0, 1]], [[0, 0, 0]])
        raise ValueError("boom")
    assert not (tmp_path / "x.nc").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.nc"]


def test_writer_rejects_inconsistent_blocks(case, tmp_path):
    body, state = case
    eph = att.propagate(body, state, np.arange(5.0))
    with pytest.raises(att.EphemerisFormatError, match="increase strictly"), \
            EphemerisWriter(tmp_path / "r.nc", body=body, epoch=state.epoch,
                            frame="EME2000") as w:
        w.append(eph)
        w.append(eph)
    other = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 1.0], frame="EME2000")
    with pytest.raises(att.EphemerisFormatError, match="epoch"), \
            EphemerisWriter(tmp_path / "r.nc", body=body, epoch=state.epoch,
                            frame="EME2000") as w:
        w.append(att.propagate(body, other, np.arange(3.0)))
    assert list(tmp_path.iterdir()) == []
    assert streaming.__all__
