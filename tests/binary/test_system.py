"""BinarySystem, BinaryState and Impulse (attitude.binary.system): what they hold, and
every bad field raising BinarySystemError with a message naming the field."""

import astropy.units as u
import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.integrals import inertia_integrals
from attitude.foundations.errors import AttitudeError, BinarySystemError

ELLIPSOID = att.MassProperties.solid_ellipsoid
PRIMARY = att.RigidBody.from_mass_properties(ELLIPSOID(5.2e11, [425.0, 410.0, 390.0]))
SECONDARY = att.RigidBody.from_mass_properties(ELLIPSOID(4.3e9, [103.16, 79.35, 66.13]))
MOMENTS_ONLY = att.RigidBody.from_principal_moments([1.0, 2.0, 2.5], mass=1.0)
I = Rotation.identity()


def state(**changes):
    fields = dict(epoch="2022-09-26T23:14:00", position=[1190.0, 0.0, 0.0],
                  velocity=[0.0, 0.17, 0.0], primary_attitude=I,
                  primary_omega=[0.0, 0.0, 7.7e-4], secondary_attitude=I,
                  secondary_omega=[0.0, 0.0, 1.46e-4])
    fields.update(changes)
    return att.BinaryState(**fields)


# --- good input -----------------------------------------------------------------------

def test_system_holds_masses_integrals_and_the_keplerian_parameter():
    system = att.BinarySystem(PRIMARY, SECONDARY, order=4, G="6.674e-11 m3 / (kg s2)")
    m1, m2 = 5.2e11, 4.3e9
    np.testing.assert_array_equal(system.masses, [m1, m2])
    assert system.reduced_mass == pytest.approx(m1 * m2 / (m1 + m2), rel=2 * np.finfo(float).eps)
    assert system.mu == pytest.approx(6.674e-11 * (m1 + m2), rel=2 * np.finfo(float).eps)
    assert system.G == 6.674e-11 and system.gravity.order == 4
    for T, body in zip(system.integrals, (PRIMARY, SECONDARY)):
        assert T.order == 4 and T.mass == body.mass
        for a, b in zip(T.degrees, inertia_integrals(body, 4).degrees):
            np.testing.assert_array_equal(a, b)
    # a body known by its moments is enough at order 2
    assert att.BinarySystem(PRIMARY, MOMENTS_ONLY).integrals[1].order == 2


def test_state_converts_units_and_holds_both_attitudes():
    turn = Rotation.from_euler("z", 30, degrees=True)
    s = state(position=[1.19, 0, 0] * u.km, velocity=[0, 17.0, 0] * u.cm / u.s,
              secondary_attitude=turn,
              primary_omega=[0, 0, 360.0] * u.deg / u.day)
    np.testing.assert_array_equal(s.position, [1190.0, 0.0, 0.0])
    np.testing.assert_allclose(s.velocity, [0.0, 0.17, 0.0], rtol=2e-16)
    np.testing.assert_allclose(s.primary_omega, [0, 0, 2 * np.pi / 86400], rtol=4e-16)
    np.testing.assert_array_equal(s.quaternions, [I.as_quat(), turn.as_quat()])
    assert s.omegas.shape == (2, 3) and s.epoch.scale == "tdb" and s.frame == "ICRF"


def test_impulse_times_in_seconds_or_as_epochs():
    epoch = Time("2022-09-26T23:14:00", scale="tdb")
    assert att.Impulse(24.0).seconds_after(epoch) == 24.0
    assert att.Impulse(2 * u.min).seconds_after(epoch) == 120.0
    assert att.Impulse("2022-09-26T23:14:24").seconds_after(epoch) == pytest.approx(
        24.0, abs=1e-6)
    # a UTC time counts in TDB: TT - UTC = 32.184 + 37 leap seconds in 2022, and
    # TDB - TT is below 2 ms
    utc = Time("2022-09-26T23:14:24", scale="utc")
    assert att.Impulse(utc).seconds_after(epoch) == pytest.approx(24.0 + 69.184, abs=2e-3)
    kick = att.Impulse(0.0, body="primary", delta_v=[1.0, 2.0, 3.0] * u.mm / u.s,
                       angular_impulse=[0, 0, 5.0] * u.kg * u.m**2 / u.s)
    np.testing.assert_allclose(kick.delta_v, [1e-3, 2e-3, 3e-3], rtol=2e-16)
    np.testing.assert_array_equal(kick.angular_impulse, [0, 0, 5.0])
    np.testing.assert_array_equal(att.Impulse(1.0).delta_v, np.zeros(3))


# --- bad input: every field -----------------------------------------------------------

