"""The movie is right, not just pretty: what the figure holds at a frame is the motion of
the ephemeris at that frame's time, and the construction holds to round-off."""

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from scipy.spatial.transform import Rotation  # noqa: E402

import attitude as att  # noqa: E402
from attitude.foundations.errors import WriterError  # noqa: E402
from attitude.pictures.animation import PoinsotAnimation, animate  # noqa: E402
from attitude.pictures.poinsot import energy_residual, momentum_residual  # noqa: E402

EPS = np.finfo(float).eps
MOMENTS = [0.61, 0.965, 1.0]


def _eph(times, omega=(0.02, 0.0, 0.1), attitude=None, moments=MOMENTS):
    body = att.RigidBody.from_principal_moments(moments)
    state = att.AttitudeState("2029-04-13", attitude or Rotation.from_euler(
        "ZXZ", [250.0, 165.0, 10.0], degrees=True), list(omega))
    return body, state, att.propagate(body, state, np.asarray(times, dtype=float))


def _drawn_axes(anim):
    """The three drawn body axes, back in the inertial frame, as the columns of a matrix."""
    tips = [np.array([a.get_data_3d()[i][1] for i in range(3)])
            for a in anim.artists["body_axes"]]
    return (anim.scene_rotation.T @ np.column_stack(tips)) / anim.axis_length


def _drawn_point(anim):
    x, y, z = anim.artists["polhode_point"].get_data_3d()
    return np.array([x[0], y[0], z[0]])


def test_drawn_body_axes_are_the_attitude_at_sample_times():
    t = np.linspace(0.0, 300.0, 31)
    _, _, eph = _eph(t)
    frames = t[::6]
    anim = PoinsotAnimation(eph, frames, figsize=(4, 2))
    for k, tk in enumerate(frames):
        anim.update(k)
        truth = eph.rotation[int(round(tk / 10.0))].as_matrix()
        # a rotation of unit vectors and back through the orthonormal scene matrix:
        # a few ulps per component
        np.testing.assert_allclose(_drawn_axes(anim), truth, rtol=0, atol=16 * EPS)


def test_drawn_body_axes_between_samples_are_the_motion_to_the_slerp_bound():
    """Between samples the attitude is slerped: its angle from the exact attitude at t is
    below the interpolation bound |d omega/dt|max h^2 / 8 (a quadratic's midpoint error)."""
    h = 2.0
    t = np.arange(0.0, 300.0 + h / 2, h)
    body, state, eph = _eph(t)
    frames = np.array([3.7, 55.0, 151.3, 299.0])
    exact = att.propagate(body, state, frames).rotation
    anim = PoinsotAnimation(eph, frames, figsize=(4, 2))
    w = eph.dataset.angular_velocity.values
    I = body.inertia
    wdot = np.linalg.solve(I, np.cross(w @ I.T, w).T).T             # Euler's equations
    bound = 1.1 * np.linalg.norm(wdot, axis=-1).max() * h ** 2 / 8 + 1e-14
    for k in range(frames.size):
        anim.update(k)
        drawn = Rotation.from_matrix(_drawn_axes(anim))
        angle = (drawn * exact[k].inv()).magnitude()
        assert angle <= bound, (frames[k], angle, bound)
    assert bound < 1e-3            # the bound says something: the samples are fine


@pytest.mark.parametrize("omega", [(0.02, 0.0, 0.1), (0.1, 0.0, 0.02), (0.0395, 0.0, 0.1)],
                         ids=["SAM", "LAM", "near-separatrix"])
def test_polhode_and_herpolhode_points_obey_poinsot_to_1e_12(omega):
    t = np.linspace(0.0, 600.0, 61)
    body, _, eph = _eph(t, omega)
    E = float(eph.dataset.kinetic_energy[0])
    L = float(np.linalg.norm(eph.dataset.angular_momentum[0]))
    frames = np.array([0.0, 33.3, 250.0, 417.77, 600.0])      # samples and between them
    anim = PoinsotAnimation(eph, frames, figsize=(4, 2))
    for k in range(frames.size):
        anim.update(k)
        p = _drawn_point(anim)
        # herpolhode: on the invariable plane, 2E/|L| from the origin along L (z = -L/|L|)
        assert abs(-p[2] / (2 * E / L) - 1) < 1e-12
        # polhode: the same point in the body frame, on both ellipsoids
        q = anim.trace.quaternion[k * 4]
        w_body = Rotation.from_quat(q).inv().apply(anim.scene_rotation.T @ p)
        assert abs(energy_residual(w_body, body.inertia, E)) < 1e-12
        assert abs(momentum_residual(w_body, body.inertia, L)) < 1e-12
        # the traced curves end at the point
        x, y, z = anim.artists["herpolhode"].get_data_3d()
        np.testing.assert_allclose([x[-1], y[-1], z[-1]], p, rtol=0, atol=1e-12 * L)


