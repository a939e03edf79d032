"""Mass properties: primitives against textbook formulas, composition (parallel-axis
theorem) against independent constructions, validation errors."""

import numpy as np
import pytest
from astropy import units as u
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import attitude as att
from attitude import InvalidInertiaError, MassProperties, RigidBody

finite = st.floats(-5.0, 5.0, allow_nan=False)
positive = st.floats(0.1, 10.0)


# --- RigidBody from tensors ----------------------------------------------------------

def test_principal_moments_sorted_and_frame_right_handed():
    body = RigidBody.from_principal_moments([3.0, 1.0, 2.0])
    np.testing.assert_array_equal(body.principal_moments, [1.0, 2.0, 3.0])
    V = body.principal_axes
    assert np.linalg.det(V) == pytest.approx(1.0, abs=1e-15)
    # V^T I V is diag(A, B, C): the principal frame diagonalises the tensor
    np.testing.assert_allclose(V.T @ body.inertia @ V, np.diag([1.0, 2.0, 3.0]), atol=1e-15)
    np.testing.assert_allclose(body.body_to_principal.as_matrix(), V.T, atol=1e-15)


def test_quantities_are_converted_to_si():
    body = RigidBody.from_principal_moments([1.0, 2.0, 2.5] * u.Unit("g cm2"))
    np.testing.assert_allclose(body.principal_moments, [1e-7, 2e-7, 2.5e-7], rtol=1e-15)
    body = RigidBody.from_principal_moments(u.Quantity([2.0, 3.0, 4.0], "kg km2"))
    np.testing.assert_allclose(body.principal_moments, [2e6, 3e6, 4e6], rtol=1e-15)


@st.composite
def inertia_tensors(draw):
    """Physical tensors: principal moments from a random mass distribution, rotated."""
    a, b, c = (draw(positive) for _ in range(3))      # ellipsoid semi-axes
    m = draw(positive)
    props = MassProperties.solid_ellipsoid(m, [a, b, c])
    q = draw(st.lists(finite, min_size=4, max_size=4).filter(
        lambda v: np.linalg.norm(v) > 0.1))
    return props.inertia, Rotation.from_quat(q).as_matrix()


@settings(max_examples=60, deadline=None)
@given(inertia_tensors())
def test_principal_moments_invariant_under_rotation(sample):
    """Principal moments are the eigenvalues of I: invariant under I -> R I R^T."""
    inertia, R = sample
    a = RigidBody(inertia)
    b = RigidBody(R @ inertia @ R.T)
    np.testing.assert_allclose(b.principal_moments, a.principal_moments,
                               rtol=1e-12, atol=1e-14 * a.principal_moments[2])
    # and the principal axes rotate with the body: V_b diagonalises the rotated tensor
    Vb = b.principal_axes
    np.testing.assert_allclose(Vb.T @ b.inertia @ Vb, np.diag(b.principal_moments),
                               atol=1e-12 * a.principal_moments[2])


# --- validation ----------------------------------------------------------------------

