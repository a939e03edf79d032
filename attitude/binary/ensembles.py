"""Ensembles of binaries: many systems in one call, and the fractions of their outcomes.

:func:`ensemble` runs each member, a ``(system, state[, impulses[, inputs]])`` tuple,
through :func:`attitude.propagate` and :func:`~attitude.binary.diagnostics.diagnose`
(and :func:`~attitude.binary.diagnostics.period_change` across its first impulse), in
this process or on dask (one task per chunk of members), and gathers the outcomes in an
``xarray.Dataset`` along ``member``: the inputs that vary, the orbit period, the period
change, the libration amplitude, the secondary's regime, the Lyapunov exponent (with
``chaos=True``), and a ``status`` (0 ok, 1 bad input, 2 failed: a member that fails does
not stop the others).  ``ds.attrs["regime_fractions"]`` holds the share of each regime
among the members that ran.

:func:`sample_dart` draws the DART family: Didymos-Dimorphos (both ellipsoids, the
secondary locked on a circular orbit at 1190 m in the mutual force) with the momentum
enhancement ``beta``, the primary's mass and the secondary's semi-axes sampled, and the
impact of :file:`scenarios/binary/didymos_dart.toml` (580 kg, its velocity in the orbit's
radial, along-track and normal directions) after one and a half orbits.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr
from scipy.spatial.transform import Rotation

from attitude.binary.diagnostics import REGIMES, diagnose, period_change
from attitude.binary.dynamics import mutual_forces
from attitude.binary.propagate import propagate_binary, propagate_family
from attitude.binary.system import BinaryState, BinarySystem, Impulse, impact_delta_v
from attitude.foundations.errors import AttitudeError, BinarySystemError
from attitude.model.body import MassProperties, RigidBody
from attitude.propagation.cluster import resolve_client

__all__ = ["ensemble", "sample_dart", "STATUS_OK", "STATUS_INVALID", "STATUS_FAILED"]

#: ``status`` of a member: ran, bad input, failed while running.
STATUS_OK, STATUS_INVALID, STATUS_FAILED = 0, 1, 2
#: The outcomes measured for each member (float, NaN where not measured).
_FLOATS = ("orbit_period", "period_change", "libration_amplitude", "eccentricity",
           "lyapunov_exponent")

#: Didymos-Dimorphos as in scenarios/binary/didymos_dart.toml.
DART = {"primary_axes": (394.0, 394.0, 290.0), "primary_spin_period": 2.26 * 3600.0,
        "secondary_mass": 4.3e9, "secondary_axes": (89.5, 84.5, 57.5),
        "separation": 1190.0, "impactor_mass": 580.0,
        # the impactor's velocity (radial, along-track, normal), m/s: the scenario's
        # [0, -5546.3, -2645.5] at the impact, where the secondary is at +x moving +y
        "impactor_velocity": (0.0, -5546.3, -2645.5)}


def _dart_member(beta: float, primary_mass: float, scales, impact_orbits: float,
                 epoch: str):
    """One DART member: ``(system, state, [impulse])``."""
    ellipsoid = MassProperties.solid_ellipsoid
    primary = RigidBody.from_mass_properties(ellipsoid(primary_mass, DART["primary_axes"]))
    axes = np.asarray(DART["secondary_axes"]) * np.asarray(scales, float)
    secondary = RigidBody.from_mass_properties(ellipsoid(DART["secondary_mass"], axes))
    system = BinarySystem(primary, secondary)
    r = DART["separation"]
    position = np.array([r, 0.0, 0.0])
    force = mutual_forces(system, position, np.eye(3), np.eye(3)).force
    speed = math.sqrt(-float(force[0]) * r / system.reduced_mass)   # circular, mutual force
    rate = speed / r
    state = BinaryState(epoch, position, [0.0, speed, 0.0], Rotation.identity(),
                        [0.0, 0.0, 2 * math.pi / DART["primary_spin_period"]],
                        Rotation.identity(), [0.0, 0.0, rate])   # long axis on the line
    t_impact = impact_orbits * 2 * math.pi / rate
    turn = Rotation.from_rotvec([0.0, 0.0, rate * t_impact])      # where the secondary is
    U = turn.apply(DART["impactor_velocity"])
    dv = impact_delta_v(DART["impactor_mass"], U, beta, DART["secondary_mass"])
    return system, state, [Impulse(t_impact, body="secondary", delta_v=dv)]


def sample_dart(n: int, rng=None, *, beta=(3.61, 0.2), primary_mass=(5.282e11, 0.1e11),
                secondary_axes_scale=(1.0, 0.02), impact_orbits: float = 1.5,
                epoch: str = "2022-09-26T00:00:00") -> list:
    """``n`` members of the DART family for :func:`ensemble`, each ``(system, state,
    [impulse], inputs)``.

    Each of ``beta``, ``primary_mass`` (kg) and ``secondary_axes_scale`` is a ``(mean,
    sigma)`` normal draw (sigma 0: fixed); the scale multiplies each of Dimorphos's
    semi-axes (89.5, 84.5, 57.5 m) with its own draw, so its elongation varies, its mass
    (4.3e9 kg) does not.  The orbit starts circular in the mutual force at 1190 m,
    Dimorphos locked (long axis on the line of centres, largest-moment axis on the orbit
    normal), Didymos spinning in 2.26 h; the impact (580 kg, the scenario's velocity
    turned with the orbit to the secondary's place) comes after ``impact_orbits`` of the
    member's circular orbit.  ``inputs``: ``beta``, ``primary_mass``,
    ``secondary_axes_scale_a``, ``_b``, ``_c``.

    Examples
    --------
    >>> members = sample_dart(4, rng=1)
    >>> len(members), sorted(members[0][3])
    (4, ['beta', 'primary_mass', 'secondary_axes_scale_a', 'secondary_axes_scale_b', \
'secondary_axes_scale_c'])
    >>> import numpy as np
    >>> along = [-np.sin(3 * np.pi), np.cos(3 * np.pi), 0.0]   # the velocity at 1.5 orbits
    >>> bool(-3.5e-3 < members[0][2][0].delta_v @ along < -2.0e-3)    # about -2.7 mm/s
    True
    """
    rng = np.random.default_rng(rng)
    members = []
    for _ in range(int(n)):
        b = rng.normal(*beta)
        m1 = rng.normal(*primary_mass)
        s = rng.normal(secondary_axes_scale[0], secondary_axes_scale[1], size=3)
        inputs = {"beta": float(b), "primary_mass": float(m1),
                  **{f"secondary_axes_scale_{k}": float(x) for k, x in zip("abc", s)}}
        try:
            member = _dart_member(b, m1, s, impact_orbits, epoch)
        except (AttitudeError, ValueError) as err:   # an impossible draw: bad input
            member = (err, None, [])
        members.append((*member, inputs))
    return members


def _split(member):
    """``(system, state, impulses, inputs)`` of a member; BinarySystemError if bad."""
    if not isinstance(member, Sequence) or not 2 <= len(member) <= 4:
        raise BinarySystemError("member: expected (system, state[, impulses[, inputs]])")
    system, state, *rest = member
    impulses = list(rest[0]) if rest and rest[0] is not None else []
    inputs = dict(rest[1]) if len(rest) > 1 and rest[1] is not None else {}
    if isinstance(system, Exception):
        raise BinarySystemError(f"member: {system}")
    if not isinstance(system, BinarySystem):
        raise BinarySystemError(f"member: system must be a BinarySystem, got "
                                f"{type(system).__name__}")
    if not isinstance(state, BinaryState):
        raise BinarySystemError(f"member: state must be a BinaryState, got "
                                f"{type(state).__name__}")
    return system, state, impulses, inputs


def _run_member(member, times, options: dict, eph=None) -> dict:
    """One member's outcome row (never raises); ``eph`` its ephemeris when the family
    already ran it."""
    row = {k: math.nan for k in _FLOATS}
    row.update(status=STATUS_OK, secondary_regime="", message="", inputs={})
    try:
        system, state, impulses, inputs = _split(member)
        row["inputs"] = inputs
    except BinarySystemError as err:
        if isinstance(member, Sequence) and len(member) == 4 and isinstance(member[3], dict):
            row["inputs"] = dict(member[3])
        row.update(status=STATUS_INVALID, message=str(err))
        return row
    try:
        if eph is None:
            eph = propagate_binary(system, state, times, events=impulses, **options["run"])
    except BinarySystemError as err:
        row.update(status=STATUS_INVALID, message=str(err))
        return row
    except Exception as err:  # noqa: BLE001  (a failed member must not stop the others)
        row.update(status=STATUS_FAILED, message=f"{type(err).__name__}: {err}")
        return row
    try:
        t_imp = [i.seconds_after(state.epoch) for i in impulses]
        d = diagnose(eph, impulses=t_imp, chaos=options["chaos"], system=system)
        t = eph.dataset["time"].values
        if t_imp and t[0] < min(t_imp) <= t[-1]:
            row["period_change"] = period_change(eph, min(t_imp)).change
        row.update(orbit_period=d.orbit_period, libration_amplitude=d.libration_amplitude,
                   eccentricity=d.eccentricity, lyapunov_exponent=d.lyapunov_exponent,
                   secondary_regime=d.secondary_regime)
        if not np.all(np.isfinite(eph.dataset["relative_position"].values)):
            raise BinarySystemError("the state is no longer finite")
    except Exception as err:  # noqa: BLE001  (a failed member must not stop the others)
        row.update(status=STATUS_FAILED, message=f"{type(err).__name__}: {err}")
    return row


def _run_chunk(members, times, options) -> list:
    # a failing member's NaNs: its status says so, not a warning per member
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        ran = _families(members, times, options)
        return [_run_member(m, times, options, ran.get(i)) for i, m in enumerate(members)]


def _families(members, times, options) -> dict:
    """With the LGVI at a given step (and no chaos measurement), the members of each
    family (one order and G, impulses at the same times, so that each member takes the
    steps it takes alone) run all at once (:func:`propagate_family`): ``{index:
    ephemeris}``.  A family that fails as a whole (a member falls into the other body)
    is left to run member by member, so that only that member fails."""
    run = options["run"]
    if (options["chaos"] or run["step"] is None or run["rtol"] is not None
            or run["method"] not in (None, "lgvi")):
        return {}
    families: dict = {}
    for i, member in enumerate(members):
        try:
            system, state, impulses, _ = _split(member)
        except BinarySystemError:
            continue
        try:
            when = tuple(sorted(e.seconds_after(state.epoch) for e in impulses))
        except Exception:  # noqa: BLE001  (a bad impulse: the member alone says why)
            continue
        families.setdefault((system.order, system.G, when), []).append(
            (i, system, state, impulses))
    out = {}
    for group in families.values():
        if len(group) < 2:
            continue
        index, systems, states, impulses = zip(*group)
        try:
            ephs = propagate_family(systems, states, times, step=run["step"], events=impulses)
        except Exception:  # noqa: BLE001  (the members then run one by one)
            continue
        if all(np.all(np.isfinite(e.dataset["relative_position"].values)) for e in ephs):
            out.update(zip(index, ephs))
    return out


def input_variables(rows: list) -> dict:
    """The members' inputs (each row's ``"inputs"`` dict) as ``member`` variables of a
    Dataset, NaN where a member lacks one (the ensembles of binaries and of encounters)."""
    names = []
    for r in rows:
        names += [k for k in r["inputs"] if k not in names]
    return {key: ("member", np.array([r["inputs"].get(key, math.nan) for r in rows],
                                     dtype=float), {"long_name": "input"})
            for key in names}


def rows_on_client(client, run_chunk, members: list, args: tuple, *,
                   chunk_size: int | None = None, chunks_per_worker: int = 1) -> list:
    """``run_chunk(chunk, *args)`` (a list of rows per chunk of ``members``) as one dask
    task per chunk on ``client`` (:func:`attitude.propagation.cluster.resolve_client`):
    the rows of all members in order.  ``chunk_size`` default: ``chunks_per_worker``
    chunks for each of the client's workers."""
    client = resolve_client(client)
    if chunk_size is None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunk_size = max(1, math.ceil(len(members) / (chunks_per_worker * workers)))
    size = int(chunk_size)
    futures = [client.submit(run_chunk, members[i:i + size], *args, pure=False)
               for i in range(0, len(members), size)]
    return [row for part in client.gather(futures) for row in part]