def test_the_time_cursor_moves_with_the_frames():
    t = np.linspace(0.0, 300.0, 31)
    _, _, eph = _eph(t)
    anim = PoinsotAnimation(eph, [0.0, 120.0, 300.0], figsize=(4, 2))
    anim.update(1)
    size, unit = anim.time_unit
    assert unit == "min" and anim.artists["cursor"].get_xdata()[0] * size == pytest.approx(120.0)


def test_gif_is_written_and_readable(tmp_path):
    from PIL import Image

    _, _, eph = _eph(np.linspace(0.0, 300.0, 31))
    out = animate(eph, tmp_path / "spin.gif", fps=5, duration=1.0, dpi=25,
                  figsize=(6, 2.4))
    with Image.open(out) as im:
        assert im.n_frames == 5
        assert im.size == (150, 60)
    assert [p.name for p in tmp_path.iterdir()] == ["spin.gif"]   # no temporary left


def test_mp4_is_written_and_readable(tmp_path):
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    _, _, eph = _eph(np.linspace(0.0, 300.0, 31))
    lines = []
    out = animate(eph, tmp_path / "spin.mp4", fps=6, duration=1.0, dpi=25,
                  figsize=(6, 2.4), progress=lambda i, n: lines.append((i, n)))
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == 6 and seconds == pytest.approx(1.0)
    assert lines == [(i, 6) for i in range(6)]


def test_unknown_suffix_is_refused_before_anything_is_written(tmp_path):
    _, _, eph = _eph(np.linspace(0.0, 300.0, 31))
    with pytest.raises(WriterError, match="suffix '.avi'"):
        animate(eph, tmp_path / "spin.avi", fps=2, duration=1.0, dpi=20)
    assert not list(tmp_path.iterdir())


def test_without_inertia_the_movie_has_the_axes_and_rates(tmp_path):
    from PIL import Image

    _, _, eph = _eph(np.linspace(0.0, 300.0, 31))
    ds = eph.dataset.copy()
    for key in ("inertia", "principal_moments"):
        del ds.attrs[key]
    ds["angular_momentum"] = ds["angular_momentum"] * np.nan
    ds["kinetic_energy"] = ds["kinetic_energy"] * np.nan
    bare = att.Ephemeris(ds)
    anim = PoinsotAnimation(bare, [0.0, 100.0], figsize=(4, 2))
    assert not anim.poinsot and "polhode_point" not in anim.artists
    anim.update(1)
    np.testing.assert_allclose(_drawn_axes(anim), eph.rotation[10].as_matrix(),
                               rtol=0, atol=16 * EPS)
    out = animate(bare, tmp_path / "bare.gif", fps=2, duration=1.0, dpi=20)
    with Image.open(out) as im:
        assert im.n_frames == 2


def test_a_body_of_a_batch_is_drawn_with_its_own_attitude():
    bodies = [att.RigidBody.from_principal_moments(MOMENTS)] * 3
    states = [att.AttitudeState("2029-04-13", Rotation.random(random_state=i),
                                [0.02, 0.0, 0.1]) for i in range(3)]
    eph = att.propagate(bodies, states, np.linspace(0.0, 300.0, 31))
    anim = PoinsotAnimation(eph, [0.0, 150.0], body_index=1, figsize=(4, 2))
    anim.update(1)
    truth = Rotation.from_quat(eph.dataset.quaternion.values[1, 15]).as_matrix()
    np.testing.assert_allclose(_drawn_axes(anim), truth,
                               rtol=0, atol=16 * EPS)


def test_under_dissipation_the_plane_follows_the_energy_and_momentum():
    """A damped run: E falls at fixed L.  In frame k the drawn point of contact lies on
    the plane drawn for that frame, at 2 E_k/|L_k| along L_k, and on the energy ellipsoid
    drawn for it (scaled by sqrt(E_k/E_0)), to 1e-12."""
    from attitude.model.torques.dissipation import EnergyDissipation

    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.05, 0.0, 0.1])
    t = np.linspace(0.0, 600.0, 121)
    eph = att.propagate(body, state, t, torques=[EnergyDissipation(time_constant=30.0)])
    E = eph.dataset.kinetic_energy.values
    assert E[-1] < 0.99 * E[0]
    anim = PoinsotAnimation(eph, t[::20], figsize=(4, 2))
    assert anim.varying
    for k in range(t[::20].size):
        anim.update(k)
        j = k * 20
        p = _drawn_point(anim)
        L = anim.scene_rotation @ eph.dataset.angular_momentum.values[j]
        n = L / np.linalg.norm(L)
        d = 2 * E[j] / np.linalg.norm(L)
        assert abs(p @ n / d - 1) < 1e-12
        plane = np.asarray(anim.artists["plane"]._faces[0])      # the corners drawn
        np.testing.assert_allclose(plane @ n, d, rtol=1e-12)