@pytest.mark.parametrize("inertia, match", [
    (np.diag([1.0, 1.0, 3.0]), "triangle inequality"),
    (np.diag([0.0, 1.0, 1.0]), "not positive-definite"),
    (np.diag([-1.0, 2.0, 2.0]), "not positive-definite"),
    ([[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], r"not symmetric: \[0\]\[1\]"),
    ([[1.0, 0.0, 0.0], [0.0, np.nan, 0.0], [0.0, 0.0, 1.0]], r"inertia\[1\]\[1\] = nan"),
    (np.eye(2), "expected a 3x3 tensor"),
    ("3 kg m2", "expected a 3x3 tensor"),
    (np.eye(3) * u.kg, "cannot be converted"),
])
def test_invalid_inertia_is_refused_with_a_clear_message(inertia, match):
    with pytest.raises(InvalidInertiaError, match=match):
        RigidBody(inertia)


def test_invalid_inertia_error_is_a_value_error_and_names_the_fix():
    with pytest.raises(ValueError) as info:
        RigidBody.from_principal_moments([1.0, 1.0, 2.5])
    msg = str(info.value)
    assert "A = 1" in msg and "C = 2.5" in msg and "units" in msg
    assert isinstance(info.value, att.AttitudeError)


def test_triangle_equality_of_a_thin_plate_is_accepted():
    # A thin plate sits exactly on A + B = C; rounding must not reject it.
    body = RigidBody.from_mass_properties(MassProperties.thin_plate(3.0, [0.7, 0.3]))
    A, B, C = body.principal_moments
    assert A + B == pytest.approx(C, rel=1e-15)


@pytest.mark.parametrize("kwargs, match", [
    (dict(mass=-1.0, size=[1, 1, 1]), "mass = -1.0"),
    (dict(mass=1.0, size=[1, 0, 1]), "lengths must be positive"),
    (dict(mass=1.0, size=[1, 1]), "expected 3 lengths"),
    (dict(mass="1 m", size=[1, 1, 1]), "cannot be converted"),
])
def test_invalid_primitive_parameters(kwargs, match):
    with pytest.raises(InvalidInertiaError, match=match):
        MassProperties.solid_box(**kwargs)


def test_invalid_mass_and_unknown_primitive():
    with pytest.raises(InvalidInertiaError, match="mass = nan"):
        RigidBody(np.eye(3), mass=float("nan"))
    with pytest.raises(InvalidInertiaError, match="primitive 'cone' is unknown"):
        MassProperties.from_primitive("cone", mass=1.0)
    with pytest.raises(InvalidInertiaError, match="inner_radius = 2.0 m exceeds"):
        MassProperties.hollow_cylinder(1.0, outer_radius=1.0, length=1.0, inner_radius=2.0)
    with pytest.raises(InvalidInertiaError, match="expected 2 masses for 2 positions"):
        MassProperties.point_masses([1.0], [[0, 0, 1], [0, 0, -1]])


def test_symmetry_tolerance_is_explicit():
    assert RigidBody.from_principal_moments([1.0, 1.0, 1.5]).symmetry == "oblate"
    assert RigidBody.from_principal_moments([1.0, 1.5, 1.5]).symmetry == "prolate"
    assert RigidBody.from_principal_moments([2.0, 2.0, 2.0]).symmetry == "spherical"
    eps = 10 * att.SYMMETRY_RTOL
    assert RigidBody.from_principal_moments([1.0, 1.0 + eps, 1.5]).symmetry == "triaxial"
    eps = 0.1 * att.SYMMETRY_RTOL
    assert RigidBody.from_principal_moments([1.0, 1.0 + eps, 1.5]).symmetry == "oblate"


# --- primitives vs textbook formulas ------------------------------------------------

def test_primitives_match_textbook_formulas():
    m = 2.0
    # Goldstein / any table of moments of inertia
    np.testing.assert_allclose(np.diag(MassProperties.solid_sphere(m, 3.0).inertia),
                               [0.4 * m * 9] * 3)
    np.testing.assert_allclose(np.diag(MassProperties.spherical_shell(m, 3.0).inertia),
                               [2 / 3 * m * 9] * 3)
    np.testing.assert_allclose(np.diag(MassProperties.solid_cylinder(m, 1.0, 4.0).inertia),
                               [m * (3 + 16) / 12, m * (3 + 16) / 12, m / 2])
    np.testing.assert_allclose(np.diag(MassProperties.thin_rod(m, 3.0).inertia),
                               [m * 9 / 12, m * 9 / 12, 0.0])
    np.testing.assert_allclose(
        np.diag(MassProperties.hollow_cylinder(m, 2.0, 1.0, inner_radius=1.0).inertia),
        [m * (3 * 5 + 1) / 12, m * (3 * 5 + 1) / 12, m * 5 / 2])


def test_thick_shell_tends_to_thin_shell_and_solid_sphere():
    m, r = 1.5, 2.0
    thin = MassProperties.spherical_shell(m, r, inner_radius=r * (1 - 1e-9)).inertia[0, 0]
    assert thin == pytest.approx(2 / 3 * m * r**2, rel=1e-8)
    solid = MassProperties.spherical_shell(m, r, inner_radius=0.0).inertia[0, 0]
    assert solid == pytest.approx(0.4 * m * r**2, rel=1e-15)


def test_hollow_cylinder_is_a_solid_cylinder_minus_its_core():
    """Independent construction: mass-weighted difference of two solid cylinders."""
    rho_vol = 1.0
    R1, R2, h = 0.4, 1.0, 2.0
    m_outer, m_inner = rho_vol * np.pi * R2**2 * h, rho_vol * np.pi * R1**2 * h
    diff = (MassProperties.solid_cylinder(m_outer, R2, h).inertia
            - MassProperties.solid_cylinder(m_inner, R1, h).inertia)
    tube = MassProperties.hollow_cylinder(m_outer - m_inner, R2, h, inner_radius=R1)
    np.testing.assert_allclose(tube.inertia, diff, rtol=1e-14)


def test_point_masses_match_direct_sum():
    rng = np.random.default_rng(1)
    ms = rng.uniform(0.5, 2.0, 5)
    pos = rng.normal(size=(5, 3))
    props = MassProperties.point_masses(ms, pos)
    com = (ms[:, None] * pos).sum(0) / ms.sum()
    r = pos - com
    direct = sum(m * (ri @ ri * np.eye(3) - np.outer(ri, ri)) for m, ri in zip(ms, r))
    np.testing.assert_allclose(props.center_of_mass, com, rtol=1e-14)
    np.testing.assert_allclose(props.inertia, direct, rtol=1e-13, atol=1e-14)


# --- composition ----------------------------------------------------------------------

def test_box_from_eight_sub_boxes():
    """A box cut into eight octants and reassembled with the parallel-axis theorem."""
    a, b, c, m = 2.0, 3.0, 5.0, 8.0
    octant = MassProperties.solid_box(m / 8, [a / 2, b / 2, c / 2])
    parts = [octant.placed([sx * a / 4, sy * b / 4, sz * c / 4])
             for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    whole = MassProperties.from_parts(parts)
    np.testing.assert_allclose(whole.inertia, MassProperties.solid_box(m, [a, b, c]).inertia,
                               rtol=1e-14)
    np.testing.assert_allclose(whole.center_of_mass, 0.0, atol=1e-15)
    assert whole.mass == pytest.approx(m, rel=1e-15)


@settings(max_examples=60, deadline=None)
@given(st.lists(finite, min_size=3, max_size=3), positive, positive,
       st.lists(finite, min_size=4, max_size=4).filter(lambda v: np.linalg.norm(v) > 0.1))
def test_parallel_axis_theorem(offset, m, size, quat):
    """I_about_point = I_cm + m (|d|^2 1 - d d^T), and placement commutes with it."""
    part = MassProperties.solid_ellipsoid(m, [size, 1.3 * size, 0.7 * size])
    R = Rotation.from_quat(quat)
    placed = part.placed(offset, R)
    d = np.asarray(offset)
    expected_origin = (R.as_matrix() @ part.inertia @ R.as_matrix().T
                       + m * (d @ d * np.eye(3) - np.outer(d, d)))
    np.testing.assert_allclose(placed.inertia_about([0, 0, 0]), expected_origin,
                               rtol=1e-12, atol=1e-12 * np.abs(expected_origin).max())
    np.testing.assert_allclose(placed.center_of_mass, d, atol=1e-14)
    # Summing two identical placed parts symmetric about the origin: I = 2 I_origin
    twin = part.placed(-d, R)
    pair = placed + twin
    np.testing.assert_allclose(pair.inertia, 2 * expected_origin, rtol=1e-12,
                               atol=1e-12 * np.abs(expected_origin).max())


def test_satellite_bus_with_two_solar_panels():
    """Hand calculation: box bus 1 x 1 x 2 m, 500 kg; panels 3 x 1 m, 20 kg each,
    centred 2 m from the bus centre along x."""
    bus = MassProperties.solid_box(500.0, [1.0, 1.0, 2.0])
    panel = MassProperties.thin_plate(20.0, [3.0, 1.0])
    body = RigidBody.from_parts([bus, panel.placed([2.0, 0, 0]), panel.placed([-2.0, 0, 0])])
    Ixx = 500 / 12 * (1 + 4) + 2 * (20 / 12 * 1)
    Iyy = 500 / 12 * (1 + 4) + 2 * (20 / 12 * 9 + 20 * 4)
    Izz = 500 / 12 * (1 + 1) + 2 * (20 / 12 * 10 + 20 * 4)
    np.testing.assert_allclose(np.diag(body.inertia), [Ixx, Iyy, Izz], rtol=1e-14)
    assert body.mass == 540.0


def test_explorer_1_cylinder_with_four_whip_antennas():
    """Explorer 1 (validation/README.md, dimensions unverified): a 2.03 m x 0.152 m
    cylinder of 14 kg with four whips at 90 deg about its axis.  The whips make the
    transverse and axial moments comparable; checked against an independent sum of
    rods written out by hand."""
    cyl = MassProperties.solid_cylinder(13.6, radius=0.076, length=2.03)
    L, mw, r0 = 0.56, 0.1, 0.076          # whip length (m) and mass (kg), root radius
    whips = []
    for k in range(4):
        ang = k * np.pi / 2
        # a rod along z, turned to lie radially along (cos ang, sin ang, 0)
        R = Rotation.from_euler("yz", [90.0, np.degrees(ang)], degrees=True)
        centre = (r0 + L / 2) * np.array([np.cos(ang), np.sin(ang), 0.0])
        whips.append(MassProperties.thin_rod(mw, L).placed(centre, R))
    body = RigidBody.from_parts([cyl] + whips)
    # independent: a radial rod from r0 to r0+L contributes m (r0^2 + r0 L + L^2/3) about z
    Iz_whips = 4 * mw * (r0**2 + r0 * L + L**2 / 3)
    Iz = 13.6 * 0.076**2 / 2 + Iz_whips
    assert body.inertia[2, 2] == pytest.approx(Iz, rel=1e-12)
    # about x: whips along x contribute nothing; whips along y contribute like about z
    Ix = 13.6 * (3 * 0.076**2 + 2.03**2) / 12 + 2 * mw * (r0**2 + r0 * L + L**2 / 3)
    assert body.inertia[0, 0] == pytest.approx(Ix, rel=1e-12)
    # four-fold symmetry about the axis: a prolate axisymmetric body, A about the axis
    assert body.symmetry == "prolate"
    assert body.principal_moments[0] == pytest.approx(Iz, rel=1e-12)


def test_body_batch_moved_from_splitting_warns():
    """``BodyBatch`` moved to attitude.body (the batch normaliser); the old path warns."""
    import attitude.model.body
    import attitude.propagation.splitting as splitting

    with pytest.warns(DeprecationWarning, match="use attitude.model.body.BodyBatch"):
        cls = splitting.BodyBatch
    assert cls is attitude.model.body.BodyBatch
    batch, single = attitude.model.body.as_bodies([RigidBody.from_principal_moments([1, 2, 3])] * 3)
    assert isinstance(batch, cls) and not single and batch.principal_moments.shape == (3, 3)
