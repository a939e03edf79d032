"""Self-shadowing of solar radiation pressure (attitude.environment.radiation): the lit
part of each facet by rays cast toward the Sun, against convex bodies (nothing shaded),
plates one behind the other (the rear one's lit area and its centroid by hand), and a
bus shaded by its solar array (the torque's sign by hand)."""

from __future__ import annotations

import importlib.util
import pickle
import sys

import numpy as np
import pytest

import attitude as att
from attitude.app.cli import main
from attitude.app.scenario import load_scenario
from attitude.environment import Facets, SolarRadiationPressure
from attitude.environment.facets import rectangle, triangle_areas
from attitude.environment.radiation import AUTO_MAX_SUBDIVISION, AUTO_SPACING
from attitude.foundations.errors import MissingDependencyError, TorqueConfigError
from attitude.foundations.quaternion import rotate
from attitude.model.surface import OpticalProperties
from attitude.propagation.compiled_torques import compile_torques

from ..tolerances import FEW_OPS, TORQUE_EVAL, assert_agree

needs_embree = pytest.mark.skipif(importlib.util.find_spec("embreex") is None,
                                  reason="embreex (the shadows extra) is not installed")

AU = 1.495978707e11
P = 1367.0 / 299_792_458.0                    # the pressure at 1 au, N/m^2: irradiance / c
SUN_X = dict(sun=[AU, 0.0, 0.0], orbit=[0.0, 0.0, 0.0], shadow=None)
BODY = att.RigidBody.from_principal_moments([400.0, 500.0, 600.0])
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def _random_attitudes(n, seed):
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _about_z(angle: float) -> np.ndarray:
    """The attitude turned by ``angle`` about z (scalar-last)."""
    return np.array([0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)])


def _sampled_ulps(k: int) -> float:
    """Round-off of a torque summed over the ``2 k^2`` samples of a rectangle: a few
    operations per sample (its position, its moment) on top of the facet sums."""
    return TORQUE_EVAL + 2 * k * k * FEW_OPS


def _scale(srp) -> float:
    """What the torque's rounding errors scale with: ``P sum_k A_k |r_k|`` (N m)."""
    f = srp.facets
    return P * float(np.sum(f.areas * np.linalg.norm(f.centroids - srp.center_of_mass,
                                                     axis=1)))


@needs_embree
def test_convex_bodies_are_unchanged():
    """A box and a 320-face ellipsoid shade nothing: the same torque and force, for
    attitudes all round."""
    q = _random_attitudes(50, 1)
    ball = att.Polyhedron.ellipsoid(1.0, 1.5, 2.0, subdivisions=2)
    for shape in (Facets.box([1.0, 2.0, 3.0], specular=0.3, diffuse=0.2),
                  Facets.from_shape(ball, OpticalProperties(0.1, 0.4))):
        plain = SolarRadiationPressure(shape, **SUN_X, center_of_mass=[0.1, -0.2, 0.3])
        shaded = SolarRadiationPressure(shape, **SUN_X, center_of_mass=[0.1, -0.2, 0.3],
                                        self_shadowing=True)
        assert_agree(shaded(0.0, q, np.zeros(3), BODY), plain(0.0, q, np.zeros(3), BODY),
                     ulps=TORQUE_EVAL, magnitude=_scale(plain))
        assert_agree(shaded.force(0.0, q), plain.force(0.0, q), ulps=TORQUE_EVAL,
                     magnitude=P * float(shape.areas.sum()))


@needs_embree
def test_unshaded_plates_keep_their_torque_through_the_samples():
    """Two plates side by side along y, one behind the other along x: each can shade the
    other in principle (so its torque goes through the sampled lit area and moment) but
    the Sun along +x finds both whole: the torque of eq. 3.73 at the facet centroids."""
    plates = Facets.join([Facets.plate(1.0, [1, 0, 0], [1.0, 0.0, 0.0], specular=0.4),
                          Facets.plate(1.0, [1, 0, 0], [0.0, 2.0, 0.5], diffuse=0.6)])
    com = [0.3, 0.4, -0.2]
    plain = SolarRadiationPressure(plates, **SUN_X, center_of_mass=com)
    for k in (1, 4):
        shaded = SolarRadiationPressure(plates, **SUN_X, center_of_mass=com,
                                        self_shadowing=True, shadow_subdivision=k)
        for q in (IDENTITY, _about_z(0.3)):
            assert_agree(shaded(0.0, q, np.zeros(3), BODY), plain(0.0, q, np.zeros(3), BODY),
                         ulps=_sampled_ulps(k), magnitude=_scale(plain))


