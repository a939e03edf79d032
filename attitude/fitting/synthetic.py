"""Synthetic closed loops: hidden states, noisy observations of them, perturbed guesses.

The checks of the fitting wing (its tests and ``benchmarks/fitting_coverage.py``) run the
same loop: draw a hidden torque-free state, synthesise observations from it with the exact
solution and Gaussian noise of known sigma, fit from a perturbed guess, and compare the
fitted parameters with the truth.  This module holds the pieces of that loop so that every
check draws its cases the same way:

- :func:`random_state` -- a random SAM or LAM state of a body, away from the separatrix
  (and, optionally, with L away from the inertial poles);
- :func:`noisy_attitudes` -- quaternions turned by Gaussian rotation vectors;
- :func:`synthetic_lightcurve` -- magnitudes of a shape along the exact solution, plus
  Gaussian noise;
- :func:`perturbed_state` -- a first guess near a state;
- :func:`parameter_differences` -- fitted minus true parameters, angles wrapped.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations.errors import AttitudeError
from ..model.body import RigidBody
from ..model.freebody import diagnose
from ..model.state import AttitudeState
from ..propagation.propagator import propagate
from .observations import LightcurveObservations
from .parameters import PARAMETERS, free_parameters

__all__ = ["random_state", "noisy_attitudes", "synthetic_lightcurve", "perturbed_state",
           "parameter_differences", "WRAPPED"]

#: The parameters compared modulo 2 pi (the declination of L is not wrapped).
WRAPPED = ("angular_momentum_ra", "phi0", "psi0")


def random_state(body: RigidBody, regime: str, rng: np.random.Generator, *,
                 epoch="2029-04-13T00:00:00", rate: float = 0.3,
                 min_separatrix_distance: float = 0.1,
                 max_abs_dec: float | None = None) -> AttitudeState:
    """A random SAM or LAM state of ``body``, drawn by rejection.

    Each draw takes a uniformly random attitude (``Rotation.random``) and body rates
    ``rate * w``, ``w`` standard normal with its C component (SAM) or A component (LAM)
    multiplied by 4, and keeps the first draw whose regime is ``regime``, whose
    ``abs(separatrix_distance)`` (:func:`attitude.diagnose`) exceeds
    ``min_separatrix_distance`` and, if ``max_abs_dec`` is given, whose L has
    ``abs(angular_momentum_dec) <= max_abs_dec`` (rad): the parameterisation by the
    direction of L is singular at the inertial poles (see
    :mod:`attitude.fitting.parameters`).

    Parameters
    ----------
    body : RigidBody
        A triaxial body (its body frame is taken as principal: the rates are drawn in it).
    regime : {"SAM", "LAM"}
    rng : numpy.random.Generator
    epoch : str or Time
    rate : float
        Scale of the rates, rad/s.
    min_separatrix_distance : float
    max_abs_dec : float, optional
        Largest declination of L, rad.

    Returns
    -------
    AttitudeState

    Raises
    ------
    AttitudeError
        ``key="regime"`` for a regime other than SAM or LAM.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> rng = np.random.default_rng(1)
    >>> state = random_state(body, "LAM", rng, max_abs_dec=np.radians(60))
    >>> att.diagnose(body, state).regime
    'LAM'
    >>> p, _ = free_parameters(body, state)
    >>> bool(abs(p["angular_momentum_dec"]) <= np.radians(60))
    True
    """
    if regime not in ("SAM", "LAM"):
        raise AttitudeError(f"must be 'SAM' or 'LAM', not {regime!r}", key="regime")
    while True:
        w = rng.normal(size=3)
        w[2 if regime == "SAM" else 0] *= 4
        state = AttitudeState(epoch, Rotation.random(random_state=rng), rate * w)
        d = diagnose(body, state)
        if d.regime != regime or abs(d.separatrix_distance) <= min_separatrix_distance:
            continue
        if max_abs_dec is not None and \
                abs(free_parameters(body, state)[0]["angular_momentum_dec"]) > max_abs_dec:
            continue
        return state


def noisy_attitudes(q: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Quaternions (T, 4) turned by body-frame rotation vectors ``sigma * N(0, 1)`` per
    axis (``sigma`` in rad): the noise model of
    :class:`~attitude.fitting.AttitudeObservations`.

    Examples
    --------
    >>> import numpy as np
    >>> q = np.tile([0.0, 0.0, 0.0, 1.0], (1000, 1))
    >>> noisy = noisy_attitudes(q, 1e-3, np.random.default_rng(0))
    >>> angle = 2 * np.arcsin(np.linalg.norm(noisy[:, :3], axis=1))
    >>> bool(abs(np.sqrt(np.mean(angle**2)) / (np.sqrt(3) * 1e-3) - 1) < 0.05)
    True
    """
    kick = Rotation.from_rotvec(sigma * rng.standard_normal((q.shape[0], 3)))
    return (Rotation.from_quat(q) * kick).as_quat()


