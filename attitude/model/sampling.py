"""Sampling models of rotation states: populations drawn from physical parameters.

A Monte Carlo cloud of an asteroid's rotation state is drawn in the parameters that
light-curve inversions publish (Pravec et al. 2014), not in quaternions and rates: the
``"tumbling"`` model (:func:`tumbling_state`) and the ``"spin"`` model
(:func:`spin_state`), whose parameters and SI units are :data:`MODELS`.
:meth:`attitude.Ensemble.sample` draws them (:func:`draw`) and builds the ensemble.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Mapping

import numpy as np
from astropy import units as u
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import InvalidStateError
from ..foundations.quantities import to_si
from .freebody import diagnose_many
from .state import direction_frame, spin_axis_quaternion

__all__ = ["MODELS", "DEFAULTS", "DIRECTION_SIGMA", "DIRECTION_PARAMETERS", "draw",
           "tumbling_state", "tumbling_parameters", "spin_state", "invalid_where"]

#: The eight parameters of a tumbler as :func:`tumbling_parameters` returns them (the
#: fits' names: ``phi0``, ``psi0`` are ``precession_angle``, ``rotation_angle``).
TUMBLING_PARAMETERS = ("angular_momentum_ra", "angular_momentum_dec", "energy_ratio",
                       "ratio_a", "ratio_b", "precession_period", "phi0", "psi0")
# principal -> kernel frame of a LAM state (A along the kernel z), as in tumbling_state
_LAM_KERNEL = Rotation.from_matrix([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
_HALF_TURNS = {"C": Rotation.from_rotvec([np.pi, 0.0, 0.0]),     # flips B and C
               "A": Rotation.from_rotvec([0.0, 0.0, np.pi])}     # flips A and B

#: Parameters of the sampling models (:meth:`Ensemble.sample`): name -> SI unit.
#: ``"tumbling"``: a non-principal-axis rotator as light-curve inversions publish it
#: (Pravec et al. 2014): the inertial direction of L (right ascension / declination, or
#: ecliptic longitude / latitude when the frame is ecliptic), the energy ratio E/E0
#: (E0 = L^2 / 2C; 1 is spin about C, C/B the separatrix, C/A spin about A), the moment
#: ratios A/C and B/C, the precession period P_phi (which sets ``|L|``) and the Euler angles
#: phi (precession) and psi (rotation) of the reference axis at the epoch; the nutation
#: angle theta follows from the energy.  ``"spin"``: a principal-axis spin about C along a
#: spin axis (RA/Dec) at a rate, with a rotation phase.
MODELS = {
    "tumbling": {"angular_momentum_ra": "rad", "angular_momentum_dec": "rad",
                 "energy_ratio": "", "ratio_a": "", "ratio_b": "",
                 "precession_period": "s", "precession_angle": "rad",
                 "rotation_angle": "rad", "moment_c": "kg m2"},
    "spin": {"spin_ra": "rad", "spin_dec": "rad", "spin_rate": "rad/s", "ratio_a": "",
             "ratio_b": "", "rotation_angle": "rad", "moment_c": "kg m2"},
}
#: The sigma key of each model's isotropic direction error, and its (ra, dec) parameters.
DIRECTION_SIGMA = {"tumbling": "angular_momentum_direction", "spin": "spin_direction"}
DIRECTION_PARAMETERS = {"tumbling": ("angular_momentum_ra", "angular_momentum_dec"),
                         "spin": ("spin_ra", "spin_dec")}

#: Defaults of parameters a model does not require.
DEFAULTS = {"precession_angle": 0.0, "rotation_angle": 0.0, "moment_c": 1.0}


def invalid_where(mask, reason) -> dict[int, str]:
    """``{index: reason(index)}`` of the rows where ``mask`` is true.

    Examples
    --------
    >>> import numpy as np
    >>> invalid_where(np.array([False, True]), lambda i: f"row {i} is bad")
    {1: 'row 1 is bad'}
    """
    return {int(i): reason(int(i)) for i in np.nonzero(mask)[0]}


def draw(n: int, *, rng=None, model: str = "tumbling", mean: Mapping | None = None,
         sigma: Mapping | None = None, cov=None, sampler: Callable | None = None,
         include_nominal: bool = True):
    """Draw ``n`` rotation states of a sampling model (the engine of
    :meth:`attitude.Ensemble.sample`, whose docstring describes the arguments).

    Returns
    -------
    moments : (n, 3) principal moments (NaN on invalid rows)
    quaternion : (n, 4) principal -> inertial, scalar-last
    omega : (n, 3) principal-frame rates, rad/s
    parameters : dict of (n,) arrays, the drawn parameters (SI)
    invalid : dict ``{index: reason}``

    Examples
    --------
    >>> m, q, w, params, bad = draw(3, rng=1, model="spin", mean={
    ...     "spin_ra": 0.0, "spin_dec": 0.5, "spin_rate": 0.1, "ratio_a": 0.5,
    ...     "ratio_b": 0.8}, sigma={"spin_rate": 0.01})
    >>> m.shape, q.shape, float(w[0, 2]), bad
    ((3, 3), (3, 4), 0.1, {})
    """
    if model not in MODELS:
        raise InvalidStateError(f"model: {model!r} is unknown; choose one of "
                                f"{sorted(MODELS)}")
    n = int(n)
    if n < 1:
        raise InvalidStateError(f"n: expected at least 1 body, got {n}")
    rng = np.random.default_rng(rng)
    spec = MODELS[model]
    mean_si = _parameters_si(mean or {}, spec, "mean")
    values = {k: np.full(n, v) for k, v in mean_si.items()}
    k0 = 1 if include_nominal else 0
    if sampler is not None:
        drawn = sampler(rng, n - k0)
        if not isinstance(drawn, Mapping):
            raise InvalidStateError("sampler: must return a dict of parameter arrays")
        for k, v in _parameters_si(drawn, spec, "sampler", arrays=True).items():
            values[k] = np.concatenate([np.full(k0, mean_si.get(k, np.nan)),
                                        np.broadcast_to(v, (n - k0,))])
    elif cov is not None:
        if sigma is not None:
            raise InvalidStateError("give sigma= or cov=, not both")
        keys = list(mean_si)
        cov = np.asarray(cov, dtype=float)
        if cov.shape != (len(keys), len(keys)):
            raise InvalidStateError(f"cov: expected shape {(len(keys),) * 2} for the "
                                    f"parameters {keys} of mean, got {cov.shape}")
        if not np.allclose(cov, cov.T) or np.linalg.eigvalsh(cov)[0] < -1e-12 * max(
                1.0, np.abs(cov).max()):
            raise InvalidStateError("cov: must be symmetric positive semi-definite")
        drawn = rng.multivariate_normal([mean_si[k] for k in keys], cov, size=n - k0)
        for j, k in enumerate(keys):
            values[k][k0:] = drawn[:, j]
    elif sigma:
        sigma = dict(sigma)
        direction = DIRECTION_SIGMA[model]
        if direction in sigma:
            _scatter_direction(values, mean_si, model, to_si(
                sigma.pop(direction), "rad", name=f"sigma.{direction}",
                error=InvalidStateError), rng, k0)
        sig = _parameters_si(sigma, spec, "sigma")
        for k, s in sig.items():
            if k not in mean_si:
                raise InvalidStateError(f"sigma.{k}: no mean value for this parameter")
            if not s >= 0:
                raise InvalidStateError(f"sigma.{k}: must be >= 0, got {s}")
            values[k][k0:] = mean_si[k] + s * rng.standard_normal(n - k0)
    for k, v in DEFAULTS.items():
        if k in spec:
            values.setdefault(k, np.full(n, v))
    missing = [k for k in spec if k not in values]
    if missing:
        raise InvalidStateError(f"mean: missing parameter(s) {', '.join(missing)} of "
                                f"the {model!r} model (all: {', '.join(spec)})")
    build = tumbling_state if model == "tumbling" else spin_state
    moments, q, w, bad = build(**{k: values[k] for k in spec})
    return moments, q, w, values, bad


def _parameters_si(values: Mapping, spec: Mapping, what: str, *,
                   arrays: bool = False) -> dict:
    out = {}
    for k, v in values.items():
        if k not in spec:
            close = difflib.get_close_matches(k, list(spec), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise InvalidStateError(f"{what}.{k}: unknown parameter{hint} (known: "
                                    f"{', '.join(spec)})")
        x = to_si(v, spec[k] or u.dimensionless_unscaled, name=f"{what}.{k}",
                  finite=False, error=InvalidStateError)   # NaN: an invalid body
        out[k] = np.asarray(x, dtype=float) if arrays else float(np.asarray(x))
    return out


def _scatter_direction(values, mean_si, model, sigma, rng, k0) -> None:
    """Isotropic error of ``sigma`` rad about the mean direction (ra, dec): tangent-plane
    offsets ``(x, y) ~ N(0, sigma^2)`` each, turned into a rotation by
    ``rho = |(x, y)|`` toward the azimuth ``atan2(y, x)``; written back as ra, dec."""
    ra_key, dec_key = DIRECTION_PARAMETERS[model]
    if ra_key not in mean_si or dec_key not in mean_si:
        raise InvalidStateError(f"sigma.{DIRECTION_SIGMA[model]}: needs mean values of "
                                f"{ra_key} and {dec_key}")
    if not sigma >= 0:
        raise InvalidStateError(f"sigma.{DIRECTION_SIGMA[model]}: must be >= 0, got {sigma}")
    frame = direction_frame(mean_si[ra_key], mean_si[dec_key])
    east, north, n0 = frame[:, 0], frame[:, 1], frame[:, 2]
    m = values[ra_key].size - k0
    x, y = sigma * rng.standard_normal(m), sigma * rng.standard_normal(m)
    rho = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        ux, uy = np.where(rho > 0, x / rho, 1.0), np.where(rho > 0, y / rho, 0.0)
    n = (np.cos(rho)[:, None] * n0 + np.sin(rho)[:, None]
         * (ux[:, None] * east + uy[:, None] * north))
    values[ra_key][k0:] = np.arctan2(n[:, 1], n[:, 0]) % (2 * np.pi)
    values[dec_key][k0:] = np.arcsin(np.clip(n[:, 2], -1.0, 1.0))


def _moments(ratio_a, ratio_b, moment_c):
    m = np.stack([ratio_a, ratio_b, np.ones_like(ratio_a)], axis=-1) * np.asarray(
        moment_c)[..., None]
    bad = invalid_where(~((0 < ratio_a) & (ratio_a <= ratio_b) & (ratio_b <= 1)
                           & (ratio_a + ratio_b >= 1) & (moment_c > 0)),
                         lambda i: f"moment ratios A/C = {ratio_a[i]:.6g}, B/C = "
                                   f"{ratio_b[i]:.6g} need 0 < A/C <= B/C <= 1 and "
                                   "A/C + B/C >= 1 (triangle inequality)")
    return m, bad


def tumbling_state(angular_momentum_ra, angular_momentum_dec, energy_ratio, ratio_a,
                   ratio_b, precession_period, precession_angle=0.0, rotation_angle=0.0,
                   moment_c=1.0):
    r"""Principal moments, attitudes and rates of non-principal-axis rotators (vectorised).

    All arguments broadcast to (N,), SI (rad, s, kg m^2).  The reference axis is C in
    SAM (``E/E0 < C/B``) and A in LAM; with the Euler angles (phi, theta, psi) of the
    reference axis about L (z-x-z, L along z of the L frame whose x axis is the node of
    L on the inertial equator), the body components of L are

    .. math::

       \mathbf{L}_{SAM} = L(\sin\theta\sin\psi, \sin\theta\cos\psi, \cos\theta),\qquad
       \mathbf{L}_{LAM} = L(\cos\theta, -\sin\theta\cos\psi, \sin\theta\sin\psi),

    and theta follows from the energy: :math:`\sin^2\theta = (E/E_0 - 1) /
    (C\sin^2\psi/A + C\cos^2\psi/B - 1)` (SAM) or :math:`(C/A - E/E_0) / (C/A -
    C\cos^2\psi/B - \sin^2\psi)` (LAM).  Periods scale as ``1/|L|`` at fixed shape and
    energy ratio, so ``|L|`` is set from the precession period.

    Returns
    -------
    moments (N, 3), quaternion (N, 4) principal -> inertial, omega (N, 3) principal-frame
    rates (rad/s), invalid ``{index: reason}``.

    Examples
    --------
    >>> from attitude.model.sampling import tumbling_state
    >>> m, q, w, bad = tumbling_state(4.36, -1.31, 1.024, 0.61, 0.965, 98568.0)
    >>> m.round(3).tolist(), bad
    ([[0.61, 0.965, 1.0]], {})
    """
    args = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=float)) for a in (
        angular_momentum_ra, angular_momentum_dec, energy_ratio, ratio_a, ratio_b,
        precession_period, precession_angle, rotation_angle, moment_c)))
    ra, dec, er, ra_, rb, pphi, phi, psi, mc = args
    m, bad = _moments(ra_, rb, mc)
    bad.update(invalid_where(~(np.isfinite(er) & (er >= 1) & (er <= 1 / np.where(
        ra_ > 0, ra_, 1))), lambda i: f"energy ratio E/E0 = {er[i]:.6g} is outside "
        f"[1, C/A = {1 / ra_[i]:.6g}]"))
    bad.update(invalid_where(~(pphi > 0), lambda i: "precession period must be > 0"))
    ok = np.ones(er.size, dtype=bool)
    ok[list(bad)] = False
    A, B, C = (np.where(ok, m[:, k], [1.0, 2.0, 2.5][k]) for k in range(3))
    er = np.where(ok, er, 1.0)
    lam = er > C / B
    s2 = np.where(lam, (C / A - er) / (C / A - C * np.cos(psi) ** 2 / B - np.sin(psi) ** 2),
                  (er - 1) / (C * np.sin(psi) ** 2 / A + C * np.cos(psi) ** 2 / B - 1))
    s2 = np.clip(np.nan_to_num(s2), 0.0, 1.0)
    st, ct = np.sqrt(s2), np.sqrt(1 - s2)
    l_sam = np.stack([st * np.sin(psi), st * np.cos(psi), ct], axis=-1)
    l_lam = np.stack([ct, -st * np.cos(psi), st * np.sin(psi)], axis=-1)
    l_unit = np.where(lam[:, None], l_lam, l_sam)                     # principal frame
    moments = np.stack([A, B, C], axis=-1)
    w1 = l_unit * C[:, None] / moments                   # rates for |L| = C * 1 rad/s
    d = diagnose_many(moments, w1)
    p1 = d["precession"]
    scale = np.where(np.isfinite(p1) & ok, p1 / np.where(pphi > 0, pphi, 1.0), np.nan)
    omega = w1 * scale[:, None]
    bad.update(invalid_where(ok & ~np.isfinite(scale), lambda i: "the state has no "
                              "precession period (on the separatrix or a principal-axis "
                              "spin); sample the energy ratio away from 1 and C/B"))
    # principal -> inertial: L frame, then Rz(phi) Rx(theta) Rz(psi) (kernel frame for LAM)
    theta = np.arctan2(st, ct)
    euler = Rotation.from_euler("ZXZ", np.stack([phi, theta, psi], axis=-1))
    r_l = Rotation.from_matrix(direction_frame(ra, dec))
    kernel_to_principal = np.where(lam[:, None], Rotation.from_matrix(
        [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]).as_quat()[None],
        [0.0, 0.0, 0.0, 1.0])
    q_k2i = (r_l * euler).as_quat()
    q = quat.multiply(q_k2i, quat.conjugate(kernel_to_principal))
    m = np.where(ok[:, None], m, np.nan)
    omega = np.where(ok[:, None], omega, np.nan)
    return m, q, omega, dict(sorted(bad.items()))


def tumbling_parameters(body, state) -> tuple[dict, Rotation]:
    """The eight parameters of a torque-free state (the inverse of
    :func:`tumbling_state`), and the body -> principal rotation they refer to.

    The reference axis (C in SAM, A in LAM) is taken with a positive component of L: the
    principal frame is turned by a half-turn about a principal axis when needed, and
    the rotation returned includes that turn.

    Parameters
    ----------
    body : RigidBody
    state : AttitudeState
        Its angles are those of the state's frame and epoch.

    Returns
    -------
    dict, Rotation
        The parameters (:data:`TUMBLING_PARAMETERS`, SI), and body -> principal.

    Raises
    ------
    ValueError
        For a state the parameterisation cannot hold: at rest, a principal-axis spin or
        on the separatrix (no precession period), an axisymmetric body.

    Examples
    --------
    >>> import attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.6, 0.9, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.from_rotvec([0.3, -0.2, 1.0]),
    ...                           [0.05, 0.1, 1.0])
    >>> p, _ = tumbling_parameters(body, state)
    >>> round(p["energy_ratio"], 6), round(p["ratio_a"], 6)
    (1.001487, 0.6)
    """
    moments = np.asarray(body.principal_moments, dtype=float)
    A, B, C = moments
    b2p = body.body_to_principal
    w_p = b2p.apply(state.omega_body)
    L_p = moments * w_p
    L2 = float(L_p @ L_p)
    if L2 == 0:
        raise ValueError("a body at rest has no rotation parameters")
    er = float(moments @ (w_p * w_p)) * C / L2
    lam = er > C / B
    axis = "A" if lam else "C"
    if (L_p[0] if lam else L_p[2]) < 0:       # turn the principal frame by a half-turn
        b2p = _HALF_TURNS[axis] * b2p
        w_p = _HALF_TURNS[axis].apply(w_p)
        L_p = moments * w_p
    q_p2i = state.attitude * b2p.inv()
    L_i = q_p2i.apply(L_p)
    ra = float(np.arctan2(L_i[1], L_i[0]) % (2 * np.pi))
    dec = float(np.arcsin(np.clip(L_i[2] / np.sqrt(L2), -1.0, 1.0)))
    d = diagnose_many(moments[None], w_p[None])
    pphi = float(d["precession"][0])
    if not np.isfinite(pphi):
        raise ValueError(f"the state ({d['regime'][0]}) has no precession period: the "
                         "parameterisation needs a tumbling (SAM or LAM) triaxial state")
    kernel = _LAM_KERNEL if lam else Rotation.identity()
    r_l = Rotation.from_matrix(direction_frame(ra, dec))
    euler = r_l.inv() * q_p2i * kernel.inv()
    phi, _, psi = euler.as_euler("ZXZ")
    params = dict(zip(TUMBLING_PARAMETERS, (ra, dec, float(er), float(A / C), float(B / C),
                                            pphi, float(phi % (2 * np.pi)),
                                            float(psi % (2 * np.pi)))))
    return params, b2p


def spin_state(spin_ra, spin_dec, spin_rate, ratio_a, ratio_b, rotation_angle=0.0,
               moment_c=1.0):
    """Principal-axis spins about C along (RA, Dec) at ``spin_rate`` (rad/s), rotated by
    ``rotation_angle`` about the spin axis from the convention of
    :func:`attitude.model.state.spin_axis_quaternion` (vectorised; SI).

    Returns moments (N, 3), quaternion (N, 4) principal -> inertial, omega (N, 3) and
    invalid ``{index: reason}``.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.sampling import spin_state
    >>> m, q, w, bad = spin_state(0.0, np.pi / 2, 2 * np.pi / 3600, 0.8, 0.9)
    >>> w.round(6).tolist()                          # one turn an hour about C
    [[0.0, 0.0, 0.001745]]
    """
    ra, dec, rate, ra_, rb, psi, mc = np.broadcast_arrays(*(np.atleast_1d(np.asarray(
        a, dtype=float)) for a in (spin_ra, spin_dec, spin_rate, ratio_a, ratio_b,
                                    rotation_angle, moment_c)))
    m, bad = _moments(ra_, rb, mc)
    bad.update(invalid_where(~np.isfinite(rate), lambda i: "spin rate must be finite"))
    q = spin_axis_quaternion(ra, dec, about="C", rotation_angle=psi)
    omega = np.stack([np.zeros_like(rate), np.zeros_like(rate), rate], axis=-1)
    return m, q, omega, dict(sorted(bad.items()))