def ensemble(members, times, *, method: str | None = None, rtol: float | None = None,
             step=None, chaos: bool = False, client=None, chunk_size: int | None = None
             ) -> xr.Dataset:
    """Run many binaries and gather their outcomes along ``member``.

    Parameters
    ----------
    members : sequence
        Each ``(system, state)``, ``(system, state, impulses)`` or ``(system, state,
        impulses, inputs)`` (``inputs``: a dict of the numbers that vary, kept as
        variables; :func:`sample_dart` makes them).
    times : array-like
        s since each state's epoch (:func:`attitude.propagate`'s ``times``).
    method, rtol, step :
        Of :func:`attitude.propagate` for a binary, the same for every member.  With the
        LGVI at a given ``step`` the members of one family (one order and ``G``, their
        impulses at the same times) run all at once, vectorised
        (:func:`attitude.binary.propagate.propagate_family`).
    chaos : bool
        Measure each member's Lyapunov exponent (``diagnose(..., chaos=True)``: three
        times the cost).
    client : None, "local", a dask ``Client`` or a scheduler address
        None: in this process, one member after another; otherwise one dask task per
        chunk of ``chunk_size`` members (default: the members shared evenly, one chunk
        per worker: each chunk runs its families at once, and with the compiled LGVI a
        chunk costs in proportion to its members); ``"local"``: the session's LocalCluster
        (:func:`attitude.propagation.cluster.shared_local_client`).
    chunk_size : int, optional

    Returns
    -------
    xarray.Dataset
        Dim ``member``: ``status`` (0 ok, 1 bad input, 2 failed), ``message`` (why not
        0), ``orbit_period`` (s, after the last impulse), ``period_change`` (s, across
        the first impulse; NaN without one), ``libration_amplitude`` (rad, NaN if it
        circulates), ``eccentricity``, ``secondary_regime``, ``lyapunov_exponent`` (1/s,
        with ``chaos``), and each input.  ``attrs["regime_fractions"]``: each regime's
        share of the members with status 0 (they add up to 1).

    Examples
    --------
    >>> import numpy as np
    >>> members = sample_dart(2, rng=3, secondary_axes_scale=(1.0, 0.0))
    >>> P = 11.92 * 3600.0
    >>> ds = ensemble(members, np.arange(0.0, 2.8 * P, 600.0), method="integrator",
    ...               rtol=1e-8)
    >>> ds.status.values.tolist(), ds.attrs["regime_fractions"]
    ([0, 0], {'librating': 1.0})
    >>> bool(np.all((-40 < ds.period_change / 60) & (ds.period_change / 60 < -25)))
    True
    """
    members = list(members)
    times = np.asarray(times, dtype=float)
    run = {"method": method, "rtol": rtol, "step": step}
    options = {"run": run, "chaos": bool(chaos)}
    if client is None:
        rows = _run_chunk(members, times, options)
    else:
        rows = rows_on_client(client, _run_chunk, members, (times, options),
                              chunk_size=chunk_size)
    return _dataset(rows, chaos)


