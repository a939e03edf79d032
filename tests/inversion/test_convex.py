"""Convex inversion: the file reader, the Gaussian image, the model's geometry, the fit,
and Minkowski's problem, each against something independent of the code under test."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from attitude.foundations.errors import LightcurveFormatError, ShapeModelError
from attitude.inversion import (
    ConvexModel,
    GaussianImage,
    ObservedLightcurve,
    fit_convex,
    invert,
    polyhedron_from_areas,
    read_damit_lightcurves,
    real_harmonics,
    spin_to_body,
)
from attitude.photometry import Geometry

ARIADNE = Path(__file__).parents[1] / "data" / "inversion" / "ariadne_lcs_rel.txt"
EPS = np.finfo(float).eps


# --- the file ----------------------------------------------------------------------------
def test_ariadne_file_reads_as_convexinv_documents_it():
    obs = read_damit_lightcurves(ARIADNE)
    assert len(obs) == 37 and sum(len(o) for o in obs) == 1541
    assert not any(o.calibrated for o in obs)
    first = obs[0]
    # first line of the first block: JD 2438882.233275, Sun (1.467574, 1.309298, 0.08242228) au
    assert first.time[0] == 0.0
    assert first.geometry.sun_distance[0] == pytest.approx(
        1.495978707e11 * np.linalg.norm([1.467574, 1.309298, 8.242228e-02]), rel=1e-15)
    # the clock is shared: block 2 starts after block 1 ends
    assert obs[1].time[0] > obs[0].time[-1]


@pytest.mark.parametrize("text, line", [
    ("", "line 1"),
    ("x\n", "line 1"),
    ("2\n1 0\n2451545 1 1 0 0 1 0 0\n", "line 3"),             # a second block missing
    ("1\n2 0\n2451545 1 1 0 0 1 0 0\n", "line 3"),             # a point missing
    ("1\n1 2\n2451545 1 1 0 0 1 0 0\n", "line 2"),             # flag neither 0 nor 1
    ("1\n1 0\n2451545 1 1 0 0 1 0\n", "line 3"),               # 7 numbers
    ("1\n1 0\n2451545 nan 1 0 0 1 0 0\n", "line 3"),
    ("1\n1 0\n2451545 -1 1 0 0 1 0 0\n", "line 3"),            # negative brightness
    ("1\n1 0\n2451545 1 0 0 0 1 0 0\n", "line 3"),             # zero Sun vector
    ("1\n1 0\n2451545 1 1 0 0 1 0 0\nextra\n", "line 4"),
])
def test_malformed_damit_files_name_the_line(tmp_path, text, line):
    path = tmp_path / "lcs"
    path.write_text(text)
    with pytest.raises(LightcurveFormatError) as err:
        read_damit_lightcurves(path)
    assert str(err.value).startswith(f"{path}: {line}:")


def test_binary_damit_file_is_refused(tmp_path):
    path = tmp_path / "lcs"
    path.write_bytes(b"\xff\xfe1\n")
    with pytest.raises(LightcurveFormatError, match="non-ASCII"):
        read_damit_lightcurves(path)


# --- the Gaussian image ------------------------------------------------------------------
def test_real_harmonics_are_orthonormal_over_the_sphere():
    # quadrature on the triangulated sphere: exact as the triangles shrink; the error
    # of the midpoint rule on triangles of side h ~ pi / (2 rows) is O(h^2 l^2)
    image = GaussianImage(rows=24, degree=4)
    y = image.basis
    gram = (y * image.weights[:, None]).T @ y * (4 * np.pi / image.weights.sum())
    h = np.pi / 48
    assert np.abs(gram - np.eye(25)).max() < 4 * (h * 4) ** 2


def test_real_harmonics_match_closed_forms():
    rng = np.random.default_rng(1)
    d = rng.normal(size=(50, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    x, y, z = d.T
    y_lm = real_harmonics(1, d)
    c = np.sqrt(3 / (4 * np.pi))
    # the Condon-Shortley phase of scipy cancels in the real form: Y_11 = c x, Y_1-1 = c y
    np.testing.assert_allclose(y_lm[:, 1:], c * np.stack([y, z, x], axis=1), atol=8 * EPS)


def test_the_gaussian_image_of_the_sphere_closes():
    image = GaussianImage(rows=8, degree=6)
    areas = image.areas(np.zeros(49))
    assert image.normals.shape == (512, 3)
    assert image.dark_facet(areas) < 64 * EPS


# --- the model's geometry ----------------------------------------------------------------
def test_spin_to_body_is_the_inverse_of_the_documented_rotation():
    rng = np.random.default_rng(2)
    lon, lat, period, phi0 = 4.1, -0.3, 5.76 * 3600, 0.7
    t = rng.uniform(0, 30 * 86400, 20)
    v = rng.normal(size=(20, 3))
    # r_ecl = Rz(lambda) Ry(90 deg - beta) Rz(phi0 + 2 pi t / P) r_body
    phi = phi0 + 2 * np.pi * t / period
    rotations = Rotation.from_euler("ZYZ", np.stack(
        [np.full(20, lon), np.full(20, np.pi / 2 - lat), phi], axis=1))
    expected = rotations.inv().apply(v)
    np.testing.assert_allclose(spin_to_body(lon, lat, period, t, phi0, v), expected,
                               atol=64 * EPS * np.abs(v).max())


# --- the fit -----------------------------------------------------------------------------
def _synthetic(truth, pole, period, rows=10, noise=0.0, seed=0):
    """Relative lightcurves of a convex model seen from five apparitions' geometry."""
    rng = np.random.default_rng(seed)
    epoch = Time("2026-01-01", scale="tdb")
    obs = []
    for k in range(8):
        t = 86400.0 * (45 * k) + np.linspace(0, 6 * 3600, 40)
        angle = 0.8 * k
        sun = [np.cos(angle), np.sin(angle), 0.05 * k - 0.2]
        seen = [np.cos(angle + 0.3), np.sin(angle + 0.3), 0.1]
        obs.append(ObservedLightcurve(epoch, t, np.ones(t.size),
                                          Geometry(sun=sun, observer=seen)))
    model = ConvexModel(obs, GaussianImage(rows, 4))
    y = model.brightness(truth, *pole, period)
    y = y * (1 + noise * rng.normal(size=y.size))
    return [ObservedLightcurve(o.epoch, o.time, y[model.block == k], o.geometry)
            for k, o in enumerate(obs)]


