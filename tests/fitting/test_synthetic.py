"""The closed-loop generators of attitude.fitting.synthetic, against what they promise:
the regime and the distances they reject on, the noise level they add (a chi-square
count), and the wrapping of angle differences."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

import attitude as att
from attitude.fitting import free_parameters
from attitude.fitting.synthetic import (
    noisy_attitudes,
    parameter_differences,
    random_state,
)
from attitude.foundations.errors import AttitudeError

BODY = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])


@pytest.mark.parametrize("regime", ["SAM", "LAM"])
def test_random_states_keep_their_regime_and_distances(regime):
    rng = np.random.default_rng(7)
    for _ in range(10):
        state = random_state(BODY, regime, rng, max_abs_dec=np.radians(45))
        d = att.diagnose(BODY, state)
        assert d.regime == regime and abs(d.separatrix_distance) > 0.1
        assert abs(free_parameters(BODY, state)[0]["angular_momentum_dec"]) \
            <= np.radians(45)


def test_random_state_names_a_bad_regime():
    with pytest.raises(AttitudeError) as err:
        random_state(BODY, "NPA", np.random.default_rng(0))
    assert err.value.key == "regime"


def test_noisy_attitudes_add_the_stated_noise():
    """The rotation vector from clean to noisy quaternions is sigma N(0, 1) per axis:
    sum |v|^2 / sigma^2 over n samples is chi-square with 3n degrees of freedom."""
    n, sigma = 2000, 1e-3
    q = att.propagate(BODY, random_state(BODY, "SAM", np.random.default_rng(1)),
                      np.linspace(0.0, 10.0, n)).dataset["quaternion"].values
    noisy = noisy_attitudes(q, sigma, np.random.default_rng(2))
    v = (Rotation.from_quat(q).inv() * Rotation.from_quat(noisy)).as_rotvec()
    stat = np.sum(v * v) / sigma**2
    assert chi2.ppf(0.0005, 3 * n) < stat < chi2.ppf(0.9995, 3 * n)


def test_differences_wrap_the_angles_only():
    truth = dict(angular_momentum_ra=0.1, angular_momentum_dec=1.5, energy_ratio=1.05,
                 ratio_a=0.6, ratio_b=0.9, precession_period=10.0, phi0=0.05, psi0=6.25)
    fitted = dict(truth, angular_momentum_ra=2 * np.pi + 0.05, angular_momentum_dec=-1.5,
                  phi0=-0.05, psi0=0.02, precession_period=10.5)
    d = parameter_differences(fitted, truth)
    assert d["angular_momentum_ra"] == pytest.approx(-0.05, abs=1e-12)
    assert d["angular_momentum_dec"] == -3.0                     # not an angle mod 2 pi
    assert d["phi0"] == pytest.approx(-0.1, abs=1e-12)
    assert d["psi0"] == pytest.approx(0.02 + 2 * np.pi - 6.25, abs=1e-12)
    assert d["precession_period"] == 0.5 and d["energy_ratio"] == 0.0