def synthetic_lightcurve(body: RigidBody, state: AttitudeState, t: np.ndarray, geometry,
                         shape, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Magnitudes of ``shape`` at ``t`` (s since the state's epoch) along the exact
    solution, plus Gaussian noise of ``sigma`` mag (the model of
    :class:`~attitude.fitting.LightcurveObservations`, default scattering law).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.05, 0.1, 1.0])
    >>> shape = att.Polyhedron.ellipsoid_from_moments(body.principal_moments,
    ...                                               subdivisions=1)
    >>> geom = att.Geometry(sun=[1.0, 0, 0], observer=[np.cos(0.4), np.sin(0.4), 0.2])
    >>> t = np.linspace(0.0, 30.0, 50)
    >>> clean = synthetic_lightcurve(body, state, t, geom, shape, 0.0, None)
    >>> noisy = synthetic_lightcurve(body, state, t, geom, shape, 0.01,
    ...                              np.random.default_rng(2))
    >>> clean.shape, bool(np.std(noisy - clean) < 0.02)
    ((50,), True)
    """
    t = np.asarray(t, dtype=float)
    q = propagate(body, state, t).dataset["quaternion"].values
    clean = LightcurveObservations(t, np.zeros(t.size), max(sigma, 1.0), geometry, shape)
    mag = clean.model_magnitudes(q[None])[0]
    if sigma == 0:
        return mag
    return mag + sigma * rng.standard_normal(t.size)


def perturbed_state(state: AttitudeState, rng: np.random.Generator,
                    scale: float) -> AttitudeState:
    """A first guess near ``state``: its attitude turned by a body-frame rotation vector
    ``scale * N(0, 1)`` (rad) per axis, each body rate multiplied by
    ``1 + scale * N(0, 1)``.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.05, 0.1, 1.0])
    >>> guess = perturbed_state(state, np.random.default_rng(0), 0.01)
    >>> bool(0 < (guess.attitude.inv() * state.attitude).magnitude() < 0.1)
    True
    >>> bool(np.allclose(guess.omega_body, state.omega_body, rtol=0.05))
    True
    """
    turn = Rotation.from_rotvec(scale * rng.standard_normal(3))
    return AttitudeState(state.epoch, state.attitude * turn,
                         state.omega_body * (1 + scale * rng.standard_normal(3)))


def parameter_differences(fitted: dict, truth: dict) -> dict:
    """Fitted minus true parameters (dicts keyed by :data:`PARAMETERS`), the angles in
    :data:`WRAPPED` wrapped into [-pi, pi).

    Examples
    --------
    >>> truth = dict.fromkeys(PARAMETERS, 0.0)
    >>> fitted = dict(truth, phi0=6.2, energy_ratio=0.5)
    >>> d = parameter_differences(fitted, truth)
    >>> round(d["phi0"], 4), d["energy_ratio"]
    (-0.0832, 0.5)
    """
    out = {}
    for name in PARAMETERS:
        d = fitted[name] - truth[name]
        if name in WRAPPED:
            d = (d + np.pi) % (2 * np.pi) - np.pi
        out[name] = float(d)
    return out
