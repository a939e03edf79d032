"""Every error class is reachable as ``att.<Name>``, derives from AttitudeError and from
the builtin that describes it, and is what the package really raises."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att

ERRORS = ["InvalidInertiaError", "InvalidStateError", "ShapeModelError", "ScenarioError",
          "EphemerisFormatError", "OrbitError", "TorqueConfigError", "DiagnosticsError",
          "InsufficientDataError", "ClassificationError"]


@pytest.mark.parametrize("name", ERRORS)
def test_input_errors_are_attitude_errors_and_value_errors(name):
    cls = getattr(att, name)
    assert name in att.__all__
    assert issubclass(cls, att.AttitudeError) and issubclass(cls, ValueError)


def test_writer_error_is_an_attitude_error_and_a_runtime_error(tmp_path):
    assert "WriterError" in att.__all__
    assert issubclass(att.WriterError, att.AttitudeError)
    assert issubclass(att.WriterError, RuntimeError)
    from attitude.formats.streaming import EphemerisWriter
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.0, 0.2])
    writer = EphemerisWriter(tmp_path / "w.nc", body=body, epoch=state.epoch)
    with pytest.raises(att.WriterError, match="not open"):
        writer.append_arrays([0.0], [[0, 0, 0, 1]], [[0.1, 0.0, 0.2]])
    with pytest.raises(att.WriterError, match="not open"):
        writer.close()


def test_warnings_are_attitude_warnings():
    for cls in (att.NearSeparatrixWarning, att.InvalidBodiesWarning):
        assert issubclass(cls, att.AttitudeWarning) and issubclass(cls, UserWarning)


def test_the_top_level_classes_are_the_ones_raised():
    with pytest.raises(att.OrbitError, match="e"):
        att.KeplerOrbit.from_elements(a=7e6, e=1.5, mu=3.986e14)
    with pytest.raises(att.TorqueConfigError):
        att.torques.from_config({"type": "no_such_torque"})
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 2.5])
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.0, 0.2])
    with pytest.raises(att.InsufficientDataError):
        att.classify(att.propagate(body, state, np.array([0.0])))
    with pytest.warns(att.InvalidBodiesWarning):
        att.Ensemble.from_arrays(principal_moments=[[1.0, 1.0, 3.0]],
                                 omega_body=[[0.0, 0.0, 1.0]], epoch="2030-01-01")


@pytest.mark.parametrize("message, key, line", [
    ("rtol: expected a number in (0, 1)", "rtol", "rtol: expected a number in (0, 1)"),
    ("rtol: too large", "propagation.rtol", "propagation.rtol: too large"),   # last part
    ("propagation.rtol: too large", "propagation.rtol", "propagation.rtol: too large"),
    ("rtolerance: x", "rtol", "rtol: rtolerance: x"),        # another word: kept
    ("rtol is 2", "rtol", "rtol: rtol is 2"),                 # a sentence: kept
])
def test_a_message_names_its_key_once(message, key, line):
    err = att.AttitudeError(message, key=key)
    assert str(err) == line and err.reason == line.split(": ", 1)[1]


def test_the_rtol_of_propagate_is_named_once():
    body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    state = att.AttitudeState("2030-01-01", Rotation.identity(), [0.1, 0.0, 0.2])
    with pytest.raises(att.InvalidStateError) as info:
        att.propagate(body, state, [0.0, 1.0], method="integrator", rtol=0.0)
    assert str(info.value).startswith("rtol: expected a number in (0, 1)")
    assert str(info.value).count("rtol") == 1