def test_fit_recovers_pole_period_and_shape_of_a_model_at_another_resolution():
    truth = np.zeros(25)
    truth[[4, 6, 8, 12]] = [0.1, -0.2, 0.35, 0.1]
    pole, period = (np.radians(130.0), np.radians(40.0)), 7.3 * 3600
    obs = _synthetic(truth, pole, period, rows=12)
    model = ConvexModel(obs, GaussianImage(rows=8, degree=4))
    fit = fit_convex(model, pole[0] + 0.1, pole[1] - 0.1, period * (1 + 2e-6))
    angle = np.arccos(np.dot(_unit(fit.longitude, fit.latitude), _unit(*pole)))
    # the data are exact: what is left is the difference between the two resolutions
    assert fit.rms < 2e-3
    assert np.degrees(angle) < 1.0
    # a rotation phase off by at most 0.01 rad over the span's N turns: dP/P < 0.01/(2 pi N)
    turns = (obs[-1].time[-1] - obs[0].time[0]) / period
    assert abs(fit.period / period - 1) < 0.01 / (2 * np.pi * turns)


def _unit(lon, lat):
    return np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])


@pytest.mark.slow
def test_ariadne_inversion_agrees_with_convexinv():
    """convexinv's solution for these data (its documentation, and its run here): pole
    (253.3, -16.9) deg, P = 5.761982 h, rms 0.0157 (Kaasalainen & Torppa's model; our
    convexity weight is scaled differently, so the agreement is to the scatter of the
    pole among equally good solutions, about a degree)."""
    obs = read_damit_lightcurves(ARIADNE)
    res = invert(obs, "principal", period=5.76198 * 3600, poles=4, max_iterations=60)
    lon, lat = np.radians(res.pole)
    truth = _unit(np.radians(253.3), np.radians(-16.9))
    mirror = _unit(np.radians(73.3), np.radians(-16.9))
    angle = np.degrees(min(np.arccos(_unit(lon, lat) @ truth),
                           np.arccos(_unit(lon, lat) @ mirror)))
    assert angle < 2.0
    assert abs(res.period / (5.761982 * 3600) - 1) < 2e-6
    assert abs(res.rms / 0.0157 - 1) < 0.10
    assert res.dark_facet < 0.02
    assert res.shape.volume == pytest.approx(1.0, rel=1e-9)


