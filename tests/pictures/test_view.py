"""The HTML view's content: sizes, frames, the cloud of a batch, photometry where
present, and the geometry drawn at a frame equal to the motion."""

import numpy as np
import pytest

pytest.importorskip("plotly")

from scipy.spatial.transform import Rotation  # noqa: E402

import attitude as att  # noqa: E402
from attitude.pictures.viewer import view  # noqa: E402

BODY = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
STATE = att.AttitudeState("2029-04-13", Rotation.from_euler("ZXZ", [250.0, 165.0, 10.0],
                                                           degrees=True), [0.02, 0.0, 0.1])


def _trace(v, name):
    return next(d for d in v.figure.data if d.name == name)


def test_ten_thousand_epochs_stay_under_10_mb(tmp_path):
    eph = att.propagate(BODY, STATE, np.linspace(0.0, 20000.0, 10_000))
    out = view(eph, tmp_path / "big.html").path
    size = out.stat().st_size
    print(f"\n10^4 epochs: {size / 1e6:.2f} MB")
    assert size < 10e6
    v = view(eph, max_frames=150)
    assert len(v.figure.frames) == 150
    assert len(_trace(v, "herpolhode").x) == 10_000          # full resolution, as a line


def test_frame_geometry_is_the_motion():
    """The axes in frame k are the attitude at that frame's time (a sample here)."""
    t = np.linspace(0.0, 300.0, 31)
    eph = att.propagate(BODY, STATE, t)
    v = view(eph, max_frames=31)                       # frames at the samples
    names = [d.name for d in v.figure.data]
    k = 17
    frame = v.figure.frames[k]
    for axis, label in enumerate("xyz"):
        data = frame.data[frame.traces.index(names.index(label))]
        tip = np.array([data.x[1], data.y[1], data.z[1]]) / 1.5
        np.testing.assert_allclose(tip, eph.rotation[k].apply(np.eye(3)[axis]),
                                   rtol=0, atol=1e-14)


def test_batch_shows_the_cloud_of_momentum_directions():
    bodies = [BODY] * 5
    states = [att.AttitudeState("2029-04-13", Rotation.random(random_state=i),
                                [0.02, 0.0, 0.1]) for i in range(5)]
    eph = att.propagate(bodies, states, np.linspace(0.0, 100.0, 11))
    v = view(eph, max_frames=3)
    cloud = _trace(v, "L directions (5 bodies)")
    L = eph.dataset.angular_momentum.values[:, 0]
    u = 1.9 * L / np.linalg.norm(L, axis=-1, keepdims=True)
    np.testing.assert_allclose(np.column_stack([cloud.x, cloud.y, cloud.z]), u, rtol=0,
                               atol=1e-6)                       # float32 in the page


def test_sun_observer_and_lightcurve_are_drawn_where_present():
    t = np.linspace(0.0, 300.0, 31)
    eph = att.propagate(BODY, STATE, t)
    ds = eph.dataset.copy()
    ds["sun_direction"] = (("time", "axis"), np.tile([1.0, 0.0, 0.0], (t.size, 1)))
    ds["magnitude"] = ("time", 15.0 + 0.1 * np.sin(t / 30.0))
    v = view(att.Ephemeris(ds), max_frames=4)
    names = [d.name for d in v.figure.data]
    assert "to the sun" in names and "magnitude" in names and "to the observer" not in names
    assert list(_trace(v, "magnitude").y) == pytest.approx(ds["magnitude"].values, rel=1e-6)


def test_under_dissipation_the_plane_and_ellipsoid_follow_the_energy():
    """E decays at fixed L: in frame k the energy ellipsoid's semi-axes are sqrt(2 E_k /
    I_i) and the invariable plane lies at 2 E_k / |L| along L (float32 in the page)."""
    from attitude.model.torques.dissipation import EnergyDissipation

    eph = att.propagate(BODY, STATE, np.linspace(0.0, 600.0, 61),
                        torques=[EnergyDissipation(time_constant=30.0)])
    v = view(eph, max_frames=61)
    names = [d.name for d in v.figure.data]
    E = eph.dataset.kinetic_energy.values
    L = eph.dataset.angular_momentum.values
    assert E[-1] < (1 - 1e-3) * E[0]               # the run does dissipate
    for k in (0, 30, 60):
        frame = v.figure.frames[k]
        plane = frame.data[frame.traces.index(names.index("invariable plane"))]
        corners = np.column_stack([plane.x, plane.y, plane.z]).astype(float)
        n = L[k] / np.linalg.norm(L[k])
        np.testing.assert_allclose(corners @ n, 2 * E[k] / np.linalg.norm(L[k]),
                                   rtol=1e-6)
        shell = frame.data[frame.traces.index(names.index("energy ellipsoid"))]
        points = np.column_stack([shell.x, shell.y, shell.z]).astype(float)
        body = eph.rotation[k].inv().apply(points)           # principal frame = body frame
        moments = np.array([0.61, 0.965, 1.0])
        residual = np.sum(body ** 2 * moments / (2 * E[k]), axis=1) - 1.0
        assert np.abs(residual).max() < 1e-5
