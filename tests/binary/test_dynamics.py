"""Equations of motion of the full two-body problem (attitude.binary.dynamics) and their
DOP853 integration, against references that share no code with them: the Kepler
orbit of two spheres (attitude.model.orbit), the conservation of energy and angular
momentum, the small-amplitude libration of a synchronous secondary, and impulses.

Integrator bound.  DOP853 keeps each step's local error estimate below ``rtol`` times
each component (plus its atol, ``rtol`` of the component's scale; in Encke's form, the
form of ``integrate_dop853``, R and V are the deviation from a Kepler orbit, at most 1e-2
of the separation, with 1e-2 of that atol: their errors are smaller still), so over
``steps`` steps a conserved quantity Q drifts by at most ``steps * rtol * sum_i |y_i
dQ/dy_i|`` (the error of each component weighted by Q's sensitivity to it).  The step
count is integrate_dop853's own on this problem: :func:`dop853_steps` counts scipy's
evaluations over its Encke segments (12 a step), scipy's solve_ivp run as the module
runs it.
"""

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

import attitude as att
import attitude.binary.dynamics as dynamics
from attitude.binary.dynamics import (
    derivatives,
    energy_momentum,
    integrate_dop853,
    matrix,
    pack,
    unpack,
)
from attitude.model.orbit import KeplerOrbit
from tests.tolerances import EPS


def sphere(mass, radius):
    return att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(mass, radius))


def ellipsoid(mass, axes):
    return att.RigidBody.from_mass_properties(att.MassProperties.solid_ellipsoid(mass, axes))


def dop853_steps(system, y0, t_end, rtol) -> float:
    """Steps integrate_dop853 takes on this problem (the module docstring)."""
    evaluations = []
    real = dynamics.solve_ivp

    def counted(*args, **kwargs):
        sol = real(*args, **kwargs)
        evaluations.append(sol.nfev)
        return sol

    dynamics.solve_ivp = counted
    try:
        integrate_dop853(system, y0, [0.0, t_end], rtol=rtol)
    finally:
        dynamics.solve_ivp = real
    return sum(evaluations) / 12


def conservation_scales(system, y):
    """``sum_i |y_i dQ/dy_i|`` for Q = E and each component of L (module docstring):
    E = mu V^2/2 + U + sum w.I w/2 (U about as sensitive to R as |U|, to the attitudes
    by its non-spherical part, < |U|); L = mu R x V + sum A I w."""
    R, V, q1, w1, q2, w2 = unpack(y)
    mu = system.reduced_mass
    U = abs(energy_momentum(system, y)[0] - 0.5 * mu * V @ V
            - sum(0.5 * w @ b.inertia @ w for w, b in ((w1, system.primary),
                                                       (w2, system.secondary))))
    spins = [np.linalg.norm(b.inertia @ w) for w, b in ((w1, system.primary),
                                                         (w2, system.secondary))]
    E_scale = mu * V @ V + 3 * U + sum(w @ b.inertia @ w for w, b in
                                       ((w1, system.primary), (w2, system.secondary)))
    L_scale = 2 * mu * np.linalg.norm(R) * np.linalg.norm(V) + 3 * sum(spins)
    return E_scale, L_scale


# --- two spheres: Kepler --------------------------------------------------------------

def test_two_spheres_follow_the_kepler_orbit():
    """e = 0.5, one and a half orbits.  The relative orbit of two spheres is Keplerian with mu =
    G (m1 + m2).  Bound: the local errors sum to ``steps * rtol`` relative in R and V;
    an error in the semi-major axis of ~3 times that drifts the phase by 3/2 n t of it,
    ``9 pi N`` for N orbits: position within ``steps rtol (1 + 9 pi N) r_apo``."""
    system = att.BinarySystem(sphere(5e11, 400.0), sphere(4e9, 80.0), order=0)
    orbit = KeplerOrbit(mu=system.mu, a=1500.0, e=0.5, i=0.3, raan=1.0, argp=-0.4)
    r0, v0 = orbit.state(0.0)
    n_orbits, rtol = 1.5, 1e-12
    t = np.linspace(0.0, n_orbits * orbit.period, 7)
    y0 = pack(r0, v0, [0, 0, 0, 1.0], [0, 0, 0], [0, 0, 0, 1.0], [0, 0, 0])
    y = integrate_dop853(system, y0, t, rtol=rtol)
    r, v = orbit.state(t)
    steps = dop853_steps(system, y0, t[-1], rtol)
    growth = steps * rtol * (1 + 9 * np.pi * n_orbits)
    assert np.abs(y[:, :3] - r).max() <= growth * orbit.apoapsis
    assert np.abs(y[:, 3:6] - v).max() <= growth * np.linalg.norm(v, axis=1).max()
    E, L = energy_momentum(system, y)
    E_scale, L_scale = conservation_scales(system, y0)
    assert np.abs(E - E[0]).max() <= steps * rtol * E_scale
    assert np.abs(L - L[0]).max() <= steps * rtol * L_scale
    # the Keplerian energy and angular momentum themselves
    mu = system.reduced_mass
    assert E[0] == pytest.approx(-system.G * system.masses.prod() / (2 * orbit.a),
                                 rel=64 * EPS)
    np.testing.assert_allclose(L[0], mu * orbit.specific_angular_momentum, rtol=0,
                               atol=64 * EPS * np.linalg.norm(L[0]))