@needs_embree
def test_rear_plate_in_the_front_plate_shadow():
    """Black square plates of 1 m^2 at x = 1 and x = 0, Sun along +x: the rear one feels
    nothing; shifted by half its width it feels half, at the centroid of its lit half
    (exactly: the shadow's edge runs along the samples' grid lines at k = 4)."""
    front = Facets.plate(1.0, [1, 0, 0], [1.0, 0.0, 0.0])
    for shift, lit in ((0.0, 0.0), (0.5, 0.5), (1.5, 1.0)):
        rear = Facets.plate(1.0, [1, 0, 0], [0.0, shift, 0.0])   # its edges along y, z
        srp = SolarRadiationPressure(Facets.join([front, rear]), **SUN_X,
                                     self_shadowing=True, shadow_subdivision=4)
        force = srp.force(0.0, IDENTITY)
        # front: P along -x; rear: P times its lit area
        assert_agree(force, [-P * (1.0 + lit), 0.0, 0.0], ulps=_sampled_ulps(4),
                     magnitude=2 * P)
        # torque about the origin: the lit part of the rear plate spans
        # y in [max(shift - 0.5, 0.5), shift + 0.5], its centroid at the middle
        y_lit = 0.5 * (max(shift - 0.5, 0.5) + shift + 0.5) if lit else 0.0
        want = [0.0, 0.0, P * lit * y_lit]         # r x F = (0, y, 0) x (-P a, 0, 0)
        assert_agree(srp(0.0, IDENTITY, np.zeros(3), BODY), want, ulps=_sampled_ulps(4),
                     magnitude=_scale(srp))


@needs_embree
@pytest.mark.parametrize("k", [2, 4, 8, 16])
def test_partial_shadow_within_the_sampling_bound(k):
    """The rear plate partly in the shadow, the Sun tilted, the shadow's edge not on the
    samples' grid: the lit area agrees with the exact one to the stated bound,
    ``(3k - 2) / k^2`` of each triangle cut, and here (an edge parallel to the grid
    lines along z) to the width of one strip of the grid, ``1 / k`` of the plate."""
    side = 1.0
    front = Facets.plate(side ** 2, [1, 0, 0], [1.0, 0.0, 0.0])
    rear = Facets.plate(side ** 2, [1, 0, 0], [0.0, 2.0 / 3.0, 0.0])
    srp = SolarRadiationPressure(Facets.join([front, rear]), **SUN_X, self_shadowing=True,
                                 shadow_subdivision=k)
    # Sun toward +x tilted by atan(0.2) about z: the front plate's shadow on the plane
    # x = 0 is the square moved by -0.2 along y, y in [-0.7, 0.3]; the rear plate spans
    # y in [1/6, 7/6]: shaded over 0.3 - 1/6 = 2/15, whatever z.
    s = np.array([1.0, 0.2, 0.0]) / np.hypot(1.0, 0.2)
    q = _about_z(-np.arctan(0.2))    # body -> inertial
    assert_agree(rotate(q, s), [1.0, 0.0, 0.0], ulps=FEW_OPS)
    f = srp.force(0.0, q)
    # black plates: F = -P A_lit cos(theta) s, inertial x-component -P A_lit cos(theta)
    cos = s[0]
    lit = -f @ s / (P * cos) - 1.0              # the rear plate's lit area
    exact = 1.0 - 2.0 / 15.0
    assert abs(lit - exact) <= (3 * k - 2) / k**2   # both triangles of the plate cut
    assert abs(lit - exact) <= 1.0 / k                # the edge inside one strip


