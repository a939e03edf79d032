"""Close encounters: a planet's flyby of a tumbling body, and its ensemble.

The planet is a homogeneous sphere (it feels no torque and gives none beyond a point
mass's) on the Kepler hyperbola relative to the body; the body is the secondary of a
:class:`~attitude.binary.system.BinarySystem`, so the same mutual potential and
propagators as for a binary carry the tide's torque.

- :func:`hyperbola` is the relative state on the hyperbola at times from perigee (the
  hyperbolic Kepler equation ``e sinh H - H = n t``, solved by Newton's method).
- :func:`close_encounter` builds ``(system, state)`` from the hyperbola (perigee distance,
  ``v_infinity``, perigee epoch), the planet's mass and radius and the body's shape and
  rotation state at the start.
- :func:`sample_encounter` draws an ensemble over the uncertainties: the tumbling state in
  the parameters light-curve inversions publish (Pravec et al. 2014 for (99942) Apophis:
  E/E0, the moment ratios, the precession period, the direction of L) with its two
  phases uniform (a period known to 0.07 h over the 15 years from 2014 to 2029 leaves
  some 13 cycles of phase unknown), and the perigee's distance and epoch.
- :func:`encounter_ensemble` runs the members (in this process or one dask task per
  chunk) and gathers the body's Pravec parameters (regime, E/E0, the precession and
  rotation periods) before and after, with their changes and the regime fractions.

:func:`attitude.binary.ensemble` measures a binary's outcomes (period change, libration,
the secondary's binary regime), not the free body's state after the flyby, so the
encounter ensemble runs its members with :func:`~attitude.binary.propagate.propagate_binary`
and reads the first and last samples.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

from attitude.binary.ensembles import input_variables, rows_on_client
from attitude.binary.propagate import propagate_binary
from attitude.binary.system import BinaryState, BinarySystem
from attitude.foundations.constants import G as GRAVITATIONAL_CONSTANT
from attitude.foundations.errors import AttitudeError, BinarySystemError
from attitude.foundations.quantities import to_si
from attitude.model.body import MassProperties, RigidBody
from attitude.model.freebody import diagnose_many
from attitude.model.sampling import tumbling_state

__all__ = ["hyperbola", "close_encounter", "sample_encounter", "encounter_ensemble",
           "ellipsoid_from_ratios"]

#: The Earth as a homogeneous sphere: kg, m.
EARTH_MASS, EARTH_RADIUS = 5.972e24, 6371e3
#: Apophis in 2029 and its tumbling state (Pravec et al. 2014, Icarus 233, 48-60; the
#: moment ratios and the direction of L are marked unverified in shared/validation; the
#: uncertainties are the paper's, taken as 3 sigma as it quotes E/E0's), its size
#: (volume-equivalent radius 170 m, Brozovic et al. 2018), an assumed density (any
#: density gives the same periods), and the 2029 hyperbola (perigee 38,000 km from the
#: Earth's centre at 5.84 km/s hyperbolic excess speed, 2029-04-13T21:46 TDB).
APOPHIS = {"energy_ratio": (1.024, 0.013 / 3), "ratio_a": (0.61, 0.095 / 3),
           "ratio_b": (0.965, 0.012 / 3), "precession_period": (27.38 * 3600.0, 0.07 * 3600.0),
           "angular_momentum_lon": 250.0, "angular_momentum_lat": -75.0,
           "radius": 170.0, "density": 2600.0, "perigee_distance": (38_000e3, 0.0),
           "v_infinity": (5.84e3, 0.0), "perigee_epoch": ("2029-04-13T21:46:00", 0.0)}


def _kepler_h(e: float, mean: np.ndarray) -> np.ndarray:
    """The hyperbolic anomaly ``H`` of ``e sinh H - H = mean`` (Newton's method from the
    asymptotic start ``asinh(mean / e)``, which it approaches from one side)."""
    mean = np.asarray(mean, dtype=float)
    H = np.arcsinh(mean / e)
    for _ in range(100):
        step = (e * np.sinh(H) - H - mean) / (e * np.cosh(H) - 1.0)
        H = H - step
        if np.all(np.abs(step) <= 4 * np.finfo(float).eps * (1.0 + np.abs(H))):
            break
    return H


def hyperbola(gm, perigee_distance, v_infinity, t):
    """The relative position and velocity on a Kepler hyperbola, ``t`` s after perigee.

    Perifocal frame: x towards perigee, z along the orbit normal (the motion is
    counter-clockwise about z).  ``a = -gm / v_inf^2``, ``e = 1 + r_p v_inf^2 / gm``.

    Parameters
    ----------
    gm : float
        ``G (M + m)``, m^3/s^2.
    perigee_distance : float or Quantity
        m.
    v_infinity : float or Quantity
        The hyperbolic excess speed, m/s.
    t : float or array-like
        s from perigee.

    Returns
    -------
    position, velocity : (..., 3) arrays, m and m/s.

    Examples
    --------
    >>> r, v = hyperbola(3.986e14, 38_000e3, 5.84e3, 0.0)
    >>> r.round(3).tolist(), round(float(v[1]), 3)          # perigee on +x, v_p along +y
    ([38000000.0, 0.0, 0.0], 7421.896)
    >>> r, v = hyperbola(3.986e14, 38_000e3, 5.84e3, [-1e7, 1e7])
    >>> (np.linalg.norm(v, axis=-1) / 5.84e3).round(3).tolist()   # far away: v_infinity
    [1.0, 1.0]
    """
    gm = float(to_si(gm, "m3 / s2", name="gm", shape=(), positive=True,
                     error=BinarySystemError))
    r_p = float(to_si(perigee_distance, "m", name="perigee_distance", shape=(), positive=True,
                      error=BinarySystemError))
    v_inf = float(to_si(v_infinity, "m/s", name="v_infinity", shape=(), positive=True,
                        error=BinarySystemError))
    t = np.asarray(to_si(t, "s", name="t", error=BinarySystemError), dtype=float)
    a = -gm / v_inf**2
    e = 1.0 - r_p / a
    n = math.sqrt(gm / -a**3)
    H = _kepler_h(e, n * t)
    H_dot = n / (e * np.cosh(H) - 1.0)
    k = -a * math.sqrt(e * e - 1.0)
    zero = np.zeros_like(H)
    position = np.stack([a * (np.cosh(H) - e), k * np.sinh(H), zero], axis=-1)
    velocity = np.stack([a * np.sinh(H) * H_dot, k * np.cosh(H) * H_dot, zero], axis=-1)
    return position, velocity


def ellipsoid_from_ratios(ratio_a: float, ratio_b: float, mass: float,
                          radius: float) -> RigidBody:
    """The uniform triaxial ellipsoid with moment ratios ``A/C``, ``B/C`` and a
    volume-equivalent ``radius`` (m): its semi-axes ``a >= b >= c`` along x, y, z.

    With ``b^2`` and ``c^2`` in units of ``a^2``, ``A/C = (b^2 + c^2) / (1 + b^2)`` and
    ``B/C = (1 + c^2) / (1 + b^2)``, so ``b^2 = (1 - (B/C - A/C)) / (1 + (B/C - A/C))``
    and ``c^2 = (B/C) (1 + b^2) - 1``.

    Examples
    --------
    >>> body = ellipsoid_from_ratios(0.61, 0.965, 5.35e10, 170.0)
    >>> A, B, C = body.principal_moments
    >>> float(round(A / C, 12)), float(round(B / C, 12))
    (0.61, 0.965)
    """
    d = ratio_b - ratio_a
    b2 = (1.0 - d) / (1.0 + d)
    c2 = ratio_b * (1.0 + b2) - 1.0
    if not (0 < c2 <= b2 <= 1):
        raise BinarySystemError(f"moment ratios A/C = {ratio_a:.6g}, B/C = {ratio_b:.6g}: "
                                "no uniform ellipsoid has them (need A/C + B/C > 1 and "
                                "A/C <= B/C <= 1)")
    shape = np.sqrt([1.0, b2, c2])
    axes = radius * shape / np.prod(shape) ** (1.0 / 3.0)
    return RigidBody.from_mass_properties(MassProperties.solid_ellipsoid(mass, axes))


def close_encounter(planet_mass, planet_radius, body: RigidBody, attitude: Rotation, omega,
                    *, perigee_distance, v_infinity, perigee_epoch, before="12 h",
                    orientation: Rotation | None = None, frame: str = "ECLIPJ2000",
                    order: int = 2, G: float = GRAVITATIONAL_CONSTANT):
    """The ``(system, state)`` of a planet's flyby of a body: the planet a homogeneous
    sphere (the primary, not spinning), the body the secondary, the relative orbit the
    Kepler hyperbola, the state ``before`` perigee.

    Parameters
    ----------
    planet_mass, planet_radius : float or Quantity
        kg, m.
    body : RigidBody
        With a mass (and, beyond ``order`` 2, its distribution).
    attitude : scipy Rotation
        The body's attitude (body -> inertial) at the start, ``before`` perigee.
    omega : (3,) array-like or Quantity
        Its body-frame angular velocity at the start, rad/s.
    perigee_distance, v_infinity : float or Quantity
        m, m/s.
    perigee_epoch : str or astropy Time
        ISO 8601, TDB.
    before : float (s), str or Quantity
        How long before perigee the state is (default 12 h).
    orientation : scipy Rotation, optional
        The hyperbola's perifocal frame (x to perigee, z the orbit normal) -> the inertial
        frame; default the identity.
    frame : str
        The inertial frame's label.
    order, G :
        Of the :class:`~attitude.binary.system.BinarySystem`.

    Returns
    -------
    (BinarySystem, BinaryState)

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> apophis = ellipsoid_from_ratios(0.61, 0.965, 5.35e10, 170.0)
    >>> system, state = close_encounter(5.972e24, 6371e3, apophis, Rotation.identity(),
    ...                                 [0.0, 0.0, 6e-5], perigee_distance=38_000e3,
    ...                                 v_infinity=5.84e3, perigee_epoch="2029-04-13T21:46:00")
    >>> state.epoch.isot, f"{np.linalg.norm(state.position) / 1e3:.0f} km"
    ('2029-04-13T09:46:00.000', '273393 km')
    >>> eph = att.propagate(system, state, [0.0, 12 * 3600.0], method="integrator",
    ...                     rtol=1e-10)
    >>> f"{np.linalg.norm(eph.dataset.relative_position.values[-1]) / 1e3:.1f} km"
    '38000.0 km'
    """
    planet = RigidBody.from_mass_properties(MassProperties.solid_sphere(
        float(to_si(planet_mass, "kg", name="planet_mass", shape=(), positive=True,
                    error=BinarySystemError)),
        float(to_si(planet_radius, "m", name="planet_radius", shape=(), positive=True,
                    error=BinarySystemError))), name="planet")
    system = BinarySystem(planet, body, order=order, G=G)
    dt = float(to_si(u.Quantity(before) if isinstance(before, str) else before, "s",
                     name="before", shape=(), error=BinarySystemError))
    r_p = float(to_si(perigee_distance, "m", name="perigee_distance", shape=(),
                      positive=True, error=BinarySystemError))
    if r_p <= float(to_si(planet_radius, "m", name="planet_radius", shape=())):
        raise BinarySystemError(f"perigee_distance: {r_p:.6g} m is inside the planet; "
                                "give the distance from its centre")
    position, velocity = hyperbola(system.mu, r_p, v_infinity, -dt)
    if orientation is not None:
        position, velocity = orientation.apply(position), orientation.apply(velocity)
    epoch = perigee_epoch if isinstance(perigee_epoch, Time) else Time(perigee_epoch,
                                                                       scale="tdb")
    state = BinaryState(epoch - dt * u.s, position, velocity, Rotation.identity(),
                        [0.0, 0.0, 0.0], attitude, omega, frame=frame)
    return system, state


def _draw(rng, value, n):
    """``n`` normal draws of a ``(mean, sigma)`` pair (or a fixed number)."""
    if np.ndim(value) == 0:
        return np.full(n, float(value))
    mean, sigma = value
    return rng.normal(float(mean), float(sigma), size=n) if sigma else np.full(n, float(mean))


def sample_encounter(n: int, rng=None, *, energy_ratio=APOPHIS["energy_ratio"],
                     ratio_a=APOPHIS["ratio_a"], ratio_b=APOPHIS["ratio_b"],
                     precession_period=APOPHIS["precession_period"],
                     angular_momentum=(APOPHIS["angular_momentum_lon"],
                                       APOPHIS["angular_momentum_lat"]),
                     direction_sigma: float = 0.0, phases: bool = True,
                     perigee_distance=APOPHIS["perigee_distance"],
                     v_infinity=APOPHIS["v_infinity"], perigee_epoch=APOPHIS["perigee_epoch"],
                     planet_mass: float = EARTH_MASS, planet_radius: float = EARTH_RADIUS,
                     radius: float = APOPHIS["radius"], density: float = APOPHIS["density"],
                     before: float = 12 * 3600.0, orientation: Rotation | None = None,
                     frame: str = "ECLIPJ2000") -> list:
    """``n`` members of a close encounter for :func:`encounter_ensemble` (or
    :func:`attitude.binary.ensemble`), each ``(system, state, [], inputs)``; by default
    Apophis's tumbling state (Pravec et al. 2014) on the Earth's 2029 hyperbola.

    The body is the uniform ellipsoid of the drawn moment ratios
    (:func:`ellipsoid_from_ratios`) at the volume-equivalent ``radius`` (m) and
    ``density`` (kg/m^3); its rotation state ``before`` perigee is the non-principal-axis
    rotator of :func:`attitude.model.sampling.tumbling_state` with the drawn E/E0, ratios
    and precession period (s), L along the ecliptic (or the frame's) longitude and
    latitude ``angular_momentum`` (deg; ``direction_sigma`` deg: an isotropic error
    about it), and the two phases (the Euler angles of precession and rotation) uniform
    on ``[0, 2 pi)`` with ``phases`` (else both 0).

    Each of ``energy_ratio``, ``ratio_a``, ``ratio_b``, ``precession_period``,
    ``perigee_distance`` (m) and ``v_infinity`` (m/s) is a ``(mean, sigma)`` normal draw
    (sigma 0, or a plain number: fixed); ``perigee_epoch`` is ``(ISO TDB, sigma s)``.  The
    defaults are the published values and their uncertainties (quoted as 3 sigma); the
    hyperbola's own, a few km and seconds, are left at 0: with the phases uniform an
    error of the perigee's epoch changes nothing but the epoch.  ``orientation``: the
    hyperbola's perifocal frame -> the inertial frame (:func:`close_encounter`).

    ``inputs``: ``energy_ratio``, ``ratio_a``, ``ratio_b``, ``precession_period``,
    ``precession_angle``, ``rotation_angle``, ``angular_momentum_lon``,
    ``angular_momentum_lat`` (rad), ``perigee_distance``, ``v_infinity``,
    ``perigee_offset`` (s).  A draw that makes no state (ratios that no ellipsoid has)
    is a member ``(error, None, [], inputs)``, which the ensembles report as bad input.

    Examples
    --------
    >>> members = sample_encounter(3, rng=1)
    >>> len(members), members[0][0].secondary.mass > 5e10
    (3, True)
    >>> sorted(members[0][3])[:4]
    ['angular_momentum_lat', 'angular_momentum_lon', 'energy_ratio', 'perigee_distance']
    """
    rng = np.random.default_rng(rng)
    n = int(n)
    er, ra_, rb = (_draw(rng, x, n) for x in (energy_ratio, ratio_a, ratio_b))
    pphi = _draw(rng, precession_period, n)
    r_p, v_inf = _draw(rng, perigee_distance, n), _draw(rng, v_infinity, n)
    epoch, epoch_sigma = (perigee_epoch, 0.0) if isinstance(perigee_epoch, (str, Time)) \
        else perigee_epoch
    offset = _draw(rng, (0.0, epoch_sigma), n)
    lon, lat = np.radians(angular_momentum[0]), np.radians(angular_momentum[1])
    lon, lat = _scatter_direction(rng, lon, lat, math.radians(direction_sigma), n)
    if phases:
        phi, psi = rng.uniform(0.0, 2 * math.pi, size=(2, n))
    else:
        phi = psi = np.zeros(n)
    mass = density * 4.0 / 3.0 * math.pi * radius**3
    perigee = epoch if isinstance(epoch, Time) else Time(epoch, scale="tdb")
    members = []
    for i in range(n):
        inputs = {"energy_ratio": er[i], "ratio_a": ra_[i], "ratio_b": rb[i],
                  "precession_period": pphi[i], "precession_angle": phi[i],
                  "rotation_angle": psi[i], "angular_momentum_lon": lon[i],
                  "angular_momentum_lat": lat[i], "perigee_distance": r_p[i],
                  "v_infinity": v_inf[i], "perigee_offset": offset[i]}
        inputs = {k: float(v) for k, v in inputs.items()}
        try:
            _, q, w, bad = tumbling_state(lon[i], lat[i], er[i], ra_[i], rb[i], pphi[i],
                                          phi[i], psi[i])
            if bad:
                raise BinarySystemError(f"rotation state: {bad[0]}")
            body = ellipsoid_from_ratios(ra_[i], rb[i], mass, radius)
            system, state = close_encounter(
                planet_mass, planet_radius, body, Rotation.from_quat(q[0]), w[0],
                perigee_distance=r_p[i], v_infinity=v_inf[i],
                perigee_epoch=perigee + offset[i] * u.s, before=before,
                orientation=orientation, frame=frame)
            members.append((system, state, [], inputs))
        except (AttitudeError, ValueError) as err:       # an impossible draw: bad input
            members.append((err, None, [], inputs))
    return members


def _scatter_direction(rng, lon: float, lat: float, sigma: float, n: int):
    """``n`` directions about (lon, lat) with an isotropic normal error of ``sigma`` rad
    (each component of the tangent offset), rad."""
    if not sigma:
        return np.full(n, lon), np.full(n, lat)
    c = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    e1 = np.array([-math.sin(lon), math.cos(lon), 0.0])
    e2 = np.cross(c, e1)
    d = rng.normal(0.0, sigma, size=(n, 2))
    v = c + d[:, :1] * e1 + d[:, 1:] * e2
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return np.arctan2(v[:, 1], v[:, 0]) % (2 * math.pi), np.arcsin(np.clip(v[:, 2], -1, 1))


#: The free body's Pravec parameters measured before and after (and their units).
_PRAVEC = {"energy_ratio": "1", "precession_period": "s", "rotation_period": "s"}


def _pravec(body: RigidBody, omega: np.ndarray) -> dict:
    """The regime, E/E0 and the precession and rotation periods of ``body`` spinning at
    the body-frame rates ``omega`` (rows), from its principal frame."""
    moments, axes = np.linalg.eigh(np.asarray(body.inertia, dtype=float))
    d = diagnose_many(np.broadcast_to(moments, omega.shape), omega @ axes)
    return {"regime": d["regime"], "energy_ratio": d["energy_ratio"],
            "precession_period": d["precession"], "rotation_period": d["rotation"]}


def _run_member(member, times, run: dict) -> dict:
    """One member's row (never raises)."""
    row = {"status": 0, "message": "", "inputs": {}}
    try:
        system, state, *rest = member
        row["inputs"] = dict(rest[1]) if len(rest) > 1 and rest[1] else {}
        if isinstance(system, Exception):
            raise BinarySystemError(str(system))
        if not isinstance(system, BinarySystem) or not isinstance(state, BinaryState):
            raise BinarySystemError("member: expected (system, state[, impulses[, inputs]])")
    except (BinarySystemError, TypeError, ValueError) as err:
        row.update(status=1, message=str(err))
        return row
    try:
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            ds = propagate_binary(system, state, times, events=rest[0] if rest else None,
                                  **run).dataset
            w = np.asarray(ds["angular_velocity"].values[1][[0, -1]], dtype=float)
            q = np.asarray(ds["quaternion"].values[1][[0, -1]], dtype=float)
            p = _pravec(system.secondary, w)
            H = Rotation.from_quat(q).apply(w @ np.asarray(system.secondary.inertia).T)
            L = np.asarray(ds["total_angular_momentum"].values, dtype=float)
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(L))):
            raise BinarySystemError("the state is no longer finite")
    except BinarySystemError as err:
        row.update(status=1, message=str(err))
        return row
    except Exception as err:  # noqa: BLE001  (a failed member must not stop the others)
        row.update(status=2, message=f"{type(err).__name__}: {err}")
        return row
    for k, when in ((0, "before"), (1, "after")):
        row[f"{when}_regime"] = str(p["regime"][k])
        for key in _PRAVEC:
            row[f"{when}_{key}"] = float(p[key][k])
    row["spin_momentum_change"] = float(np.linalg.norm(H[1] - H[0]) / np.linalg.norm(H[0]))
    row["angular_momentum_drift"] = float(np.linalg.norm(L - L[0], axis=1).max()
                                          / np.linalg.norm(L[0]))
    return row