# --- ellipsoids: conservation -------------------------------------------------------

@pytest.mark.parametrize("order", [2, 3])
def test_energy_and_angular_momentum_are_conserved(order):
    """A Didymos-like pair, both bodies turning about tilted axes (every component of L
    non-zero), three hours: E and L within ``steps * rtol`` of their scales."""
    system = att.BinarySystem(ellipsoid(5.2e11, [425.0, 410.0, 390.0]),
                              ellipsoid(4.3e9, [103.16, 79.35, 66.13]), order=order)
    n = np.sqrt(system.mu / 1190.0**3)
    q1 = Rotation.from_euler("xy", [0.3, -0.2]).as_quat()
    q2 = Rotation.from_euler("zx", [0.1, 0.25]).as_quat()
    y0 = pack([1190.0, 30.0, -40.0], [0.0, n * 1190.0, 0.02], q1,
              [1e-5, 0.0, 2 * np.pi / 8136.0], q2, [2e-6, -1e-6, n])
    rtol, t_end = 1e-12, 3 * 3600.0
    y = integrate_dop853(system, y0, np.linspace(0.0, t_end, 7), rtol=rtol)
    E, L = energy_momentum(system, y)
    E_scale, L_scale = conservation_scales(system, y0)
    steps = dop853_steps(system, y0, t_end, rtol)
    assert np.abs(E - E[0]).max() <= steps * rtol * E_scale
    assert np.abs(L - L[0]).max() <= steps * rtol * L_scale
    assert (np.abs(L[0]) > 1e-3 * np.linalg.norm(L[0])).all()
    # the attitudes stay unit quaternions and the spins really change (torques act)
    np.testing.assert_allclose(np.linalg.norm(y[:, 6:10], axis=1), 1.0, rtol=0, atol=4 * EPS)
    assert np.abs(y[-1, 17:20] - y0[17:20]).max() > 1e3 * rtol * n


def test_bodies_that_do_not_spin_at_first_integrate_like_spinning_ones():
    """Regression: the absolute tolerance of a body's rate was a fraction of its initial
    rate, so a body at rest in rotation got none: DOP853 failed ("required step size
    is less than spacing between numbers") for a secondary at rest, and took 11 times
    the steps for a primary at rest.  Now either takes about the steps of a spinning
    pair (within a factor 2: the same orbit sets the step) and conserves E and L."""
    system = att.BinarySystem(ellipsoid(5.2e11, [425.0, 410.0, 390.0]),
                              ellipsoid(4.3e9, [103.16, 79.35, 66.13]), order=2)
    n = np.sqrt(system.mu / 1190.0**3)
    q2 = Rotation.from_euler("z", 0.4).as_quat()
    t_end, rtol = 2 * 3600.0, 1e-12

    def start(w1, w2):
        return pack([1190.0, 0, 0], [0, n * 1190.0, 0], [0, 0, 0, 1.0], w1, q2, w2)

    spinning = dop853_steps(system, start([0, 0, 7.7e-4], [0, 0, n]), t_end, rtol)
    for w1, w2 in (([0, 0, 0], [0, 0, 0]), ([0, 0, 0], [0, 0, n])):
        assert dop853_steps(system, start(w1, w2), t_end, rtol) <= 2 * spinning, (w1, w2)
    y0 = start([0, 0, 7.7e-4], [0, 0, 0])              # the case that failed outright
    steps = dop853_steps(system, y0, t_end, rtol)
    assert steps <= 2 * spinning
    y = integrate_dop853(system, y0, [0.0, t_end], rtol=rtol)
    E, L = energy_momentum(system, y)
    E_scale, L_scale = conservation_scales(system, y0)
    assert abs(E[1] - E[0]) <= steps * rtol * E_scale
    assert np.abs(L[1] - L[0]).max() <= steps * rtol * L_scale
    assert abs(y[1, 19]) > 1e-3 * n                   # the secondary's torque turned it