def _clipped_area(polygon, half: float) -> float:
    """Area of a polygon (y, z) inside the square ``|y|, |z| <= half``
    (Sutherland-Hodgman clipping, then the shoelace formula)."""
    poly = [np.asarray(p, dtype=float) for p in polygon]
    for axis in (0, 1):
        for sign in (1.0, -1.0):
            out = []
            for a, b in zip(np.roll(np.array(poly), 1, axis=0), poly, strict=True):
                inside_a, inside_b = sign * a[axis] <= half, sign * b[axis] <= half
                if inside_a != inside_b:
                    t = (sign * half - a[axis]) / (b[axis] - a[axis])
                    out.append(a + t * (b - a))
                if inside_b:
                    out.append(b)
            poly = out
    y, z = np.array(poly).T
    return 0.5 * abs(float(y @ np.roll(z, -1) - z @ np.roll(y, -1)))


@needs_embree
@pytest.mark.parametrize("k", [2, 4, 8, 16, 32, None])
def test_oblique_shadow_against_polygon_clipping(k):
    """The rear plate turned in its plane (edge along (0, 1, 0.5)) under the corner of
    the front plate's shadow: its lit area against the exact one, the square clipped by
    the shadow by hand; two shadow edges cross it, so the bound is twice
    ``(3k - 2) / k^2`` (measured: 4 % at k = 4, 0.1 % at k = 16)."""
    front = Facets.plate(1.0, [1, 0, 0], [1.0, 0.0, 0.0])
    center, edge = np.array([0.6, 0.1]), np.array([1.0, 0.5]) / np.hypot(1.0, 0.5)
    rear = Facets.plate(1.0, [1, 0, 0], [0.0, *center], edge=[0.0, *edge])
    srp = SolarRadiationPressure(Facets.join([front, rear]), **SUN_X, self_shadowing=True,
                                 shadow_subdivision=k)
    if k is None:      # by default: edges of 1.41 m, extent 1.77 m, cut into <= 1/24: 16
        k = AUTO_MAX_SUBDIVISION
    lit = -srp.force(0.0, IDENTITY)[0] / P - 1.0         # black, Sun along +x
    across = np.array([-edge[1], edge[0]])
    square = [center + 0.5 * (a * edge + b * across)
              for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    exact = 1.0 - _clipped_area(square, 0.5)
    assert abs(lit - exact) <= 2 * (3 * k - 2) / k**2


@needs_embree
def test_solar_array_shading_the_bus_reverses_the_torque():
    """A 1 m cube and a black 0.5 x 1 m array 1 m in front of its +x face, over y in
    [0, 0.5]; Sun along +x, centre of mass at y = 0.05.  By hand (torque about z is
    ``-sum (y_i - y_c) F_x,i``, ``F_x = -P A``): unshaded, the bus face (A = 1, y = 0) and
    the array (A = 0.5, y = 0.25) give ``P (0.125 - 1.5 y_c) = +0.05 P``; shaded, the bus
    face keeps y in [-0.5, 0] (A = 0.5, y = -0.25): ``-P y_c = -0.05 P``."""
    y_c = 0.05
    shape = Facets.join([Facets.box([1.0, 1.0, 1.0]),
                         Facets.plate(None, [1, 0, 0], [1.5, 0.25, 0.0], size=(0.5, 1.0),
                                      edge=[0, 1, 0])])
    com = [0.0, y_c, 0.0]
    plain = SolarRadiationPressure(shape, **SUN_X, center_of_mass=com)
    # k = 4: the shadow's edge, y = 0, runs along grid lines of the bus face: exact
    shaded = SolarRadiationPressure(shape, **SUN_X, center_of_mass=com, self_shadowing=True,
                                    shadow_subdivision=4)
    w = np.zeros(3)
    assert_agree(plain(0.0, IDENTITY, w, BODY), [0, 0, P * (0.125 - 1.5 * y_c)],
                 ulps=TORQUE_EVAL, magnitude=_scale(plain))
    assert_agree(shaded(0.0, IDENTITY, w, BODY), [0, 0, -P * y_c], ulps=_sampled_ulps(4),
                 magnitude=_scale(plain))
    # a batch of attitudes is the attitudes one by one
    q = _random_attitudes(12, 3)
    batch = shaded(0.0, q, w, BODY)
    one = np.array([shaded(0.0, qi, w, BODY) for qi in q])
    assert_agree(batch, one, ulps=_sampled_ulps(4), magnitude=_scale(plain))
    # no compiled form: the integrators call the Python model
    assert shaded.compiled_parameters(BODY) is None
    assert compile_torques([shaded], BODY) is None
    assert compile_torques([plain], BODY) is not None
    # and the bound on the torque still holds
    assert np.linalg.norm(batch, axis=1).max() <= shaded.torque_bound(0.0)


@needs_embree
def test_default_subdivision_follows_the_triangle_size():
    """By default each triangle gets the smallest k that cuts its longest edge into at
    most 1/24 of the body's extent: a 0.1 m plate 1 m in front of a 2 x 1 m one (extent
    2 m, pieces of 1/12 m) takes k = 2 on its 0.141 m diagonal, the big one k = 16 (27
    capped).  Sun on the +x side: only the big plate's front is shaded (by the small
    one), the answer of k = 16; on the -x side only the small plate's back (by the big
    one), the answer of k = 2."""
    small = Facets.plate(0.01, [1, 0, 0], [1.0, 0.0, 0.0])
    big = Facets.plate(None, [1, 0, 0], [0.0, 0.0, 0.0], size=(2.0, 1.0), edge=[0, 1, 0])
    pair = Facets.join([small, big])
    assert np.ceil(np.sqrt(0.02) / (AUTO_SPACING * 2.0)) == 2
    assert np.ceil(np.sqrt(5.0) / (AUTO_SPACING * 2.0)) > AUTO_MAX_SUBDIVISION
    auto = SolarRadiationPressure(pair, **SUN_X, self_shadowing=True)
    assert list(auto.shadeable) == [1, 2]          # the faces turned to the other plate
    q = _random_attitudes(40, 9)
    sun_x = rotate(q, [1.0, 0.0, 0.0], inverse=True)[:, 0]
    for k, side in ((16, sun_x > 0), (2, sun_x < 0)):
        fixed = SolarRadiationPressure(pair, **SUN_X, self_shadowing=True,
                                       shadow_subdivision=k)
        assert side.any()
        assert_agree(auto.force(0.0, q[side]), fixed.force(0.0, q[side]),
                     ulps=_sampled_ulps(k), magnitude=P * 4.0)


@needs_embree
def test_a_pickled_model_casts_the_same_rays():
    """Models travel to dask workers and processes pickled: the embree scene is built
    again on loading, and the torque is the same."""
    pair = Facets.join([Facets.plate(1.0, [1, 0, 0], [1.0, 0.0, 0.0]),
                        Facets.plate(1.0, [1, 0, 0], [0.0, 0.5, 0.0])])
    srp = SolarRadiationPressure(pair, **SUN_X, self_shadowing=True)
    copy = pickle.loads(pickle.dumps(srp))
    q = _random_attitudes(10, 4)
    np.testing.assert_array_equal(copy(0.0, q, np.zeros(3), BODY),
                                  srp(0.0, q, np.zeros(3), BODY))


def test_facet_outlines():
    """Squares by area, rectangles by size along an edge, and outlines that must cover
    the facets."""
    tris = rectangle(None, [0, 0, 2], [1.0, 2.0, 3.0], size=(4.0, 0.5), edge=[1, 1, 0])
    assert_agree(triangle_areas(tris).sum(), 2.0, ulps=FEW_OPS)
    corners = np.unique(tris.reshape(-1, 3), axis=0)            # the four corners
    assert_agree(corners.mean(axis=0), [1.0, 2.0, 3.0], ulps=FEW_OPS)
    u, v = np.array([1.0, 1.0, 0.0]) / np.sqrt(2), np.array([-1.0, 1.0, 0.0]) / np.sqrt(2)
    assert_agree([np.ptp(corners @ u), np.ptp(corners @ v)], [4.0, 0.5], ulps=FEW_OPS)
    with pytest.raises(TorqueConfigError, match="edge"):
        rectangle(1.0, [0, 0, 1], [0, 0, 0], edge=[0, 0, 3])
    with pytest.raises(TorqueConfigError, match="size"):
        Facets.plate(2.0, [0, 0, 1], size=(1.0, 1.0))
    with pytest.raises(TorqueConfigError, match="triangles"):
        Facets([2.0], [[0, 0, 1]], [[0, 0, 0]], triangles=rectangle(1.0, [0, 0, 1], [0, 0, 0]),
               triangle_facets=[0, 0])


SCENARIO = """
[scenario]
name = "a bus shaded by its array"

[body]
principal_moments = [400.0, 500.0, 600.0]

[state]
epoch = "2016-10-19T00:00:00"
time_scale = "utc"
frame = "GCRF"
attitude = { quaternion_scalar_last = [0.1, 0.2, 0.3, 0.9273618495495703] }
omega_body = { value = [0.5, -1.0, 3.0], unit = "deg/s" }

[propagation]
duration = "20 s"
step = "10 s"
integrator_step = "1 s"

[[torques]]
type = "solar_radiation"
orbit.a = "6878 km"
shadow = "none"
center_of_mass = [0.0, 0.05, 0.0]
self_shadowing = true
shadow_subdivision = 3

[[torques.facets]]
type = "box"
size = [1.0, 1.0, 1.0]

[[torques.facets]]
type = "plate"
size = [0.5, 1.0]
edge = [0.0, 1.0, 0.0]
normal = [1.0, 0.0, 0.0]
center = [1.5, 0.25, 0.0]
"""


@needs_embree
def test_flag_through_the_scenario_file(tmp_path):
    path = tmp_path / "shaded.toml"
    path.write_text(SCENARIO)
    sc = load_scenario(path)
    (built,) = sc.torques
    assert built.self_shadowing and built.shadow_subdivision == 3
    ref = SolarRadiationPressure(
        Facets.join([Facets.box([1.0, 1.0, 1.0]),
                     Facets.plate(None, [1, 0, 0], [1.5, 0.25, 0.0], size=(0.5, 1.0),
                                  edge=[0, 1, 0])]),
        sun=built.sun, orbit=built.orbit, shadow=None, center_of_mass=[0.0, 0.05, 0.0],
        self_shadowing=True, shadow_subdivision=3)
    q = _random_attitudes(8, 5)
    assert_agree(built(np.zeros(8), q, np.zeros(3), sc.body),
                 ref(np.zeros(8), q, np.zeros(3), sc.body), ulps=_sampled_ulps(3),
                 magnitude=_scale(ref))
    # without the flag the same file gives the unshaded model
    plain = load_scenario(_write(tmp_path, SCENARIO.replace("self_shadowing = true\n", "")))
    assert not plain.torques[0].self_shadowing
    # the run goes through the Python torque path (no compiled form) and moves the rates
    eph = att.propagate(sc.body, sc.state, sc.times, torques=sc.torques, step=1.0)
    w = eph.dataset["angular_velocity"].values
    assert np.all(np.isfinite(w)) and np.abs(w[-1] - w[0]).max() > 0


def _write(tmp_path, text):
    path = tmp_path / "other.toml"
    path.write_text(text)
    return path


def test_missing_embree_names_the_extra(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "embreex", None)
    box = Facets.box([1.0, 1.0, 1.0])
    with pytest.raises(MissingDependencyError,
                       match=r"attitude-dynamics\[shadows\].*self_shadowing = false") as err:
        SolarRadiationPressure(box, **SUN_X, self_shadowing=True)
    assert err.value.key == "self_shadowing"
    # the default needs no embree
    assert SolarRadiationPressure(box, **SUN_X).self_shadowing is False
    # the scenario run exits 2 with one line naming the key and the extra
    path = tmp_path / "shaded.toml"
    path.write_text(SCENARIO)
    assert main(["run", str(path), "--quiet", "-o", str(tmp_path / "o.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith(f"attitude: error: {path}: torques[0].self_shadowing: "), err
    assert "attitude-dynamics[shadows]" in err
