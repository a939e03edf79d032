"""Polyhedron.ellipsoid / ellipsoid_from_moments and the facet properties: the mesh
converges to the exact ellipsoid, its inertia has the requested ratios, and the facet
areas and normals agree with the divergence theorem."""

from __future__ import annotations

import numpy as np
import pytest

import attitude as att
from attitude.foundations.errors import ShapeModelError


def test_ellipsoid_volume_converges_quadratically():
    """The inscribed mesh's volume deficit falls by ~4 per subdivision (O(h^2))."""
    a, b, c = 3.0, 2.0, 1.0
    exact = 4 / 3 * np.pi * a * b * c
    deficits = [1 - att.Polyhedron.ellipsoid(a, b, c, subdivisions=n).volume / exact
                for n in (2, 3, 4)]
    assert all(d > 0 for d in deficits)
    assert deficits[0] / deficits[1] == pytest.approx(4, rel=0.1)
    assert deficits[1] / deficits[2] == pytest.approx(4, rel=0.1)


def test_ellipsoid_from_moments_has_the_moment_ratios():
    """Independent check: the mesh's own inertia integral (Polyhedron's tetrahedra) has
    the requested ratios A : B : C, with x the long axis (smallest moment)."""
    moments = np.array([0.61, 0.965, 1.0])
    shape = att.Polyhedron.ellipsoid_from_moments(moments, volume=2.0, subdivisions=5)
    inertia = shape.inertia_per_density()
    np.testing.assert_allclose(np.diag(inertia) / inertia[2, 2], moments, rtol=2e-4)
    assert shape.volume == pytest.approx(2.0, rel=2e-3)
    with pytest.raises(ShapeModelError, match="A \\+ B > C"):
        att.Polyhedron.ellipsoid_from_moments([1.0, 1.0, 2.0])


def test_facet_properties_close_the_surface():
    """sum A_k n_k = 0 for a closed surface, and sum A_k (n_k . c_k) / 3 = volume
    (divergence theorem)."""
    shape = att.Polyhedron.ellipsoid(2.0, 1.5, 1.0, subdivisions=2)
    areas, normals, centres = shape.face_areas, shape.face_normals, shape.face_centroids
    np.testing.assert_allclose((areas[:, None] * normals).sum(axis=0), 0.0, atol=1e-12)
    assert np.sum(areas * np.einsum("ij,ij->i", normals, centres)) / 3 == pytest.approx(
        shape.volume, rel=1e-12)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=1e-15)
    assert shape.is_convex()


def test_non_convex_and_bad_arguments():
    one = att.Polyhedron.ellipsoid(1.0, 1.0, 1.0, subdivisions=1)
    n = len(one.vertices)
    pair = att.Polyhedron(np.vstack([one.vertices, one.vertices + [3.0, 0, 0]]),
                          np.vstack([one.faces, one.faces + n]))
    assert not pair.is_convex()
    with pytest.raises(ShapeModelError, match="semi-axis b"):
        att.Polyhedron.ellipsoid(1.0, -1.0, 1.0)
    with pytest.raises(ShapeModelError, match="subdivisions"):
        att.Polyhedron.ellipsoid(1.0, 1.0, 1.0, subdivisions=9)