# --- a synchronous secondary: libration --------------------------------------------------

def test_synchronous_secondary_librates_at_n_sqrt_3_b_minus_a_over_c():
    """A small ellipsoid (11 x 10 x 9 m, 8.3e6 kg) on a circular orbit of 2 km about a
    1e12 kg sphere, long axis 1e-3 rad off the radius, spinning at the mean motion n.

    Leading order: ``omega = n sqrt(3 (B - A)/C)``.  The neglected first-order terms,
    each a relative change of omega: (1) ``G m1 / r^3 = n^2 m1/(m1 + m2) / (1 + q)``,
    with ``q = 3 (B + C - 2A)/(2 m2 r^2)`` the secondary's own quadrupole on the orbit:
    ``-(m2/m1 + q)/2``; (2) the orbit takes part in the libration (angular momentum is
    shared with it, and the radius responds): linearising ``phi = psi - theta``, the
    orbital rate ``nu`` and ``x = dr/r``, ``phi'' = -k phi (1/C + (1 - 4 n^2/(n^2 -
    omega^2))/(mu r^2))`` with ``k = 3 G m1 (B - A)/r^3``, i.e. ``(C/(mu r^2)) (1 - 4n^2/
    (n^2 - omega^2))/2``; (3) the amplitude: ``sin(2 phi)/2`` for ``phi`` lowers omega by
    ``phi0^2/4``.  The leading formula must hold within the sum of these; the formula
    with them within the next order: the products of the terms (< 1e-9) and the bias of
    the fit by the epicycle that the start excites (relative amplitude ``x ~ 2 n omega
    C phi0 / (mu r^2 (n^2 - omega^2))``, which modulates k by 3x and puts sidebands at
    omega +- n that the fit does not model: at most ~3x)."""
    G = att.binary.G
    m1, axes = 1e12, np.array([11.0, 10.0, 9.0])
    m2 = 2000.0 * 4 / 3 * np.pi * axes.prod()
    system = att.BinarySystem(sphere(m1, 400.0), ellipsoid(m2, axes), order=2)
    A, B, C = system.secondary.principal_moments
    r, mu = 2000.0, system.reduced_mass
    # circular: mu n^2 r = the radial pull, point mass plus the secondary's quadrupole
    # with its long axis on the radius (MacCullagh)
    n = np.sqrt((G * m1 * m2 / r**2 + 3 * G * m1 * (B + C - 2 * A) / (2 * r**4)) / (mu * r))
    phi0 = 1e-3
    y0 = pack([r, 0, 0], [0, n * r, 0], [0, 0, 0, 1.0], [0, 0, 0],
              [0, 0, np.sin(phi0 / 2), np.cos(phi0 / 2)], [0, 0, n])
    leading = n * np.sqrt(3 * (B - A) / C)
    t = np.linspace(0.0, 1.6 * 2 * np.pi / leading, 200)
    y = integrate_dop853(system, y0, t, rtol=1e-10)
    long_axis = matrix(y[:, 13:17])[:, :, 0]
    phi = np.arctan2(long_axis[:, 1], long_axis[:, 0]) - np.arctan2(y[:, 1], y[:, 0])

    def residual(p):
        return (p[0] + p[1] * np.cos(p[3] * t) + p[2] * np.sin(p[3] * t)
                + p[4] * np.cos(n * t) + p[5] * np.sin(n * t) - phi)

    fit = least_squares(residual, [0, phi0, 0, leading, 0, 0], xtol=1e-15, ftol=1e-15,
                        gtol=1e-15, x_scale=[phi0, phi0, phi0, 1e-3 * leading, phi0, phi0])
    omega = fit.x[3]

    q = 3 * (B + C - 2 * A) / (2 * m2 * r**2)
    k = 3 * G * m1 * (B - A) / r**3
    coupled = leading
    for _ in range(20):                 # omega appears in its own coupling term
        coupled = np.sqrt(k * (1 / C + (1 - 4 * n**2 / (n**2 - coupled**2)) / (mu * r**2)))
    terms = [m2 / (2 * m1), q / 2,
             C / (mu * r**2) * abs(1 - 4 * n**2 / (n**2 - coupled**2)) / 2, phi0**2 / 4]
    epicycle = 2 * n * coupled * C / (mu * r**2 * (n**2 - coupled**2))
    second = sum(terms) ** 2 + 3 * epicycle * phi0
    assert abs(omega / leading - 1) <= sum(terms) + second, (omega / leading - 1, terms)
    assert abs(omega / (coupled * (1 - phi0**2 / 4)) - 1) <= second
    assert sum(terms) > 100 * second            # the corrections are resolved
    assert abs(fit.x[1] - phi0) <= 1e-3 * phi0   # the amplitude is the one set