def _dataset(rows: list, chaos: bool) -> xr.Dataset:
    n = len(rows)
    data = {
        "status": ("member", np.array([r["status"] for r in rows], dtype=np.int8),
                   {"flag_values": [0, 1, 2],
                    "flag_meanings": "ok invalid_input propagation_failed"}),
        "message": ("member", np.array([r["message"] for r in rows], dtype=object)),
        "secondary_regime": ("member", np.array([r["secondary_regime"] for r in rows],
                                                dtype=object)),
    }
    units = {"orbit_period": "s", "period_change": "s", "libration_amplitude": "rad",
             "eccentricity": "1", "lyapunov_exponent": "s-1"}
    for key in _FLOATS:
        if key == "lyapunov_exponent" and not chaos:
            continue
        data[key] = ("member", np.array([r[key] for r in rows], dtype=float),
                     {"units": units[key]})
    inputs = input_variables(rows)
    data.update(inputs)
    ok = [r["secondary_regime"] for r in rows if r["status"] == STATUS_OK]
    fractions = {reg: ok.count(reg) / len(ok) for reg in REGIMES if ok.count(reg)}
    return xr.Dataset(data, coords={"member": np.arange(n)},
                      attrs={"title": "attitude: an ensemble of binary systems",
                             "regime_fractions": fractions,
                             "inputs": list(inputs)})