def _run_chunk(members, times, run) -> list:
    return [_run_member(m, times, run) for m in members]


def encounter_ensemble(members, times, *, method: str | None = None,
                       rtol: float | None = None, step=None, client=None,
                       chunk_size: int | None = None) -> xr.Dataset:
    """Run close encounters and gather the body's Pravec parameters before and after.

    Parameters
    ----------
    members : sequence
        Each ``(system, state[, impulses[, inputs]])`` (:func:`sample_encounter`), the
        body the secondary.
    times : array-like
        s since each state's epoch; the first and last samples are "before" and "after"
        (from ``before`` perigee to as long after, the tide beyond is a percent of it).
    method, rtol, step :
        Of :func:`attitude.propagate` for a binary; given none of them, DOP853 at
        ``rtol`` 1e-10 (a ``step`` alone: the LGVI at that step, s).
    client : None, "local", a dask ``Client`` or a scheduler address
        None: in this process; otherwise one dask task per chunk of ``chunk_size``
        members (default: two chunks per worker).

    Returns
    -------
    xarray.Dataset
        Dim ``member``: ``status`` (0 ok, 1 bad input, 2 failed), ``message``;
        ``before_regime`` and ``after_regime`` (``SAM``, ``LAM``, ...); ``before_`` and
        ``after_`` ``energy_ratio`` (E/E0), ``precession_period`` and
        ``rotation_period`` (s); their changes ``energy_ratio_change``,
        ``precession_change``, ``rotation_change`` (after - before);
        ``spin_momentum_change`` (``|H1 - H0| / |H0|``, the spin angular momentum,
        inertial); ``angular_momentum_drift`` (the total's largest relative change, the
        integrator's error); each input.  ``attrs["regime_fractions"]``: each regime's
        share after, among the members that ran (``"regime_fractions_before"``: before).

    Examples
    --------
    >>> members = sample_encounter(2, rng=2)
    >>> ds = encounter_ensemble(members, [0.0, 24 * 3600.0])
    >>> ds.status.values.tolist(), ds.before_regime.values.tolist()
    ([0, 0], ['SAM', 'SAM'])
    >>> bool(np.all(np.abs(ds.before_energy_ratio - ds.energy_ratio) < 1e-9))
    True
    >>> bool(np.all(ds.spin_momentum_change > 1e-3))     # the tide changed every spin
    True
    """
    members = list(members)
    times = np.asarray(times, dtype=float)
    if method is None and step is None:
        method, rtol = "integrator", 1e-10 if rtol is None else rtol
    run = {"method": method, "rtol": rtol, "step": step}
    if client is None:
        rows = _run_chunk(members, times, run)
    else:
        rows = rows_on_client(client, _run_chunk, members, (times, run),
                              chunk_size=chunk_size, chunks_per_worker=2)
    return _dataset(rows)