# --- impulses ------------------------------------------------------------------------

def _impulse_run(body, delta_v=(0, 0, 0), angular_impulse=(0, 0, 0)):
    system = att.BinarySystem(ellipsoid(5.2e11, [425.0, 410.0, 390.0]),
                              ellipsoid(4.3e9, [103.16, 79.35, 66.13]), order=2)
    n = np.sqrt(system.mu / 1190.0**3)
    state = att.BinaryState("2022-09-26T23:00:00", [1190.0, 50.0, 0.0],
                            [0.0, n * 1190.0, 0.01],
                            Rotation.from_euler("xyz", [0.2, 0.1, -0.3]),
                            [0.0, 1e-5, 2 * np.pi / 8136.0],
                            Rotation.from_euler("xyz", [-0.1, 0.3, 0.5]), [1e-6, 0.0, n])
    times = [0.0, 1800.0]
    kick = att.Impulse(1800.0, body=body, delta_v=delta_v, angular_impulse=angular_impulse)
    before = att.propagate(system, state, times, method="integrator").dataset
    after = att.propagate(system, state, times, method="integrator", events=[kick]).dataset
    return system, before.isel(time=-1), after.isel(time=-1)


@pytest.mark.parametrize("body, sign", [("secondary", 1.0), ("primary", -1.0)])
def test_delta_v_changes_the_relative_velocity_by_exactly_delta_v(body, sign):
    """The same integration up to the impulse (the same call on the same inputs), so the
    only difference is the impulse: V + dv rounds to half an ulp of |V + dv|; the
    angular momentum changes by ``sign mu R x dv`` (the impulse m dv at the body's
    place about the centre of mass), to the rounding of L's terms."""
    dv = np.array([-2.98e-3, 1.1e-3, 0.4e-3])
    system, before, after = _impulse_run(body, delta_v=dv)
    V0, V1 = before.relative_velocity.values, after.relative_velocity.values
    np.testing.assert_allclose(V1 - V0, sign * dv, rtol=0, atol=2 * np.spacing(
        np.abs(V1).max()))
    np.testing.assert_array_equal(after.relative_position.values,
                                  before.relative_position.values)
    L0, L1 = before.total_angular_momentum.values, after.total_angular_momentum.values
    R = before.relative_position.values
    expected = sign * system.reduced_mass * np.cross(R, dv)
    assert np.abs(L1 - L0 - expected).max() <= 16 * EPS * np.abs(L1).max()


@pytest.mark.parametrize("body", ["secondary", "primary"])
def test_angular_impulse_changes_the_total_angular_momentum_by_exactly_it(body):
    """``w += I^-1 A^T dH``, so ``A I w`` grows by dH: the rounding of the solve (the
    inertia's condition number, ~1.2, times a few ulps of dH), of the two rotations
    (3 ulp each) and of L's sum (a few ulps of |L|)."""
    system, before, _ = _impulse_run(body)
    spin = np.linalg.norm(system.primary.inertia @ [0, 1e-5, 2 * np.pi / 8136.0])
    dH = np.array([0.3, -0.2, 0.5]) * 1e-2 * spin
    system, before, after = _impulse_run(body, angular_impulse=dH)
    L0, L1 = before.total_angular_momentum.values, after.total_angular_momentum.values
    I = (system.secondary if body == "secondary" else system.primary).inertia
    cond = np.linalg.cond(I)
    bound = 8 * EPS * np.abs(L1).max() + (4 * cond + 12) * EPS * np.linalg.norm(dH)
    assert np.abs(L1 - L0 - dH).max() <= bound
    np.testing.assert_array_equal(after.relative_velocity.values,
                                  before.relative_velocity.values)
    index = 1 if body == "secondary" else 0
    other = 1 - index
    np.testing.assert_array_equal(after.angular_velocity.values[other],
                                  before.angular_velocity.values[other])