BAD_SYSTEM = [
    ("primary", dict(primary="didymos.obj")),
    ("secondary", dict(secondary=None)),
    ("primary", dict(primary=att.RigidBody.from_principal_moments([1.0, 2.0, 2.5]))),
    ("secondary", dict(secondary=att.RigidBody.from_principal_moments([1.0, 2.0, 2.5]))),
    ("secondary", dict(secondary=MOMENTS_ONLY, order=3)),
    ("primary", dict(primary=MOMENTS_ONLY, order=4)),
    ("order", dict(order=-1)),
    ("order", dict(order=2.5)),
    ("order", dict(order=True)),
    ("order", dict(order="4")),
    ("order", dict(order=None)),
    ("G", dict(G=-6.674e-11)),
    ("G", dict(G=0.0)),
    ("G", dict(G=float("nan"))),
    ("G", dict(G=float("inf"))),
    ("G", dict(G="fast")),
    ("G", dict(G="1 m/s")),
    ("G", dict(G=[6.674e-11, 1.0])),
    ("G", dict(G=[])),
]


@pytest.mark.parametrize("field, changes", BAD_SYSTEM)
def test_bad_system_field_is_named(field, changes):
    kwargs = dict(primary=PRIMARY, secondary=SECONDARY, order=2)
    kwargs.update(changes)
    with pytest.raises(BinarySystemError) as err:
        att.BinarySystem(**kwargs)
    assert str(err.value).startswith(field), str(err.value)
    assert isinstance(err.value, (AttitudeError, ValueError))


BAD_STATE = [
    ("epoch", dict(epoch="yesterday-ish")),
    ("epoch", dict(epoch=None)),
    ("epoch", dict(epoch=2459849.5)),
    ("epoch", dict(epoch=Time(["2022-09-26", "2022-09-27"]))),
    ("position", dict(position=[1190.0, 0.0])),
    ("position", dict(position=[np.nan, 0.0, 0.0])),
    ("position", dict(position=[np.inf, 0.0, 0.0])),
    ("position", dict(position=[])),
    ("position", dict(position="far")),
    ("position", dict(position=None)),
    ("position", dict(position=[0.0, 0.0, 0.0])),            # coincident centres of mass
    ("position", dict(position=[1.0, 2.0, 3.0] * u.s)),
    ("position", dict(position=[[1190.0, 0.0, 0.0]])),
    ("velocity", dict(velocity=[0.0, np.nan, 0.0])),
    ("velocity", dict(velocity=[0.0, 0.17, 0.0, 0.0])),
    ("velocity", dict(velocity="1 kg")),
    ("velocity", dict(velocity=[])),
    ("primary_attitude", dict(primary_attitude="identity")),
    ("primary_attitude", dict(primary_attitude=[0.0, 0.0, 0.0, 1.0])),
    ("secondary_attitude", dict(secondary_attitude=Rotation.random(2, random_state=0))),
    ("secondary_attitude", dict(secondary_attitude=None)),
    ("primary_omega", dict(primary_omega=[np.nan, 0.0, 0.0])),
    ("primary_omega", dict(primary_omega=[0.0, 1.0])),
    ("secondary_omega", dict(secondary_omega=[])),
    ("secondary_omega", dict(secondary_omega="spinning")),
    ("secondary_omega", dict(secondary_omega=[1.0, 2.0, 3.0] * u.m)),
    ("frame", dict(frame=3)),
]


@pytest.mark.parametrize("field, changes", BAD_STATE)
def test_bad_state_field_is_named(field, changes):
    with pytest.raises(BinarySystemError) as err:
        state(**changes)
    assert str(err.value).startswith(field), str(err.value)


def test_unknown_frame_is_named():
    with pytest.raises(BinarySystemError, match="frame"):
        state(frame="NOT_A_FRAME")


BAD_IMPULSE = [
    ("body", dict(body="tertiary")),
    ("body", dict(body=None)),
    ("body", dict(body=["secondary"])),
    ("body", dict(body=np.array(["primary", "secondary"]))),
    ("delta_v", dict(delta_v=[1.0, 2.0])),
    ("delta_v", dict(delta_v=[np.nan, 0.0, 0.0])),
    ("delta_v", dict(delta_v=[])),
    ("delta_v", dict(delta_v="quick")),
    ("delta_v", dict(delta_v=[1.0, 2.0, 3.0] * u.kg)),
    ("delta_v", dict(delta_v=None)),
    ("angular_impulse", dict(angular_impulse=[np.inf, 0.0, 0.0])),
    ("angular_impulse", dict(angular_impulse=[1.0])),
    ("angular_impulse", dict(angular_impulse=[1.0, 2.0, 3.0] * u.m / u.s)),
    ("time", dict(time=float("nan"))),
    ("time", dict(time=-np.inf)),
    ("time", dict(time="not a date")),
    ("time", dict(time=None)),
    ("time", dict(time=[1.0, 2.0])),
    ("time", dict(time=3.0 * u.kg)),
    ("time", dict(time=Time(["2022-09-26", "2022-09-27"]))),
]


@pytest.mark.parametrize("field, changes", BAD_IMPULSE)
def test_bad_impulse_field_is_named_when_made(field, changes):
    kwargs = dict(time=10.0)
    kwargs.update(changes)
    with pytest.raises(BinarySystemError) as err:
        att.Impulse(**kwargs)
    assert str(err.value).startswith(field), str(err.value)