def _dataset(rows: list) -> xr.Dataset:
    data = {"status": ("member", np.array([r["status"] for r in rows], dtype=np.int8),
                       {"flag_values": [0, 1, 2],
                        "flag_meanings": "ok invalid_input propagation_failed"}),
            "message": ("member", np.array([r["message"] for r in rows], dtype=object))}
    for when in ("before", "after"):
        data[f"{when}_regime"] = ("member", np.array([r.get(f"{when}_regime", "")
                                                      for r in rows], dtype=object))
        for key, unit in _PRAVEC.items():
            data[f"{when}_{key}"] = ("member", np.array(
                [r.get(f"{when}_{key}", math.nan) for r in rows], dtype=float),
                {"units": unit})
    for key, name in (("energy_ratio", "energy_ratio_change"),
                      ("precession_period", "precession_change"),
                      ("rotation_period", "rotation_change")):
        data[name] = ("member", data[f"after_{key}"][1] - data[f"before_{key}"][1],
                      {"units": _PRAVEC[key]})
    for key in ("spin_momentum_change", "angular_momentum_drift"):
        data[key] = ("member", np.array([r.get(key, math.nan) for r in rows], dtype=float),
                     {"units": "1"})
    inputs = input_variables(rows)
    data.update(inputs)
    ok = [r for r in rows if r["status"] == 0]

    def fractions(when):
        labels = [r[f"{when}_regime"] for r in ok]
        return {k: labels.count(k) / len(labels) for k in sorted(set(labels))}

    return xr.Dataset(data, coords={"member": np.arange(len(rows))},
                      attrs={"title": "attitude: an ensemble of close encounters",
                             "regime_fractions": fractions("after"),
                             "regime_fractions_before": fractions("before"),
                             "inputs": list(inputs)})
