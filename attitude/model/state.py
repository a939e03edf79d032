"""The rotational state of a rigid body at an epoch.

An :class:`AttitudeState` holds an epoch (astropy ``Time`` with an explicit scale), the
attitude as a scipy ``Rotation`` mapping body-frame vectors into the inertial frame
(``v_inertial = attitude.apply(v_body)``), the body-frame angular velocity in rad/s,
and the label of the inertial frame.
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from astropy import units as u
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ..foundations.errors import InvalidStateError
from ..foundations.quantities import DEFAULT_TIME_SCALE, to_si, to_time  # the one default
from ..foundations.spec import Key, Table
from .body import RigidBody

__all__ = ["AttitudeState", "INERTIAL_FRAMES", "DEFAULT_TIME_SCALE", "QUATERNION_NORM_TOL",
           "direction_frame", "spin_axis_quaternion", "stack_states", "format_epoch",
           "ATTITUDE_TABLE", "rotation_from_table"]

#: Inertial frame labels accepted (case-insensitive).  No frame conversion is ever done:
#: the label travels with the data.  ``INERTIAL`` is a generic label for synthetic studies.
INERTIAL_FRAMES = (
    "ICRF", "GCRF", "EME2000", "J2000", "ECLIPJ2000", "ECLIPTIC_J2000", "MOD", "TOD",
    "TEME", "SATURN_EQUATORIAL", "INERTIAL",
)

#: A quaternion given by the user must have a norm within this of 1.
QUATERNION_NORM_TOL = 1e-6


def check_frame(frame: str, *, error=InvalidStateError) -> str:
    """Return the canonical upper-case label, or raise naming the closest known one."""
    if not isinstance(frame, str):
        raise error(f"frame: expected a string label such as 'ICRF', got {frame!r}")
    label = frame.strip().upper()
    if label not in INERTIAL_FRAMES:
        near = difflib.get_close_matches(label, INERTIAL_FRAMES, n=1)
        hint = f"did you mean {near[0]!r}? " if near else ""
        raise error(f"frame {frame!r} is not a known inertial frame; {hint}"
                    f"use one of {', '.join(INERTIAL_FRAMES)}")
    return label


def as_epoch(epoch, *, error=InvalidStateError) -> Time:
    """A scalar astropy Time; strings are parsed in :data:`DEFAULT_TIME_SCALE`."""
    if isinstance(epoch, (str, Mapping)):
        epoch = to_time(epoch, scale=DEFAULT_TIME_SCALE, key="epoch", error=error,
                        precision=None)
    if not isinstance(epoch, Time):
        raise error(f"epoch: expected an astropy Time or an ISO 8601 string, got {epoch!r}")
    if not epoch.isscalar:
        raise error(f"epoch: expected a single time, got an array of shape {epoch.shape}")
    return epoch


def format_epoch(time: Time, digits: int = 9) -> str | np.ndarray:
    """ISO 8601 calendar text (``isot``) of ``time`` with ``digits`` decimals of seconds.

    The text is taken from astropy's two-double representation, so with the default 9
    digits an epoch is exact to 0.5 ns; ``time`` itself is not modified (a copy carries
    the precision).  This is how ephemeris files write epochs (the netCDF ``epoch``
    attribute, the CCSDS AEM time tags).

    Parameters
    ----------
    time : astropy.time.Time
        A scalar or an array of times; the text is in its own time scale.
    digits : int
        Decimals of the seconds, 0 to 9.

    Returns
    -------
    str or numpy.ndarray of str
        One string for a scalar time, an array of strings of the same shape otherwise.

    Examples
    --------
    >>> from astropy.time import Time, TimeDelta
    >>> t = Time("2029-04-13T21:46:00", scale="tdb") + TimeDelta(1e-9, format="sec")
    >>> format_epoch(t)
    '2029-04-13T21:46:00.000000001'
    >>> format_epoch(t, digits=3)
    '2029-04-13T21:46:00.000'
    >>> format_epoch(t + TimeDelta([0.0, 0.5], format="sec"), digits=1).tolist()
    ['2029-04-13T21:46:00.0', '2029-04-13T21:46:00.5']
    """
    copy = time.copy()
    copy.precision = int(digits)
    return copy.isot


def as_omega(omega, *, name: str = "omega_body", error=InvalidStateError) -> np.ndarray:
    """Angular velocity in rad/s from floats (rad/s), a Quantity or a string."""
    w = np.array(to_si(omega, "rad/s", name=name, finite=False, error=error), dtype=float)  # a copy
    if w.shape != (3,):
        raise error(f"{name}: expected 3 components, got shape {w.shape}")
    if not np.all(np.isfinite(w)):
        raise error(f"{name} = {w.tolist()} rad/s: every component must be finite "
                    "(NaN or inf rates cannot be propagated)")
    return w


def direction_frame(ra, dec) -> np.ndarray:
    """Right-handed frames ``(..., 3, 3)`` (columns: x, y, z in inertial components)
    whose z axis points to right ascension ``ra``, declination ``dec`` (rad) and whose x
    axis is the node ``z_inertial x n`` of that direction (the inertial y axis at a
    pole).  The frame of a spin-axis state and of the angular momentum of a sampled
    tumbler.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude.model.state import direction_frame
    >>> direction_frame(0.0, 0.0).round(12) + 0.0    # z toward RA 0, Dec 0; x the node
    array([[0., 0., 1.],
           [1., 0., 0.],
           [0., 1., 0.]])
    """
    n = np.stack([np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)], axis=-1)
    node = np.cross([0.0, 0.0, 1.0], n)
    norm = np.linalg.norm(node, axis=-1, keepdims=True)
    node = np.where(norm < 1e-12, [0.0, 1.0, 0.0], node / np.where(norm < 1e-12, 1.0, norm))
    return np.stack([node, np.cross(n, node), n], axis=-1)


def spin_axis_quaternion(ra, dec, *, about: str = "C", rotation_angle=0.0) -> np.ndarray:
    """Quaternions (..., 4), principal -> inertial, scalar-last, of bodies whose principal
    axis ``about`` (``"A"``, ``"B"`` or ``"C"``) points to right ascension ``ra`` and
    declination ``dec`` (rad; arrays broadcast).

    The rotation phase is fixed by putting the next principal axis (B for A, C for B, A
    for C) along the node ``z x n`` of the direction ``n`` (the inertial y axis at a
    pole, :func:`direction_frame`), then turning by ``rotation_angle`` (rad) about the
    spin axis.

    Examples
    --------
    >>> import numpy as np
    >>> q = spin_axis_quaternion(0.0, np.pi / 2)       # C along the inertial z axis
    >>> r = Rotation.from_quat(q)
    >>> np.round(r.apply([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), 12) + 0.0   # C to n, A to y
    array([[0., 0., 1.],
           [0., 1., 0.]])
    >>> spin_axis_quaternion([0.0, 1.0], [0.0, 0.5], about="A").shape
    (2, 4)
    """
    if about not in ("A", "B", "C"):
        raise InvalidStateError(f"about: expected 'A', 'B' or 'C', got {about!r}")
    k = "ABC".index(about)
    ra, dec, angle = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in
                                           (ra, dec, rotation_angle)))
    # principal -> inertial: column k is n, column k+1 the node, column k+2 completes it
    frame = np.roll(direction_frame(ra, dec), k + 1, axis=-1)
    turn = np.zeros(angle.shape + (3,))
    turn[..., k] = angle
    return (Rotation.from_matrix(frame.reshape(-1, 3, 3))
            * Rotation.from_rotvec(turn.reshape(-1, 3))).as_quat().reshape(angle.shape + (4,))


@dataclass(frozen=True, eq=False)
class AttitudeState:
    """Epoch, attitude and body rates of a rigid body.

    Parameters
    ----------
    epoch : astropy Time or str
        A single epoch; strings are read as ISO 8601 in TDB.
    attitude : scipy Rotation
        Body -> inertial: ``v_inertial = attitude.apply(v_body)``.
    omega_body : (3,) array-like or Quantity
        Angular velocity in body-frame components; plain numbers are rad/s.
    frame : str
        Label of the inertial frame (:data:`INERTIAL_FRAMES`), default ``"ICRF"``.

    Examples
    --------
    >>> import astropy.units as u
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude import AttitudeState, RigidBody
    >>> state = AttitudeState(epoch="2029-04-13T00:00:00", attitude=Rotation.identity(),
    ...                       omega_body=[0.0, 0.0, 360.0] * u.deg / u.day)
    >>> state.epoch.scale, state.frame
    ('tdb', 'ICRF')
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> float(state.kinetic_energy(body))  # 1/2 C w^2
    7.93...e-09
    """

    epoch: Time
    attitude: Rotation
    omega_body: np.ndarray
    frame: str = "ICRF"

    def __post_init__(self):
        object.__setattr__(self, "epoch", as_epoch(self.epoch))
        if not isinstance(self.attitude, Rotation) or not self.attitude.single:
            raise InvalidStateError(
                "attitude: expected a single scipy Rotation (body -> inertial), got "
                f"{type(self.attitude).__name__}; build one with "
                "AttitudeState.from_quaternion or Rotation.from_quat")
        object.__setattr__(self, "omega_body", as_omega(self.omega_body))
        object.__setattr__(self, "frame", check_frame(self.frame))

    # --- constructors ---------------------------------------------------------
    @classmethod
    def from_quaternion(cls, quaternion, *, scalar_first: bool = False, epoch,
                        omega_body, frame: str = "ICRF") -> AttitudeState:
        """From a body -> inertial quaternion, scalar-last ``(x, y, z, w)`` unless
        ``scalar_first=True``.  Its norm must be 1 within :data:`QUATERNION_NORM_TOL`."""
        q = np.asarray(quaternion, dtype=float)
        if q.shape != (4,) or not np.all(np.isfinite(q)):
            raise InvalidStateError(f"quaternion: expected 4 finite components, got {q!r}")
        norm = np.linalg.norm(q)
        if abs(norm - 1.0) > QUATERNION_NORM_TOL:
            raise InvalidStateError(
                f"quaternion {q.tolist()} has norm {norm:.9g}, not 1; normalise it, and "
                f"check the component order (scalar_first={scalar_first})")
        return cls(epoch, Rotation.from_quat(q, scalar_first=scalar_first), omega_body, frame)

    @classmethod
    def from_euler(cls, seq: str, angles, *, degrees: bool = False, epoch, omega_body,
                   frame: str = "ICRF") -> AttitudeState:
        """From Euler angles of the body -> inertial rotation in any scipy sequence
        (``"ZXZ"`` intrinsic, ``"zxz"`` extrinsic, ...).  ``angles`` may be a Quantity."""
        if hasattr(angles, "unit") or isinstance(angles, str):
            angles, degrees = to_si(angles, "rad", name="angles", error=InvalidStateError), False
        try:
            rot = Rotation.from_euler(seq, np.asarray(angles, dtype=float), degrees=degrees)
        except ValueError as exc:
            raise InvalidStateError(f"euler: {exc}") from None
        return cls(epoch, rot, omega_body, frame)

    @classmethod
    def from_spin_axis(cls, body: RigidBody, ra, dec, rate, *, epoch, about: str = "C",
                       rotation_angle=0.0, frame: str = "ICRF") -> AttitudeState:
        """A principal-axis spin at ``rate`` about the principal axis ``about`` of
        ``body``, pointing to right ascension ``ra``, declination ``dec`` of the inertial
        frame (angles and rate: Quantities, strings, or rad and rad/s), turned by
        ``rotation_angle`` about it from the phase of :func:`spin_axis_quaternion`.

        Examples
        --------
        >>> import astropy.units as u
        >>> from attitude import AttitudeState, RigidBody
        >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
        >>> s = AttitudeState.from_spin_axis(body, 250 * u.deg, -75 * u.deg,
        ...                                  360 * u.deg / u.h, epoch="2030-01-01")
        >>> s.omega_body.round(6) + 0.0      # about C, 1 turn per hour
        array([0.      , 0.      , 0.001745])
        >>> bool(s.angular_momentum(body)[2] < 0)    # the pole is at dec = -75 deg
        True
        """
        ra, dec, angle = (float(to_si(x, "rad", name=name, error=InvalidStateError))
                          for x, name in ((ra, "ra"), (dec, "dec"),
                                          (rotation_angle, "rotation_angle")))
        rate = float(to_si(rate, "rad/s", name="rate", error=InvalidStateError))
        if not abs(dec) <= np.pi / 2 * (1 + 1e-12):
            raise InvalidStateError(f"dec: must be within +-90 deg, got "
                                    f"{np.degrees(dec):.6g} deg")
        q = spin_axis_quaternion(ra, dec, about=about, rotation_angle=angle)
        attitude = Rotation.from_quat(q) * body.body_to_principal
        axis = body.principal_axes[:, "ABC".index(about)]
        return cls(epoch, attitude, rate * axis, frame)

    def replace(self, **changes) -> AttitudeState:
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    # --- derived quantities -----------------------------------------------------
    def angular_momentum_body(self, body: RigidBody) -> np.ndarray:
        """``L = I omega`` in body-frame components, kg m^2/s."""
        return body.inertia @ self.omega_body

    def angular_momentum(self, body: RigidBody) -> np.ndarray:
        """Angular momentum in inertial-frame components, kg m^2/s."""
        return self.attitude.apply(self.angular_momentum_body(body))

    def kinetic_energy(self, body: RigidBody) -> float:
        """Rotational kinetic energy ``omega . I omega / 2``, J."""
        return 0.5 * float(self.omega_body @ body.inertia @ self.omega_body)

    def dynamic_inertia(self, body: RigidBody) -> float:
        """``L^2 / 2E`` (kg m^2), between A and C; NaN for a body at rest."""
        e2 = 2.0 * self.kinetic_energy(body)
        L = self.angular_momentum_body(body)
        return float(L @ L / e2) if e2 > 0 else float("nan")

    def omega_principal(self, body: RigidBody) -> np.ndarray:
        """Angular velocity in the principal frame of ``body``, rad/s."""
        return body.body_to_principal.apply(self.omega_body)

    def __repr__(self) -> str:
        q = self.attitude.as_quat()
        return (f"AttitudeState(epoch={self.epoch.isot} {self.epoch.scale.upper()}, "
                f"quat_xyzw={np.array2string(q, precision=6)}, "
                f"omega_body={np.array2string(self.omega_body, precision=6)} rad/s, "
                f"frame={self.frame})")


def stack_states(states, n: int | None = None
                 ) -> tuple[Time, str, np.ndarray, np.ndarray]:
    """The one batch normaliser of states: a sequence of :class:`AttitudeState` sharing
    one epoch and frame -> ``(epoch, frame, quaternion (N, 4), omega_body (N, 3))``.

    The epochs are compared in one array operation on their two-part Julian dates, each
    distinct ``Time`` object once (the states of a batch normally share one epoch
    object; a state in another scale is compared through astropy on its own).

    Parameters
    ----------
    states : sequence of AttitudeState
    n : int, optional
        The number of bodies the states go with.

    Raises
    ------
    InvalidStateError
        Naming the index of a state that is not an ``AttitudeState`` or whose epoch or
        frame differs from the first.

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> s = AttitudeState("2029-04-13", Rotation.identity(), [0.0, 0.0, 1.0])
    >>> epoch, frame, q, w = stack_states([s, s])
    >>> frame, q.shape, w.shape
    ('ICRF', (2, 4), (2, 3))
    """
    states = list(states)
    if not states or (n is not None and len(states) != n):
        raise InvalidStateError(f"batch: got {n} bodies and {len(states)} states; give one "
                                "state per body")
    first = states[0]
    if not isinstance(first, AttitudeState):
        raise InvalidStateError(f"states[0]: expected an AttitudeState, got "
                                f"{type(first).__name__}")
    epoch, frame = first.epoch, first.frame
    # one pass: the type, the frame, and each distinct epoch object (the epochs of a batch
    # are usually one Time object shared by all states; reading a Time's Julian date
    # costs ~50 us, so each distinct object is compared once, below)
    distinct: dict[int, int] = {}
    for i, s in enumerate(states):
        if not isinstance(s, AttitudeState):
            raise InvalidStateError(f"states[{i}]: expected an AttitudeState, got "
                                    f"{type(s).__name__}")
        if s.frame != frame:
            raise InvalidStateError(f"states[{i}].frame = {s.frame} differs from "
                                    f"states[0].frame = {frame}")
        if s.epoch is not epoch:
            distinct.setdefault(id(s.epoch), i)
    rows = np.array(list(distinct.values()), dtype=int)
    others = [states[i].epoch for i in rows]
    same_scale = np.array([e.scale == epoch.scale for e in others], dtype=bool)
    jd1 = np.array([e.jd1 if ok else 0.0 for e, ok in zip(others, same_scale)], dtype=float)
    jd2 = np.array([e.jd2 if ok else 0.0 for e, ok in zip(others, same_scale)], dtype=float)
    # the same instant in the same scale: the two-part Julian dates differ by exactly 0
    differs = same_scale & (((jd1 - epoch.jd1) + (jd2 - epoch.jd2)) != 0.0)
    for k in np.flatnonzero(~same_scale):
        differs[k] = abs((others[k] - epoch).to_value(u.s)) > 0
    if differs.any():
        i = int(rows[np.argmax(differs)])
        raise InvalidStateError(f"states[{i}].epoch differs from states[0].epoch; a batch "
                                "shares one epoch")
    quaternion = np.stack([s.attitude.as_quat() for s in states])     # body -> inertial
    omega = np.array([s.omega_body for s in states], dtype=float)
    return epoch, frame, quaternion, omega


#: An attitude (body -> inertial) in a scenario file: a quaternion or Euler angles.  The
#: one declaration of the single-body scenario's (``[state] attitude``, a part's
#: ``orientation``) and the binary's (each body's ``attitude``).
ATTITUDE_TABLE = Table("rotation", (
    Key("quaternion_scalar_last", "quantity", unit="", shape=(4,), doc="x, y, z, w"),
    Key("quaternion_scalar_first", "quantity", unit="", shape=(4,), doc="w, x, y, z"),
    Key("euler", "string", doc="scipy sequence: upper case intrinsic ('ZXZ'), lower case "
                               "extrinsic"),
    Key("angles", "quantity", unit="rad", shape=((), (1,), (2,), (3,)),
        doc="the Euler angles, one per axis of `euler`"),
), exactly_one=(("quaternion_scalar_last", "quaternion_scalar_first", "euler"),),
    needs=(("euler", ("angles",)), ("angles", ("euler",))),
    doc="body -> inertial: one of quaternion_scalar_last, quaternion_scalar_first, or euler "
        "with angles")


def rotation_from_table(table: Mapping, key: str, fail) -> Rotation:
    """The scipy Rotation of a validated :data:`ATTITUDE_TABLE` table (``key`` its place
    in the file); ``fail(key, message)`` returns the error to raise: for Euler angles
    scipy refuses, or a quaternion whose norm is not 1 within
    :data:`QUATERNION_NORM_TOL`.

    Examples
    --------
    >>> r = rotation_from_table({"euler": "z", "angles": 0.5}, "state.attitude", None)
    >>> float(r.magnitude())
    0.5
    >>> rotation_from_table({"quaternion_scalar_first": [2.0, 0.0, 0.0, 0.0]}, "q",
    ...                     lambda k, m: ValueError(f"{k}: {m}"))
    Traceback (most recent call last):
    ...
    ValueError: q.quaternion_scalar_first: quaternion [2.0, 0.0, 0.0, 0.0] has norm 2, ...
    """
    if "euler" in table:
        try:
            return Rotation.from_euler(table["euler"], table["angles"])
        except (ValueError, TypeError) as exc:
            raise fail(f"{key}.euler", f"{exc}; write a scipy sequence such as 'ZXZ' "
                                       "with one angle per axis") from None
    form = next(k for k in ("quaternion_scalar_last", "quaternion_scalar_first") if k in table)
    q = np.asarray(table[form], dtype=float)
    norm = np.linalg.norm(q)
    if abs(norm - 1) > QUATERNION_NORM_TOL:
        raise fail(f"{key}.{form}", f"quaternion {q.tolist()} has norm {norm:.9g}, not 1; "
                                    "normalise it and check the component order")
    return Rotation.from_quat(q, scalar_first=(form == "quaternion_scalar_first"))