# --- the right-hand side ------------------------------------------------------------

def test_derivatives_of_a_batch_equal_single_states():
    system = att.BinarySystem(ellipsoid(5.2e11, [425.0, 410.0, 390.0]),
                              ellipsoid(4.3e9, [103.16, 79.35, 66.13]), order=3)
    rng = np.random.default_rng(1)
    ys = np.stack([pack(rng.normal(size=3) * 300 + [1200, 0, 0], rng.normal(size=3) * 0.1,
                        Rotation.random(random_state=i).as_quat(), rng.normal(size=3) * 1e-4,
                        Rotation.random(random_state=i + 9).as_quat(),
                        rng.normal(size=3) * 1e-4) for i in range(4)])
    batch = derivatives(system, ys)
    for y, d in zip(ys, batch):
        one = derivatives(system, y)
        # the same operations on each state; einsum/matmul may group sums differently
        # over a batch: a few ulps of each part's scale
        for a, b in zip(unpack(d), unpack(one)):
            np.testing.assert_allclose(a, b, rtol=0, atol=64 * EPS * np.abs(b).max())


def test_derivatives_of_a_list_equal_those_of_an_array():
    """A state given as a list (it used to fail: part of the code indexed the input)."""
    system = att.BinarySystem(sphere(1e9, 50.0), ellipsoid(1e8, [30.0, 20.0, 10.0]))
    y = pack([500.0, 0, 0], [0, 0.01, 0], [0, 0, 0, 1.0], [0, 0, 1e-4],
             Rotation.from_euler("z", 0.3).as_quat(), [0, 0, 1e-4])
    np.testing.assert_array_equal(derivatives(system, y.tolist()), derivatives(system, y))


def test_polyhedral_primary_off_its_origin_conserves_energy_and_momentum():
    """A non-convex L prism whose vertices sit far from its centre of mass (its frame's
    origin is not the centre of mass: the integrals and the inertia are about the latter)
    with every degree present, at order 3, G = 1 to keep the times short; half an orbit
    at close range (R / size ~ 3) where the torques are large."""
    from attitude.model.body import MassDistribution
    from attitude.model.shape import Polyhedron
    from tests.binary.test_integrals import l_prism

    base = l_prism(0.75)
    shape = Polyhedron(base.vertices + [5.0, -3.0, 2.0], base.faces)
    mass, com, inertia = shape.mass_properties(1.0)
    primary = att.RigidBody(inertia, mass=mass, center_of_mass=com,
                            distribution=MassDistribution("polyhedron", mass, shape=shape))
    system = att.BinarySystem(primary, ellipsoid(0.5, [0.6, 0.4, 0.3]), order=3, G=1.0)
    r = 8.0
    n = np.sqrt(system.mu / r**3)
    y0 = pack([r, 1.0, 0.5], [0.0, n * r, 0.1 * n * r],
              Rotation.from_euler("xyz", [0.3, -0.5, 0.2]).as_quat(), [0.3 * n, -0.6 * n, 1.5 * n],
              Rotation.from_euler("zy", [0.7, 0.2]).as_quat(), [0.0, 0.1, n])
    rtol, t_end = 1e-12, np.pi / n
    y = integrate_dop853(system, y0, np.linspace(0.0, t_end, 5), rtol=rtol)
    E, L = energy_momentum(system, y)
    E_scale, L_scale = conservation_scales(system, y0)
    steps = dop853_steps(system, y0, t_end, rtol)
    assert np.abs(E - E[0]).max() <= steps * rtol * E_scale
    assert np.abs(L - L[0]).max() <= steps * rtol * L_scale
    # the spins were changed by the torques far beyond what the bounds allow
    assert np.abs(y[-1, 10:13] - y0[10:13]).max() > 1e3 * steps * rtol * 1.5 * n
