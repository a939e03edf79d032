"""A tumbler's start given as a body and a state (a scenario's), not as its parameters.

The state may be at any epoch and in an equatorial frame: it is turned to the
lightcurves' ecliptic frame and propagated (the exact torque-free solution) to the first
data epoch, where the tumbler's eight parameters are read off it.
"""

from __future__ import annotations

import numpy as np
import pytest
from astropy.time import TimeDelta
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.foundations.constants import OBLIQUITY_J2000
from attitude.foundations.errors import PhotometryError
from attitude.inversion.invert import _example_tumbler, _parameters_of_state
from attitude.inversion.observations import engine_blocks
from attitude.model.sampling import tumbling_state
from attitude.propagation.torquefree import free_rotation

#: Days between the state given and the first data point (~16 precession periods).
LEAD = 1.3


def body_and_state(truth, blocks, *, frame="ICRF"):
    """A body whose frame is not its principal frame, and its state ``LEAD`` days before
    the data, in ``frame``: the tumbler of ``truth`` seen otherwise."""
    m, q, w, _ = tumbling_state(*truth)
    t0 = min(float(o.time.min()) for o in blocks)
    dt = -86400.0 * LEAD
    q_then, w_then = free_rotation(m[0], q[0], w[0], np.array([dt]))
    turn = Rotation.from_rotvec([0.2, 0.1, -0.3])                  # principal -> body
    body = att.RigidBody(turn.as_matrix() @ np.diag(m[0]) @ turn.as_matrix().T)
    b2p = body.body_to_principal
    attitude = Rotation.from_quat(q_then[0]) * b2p
    if frame == "ICRF":
        attitude = Rotation.from_rotvec([OBLIQUITY_J2000, 0.0, 0.0]) * attitude
    state = att.AttitudeState(blocks[0].epoch + TimeDelta(t0 + dt, format="sec"), attitude,
                              b2p.inv().apply(w_then[0]), frame=frame)
    return body, state


@pytest.mark.parametrize("frame", ["ICRF", "ECLIPJ2000"])
def test_a_body_and_state_give_the_tumblers_parameters(frame):
    obs, truth = _example_tumbler()
    blocks = engine_blocks(obs)
    p = _parameters_of_state(body_and_state(truth, blocks, frame=frame), blocks)
    # the exact solution over 1.3 d (16 P_phi) and back keeps the angles to ~1e-13 rad
    # (its elliptic functions to a few ulps per period); 1e-10 rad leaves a margin
    np.testing.assert_allclose(p[[0, 1, 6, 7]], np.asarray(truth)[[0, 1, 6, 7]], rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose(p[[2, 3, 4, 5]], np.asarray(truth)[[2, 3, 4, 5]],
                               rtol=1e-12)


def test_invert_starts_from_a_body_and_a_state():
    obs, truth = _example_tumbler()
    body, state = body_and_state(truth, engine_blocks(obs))
    res = att.invert(obs, rotation="tumbling", start=(body, state), rows=4, degree=2,
                     alternatives=False)
    # noise-free data of the model itself: the fit returns to the truth
    assert res.regime == "SAM" and res.rms < 1e-9
    assert res.period == pytest.approx(truth[5], rel=1e-9)


def test_a_start_in_an_unknown_frame_or_of_another_kind_is_refused():
    obs, truth = _example_tumbler()
    body, state = body_and_state(truth, engine_blocks(obs), frame="ECLIPJ2000")
    other = att.AttitudeState(state.epoch, state.attitude, state.omega_body, frame="TEME")
    with pytest.raises(PhotometryError, match="TEME") as err:
        att.invert(obs, rotation="tumbling", start=(body, other), rows=4, degree=2)
    assert err.value.key == "start.frame"
    with pytest.raises(PhotometryError, match="body and a state") as err:
        att.invert(obs, rotation="tumbling", start="guess.toml", rows=4, degree=2)
    assert err.value.key == "start"
