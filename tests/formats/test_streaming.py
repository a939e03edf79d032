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

from ..tolerances import EXACT_SOLUTION, FEW_OPS, assert_agree

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
    """Same schema, attributes and chunking; the same values to a few ulps (the same
    arithmetic per epoch, on arrays cut differently)."""
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


# --- batches, torques, bounded memory ----------------------------------------------------
EPS = np.finfo(float).eps


def _batch():
    bodies = [att.RigidBody.from_principal_moments(m, name=f"b{i}")
              for i, m in enumerate(([0.61, 0.965, 1.0], [1.0, 2.0, 3.0], [2.0, 2.5, 4.0]))]
    rot = Rotation.from_euler("ZXZ", [[0.3, 1.1, -0.7], [1.0, 0.2, 0.4], [-2.0, 2.5, 0.1]])
    epoch = Time("2029-04-13T01:02:03.123456789", scale="tdb")
    states = [att.AttitudeState(epoch, rot[i], w, frame="EME2000") for i, w in
              enumerate(([0.02, 0.003, 0.05], [0.01, 0.04, -0.02], [0.0, 0.03, 0.06]))]
    return bodies, states


def _close_to_ulps(a, b, ulps, name):
    """|a - b| <= ulps * eps * (largest magnitude of the variable): the two runs do the
    same arithmetic on every epoch; a few ulps cover a different summation order."""
    scale = max(np.max(np.abs(a)), np.finfo(float).tiny)
    np.testing.assert_allclose(a, b, rtol=0, atol=ulps * EPS * scale, err_msg=name)


def test_batch_stream_equals_in_memory(tmp_path):
    bodies, states = _batch()
    t = -20.0 + 3.25 * np.arange(757)
    one = att.propagate(bodies, states, t)
    path = propagate_to_netcdf(bodies, states, UniformTimes(-20.0, 3.25, 757),
                               tmp_path / "batch.nc", block=100, chunk=64)
    back = att.Ephemeris.from_netcdf(path)
    assert back.is_batch and back.dataset.quaternion.dims == ("body", "time",
                                                               "quaternion_component")
    np.testing.assert_array_equal(back.time, t)
    for name in VARIABLES[1:]:
        _close_to_ulps(back.dataset[name].values, one.dataset[name].values, 4, name)
    assert [b.name for b in back.bodies] == ["b0", "b1", "b2"]
    np.testing.assert_array_equal(back.dataset.inertia.values, one.dataset.inertia.values)


def _torques():
    """An inertially fixed torque (depends on the attitude) and a time-varying one (so
    that the time carried across blocks matters); both cheap to evaluate."""
    def wobble(t, quaternion, omega_body, body):
        return np.broadcast_to([0.0, 3e-4 * np.cos(2e-3 * t), 0.0], np.shape(omega_body))

    return [att.torques.ConstantTorque([2e-4, 0.0, 1e-4], frame="inertial"),
            att.torques.FunctionTorque(wobble, velocity_dependent=False)]


def _roundoff_spread(bodies, states, t, torques, step):
    """How far the in-memory splitting run moves when its initial state changes by one
    ulp (each rate component, then a rotation by eps about x): the round-off
    level of the integration over the run, relative to the largest component.  The
    exact free flow is accurate to a few hundred ulps, not to one, so this grows far
    faster than the linear sensitivity of the motion (measured: 4e4 ulps after 1200
    steps for a 1-ulp change, against a linear gain of 180)."""
    ref = att.propagate(bodies, states, t, torques=torques, step=step)
    worst = 0.0
    for k in range(4):
        pert = []
        for s in states:
            w, rot = s.omega_body.copy(), s.attitude
            if k < 3:
                w[k] = w[k] + EPS * np.max(np.abs(w))
            else:
                rot = rot * Rotation.from_rotvec(EPS * np.eye(3)[k - 3])
            pert.append(att.AttitudeState(s.epoch, rot, w, frame=s.frame))
        run = att.propagate(bodies, pert, t, torques=torques, step=step)
        for name in ("quaternion", "angular_velocity"):
            a, b = ref.dataset[name].values, run.dataset[name].values
            worst = max(worst, np.max(np.abs(a - b)) / np.max(np.abs(a)))
    return ref, worst


