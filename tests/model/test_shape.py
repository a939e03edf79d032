"""Tests of attitude.shape: exact mass properties of homogeneous polyhedra.

Each physics test names its independent reference: closed-form moments of a
box, an ellipsoid and a tetrahedron, or invariance under rigid motions.
"""

from __future__ import annotations

import dataclasses

import astropy.units as u
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from attitude.foundations.errors import InvalidInertiaError, ShapeModelError
from attitude.model.shape import Polyhedron

# ----------------------------------------------------------------------------- meshes
# Unit cube [0, 1]^3, two counter-clockwise (outward) triangles per side.
CUBE_VERTICES = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=float,
)
CUBE_FACES = np.array(
    [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
     [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]
)  # fmt: skip
# The same cube as outward quads (1-based, OBJ order).
CUBE_QUADS = [[1, 4, 3, 2], [5, 6, 7, 8], [1, 2, 6, 5], [2, 3, 7, 6], [3, 4, 8, 7], [4, 1, 5, 8]]

# Canonical tetrahedron (0, e1, e2, e3), outward faces.
TET_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def box(a, b, c, rotation=None, offset=(0.0, 0.0, 0.0)):
    """Vertices of an a x b x c box centred at `offset`, rotated by `rotation`."""
    vertices = (CUBE_VERTICES - 0.5) * [a, b, c]
    if rotation is not None:
        vertices = rotation.apply(vertices)
    return vertices + offset


def icosphere(level):
    """Unit icosphere: the icosahedron subdivided `level` times, vertices on the sphere."""
    t = (1 + 5**0.5) / 2
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    )  # fmt: skip
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    )  # fmt: skip
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(level):
        edges = np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        keys, inverse = np.unique(edges[:, 0] * len(v) + edges[:, 1], return_inverse=True)
        mid = v[keys // len(v)] + v[keys % len(v)]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        m01, m12, m20 = (inverse.reshape(-1, 3) + len(v)).T
        a, b, c = f.T
        f = np.concatenate(
            [np.c_[a, m01, m20], np.c_[b, m12, m01], np.c_[c, m20, m12], np.c_[m01, m12, m20]]
        )
        v = np.concatenate([v, mid])
    return v, f


def uv_sphere(n_lat, n_lon):
    """Unit UV sphere with 2 n_lon (n_lat - 1) outward triangles."""
    theta = np.pi * np.arange(1, n_lat) / n_lat
    phi = 2 * np.pi * np.arange(n_lon) / n_lon
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    v = np.concatenate([[[0.0, 0.0, 1.0]], ring.reshape(-1, 3), [[0.0, 0.0, -1.0]]])
    idx = 1 + np.arange((n_lat - 1) * n_lon).reshape(n_lat - 1, n_lon)
    nxt = np.roll(idx, -1, axis=1)
    top = np.c_[np.zeros(n_lon, int), idx[0], nxt[0]]
    bottom = np.c_[np.full(n_lon, len(v) - 1), nxt[-1], idx[-1]]
    a, b, c, d = idx[:-1], idx[1:], nxt[1:], nxt[:-1]
    upper = np.stack([a, b, c], -1).reshape(-1, 3)
    lower = np.stack([a, c, d], -1).reshape(-1, 3)
    return v, np.concatenate([top, upper, lower, bottom])


def write_obj(path, vertices, polygons, entry="{}", header=""):
    """Write an OBJ file; `entry` formats each 1-based index (e.g. "{0}//{0}")."""
    lines = [header] if header else []
    lines += ["v {!r} {!r} {!r}".format(*map(float, p)) for p in vertices]
    lines += ["f " + " ".join(entry.format(int(i)) for i in poly) for poly in polygons]
    path.write_text("\n".join(lines) + "\n")
    return path


def box_inertia(mass, a, b, c):
    """Solid box about its centre, principal frame: m (b^2 + c^2) / 12, ..."""
    return mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def assert_same_properties(p, q, rtol=1e-15):
    assert p.volume == pytest.approx(q.volume, rel=rtol)
    np.testing.assert_allclose(p.centroid, q.centroid, rtol=rtol, atol=rtol)
    scale = np.abs(q.inertia_per_density()).max()
    np.testing.assert_allclose(
        p.inertia_per_density(), q.inertia_per_density(), rtol=rtol, atol=rtol * scale
    )


# ----------------------------------------------------------------------------- exact values
def test_unit_cube_matches_closed_form():
    # Reference: solid cube, I = m (a^2 + a^2) / 12 = 1/6 for m = a = 1; products vanish.
    cube = Polyhedron(CUBE_VERTICES, CUBE_FACES)
    assert cube.volume == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(cube.centroid, [0.5, 0.5, 0.5], rtol=1e-12)
    np.testing.assert_allclose(cube.inertia_per_density(), np.eye(3) / 6, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(cube.faces, CUBE_FACES)  # outward already: not flipped


def test_offset_rotated_box_matches_closed_form():
    # Reference: solid box, I = m diag(b^2 + c^2, a^2 + c^2, a^2 + b^2) / 12 in its
    # principal frame, rotated as R I R^T; centre of mass at the box centre.
    a, b, c = 2.0, 3.0, 5.0
    rotation = Rotation.from_euler("ZXZ", [0.3, 1.1, -2.0])
    offset = np.array([1.0e3, -2.0e3, 5.0e2])
    poly = Polyhedron(box(a, b, c, rotation, offset), CUBE_FACES)
    rho = 1500.0
    mass, com, inertia = poly.mass_properties(rho)
    R = rotation.as_matrix()
    expected = R @ box_inertia(rho * a * b * c, a, b, c) @ R.T
    assert poly.volume == pytest.approx(a * b * c, rel=1e-12)
    assert mass == pytest.approx(rho * a * b * c, rel=1e-12)
    np.testing.assert_allclose(com, offset, rtol=1e-12)
    np.testing.assert_allclose(inertia, expected, rtol=1e-12, atol=1e-12 * expected.max())


def test_fine_ellipsoid_matches_closed_form():
    # Reference: solid ellipsoid, V = 4/3 pi a b c, I = m diag(b^2 + c^2, ...) / 5.
    # An inscribed icosphere (81920 faces) converges as h^2: here within 2.3e-4.
    a, b, c = 3.0, 2.0, 1.0
    v, f = icosphere(6)
    poly = Polyhedron(v * [a, b, c] + [10.0, -4.0, 7.0], f)
    rho = 2000.0
    _, com, inertia = poly.mass_properties(rho)
    volume = 4 / 3 * np.pi * a * b * c
    expected = rho * volume / 5 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    assert poly.volume == pytest.approx(volume, rel=1e-3)
    np.testing.assert_allclose(com, [10.0, -4.0, 7.0], atol=1e-9)
    np.testing.assert_allclose(inertia, expected, rtol=1e-3, atol=1e-9 * expected.max())


def test_canonical_tetrahedron():
    # Reference: the tetrahedron (0, e1, e2, e3) has V = 1/6, centroid (1/4, 1/4, 1/4) and
    # second moment about the origin C = [[2, 1, 1], [1, 2, 1], [1, 1, 2]] / 120
    # (Blow & Binstock 2004), so about the centroid C' = C - V c c^T, I = tr(C') E - C':
    # 1/80 on the diagonal and +1/480 off it.
    tet = Polyhedron(np.vstack([np.zeros(3), np.eye(3)]), TET_FACES)
    assert tet.volume == pytest.approx(1 / 6, rel=1e-14)
    np.testing.assert_allclose(tet.centroid, [0.25, 0.25, 0.25], rtol=1e-14)
    expected = np.full((3, 3), 1 / 480) + np.eye(3) * (1 / 80 - 1 / 480)
    np.testing.assert_allclose(tet.inertia_per_density(), expected, rtol=1e-13)


def test_tonon_2004_tetrahedron():
    # Reference: Tonon (2004), J. Math. Stat. 1(1), 8-11, numerical example: a, b, c on the
    # diagonal and a' (yz), b' (xz), c' (xy) products, I = [[a, -c', -b'], [-c', b, -a'],
    # [-b', -a', c]] (the paper's eq. 2 swaps b' and c'; its eq. 9e/9f define them as here).
    # The printed values carry 10 significant digits but were evidently computed from
    # slightly different inputs (the volume is quoted as 1873.233236), hence rtol 1e-7.
    vertices = [
        [8.33220, -11.86875, 0.93355],
        [0.75523, 5.00000, 16.37072],
        [52.61236, 5.00000, -5.38580],
        [2.00000, 5.00000, 3.00000],
    ]
    tet = Polyhedron(vertices, [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    a, b, c = 43520.33257, 194711.28938, 191168.76173
    a_, b_, c_ = 4417.66150, -46343.16662, 11996.20119
    expected = np.array([[a, -c_, -b_], [-c_, b, -a_], [-b_, -a_, c]])
    assert tet.volume == pytest.approx(1873.233236, rel=1e-7)
    np.testing.assert_allclose(tet.centroid, [15.92492, 0.78281, 3.72962], atol=4e-5)
    np.testing.assert_allclose(tet.inertia_per_density(), expected, rtol=1e-7)


# ----------------------------------------------------------------------------- units
@pytest.mark.parametrize("unit", ["km", u.km, 1 * u.km, "1 km", "1000 m"])
def test_length_unit_km_scales_volume_and_inertia(tmp_path, unit):
    # Reference: dimensional analysis, V ~ L^3 and I / rho ~ L^5.
    path = write_obj(tmp_path / "cube.obj", CUBE_VERTICES, CUBE_FACES + 1)
    metres = Polyhedron.from_obj(path)
    km = Polyhedron.from_obj(path, length_unit=unit)
    assert km.volume == pytest.approx(1e9 * metres.volume, rel=1e-14)
    np.testing.assert_allclose(km.centroid, 1e3 * metres.centroid, rtol=1e-14)
    np.testing.assert_allclose(
        km.inertia_per_density(), 1e15 * metres.inertia_per_density(), rtol=1e-14, atol=1e-3
    )


@pytest.mark.parametrize("unit", ["kg", u.s, "furlongs per fortnight", 3, -1 * u.m, "0 km"])
def test_bad_length_unit(tmp_path, unit):
    path = write_obj(tmp_path / "cube.obj", CUBE_VERTICES, CUBE_FACES + 1)
    with pytest.raises(ShapeModelError, match="length_unit"):
        Polyhedron.from_obj(path, length_unit=unit)


@pytest.mark.parametrize("density", ["2.6 g/cm3", 2.6 * u.g / u.cm**3, 2600 * u.kg / u.m**3])
def test_density_quantity_equals_si_float(density):
    # Reference: 2.6 g/cm^3 = 2600 kg/m^3.
    cube = Polyhedron(box(1.0, 2.0, 3.0), CUBE_FACES)
    mass, com, inertia = cube.mass_properties(density)
    mass_si, com_si, inertia_si = cube.mass_properties(2600.0)
    assert mass == pytest.approx(mass_si, rel=1e-14)
    assert mass_si == pytest.approx(2600.0 * 6.0, rel=1e-14)
    np.testing.assert_array_equal(com, com_si)
    np.testing.assert_allclose(inertia, inertia_si, rtol=1e-14, atol=1e-10)


@pytest.mark.parametrize(
    ("density", "match"),
    [
        (0.0, "positive"),
        (-2600.0, "positive"),
        (float("nan"), "finite"),
        (float("inf"), "finite"),
        ("2.6 m", "cannot be converted to 'kg / m3' .not a mass density unit"),
        (3 * u.s, "cannot be converted to 'kg / m3' .not a mass density unit"),
        ("dense", "cannot parse 'dense'"),
        ([1.0, 2.0], "expected a single number"),
        (True, "True"),
    ],
)
def test_bad_density_raises(density, match):
    cube = Polyhedron(CUBE_VERTICES, CUBE_FACES)
    with pytest.raises(InvalidInertiaError, match=match):
        cube.mass_properties(density)


# ----------------------------------------------------------------------------- OBJ syntax
@pytest.mark.parametrize(
    ("entry", "header"),
    [
        ("{}", ""),
        ("{0}/{0}/{0}", "vt 0 0\nvn 0 0 1"),
        ("{0}//{0}", "vn 0 0 1"),
        ("{0}/{0}", "vt 0.5 0.5"),
    ],
)
def test_obj_entry_variants_parse_alike(tmp_path, entry, header):
    # Reference: the array constructor on the same triangles.
    path = write_obj(tmp_path / "cube.obj", CUBE_VERTICES, CUBE_FACES + 1, entry, header)
    reference = Polyhedron(CUBE_VERTICES, CUBE_FACES)
    poly = Polyhedron.from_obj(path)
    np.testing.assert_array_equal(poly.faces, CUBE_FACES)
    assert_same_properties(poly, reference)


def test_obj_quads_comments_and_other_statements(tmp_path):
    # Reference: the array constructor on a triangulation of the same quads.
    text = "\r\n".join(
        ["# exported by a tool", "mtllib cube.mtl", "o cube", "g body"]
        + ["v {} {} {} 1.0".format(*p) for p in CUBE_VERTICES]  # optional w column
        + ["vt 0 0", "vn 0 0 -1", "usemtl rock", "s off"]
        + ["  f\t" + " ".join(f"{i}/1/1" for i in quad) for quad in CUBE_QUADS]
        + ["l 1 2", "# end"]
    )
    path = tmp_path / "cube.obj"
    path.write_text(text)
    poly = Polyhedron.from_obj(path)
    assert poly.faces.shape == (12, 3)
    assert_same_properties(poly, Polyhedron(CUBE_VERTICES, CUBE_FACES), rtol=1e-14)


def test_obj_negative_indices_count_back_from_vertices_defined_so_far(tmp_path):
    # Reference: the same cube with positive indices.  The bottom quad is written after
    # the first four vertices only, so -4..-1 refer to vertices 1..4 there, and to 5..8 later.
    lines = ["v {} {} {}".format(*p) for p in CUBE_VERTICES[:4]]
    lines += ["f -4 -1 -2 -3"]  # = f 1 4 3 2
    lines += ["v {} {} {}".format(*p) for p in CUBE_VERTICES[4:]]
    lines += ["f " + " ".join(str(i - 9) for i in quad) for quad in CUBE_QUADS[1:]]
    path = tmp_path / "cube.obj"
    path.write_text("\n".join(lines) + "\n")
    positive = write_obj(tmp_path / "positive.obj", CUBE_VERTICES, CUBE_QUADS)
    poly = Polyhedron.from_obj(path)
    np.testing.assert_array_equal(poly.faces, Polyhedron.from_obj(positive).faces)
    assert_same_properties(poly, Polyhedron(CUBE_VERTICES, CUBE_FACES), rtol=1e-14)


def test_obj_pentagon_fan_triangulation(tmp_path):
    # Reference: closed form of a regular pentagonal prism (no triangles in the file).
    k = np.arange(5)
    ring = np.c_[np.cos(2 * np.pi * k / 5), np.sin(2 * np.pi * k / 5)]
    vertices = np.r_[np.c_[ring, np.zeros(5)], np.c_[ring, np.ones(5)]]
    polygons = [[5, 4, 3, 2, 1], [6, 7, 8, 9, 10]]
    polygons += [[i + 1, (i + 1) % 5 + 1, (i + 1) % 5 + 6, i + 6] for i in range(5)]
    poly = Polyhedron.from_obj(write_obj(tmp_path / "prism.obj", vertices, polygons))
    assert poly.faces.shape == (2 * 3 + 5 * 2, 3)
    area = 5 / 2 * np.sin(2 * np.pi / 5)  # regular pentagon of circumradius 1
    assert poly.volume == pytest.approx(area, rel=1e-14)
    np.testing.assert_allclose(poly.centroid, [0, 0, 0.5], atol=1e-15)


# ----------------------------------------------------------------------------- validation
def test_inward_facing_mesh_is_flipped():
    inward = CUBE_FACES[:, ::-1]
    cube = Polyhedron(CUBE_VERTICES, inward)
    assert cube.volume == pytest.approx(1.0, rel=1e-14)
    np.testing.assert_allclose(cube.inertia_per_density(), np.eye(3) / 6, atol=1e-15)
    # every face now has an outward normal: (v1 - v0) x (v2 - v0) . (v0 - centre) > 0
    tri = cube.vertices[cube.faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", normal, tri[:, 0] - cube.centroid) > 0).all()


def test_open_mesh():
    with pytest.raises(
        ShapeModelError,
        match=r"not closed: 3 edges belong to a single face \(first: vertices \d+-\d+\)",
    ):
        Polyhedron(CUBE_VERTICES, CUBE_FACES[:-1])


def test_one_face_flipped():
    faces = CUBE_FACES.copy()
    faces[5] = faces[5, ::-1]
    with pytest.raises(ShapeModelError, match=r"inconsistently oriented: 3 edges .* faces \d+ and"):
        Polyhedron(CUBE_VERTICES, faces)


def test_non_manifold_edge():
    # two tetrahedra sharing only the edge 0-1
    vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0, -1, 0], [0, 0, -1]]
    faces = np.r_[TET_FACES, np.array([[0, 4, 1], [0, 1, 5], [0, 5, 4], [1, 4, 5]])]
    with pytest.raises(ShapeModelError, match=r"non-manifold: 1 edge is shared by .*vertices 0-1"):
        Polyhedron(vertices, faces)


def test_index_out_of_range():
    faces = CUBE_FACES.copy()
    faces[3, 1] = 8
    with pytest.raises(ShapeModelError, match=r"1 face has vertex indices out of range.*0\.\.7"):
        Polyhedron(CUBE_VERTICES, faces)
    with pytest.raises(ShapeModelError, match="out of range"):
        Polyhedron(CUBE_VERTICES, -CUBE_FACES - 1)


def test_degenerate_face():
    faces = np.r_[CUBE_FACES, [[0, 0, 6]]]
    with pytest.raises(ShapeModelError, match=r"1 face is degenerate .*first: face 12"):
        Polyhedron(CUBE_VERTICES, faces)


def test_collinear_face_is_degenerate():
    vertices = np.r_[CUBE_VERTICES, [[0.5, 0.0, 0.0]]]  # midpoint of edge 0-1
    faces = np.r_[CUBE_FACES, [[0, 8, 1]]]
    with pytest.raises(ShapeModelError, match="degenerate"):
        Polyhedron(vertices, faces)


def test_non_finite_vertex():
    vertices = CUBE_VERTICES.copy()
    vertices[6, 2] = np.nan
    with pytest.raises(ShapeModelError, match=r"1 vertex has non-finite .*vertex 6"):
        Polyhedron(vertices, CUBE_FACES)


def test_zero_volume_surface():
    # a doubly covered triangle: closed, manifold, consistently oriented, flat
    with pytest.raises(ShapeModelError, match="zero volume"):
        Polyhedron(np.eye(3), [[0, 1, 2], [0, 2, 1]])


@pytest.mark.parametrize(
    ("vertices", "faces", "match"),
    [
        (np.zeros((0, 3)), CUBE_FACES, "no vertices"),
        (CUBE_VERTICES, np.zeros((0, 3), int), "no faces"),
        (CUBE_VERTICES[:, :2], CUBE_FACES, r"shape \(n, 3\), got \(8, 2\)"),
        (CUBE_VERTICES, np.array(CUBE_QUADS) - 1, r"\(triangles\), got \(6, 4\)"),
        (CUBE_VERTICES, CUBE_FACES + 0.5, "integer"),
    ],
)
def test_bad_arrays(vertices, faces, match):
    with pytest.raises(ShapeModelError, match=match):
        Polyhedron(vertices, faces)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", "no vertices"),
        ("# only a comment\nvn 0 0 1\n", "no vertices"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"),
        ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", r"1 v line has fewer than 3 .*line 2"),
        ("v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", r"vertex coordinates on line 2"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 a\n", r"face indices on line 6"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", r"fewer than 3 vertices .*line 4"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", r"line 4 uses vertex index 0.*1-based"),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            r"index 4 on line 4, where 3 vertices are defined",
        ),
        (
            "v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n",
            r"index -2 on line 2, where 1 vertex is defined",
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not closed"),
    ],
)
def test_bad_obj_files(tmp_path, text, match):
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(ShapeModelError, match=match) as info:
        Polyhedron.from_obj(path)
    assert str(info.value).startswith(str(path))


def test_missing_file(tmp_path):
    with pytest.raises(ShapeModelError, match=r"cannot read shape model file .*nope\.obj"):
        Polyhedron.from_obj(tmp_path / "nope.obj")
    with pytest.raises(ShapeModelError, match="cannot read"):
        Polyhedron.from_obj(tmp_path)  # a directory


def test_errors_are_value_errors():
    with pytest.raises(ValueError, match="not closed"):
        Polyhedron(CUBE_VERTICES, CUBE_FACES[:-1])
    with pytest.raises(ValueError, match="positive"):
        Polyhedron(CUBE_VERTICES, CUBE_FACES).mass_properties(-1.0)


# ----------------------------------------------------------------------------- value type
def test_polyhedron_is_immutable():
    vertices = CUBE_VERTICES.copy()
    cube = Polyhedron(vertices, CUBE_FACES)
    vertices[0] = 99.0  # the caller's array is copied
    assert cube.volume == pytest.approx(1.0)
    with pytest.raises(ValueError, match="read-only"):
        cube.vertices[0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        cube.faces[0, 0] = 1
    cube.centroid[0] = 1.0  # a copy
    assert cube.centroid[0] == 0.5
    with pytest.raises(dataclasses.FrozenInstanceError):
        cube.volume = 2.0
    cube.inertia_per_density()[0, 0] = 1e9  # a copy
    assert cube.inertia_per_density()[0, 0] == pytest.approx(1 / 6)
    assert "n_faces=12" in repr(cube)


# ----------------------------------------------------------------------------- invariance
def _lumpy_asteroid():
    rng = np.random.default_rng(20040101)
    v, f = icosphere(2)
    radius = 1.0 + 0.15 * rng.standard_normal(len(v))
    return v * radius[:, None] * [1.8, 1.1, 0.7], f


ASTEROID_VERTICES, ASTEROID_FACES = _lumpy_asteroid()
ASTEROID = Polyhedron(ASTEROID_VERTICES, ASTEROID_FACES)


@settings(max_examples=40, deadline=None)
@given(
    quaternion=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
        lambda q: np.linalg.norm(q) > 0.1
    ),
    offset=st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3),
)
def test_rigid_motion_invariance(quaternion, offset):
    # Reference: volume and principal moments are invariant under rotations and
    # translations; the centroid moves with the body and I -> R I R^T.
    rotation = Rotation.from_quat(quaternion)
    moved = Polyhedron(rotation.apply(ASTEROID_VERTICES) + offset, ASTEROID_FACES)
    assert moved.volume == pytest.approx(ASTEROID.volume, rel=1e-9)
    np.testing.assert_allclose(
        np.linalg.eigvalsh(moved.inertia_per_density()),
        np.linalg.eigvalsh(ASTEROID.inertia_per_density()),
        rtol=1e-9,
    )
    np.testing.assert_allclose(
        moved.centroid, rotation.apply(ASTEROID.centroid) + offset, rtol=1e-9, atol=1e-9
    )
    R = rotation.as_matrix()
    expected = R @ ASTEROID.inertia_per_density() @ R.T
    np.testing.assert_allclose(
        moved.inertia_per_density(), expected, atol=1e-9 * np.abs(expected).max()
    )


# ----------------------------------------------------------------------------- speed
def test_100k_face_obj_loads(tmp_path):
    v, f = uv_sphere(201, 250)
    assert len(f) == 100_000
    a, b, c = 3.0, 2.0, 1.0
    text = "# 100k-face ellipsoid\no body\nvn 0 0 1\n"
    text += ("v %.9f %.9f %.9f\n" * len(v)) % tuple((v * [a, b, c]).ravel().tolist())
    text += ("f %d//1 %d//1 %d//1\n" * len(f)) % tuple((f + 1).ravel().tolist())
    path = tmp_path / "ellipsoid.obj"
    path.write_text(text)
    # (its speed, ~0.3 s, is the reader's vectorised parsing: no timing here, the suite
    # must pass on any machine under any load)
    mass, _, _ = Polyhedron.from_obj(path, length_unit="km").mass_properties(1000.0)
    assert mass == pytest.approx(1000.0 * 4 / 3 * np.pi * a * b * c * 1e9, rel=1e-3)
