"""Populations: many bodies and their states at one epoch, as arrays along ``body``.

An :class:`Ensemble` is a batch of N rigid bodies and their initial states at one
epoch, in one inertial frame, held as arrays along a ``body`` dimension: inertia
tensors (N, 3, 3) in the body frames, attitudes (N, 4) body -> inertial (scalar-last)
and body-frame rates (N, 3) in rad/s.  It is what a debris catalogue or a Monte Carlo
cloud of an asteroid's rotation state looks like to :func:`attitude.propagate`::

    ens = att.Ensemble.from_table("debris.csv", epoch="2030-01-01", frame="GCRF")
    eph = att.propagate(ens, times)                    # dims (body, time)
    eph = att.propagate(ens, times, client=client)     # the same on a dask cluster

Constructors: :meth:`Ensemble.from_arrays`, :meth:`Ensemble.from_bodies` (sequences of
:class:`~attitude.RigidBody` and :class:`~attitude.AttitudeState`),
:meth:`Ensemble.from_table` (CSV, Parquet, a pandas DataFrame or an xarray Dataset) and
:meth:`Ensemble.sample` (a seeded Monte Carlo draw from a mean and covariance of
physical parameters, :data:`attitude.model.sampling.MODELS`, or from a user callable).

A row whose input is not physical (inertia not positive-definite or violating the
triangle inequality, a NaN rate, a zero quaternion, moment ratios out of range) does not
sink the others: it is recorded in :attr:`Ensemble.invalid` with its index and the
reason, reported once (:class:`InvalidBodiesWarning`), and propagated as NaN with
``status = 1`` in the ephemeris.

Sampling models live in :mod:`attitude.model.sampling`, table reading in
:mod:`attitude.model.tables`, the statistics of a population in :mod:`attitude.analysis.statistics`
and its propagation in chunks (locally or on dask) in :mod:`attitude.propagation.batch`;
:mod:`attitude.ensemble` gathers them for users.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import InvalidBodiesWarning, InvalidInertiaError, InvalidStateError
from ..foundations.quantities import to_si
from .body import RigidBody, as_bodies, check_inertia, diagonal_inertia, principal_quaternions
from .sampling import draw, invalid_where
from .state import AttitudeState, as_epoch, check_frame, stack_states
from .tables import ensemble_columns

__all__ = ["Ensemble", "check_batch"]


class Ensemble:
    """N rigid bodies and their states at one epoch, along a ``body`` dimension.

    Parameters
    ----------
    inertia : (N, 3, 3) array_like or Quantity
        Inertia tensors in the body frames (kg m^2).
    quaternion : (N, 4) array_like
        Attitudes, body -> inertial, scalar-last ``(x, y, z, w)``.
    omega_body : (N, 3) array_like or Quantity
        Body-frame angular velocities (plain numbers are rad/s).
    epoch : astropy Time or str
        The common epoch (strings are ISO 8601 in TDB).
    frame : str
        Inertial frame label (:data:`attitude.INERTIAL_FRAMES`).
    names : sequence of str, optional
        One name per body.
    mass : (N,) array_like or Quantity, optional
        Masses (kg; NaN where unknown), for torque models that need them (the heavy
        top).
    parameters : dict of (N,) arrays, optional
        The physical parameters a sampled ensemble was drawn from (SI).
    on_invalid : {"report", "raise"}
        ``"report"`` (default): non-physical rows are kept, listed in :attr:`invalid`
        and propagated as NaN (one :class:`InvalidBodiesWarning`); ``"raise"``: the
        first one raises :class:`~attitude.InvalidInertiaError` or
        :class:`~attitude.InvalidStateError` naming its index.
    invalid : dict, optional
        Rows already known to be invalid, ``{index: reason}`` (a sampling model's
        verdict); merged with the checks, the given reason first.
    nominal : int, optional
        Index of the nominal member (the mean state of a sampled ensemble), from which
        :func:`attitude.analysis.statistics.attitude_spread` measures; None for a catalogue.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> ens = att.Ensemble.from_arrays(
    ...     principal_moments=[[1.0, 2.0, 3.0], [2.0, 2.5, 4.0]],
    ...     quaternion=[[0, 0, 0, 1], [0, 0, 0, 1]],
    ...     omega_body=[[0.1, 0.0, 0.3], [0.0, 0.2, 0.01]], epoch="2030-01-01")
    >>> len(ens), ens.principal_moments[1]
    (2, array([2. , 2.5, 4. ]))
    >>> eph = att.propagate(ens, np.linspace(0.0, 100.0, 11))
    >>> eph.dataset.quaternion.dims
    ('body', 'time', 'quaternion_component')
    """

    __slots__ = ("inertia", "quaternion", "omega_body", "epoch", "frame", "names",
                 "parameters", "invalid", "principal_moments", "body_to_principal",
                 "nominal", "mass")

    def __init__(self, inertia, quaternion, omega_body, *, epoch, frame: str = "ICRF",
                 names: Sequence[str] | None = None,
                 parameters: Mapping[str, np.ndarray] | None = None,
                 on_invalid: str = "report", invalid: Mapping[int, str] | None = None,
                 nominal: int | None = None, mass=None):
        if on_invalid not in ("report", "raise"):
            raise InvalidStateError(f"on_invalid: expected 'report' or 'raise', got "
                                    f"{on_invalid!r}")
        inertia = np.array(to_si(inertia, "kg m2", name="inertia", finite=False,
                                 error=InvalidInertiaError),
                           dtype=float, ndmin=3)
        quaternion = np.array(quaternion, dtype=float, ndmin=2)
        omega = np.array(to_si(omega_body, "rad/s", name="omega_body", finite=False,
                               error=InvalidStateError), dtype=float, ndmin=2)
        n = inertia.shape[0]
        for name, arr, shape in (("inertia", inertia, (n, 3, 3)),
                                 ("quaternion", quaternion, (n, 4)),
                                 ("omega_body", omega, (n, 3))):
            if arr.shape != shape:
                raise InvalidStateError(f"{name}: expected shape {shape} for {n} bodies, got "
                                        f"{arr.shape}")
        if n == 0:
            raise InvalidStateError("an ensemble needs at least one body")
        names = [""] * n if names is None else [str(x) for x in names]
        if len(names) != n:
            raise InvalidStateError(f"names: expected {n} names, got {len(names)}")
        mass = np.full(n, np.nan) if mass is None else np.array(to_si(
            mass, "kg", name="mass", finite=False, error=InvalidInertiaError), dtype=float, ndmin=1)
        if mass.shape != (n,):
            raise InvalidInertiaError(f"mass: expected {n} masses, got shape {mass.shape}")
        checked, moments, b2p = _check_rows(inertia, quaternion, omega)
        invalid = {int(i): str(why) for i, why in (invalid or {}).items()}
        invalid = dict(sorted({**checked, **invalid}.items()))
        if invalid and on_invalid == "raise":
            i, why = next(iter(invalid.items()))
            error = (InvalidInertiaError if why.startswith(("inertia", "principal moments"))
                     else InvalidStateError)
            raise error(f"body {i}: {why}")
        if invalid:
            shown = "; ".join(f"body {i}: {why}" for i, why in list(invalid.items())[:5])
            more = f" (and {len(invalid) - 5} more)" if len(invalid) > 5 else ""
            warnings.warn(f"{len(invalid)} of {n} bodies are not physical and will be "
                          f"propagated as NaN (status 1): {shown}{more}; see "
                          "Ensemble.invalid", InvalidBodiesWarning, stacklevel=2)
        params = {k: np.asarray(v, dtype=float) for k, v in (parameters or {}).items()}
        for slot, value in (("inertia", inertia), ("quaternion", quaternion),
                            ("omega_body", omega), ("epoch", as_epoch(epoch)),
                            ("frame", check_frame(frame)), ("names", tuple(names)),
                            ("parameters", params), ("invalid", dict(invalid)),
                            ("principal_moments", moments), ("body_to_principal", b2p),
                            ("nominal", None if nominal is None else int(nominal)),
                            ("mass", mass)):
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(self, slot, value)

    def __setattr__(self, name, value):
        raise AttributeError("Ensemble is immutable; build a new one")

    # --- constructors -------------------------------------------------------------
    @classmethod
    def from_arrays(cls, *, quaternion=None, omega_body, epoch, inertia=None,
                    principal_moments=None, frame: str = "ICRF", scalar_first: bool = False,
                    names=None, on_invalid: str = "report") -> Ensemble:
        """An ensemble from arrays: ``inertia`` (N, 3, 3) *or* ``principal_moments``
        (N, 3) (body frame = principal frame), ``quaternion`` (N, 4) (default identity;
        ``scalar_first=True`` for ``(w, x, y, z)``) and ``omega_body`` (N, 3)."""
        if (inertia is None) == (principal_moments is None):
            raise InvalidInertiaError("give exactly one of inertia= (N, 3, 3) and "
                                      "principal_moments= (N, 3)")
        if principal_moments is not None:
            m = np.array(to_si(principal_moments, "kg m2", name="principal_moments",
                               finite=False, error=InvalidInertiaError), dtype=float, ndmin=2)
            if m.ndim != 2 or m.shape[1] != 3:
                raise InvalidInertiaError(f"principal_moments: expected shape (N, 3), got "
                                          f"{m.shape}")
            inertia = diagonal_inertia(m)
        omega = np.array(to_si(omega_body, "rad/s", name="omega_body", finite=False,
                               error=InvalidStateError), dtype=float, ndmin=2)
        if quaternion is None:
            quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (omega.shape[0], 1))
        quaternion = np.array(quaternion, dtype=float, ndmin=2)
        if scalar_first:
            quaternion = np.roll(quaternion, -1, axis=-1)
        return cls(inertia, quaternion, omega, epoch=epoch, frame=frame, names=names,
                   on_invalid=on_invalid)

    @classmethod
    def from_bodies(cls, bodies: Sequence[RigidBody],
                    states: Sequence[AttitudeState]) -> Ensemble:
        """An ensemble from equal-length sequences of bodies and states (one epoch and
        frame)."""
        bodies, states = check_batch(bodies, states)
        return cls(np.stack([b.inertia for b in bodies]),
                   np.stack([s.attitude.as_quat() for s in states]),
                   np.stack([s.omega_body for s in states]), epoch=states[0].epoch,
                   frame=states[0].frame, names=[b.name for b in bodies],
                   mass=[np.nan if b.mass is None else b.mass for b in bodies],
                   on_invalid="raise")

    @classmethod
    def from_table(cls, table, *, epoch, frame: str = "ICRF",
                   on_invalid: str = "report") -> Ensemble:
        """An ensemble from a table with one row per body.

        ``table``: a path to a ``.csv`` or ``.parquet`` file (read with pandas), a pandas
        DataFrame or an xarray Dataset (one ``body`` dimension).  Columns (a unit in
        brackets, as ``wx [deg/s]``, overrides the SI default):

        - the body: ``A B C`` (principal moments, kg m^2; body frame = principal frame)
          or ``Ixx Iyy Izz Ixy Ixz Iyz`` (tensor, kg m^2);
        - the attitude (optional, identity if absent): ``qx qy qz qw`` (body -> inertial,
          scalar-last);
        - the rates: ``wx wy wz`` (body frame, rad/s);
        - optionally ``name``.

        Examples
        --------
        >>> import io, attitude as att
        >>> csv = io.StringIO("name,A,B,C,wx [deg/s],wy [deg/s],wz [deg/s]\\n"
        ...                   "sat-1,10,12,15,0.5,0.1,2.0\\nsat-2,3,4,5,0,0,1\\n")
        >>> ens = att.Ensemble.from_table(csv, epoch="2030-01-01", frame="GCRF")
        >>> ens.names, float(ens.omega_body[1, 2].round(6))
        (('sat-1', 'sat-2'), 0.017453)
        """
        inertia, q, omega, names = ensemble_columns(table)
        return cls(inertia, q, omega, epoch=epoch, frame=frame, names=names,
                   on_invalid=on_invalid)

    @classmethod
    def sample(cls, n: int, *, epoch, rng=None, model: str = "tumbling",
               mean: Mapping | None = None, sigma: Mapping | None = None, cov=None,
               sampler: Callable | None = None, frame: str = "ICRF",
               include_nominal: bool = True) -> Ensemble:
        """A Monte Carlo ensemble drawn from a distribution of physical parameters.

        Parameters
        ----------
        n : int
            Number of bodies (the nominal included).
        epoch, frame
            Common epoch and inertial frame.
        rng : numpy Generator or int, optional
            The random generator (or a seed for ``numpy.random.default_rng``): the same
            seed gives the same ensemble.
        model : {"tumbling", "spin"}
            The parameterisation (:data:`attitude.model.sampling.MODELS`).
        mean : dict
            Parameter name -> value (a Quantity, a string astropy parses, or a number in
            SI: rad, rad/s, s, kg m^2).  Required parameters of the model must be given;
            ``precession_angle``, ``rotation_angle`` and ``moment_c`` default to 0, 0, 1.
        sigma : dict, optional
            Parameter name -> standard deviation (same units as ``mean``); independent
            normal errors.  Parameters without a sigma are fixed at the mean.  The
            direction (``"angular_momentum_direction"`` for the tumbling model,
            ``"spin_direction"`` for the spin model) takes an angle: an isotropic error
            about the mean direction, the same at the pole as at the equator (the
            offsets on the sky are normal with this sigma in each of two perpendicular
            directions), instead of sigmas on the right ascension and declination.
        cov : (k, k) array_like, optional
            Instead of ``sigma``: the covariance of the ``k`` parameters of ``mean``, in
            the order of ``mean``'s keys and in SI units (rad, rad/s, s).
        sampler : callable, optional
            ``sampler(rng, n) -> dict`` of (n,) arrays of model parameters (SI), for
            any other distribution; replaces ``mean``/``sigma``/``cov`` draws (``mean``
            still supplies parameters the sampler does not return).
        include_nominal : bool
            Body 0 is the mean state itself (default), so that
            :func:`~attitude.analysis.statistics.attitude_spread` measures the spread from the
            nominal.

        Returns
        -------
        Ensemble
            With :attr:`parameters` holding the drawn values; draws that give a
            non-physical body or state (moment ratios violating the triangle inequality,
            an energy ratio outside [1, C/A]) are reported invalid by index.

        Examples
        --------
        >>> import astropy.units as u, attitude as att
        >>> ens = att.Ensemble.sample(
        ...     100, rng=42, epoch="2029-04-13", frame="ECLIPJ2000",
        ...     mean={"angular_momentum_ra": 250 * u.deg, "angular_momentum_dec": -75 * u.deg,
        ...           "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
        ...           "precession_period": 27.38 * u.h},
        ...     sigma={"energy_ratio": 0.013 / 3, "precession_period": 0.07 / 3 * u.h})
        >>> d = att.ensemble.diagnose_ensemble(ens)
        >>> float(d["precession"][0] / 3600)      # the nominal reproduces P_phi
        27.38...
        """
        moments, q, w, values, bad = draw(n, rng=rng, model=model, mean=mean, sigma=sigma,
                                          cov=cov, sampler=sampler,
                                          include_nominal=include_nominal)
        k0 = 1 if include_nominal else 0
        inertia = diagonal_inertia(np.where(np.isfinite(moments), moments, 1.0))
        names = ["nominal" if i < k0 else f"sample {i}" for i in range(len(q))]
        return cls(inertia, q, w, epoch=epoch, frame=frame, names=names,
                   parameters=values, invalid=bad, nominal=0 if k0 else None)

    # --- views --------------------------------------------------------------------
    def __len__(self) -> int:
        return self.inertia.shape[0]

    def __repr__(self) -> str:
        bad = f", {len(self.invalid)} invalid" if self.invalid else ""
        return (f"<Ensemble {len(self)} bodies{bad}, epoch {self.epoch.isot} "
                f"{self.epoch.scale.upper()}, frame {self.frame}>")

    @property
    def valid(self) -> np.ndarray:
        """(N,) bool: the rows that are physical."""
        ok = np.ones(len(self), dtype=bool)
        ok[list(self.invalid)] = False
        return ok

    def body_at(self, index: int) -> RigidBody | None:
        """Body ``index`` as a :class:`~attitude.RigidBody` (None for an invalid row)."""
        if index in self.invalid:
            return None
        mass = self.mass[index]
        return RigidBody(self.inertia[index], name=self.names[index],
                         mass=mass if np.isfinite(mass) else None)

    def state_at(self, index: int) -> AttitudeState | None:
        """The initial state of body ``index`` (None for an invalid row)."""
        if index in self.invalid:
            return None
        return AttitudeState(self.epoch, Rotation.from_quat(self.quaternion[index]),
                             self.omega_body[index], frame=self.frame)

    @property
    def bodies(self) -> list[RigidBody | None]:
        """The bodies as :class:`~attitude.RigidBody` objects (None for invalid rows)."""
        return [self.body_at(i) for i in range(len(self))]

    @property
    def states(self) -> list[AttitudeState | None]:
        """The initial states (None for invalid rows)."""
        return [self.state_at(i) for i in range(len(self))]

    def omega_principal(self) -> np.ndarray:
        """(N, 3) rates in principal-frame components (rad/s)."""
        return quat.rotate(self.body_to_principal, self.omega_body)

    def subset(self, index) -> Ensemble:
        """The bodies at ``index`` (a slice, an index array or a boolean mask)."""
        idx = np.arange(len(self))[index]
        keep = {int(i): j for j, i in enumerate(idx)}
        out = object.__new__(Ensemble)
        for slot in Ensemble.__slots__:
            value = getattr(self, slot)
            if isinstance(value, np.ndarray):
                value = value[idx]
            elif slot == "names":
                value = tuple(self.names[i] for i in idx)
            elif slot == "parameters":
                value = {k: v[idx] for k, v in value.items()}
            elif slot == "invalid":
                value = {keep[i]: why for i, why in value.items() if i in keep}
            elif slot == "nominal" and value is not None:
                value = keep.get(value)
            object.__setattr__(out, slot, value)
        return out


def check_batch(bodies, states) -> tuple[list[RigidBody], list[AttitudeState]]:
    """Equal-length, non-empty sequences of bodies and states sharing one epoch and
    frame, as lists; otherwise :class:`~attitude.InvalidStateError` naming the index.

    The checks are those of the batch normalisers :func:`attitude.model.body.as_bodies` and
    :func:`attitude.model.state.stack_states`.

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> body = RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = AttitudeState("2029-04-13", Rotation.identity(), [0.0, 0.0, 1.0])
    >>> [len(x) for x in check_batch([body, body], [state, state])]
    [2, 2]
    """
    bodies, states = list(bodies), list(states)
    if len(bodies) != len(states) or not bodies:
        raise InvalidStateError(f"batch: got {len(bodies)} bodies and {len(states)} "
                                "states; give one state per body")
    batch, _ = as_bodies(bodies, moments=False)
    stack_states(states, len(batch))
    return list(batch), states


def _check_rows(inertia, quaternion, omega):
    """Invalid rows ``{index: reason}``, principal moments (N, 3) and body -> principal
    quaternions (N, 4) (identity placeholders on invalid rows)."""
    n = inertia.shape[0]
    invalid: dict[int, str] = {}

    def flag(mask, reason):                 # the first reason of a row is kept
        for i, why in invalid_where(mask, reason).items():
            invalid.setdefault(i, why)

    moments, axes, inertia_invalid = check_inertia(inertia)    # the one inertia validator
    invalid.update(inertia_invalid)
    qn = np.linalg.norm(quaternion, axis=1)
    flag(~(np.isfinite(qn) & (qn > 0)),
         lambda i: "quaternion must be finite and non-zero (x, y, z, w)")
    flag(~np.all(np.isfinite(omega), axis=1),
         lambda i: "omega_body has a NaN or infinite component; give finite rad/s")
    b2p = principal_quaternions(axes)
    bad = np.zeros(n, dtype=bool)
    bad[list(invalid)] = True
    moments[bad] = [1.0, 2.0, 2.5]
    b2p[bad] = [0.0, 0.0, 0.0, 1.0]
    return dict(sorted(invalid.items())), moments, b2p
