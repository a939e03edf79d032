"""The view of a binary system: both bodies where the ephemeris puts them, at true size,
and the libration angle against an independent construction."""

import numpy as np
import pytest

pytest.importorskip("plotly")

from scipy.spatial.transform import Rotation  # noqa: E402

import attitude as att  # noqa: E402
from attitude.binary.diagnostics import libration_angle  # noqa: E402
from attitude.pictures.poinsot import solid_semi_axes  # noqa: E402
from attitude.pictures.viewer import view  # noqa: E402

SEMI = np.array([103.16, 79.35, 66.13])
PRIMARY = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(5e11, 400.0))
SECONDARY = att.RigidBody.from_mass_properties(att.MassProperties.solid_ellipsoid(4.3e9, SEMI))


def _ephemeris(yaw_deg=12.0):
    times = np.linspace(0.0, 20000.0, 41)
    system = att.BinarySystem(PRIMARY, SECONDARY)
    n = np.sqrt(system.mu / 1190.0**3)
    state = att.BinaryState("2026-12-01", [1190.0, 0, 0], [0, n * 1190.0, 0],
                            Rotation.identity(), [0, 0, 7.7e-4],
                            Rotation.from_euler("z", yaw_deg, degrees=True), [0, 0, n])
    return att.propagate(system, state, times, method="integrator", rtol=1e-10)


def _trace(fig, name):
    return next(i for i, d in enumerate(fig.data) if d.name == name)


def test_the_secondary_is_drawn_at_the_relative_position_with_its_attitude():
    eph = _ephemeris()
    fig = view(eph, max_frames=41).figure           # frames at the samples
    k = 29
    frame = fig.frames[k]
    mesh = frame.data[frame.traces.index(_trace(fig, "secondary"))]
    points = np.column_stack([mesh.x, mesh.y, mesh.z]).astype(float)
    R = eph.dataset.relative_position.values[k] / 1e3
    # in the body frame (turned back and shifted), the vertices lie on the true-size
    # ellipsoid: float32 in the page, so 1e-6 relative of the orbit's 1.19 km scale
    body = att.Ephemeris(eph.dataset.isel(body=1)).rotation[k].inv().apply(points - R)
    residual = np.sum((body / (SEMI / 1e3)) ** 2, axis=1) - 1.0
    assert np.abs(residual).max() < 2e-6 * 1.19 / (SEMI.min() / 1e3)
    primary = frame.data[frame.traces.index(_trace(fig, "primary"))]
    centre = np.column_stack([primary.x, primary.y, primary.z]).astype(float).mean(axis=0)
    assert np.linalg.norm(centre) < 1e-3 * 0.4                 # the primary at the origin


def test_true_size_from_moments_and_mass():
    np.testing.assert_allclose(solid_semi_axes(SECONDARY.principal_moments, SECONDARY.mass),
                               SEMI, rtol=1e-14)


def test_libration_angle_is_the_long_axis_against_the_primary_direction():
    """At t = 0 the long axis is turned by the yaw from the direction away from the
    primary (either end of the axis counts); later the angle follows the independent
    construction from the rotation matrices."""
    eph = _ephemeris(yaw_deg=-20.0)
    angle = libration_angle(eph)
    assert abs(np.degrees(angle[0]) + 20.0) < 1e-9
    second = att.Ephemeris(eph.dataset.isel(body=1))
    R = eph.dataset.relative_position.values
    long_axis = second.rotation.apply([1.0, 0.0, 0.0])
    # planar motion (no tilt): the angle between the long axis and -R, modulo pi
    direct = np.arctan2(np.cross(-R, long_axis)[:, 2], np.sum(-R * long_axis, -1))
    direct = (direct + np.pi / 2) % np.pi - np.pi / 2
    np.testing.assert_allclose(angle, direct, rtol=0, atol=1e-12)