@pytest.mark.parametrize("batch", [False, True])
def test_torque_stream_equals_in_memory(tmp_path, batch):
    """Streamed with torques, block by block, against one in-memory splitting run.

    The step is fixed for the run and the output times are dyadic (multiples of 0.25 s),
    so every interval gets the same steps, step lengths and kick times in both runs: the
    blocks change no step, and the truncation error is the same.  The runs differ only
    by the re-normalisation of the quaternion carried across each of the K block
    boundaries, a change of the state of <= 2 ulps (the bodies are in their principal
    frames, so no frame rotation is redone).  Each such change moves the rest of the
    run by at most what a change of the initial state does, the round-off spread D
    measured on the run (:func:`_roundoff_spread`), so
    ``|streamed - in memory| <= 2 (K + 1) D`` times the largest component."""
    bodies, states = _batch()
    if not batch:
        bodies, states = bodies[0], states[0]
    torques = _torques()
    times = UniformTimes(0.0, 12.25, 120)
    block, step = 25, 6.2
    ref, spread = _roundoff_spread(bodies if batch else [bodies],
                                   states if batch else [states], times[0:120], torques,
                                   step)
    path = propagate_to_netcdf(bodies, states, times, tmp_path / "torqued.nc",
                               torques=torques, step=step, block=block)
    back = att.Ephemeris.from_netcdf(path)
    k = len(times) // block
    tol = 2 * (k + 1) * max(spread, EPS)
    assert tol < 1e-8                                 # a bound that can fail
    for name in ("quaternion", "angular_velocity"):
        a = back.dataset[name].values
        b = ref.dataset[name].values if batch else ref.dataset[name].values[0]
        np.testing.assert_allclose(a, b, rtol=0, atol=tol * np.max(np.abs(b)), err_msg=name)
    # the torque acted: the run is far from the torque-free motion
    free = att.propagate(bodies, states, times[0:120])
    assert np.max(np.abs(free.dataset.angular_velocity.values
                         - back.dataset.angular_velocity.values)) > 1e3 * tol


def test_torque_stream_default_step_is_fixed_for_the_run(tmp_path, monkeypatch):
    """Without step=, choose_step runs once at the initial state and every block uses it."""
    body, state = _batch()[0][0], _batch()[1][0]
    seen = []
    real = streaming.integrate_splitting

    def spy(*args, **kwargs):
        seen.append(kwargs["step"])
        return real(*args, **kwargs)

    monkeypatch.setattr(streaming, "integrate_splitting", spy)
    propagate_to_netcdf(body, state, UniformTimes(0.0, 30.0, 50), tmp_path / "s.nc",
                        torques=_torques(), block=20)
    expected = att.propagation.splitting.choose_step(
        body, state.attitude.as_quat(), state.omega_body, _torques())
    assert len(seen) == 3 and seen == [expected] * 3


def test_stream_argument_errors(case, tmp_path):
    body, state = case
    with pytest.raises(att.InvalidStateError, match="times >= 0"):
        propagate_to_netcdf(body, state, np.arange(-5.0, 5.0), tmp_path / "n.nc",
                            torques=_torques())
    with pytest.raises(att.InvalidStateError, match="method='integrator'"):
        propagate_to_netcdf(body, state, np.arange(5.0), tmp_path / "n.nc",
                            torques=_torques(), method="integrator")
    with pytest.raises(att.InvalidStateError, match="block"):
        propagate_to_netcdf(body, state, np.arange(5.0), tmp_path / "n.nc", block=0)
    for bad in ({"block": 2.5}, {"block": "10"}, {"step": -1.0, "torques": _torques()},
                {"step": "1 s", "torques": _torques()}):
        with pytest.raises(att.InvalidStateError):
            propagate_to_netcdf(body, state, np.arange(5.0), tmp_path / "n.nc", **bad)
    with pytest.raises(att.InvalidStateError, match="count"):
        UniformTimes(0.0, 1.0, "many")
    with pytest.raises(att.InvalidStateError, match="slices"):
        UniformTimes(0.0, 1.0, 3)[1]
    with pytest.raises(att.EphemerisFormatError, match="batch"), \
            EphemerisWriter(tmp_path / "n.nc", body=[body, body], epoch=state.epoch,
                            frame="EME2000") as w:
        w.append(att.propagate(body, state, np.arange(3.0)))
    assert list(tmp_path.iterdir()) == []


def _peak_bytes(run) -> int:
    import tracemalloc
    tracemalloc.start()
    try:
        run()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("torqued", [False, True])
def test_peak_memory_does_not_grow_with_the_epoch_count(tmp_path, torqued):
    """10x the epochs at the same block size: the peak of Python-allocated memory
    (numpy arrays included) grows by far less than the ephemeris would take in memory
    (14 float64 per body and epoch); a writer that kept the blocks would grow by all of
    it.  (What does grow, ~1 kB per block, are small library caches.)"""
    bodies, states = _batch()
    n_bodies = len(bodies)
    kwargs = {}
    if torqued:     # the splitting integrator costs ~1 ms per step: one body, Strang
        bodies, states, n_bodies = bodies[0], states[0], 1
        kwargs = {"torques": _torques(), "step": 10.0, "order": 2}
    block, counts = (100, (200, 2_000)) if torqued else (500, (2_000, 20_000))

    def run(n):
        return lambda: propagate_to_netcdf(bodies, states, UniformTimes(0.0, 10.0, n),
                                           tmp_path / f"m{n}.nc", block=block, **kwargs)

    run(counts[0])()                                     # warm the caches
    small, large = (_peak_bytes(run(n)) for n in counts)
    data = (counts[1] - counts[0]) * n_bodies * 14 * 8   # growth of the whole ephemeris
    assert large - small < data / 4, (small, large, data)