# --- Minkowski's problem -----------------------------------------------------------------
def test_minkowski_returns_a_random_convex_polyhedron_from_its_areas():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(40, 3)) * [1.0, 0.7, 0.5]
    hull = ConvexHull(points)
    # merge coplanar triangles into facets: one normal, one area each
    normals = hull.equations[:, :3]
    keys, inverse = np.unique(np.round(normals, 9), axis=0, return_inverse=True)
    tri = points[hull.simplices]
    tri_area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]),
                                    axis=1)
    areas = np.bincount(inverse.ravel(), tri_area)
    shape, mismatch = polyhedron_from_areas(keys, areas, volume=hull.volume)
    assert mismatch < 1e-5
    # unique up to translation: the same support distances about the centroids
    centre = tri.mean(axis=1)  # not the centroid; use the hull's own
    v_true = points[hull.vertices] - shape_centroid(points, hull)
    v_ours = shape.vertices - shape.centroid
    support_true = (v_true @ keys.T).max(axis=0)
    support_ours = (v_ours @ keys.T).max(axis=0)
    size = np.ptp(points, axis=0).max()
    assert np.abs(support_true - support_ours).max() < 1e-3 * size
    assert centre.shape[1] == 3


def shape_centroid(points, hull):
    """Centroid of the solid hull (tetrahedra from its first vertex)."""
    o = points[hull.vertices[0]]
    tri = points[hull.simplices]
    vol = np.einsum("ij,ij->i", tri[:, 0] - o, np.cross(tri[:, 1] - o, tri[:, 2] - o)) / 6
    cent = (tri.sum(axis=1) + o) / 4
    return (np.abs(vol)[:, None] * cent).sum(axis=0) / np.abs(vol).sum()


def test_minkowski_rejects_what_is_not_a_gaussian_image():
    n = np.vstack([np.eye(3), -np.eye(3)])
    with pytest.raises(ShapeModelError, match="non-negative"):
        polyhedron_from_areas(n, [1, 1, 1, 1, 1, -1])
    with pytest.raises(ShapeModelError, match="normals"):
        polyhedron_from_areas(n, [1, 1, 1])


@pytest.mark.parametrize("cut", [1e-7, 1e-4])
def test_a_tiny_facet_still_gives_a_valid_shape_model(cut):
    """A cube with one corner cut by a plane ``cut`` inside it: a facet of side ~cut.  The
    mesh must be a valid Polyhedron (no sliver triangle).  Where the facet is too small to
    triangulate its corners become one point, moved by at most ~cut: the volume changes by
    at most that times the area of the three faces it touches (3 x 4)."""
    from attitude.inversion.minkowski import facet_mesh
    from attitude.model.shape import Polyhedron
    diagonal = np.ones(3) / np.sqrt(3)
    n = np.vstack([np.eye(3), -np.eye(3), diagonal])
    h = np.append(np.ones(6), np.sqrt(3) - cut)
    shape = Polyhedron(*facet_mesh(n, h))
    assert shape.volume == pytest.approx(8.0, abs=12.0 * cut)


def test_a_high_degree_on_few_points_rejects_overflowing_steps_quietly():
    """Degree 12 (169 coefficients) on 240 points: trial steps whose areas overflow in
    ``exp`` are rejected as a cost above any finite one (no warning, no NaN), and the fit
    still reaches the data's noise (1 % per point: rms ~0.01 in relative flux, below
    twice that with the shape's freedom)."""
    import warnings

    image = GaussianImage(rows=4, degree=2)
    t = np.linspace(0.0, 8 * 3600.0, 80)
    obs = [ObservedLightcurve(Time("2026-01-01", scale="tdb"), t + 86400.0 * k, np.ones(80),
                              Geometry(sun=[1, 0.3 * k, 0.1], observer=[1, 0.3 * k - 0.2, 0]))
           for k in range(3)]
    truth = np.zeros(9)
    truth[8] = 0.4
    m = ConvexModel(obs, image)
    y = m.brightness(truth, 0.5, 1.0, 7200.0)
    y = y * (1 + 0.01 * np.random.default_rng(1).standard_normal(y.size))
    obs = [ObservedLightcurve(o.epoch, o.time, y[m.block == k], o.geometry)
           for k, o in enumerate(obs)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = fit_convex(ConvexModel(obs, GaussianImage(rows=4, degree=12)), 0.6, 0.9,
                         7200.0 * (1 + 1e-5))
    assert np.all(np.isfinite(fit.areas)) and np.isfinite(fit.chi2)
    assert fit.rms < 0.02
