"""Ensembles: populations of bodies and states, propagated together.

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
physical parameters, :data:`MODELS`, or from a user callable).

A row whose input is not physical (inertia not positive-definite or violating the
triangle inequality, a NaN rate, a zero quaternion, moment ratios out of range) does not
sink the others: it is recorded in :attr:`Ensemble.invalid` with its index and the
reason, reported once (:class:`InvalidBodiesWarning`), and propagated as NaN with
``status = 1`` in the ephemeris.

Statistics (:func:`diagnose_ensemble`, :func:`regime_fractions`,
:func:`period_quantiles`, :func:`attitude_spread`, :func:`spread_quantiles`) summarise
a population; :func:`local_cluster` starts a dask ``LocalCluster`` for
``propagate(..., client=...)``.
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Callable, Mapping, Sequence
from os import PathLike
from pathlib import Path

import numpy as np
import xarray as xr
from astropy import units as u
from scipy.spatial.transform import Rotation

from . import _quat
from ._units import to_si
from .body import TRIANGLE_RTOL, RigidBody
from .errors import AttitudeError, AttitudeWarning, InvalidInertiaError, InvalidStateError
from .state import AttitudeState, as_epoch, check_frame, direction_frame

__all__ = [
    "Ensemble",
    "MODELS",
    "InvalidBodiesWarning",
    "STATUS_OK",
    "STATUS_INVALID",
    "STATUS_FAILED",
    "tumbling_state",
    "spin_state",
    "diagnose_ensemble",
    "classify_ensemble",
    "regime_fractions",
    "period_quantiles",
    "attitude_spread",
    "spread_quantiles",
    "propagate_ensemble",
    "local_cluster",
]

#: ``status`` values of an ensemble ephemeris (CF ``flag_values``).
STATUS_OK, STATUS_INVALID, STATUS_FAILED = 0, 1, 2
_STATUS_MEANINGS = "ok invalid_input propagation_failed"

#: Epochs per dask chunk when ``chunks=`` is not given (about 90 MB of float64 output).
_EPOCHS_PER_CHUNK = 1_000_000

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
_DIRECTION = {"tumbling": "angular_momentum_direction", "spin": "spin_direction"}
_DIRECTION_PARAMETERS = {"tumbling": ("angular_momentum_ra", "angular_momentum_dec"),
                         "spin": ("spin_ra", "spin_dec")}

#: Defaults of parameters a model does not require.
_DEFAULTS = {"precession_angle": 0.0, "rotation_angle": 0.0, "moment_c": 1.0}


class InvalidBodiesWarning(AttitudeWarning):
    """Some rows of an ensemble are not physical; they are propagated as NaN."""


# ============================================================================
# the ensemble
# ============================================================================
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
        :func:`attitude_spread` measures; None for a catalogue.

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
        inertia = np.array(to_si(inertia, "kg m2", name="inertia", error=InvalidInertiaError),
                           dtype=float, ndmin=3)
        quaternion = np.array(quaternion, dtype=float, ndmin=2)
        omega = np.array(to_si(omega_body, "rad/s", name="omega_body",
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
            mass, "kg", name="mass", error=InvalidInertiaError), dtype=float, ndmin=1)
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
                               error=InvalidInertiaError), dtype=float, ndmin=2)
            if m.ndim != 2 or m.shape[1] != 3:
                raise InvalidInertiaError(f"principal_moments: expected shape (N, 3), got "
                                          f"{m.shape}")
            inertia = _diagonal(m)
        omega = np.array(to_si(omega_body, "rad/s", name="omega_body",
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
        columns = _read_table(table)
        get = _column_getter(columns)
        if all(k in columns for k in ("A", "B", "C")):
            inertia = _diagonal(np.column_stack([get(k, "kg m2") for k in ("A", "B", "C")]))
            n = inertia.shape[0]
        elif all(k in columns for k in ("Ixx", "Iyy", "Izz")):
            xx, yy, zz = (get(k, "kg m2") for k in ("Ixx", "Iyy", "Izz"))
            n = xx.size
            xy, xz, yz = (get(k, "kg m2") if k in columns else np.zeros(n)
                          for k in ("Ixy", "Ixz", "Iyz"))
            inertia = np.stack([np.column_stack(r) for r in
                                ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))], axis=1)
        else:
            raise InvalidInertiaError(
                f"table: no body columns; give A, B, C (principal moments) or Ixx, Iyy, "
                f"Izz[, Ixy, Ixz, Iyz] (found {', '.join(columns) or 'no columns'})")
        missing = [k for k in ("wx", "wy", "wz") if k not in columns]
        if missing:
            raise InvalidStateError(f"table: missing rate column(s) {', '.join(missing)} "
                                    "(body-frame angular velocity, rad/s)")
        omega = np.column_stack([get(k, "rad/s") for k in ("wx", "wy", "wz")])
        if all(k in columns for k in ("qx", "qy", "qz", "qw")):
            q = np.column_stack([get(k, "") for k in ("qx", "qy", "qz", "qw")])
        else:
            q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        names = [str(x) for x in columns["name"][1]] if "name" in columns else None
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
            The parameterisation (:data:`MODELS`).
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
            Body 0 is the mean state itself (default), so that :func:`attitude_spread`
            measures the spread from the nominal.

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
            draw = rng.multivariate_normal([mean_si[k] for k in keys], cov, size=n - k0)
            for j, k in enumerate(keys):
                values[k][k0:] = draw[:, j]
        elif sigma:
            sigma = dict(sigma)
            direction = _DIRECTION[model]
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
        for k, v in _DEFAULTS.items():
            if k in spec:
                values.setdefault(k, np.full(n, v))
        missing = [k for k in spec if k not in values]
        if missing:
            raise InvalidStateError(f"mean: missing parameter(s) {', '.join(missing)} of "
                                    f"the {model!r} model (all: {', '.join(spec)})")
        build = tumbling_state if model == "tumbling" else spin_state
        moments, q, w, bad = build(**{k: values[k] for k in spec})
        inertia = _diagonal(np.where(np.isfinite(moments), moments, 1.0))
        names = ["nominal" if i < k0 else f"sample {i}" for i in range(n)]
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
        return _quat.rotate(self.body_to_principal, self.omega_body)

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
    frame, as lists; otherwise :class:`~attitude.InvalidStateError` naming the index."""
    bodies, states = list(bodies), list(states)
    if len(bodies) != len(states) or not bodies:
        raise InvalidStateError(f"batch: got {len(bodies)} bodies and {len(states)} "
                                "states; give one state per body")
    for i, (b, s) in enumerate(zip(bodies, states)):
        if not isinstance(b, RigidBody):
            raise InvalidStateError(f"bodies[{i}]: expected a RigidBody, got "
                                    f"{type(b).__name__}")
        if not isinstance(s, AttitudeState):
            raise InvalidStateError(f"states[{i}]: expected an AttitudeState, got "
                                    f"{type(s).__name__}")
        if s.frame != states[0].frame:
            raise InvalidStateError(f"states[{i}].frame = {s.frame} differs from "
                                    f"states[0].frame = {states[0].frame}")
        if abs((s.epoch - states[0].epoch).to_value(u.s)) > 0:
            raise InvalidStateError(f"states[{i}].epoch differs from states[0].epoch; "
                                    "a batch shares one epoch")
    return bodies, states


# ============================================================================
# row validation and principal frames, vectorised
# ============================================================================
def _diagonal(moments) -> np.ndarray:
    """(N, 3, 3) inertia tensors of bodies whose frame is their principal frame."""
    return np.asarray(moments, dtype=float)[:, :, None] * np.eye(3)


def _invalid_where(mask, reason) -> dict[int, str]:
    """``{index: reason(index)}`` of the rows where ``mask`` is true."""
    return {int(i): reason(int(i)) for i in np.nonzero(mask)[0]}


def _check_rows(inertia, quaternion, omega):
    """Invalid rows ``{index: reason}``, principal moments (N, 3) and body -> principal
    quaternions (N, 4) (identity placeholders on invalid rows)."""
    n = inertia.shape[0]
    invalid: dict[int, str] = {}

    def flag(mask, reason):                 # the first reason of a row is kept
        for i, why in _invalid_where(mask, reason).items():
            invalid.setdefault(i, why)

    finite = np.all(np.isfinite(inertia), axis=(1, 2))
    flag(~finite, lambda i: "inertia has a non-finite element; give finite kg m^2 values")
    scale = np.where(finite, np.abs(np.where(np.isfinite(inertia), inertia, 0)).max(axis=(1, 2)),
                     1.0)
    asym = np.abs(inertia - inertia.transpose(0, 2, 1)).max(axis=(1, 2)) if n else []
    flag(finite & (asym > 1e-12 * np.maximum(scale, 1e-300)),
         lambda i: "inertia is not symmetric; give the tensor with I_ij = I_ji")
    good = np.array([i not in invalid for i in range(n)], dtype=bool)
    safe = np.where(good[:, None, None], inertia, np.eye(3))
    safe = 0.5 * (safe + safe.transpose(0, 2, 1))
    moments, axes = np.linalg.eigh(safe)
    A, B, C = moments[:, 0], moments[:, 1], moments[:, 2]
    flag(good & ~(A > 0), lambda i: f"inertia is not positive-definite (smallest principal "
         f"moment {moments[i, 0]:.6g} kg m^2)")
    flag(good & (A > 0) & (A + B < C * (1 - TRIANGLE_RTOL)),
         lambda i: f"principal moments {moments[i, 0]:.6g}, {moments[i, 1]:.6g}, "
                   f"{moments[i, 2]:.6g} kg m^2 violate the triangle inequality A + B >= C")
    qn = np.linalg.norm(quaternion, axis=1)
    flag(~(np.isfinite(qn) & (qn > 0)),
         lambda i: "quaternion must be finite and non-zero (x, y, z, w)")
    flag(~np.all(np.isfinite(omega), axis=1),
         lambda i: "omega_body has a NaN or infinite component; give finite rad/s")
    # proper rotation: principal axes as columns, det +1
    det = np.linalg.det(axes)
    axes[:, :, 2] *= np.where(det < 0, -1.0, 1.0)[:, None]
    b2p = Rotation.from_matrix(axes.transpose(0, 2, 1)).as_quat()
    bad = np.zeros(n, dtype=bool)
    bad[list(invalid)] = True
    moments[bad] = [1.0, 2.0, 2.5]
    b2p[bad] = [0.0, 0.0, 0.0, 1.0]
    return dict(sorted(invalid.items())), moments, b2p


# ============================================================================
# sampling models
# ============================================================================
def _parameters_si(values: Mapping, spec: Mapping, what: str, *,
                   arrays: bool = False) -> dict:
    out = {}
    for k, v in values.items():
        if k not in spec:
            import difflib

            close = difflib.get_close_matches(k, list(spec), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise InvalidStateError(f"{what}.{k}: unknown parameter{hint} (known: "
                                    f"{', '.join(spec)})")
        x = to_si(v, spec[k] or u.dimensionless_unscaled, name=f"{what}.{k}",
                  error=InvalidStateError)
        out[k] = np.asarray(x, dtype=float) if arrays else float(np.asarray(x))
    return out


def _scatter_direction(values, mean_si, model, sigma, rng, k0) -> None:
    """Isotropic error of ``sigma`` rad about the mean direction (ra, dec): tangent-plane
    offsets ``(x, y) ~ N(0, sigma^2)`` each, turned into a rotation by
    ``rho = |(x, y)|`` toward the azimuth ``atan2(y, x)``; written back as ra, dec."""
    ra_key, dec_key = _DIRECTION_PARAMETERS[model]
    if ra_key not in mean_si or dec_key not in mean_si:
        raise InvalidStateError(f"sigma.{_DIRECTION[model]}: needs mean values of "
                                f"{ra_key} and {dec_key}")
    if not sigma >= 0:
        raise InvalidStateError(f"sigma.{_DIRECTION[model]}: must be >= 0, got {sigma}")
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
    bad = _invalid_where(~((0 < ratio_a) & (ratio_a <= ratio_b) & (ratio_b <= 1)
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
    """
    from .torquefree import diagnose_many

    args = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=float)) for a in (
        angular_momentum_ra, angular_momentum_dec, energy_ratio, ratio_a, ratio_b,
        precession_period, precession_angle, rotation_angle, moment_c)))
    ra, dec, er, ra_, rb, pphi, phi, psi, mc = args
    m, bad = _moments(ra_, rb, mc)
    bad.update(_invalid_where(~(np.isfinite(er) & (er >= 1) & (er <= 1 / np.where(
        ra_ > 0, ra_, 1))), lambda i: f"energy ratio E/E0 = {er[i]:.6g} is outside "
        f"[1, C/A = {1 / ra_[i]:.6g}]"))
    bad.update(_invalid_where(~(pphi > 0), lambda i: "precession period must be > 0"))
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
    bad.update(_invalid_where(ok & ~np.isfinite(scale), lambda i: "the state has no "
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
    q = _quat.multiply(q_k2i, _quat.conjugate(kernel_to_principal))
    m = np.where(ok[:, None], m, np.nan)
    omega = np.where(ok[:, None], omega, np.nan)
    return m, q, omega, dict(sorted(bad.items()))


def spin_state(spin_ra, spin_dec, spin_rate, ratio_a, ratio_b, rotation_angle=0.0,
               moment_c=1.0):
    """Principal-axis spins about C along (RA, Dec) at ``spin_rate`` (rad/s), rotated by
    ``rotation_angle`` about the spin axis from the convention of
    :func:`attitude.scenario.spin_axis_state` (vectorised; SI).

    Returns moments (N, 3), quaternion (N, 4) principal -> inertial, omega (N, 3) and
    invalid ``{index: reason}``.
    """
    ra, dec, rate, ra_, rb, psi, mc = np.broadcast_arrays(*(np.atleast_1d(np.asarray(
        a, dtype=float)) for a in (spin_ra, spin_dec, spin_rate, ratio_a, ratio_b,
                                    rotation_angle, moment_c)))
    m, bad = _moments(ra_, rb, mc)
    bad.update(_invalid_where(~np.isfinite(rate), lambda i: "spin rate must be finite"))
    q = (Rotation.from_matrix(direction_frame(ra, dec))
         * Rotation.from_euler("Z", psi[:, None])).as_quat()
    omega = np.stack([np.zeros_like(rate), np.zeros_like(rate), rate], axis=-1)
    return m, q, omega, dict(sorted(bad.items()))


# ============================================================================
# tables
# ============================================================================
def _read_table(table) -> dict[str, tuple[str, np.ndarray]]:
    """``{column: (unit, values)}`` from a path, DataFrame or Dataset."""
    import pandas as pd

    if isinstance(table, (str, PathLike)):
        path = Path(table)
        if not path.is_file():
            raise InvalidStateError(f"{path}: no such table file")
        try:
            if path.suffix.lower() in (".parquet", ".pq"):
                table = pd.read_parquet(path)
            elif path.suffix.lower() in (".nc", ".cdf"):
                table = xr.load_dataset(path)
            else:
                table = pd.read_csv(path, skipinitialspace=True, comment="#")
        except ImportError as exc:
            raise InvalidStateError(f"{path}: reading it needs an optional package "
                                    f"({exc})") from None
        except (ValueError, OSError) as exc:
            raise InvalidStateError(f"{path}: not a readable table ({exc})") from None
    elif hasattr(table, "read"):
        table = pd.read_csv(table, skipinitialspace=True, comment="#")
    if isinstance(table, xr.Dataset):
        items = {k: (v.attrs.get("units", ""), v.values) for k, v in table.data_vars.items()}
    elif isinstance(table, pd.DataFrame):
        items = {}
        for col in table.columns:
            name, unit = str(col).strip(), ""
            if name.endswith("]") and "[" in name:
                name, unit = name[:-1].split("[", 1)
                name, unit = name.strip(), unit.strip()
            items[name] = (unit, table[col].to_numpy())
    else:
        raise InvalidStateError(f"table: expected a path, a pandas DataFrame or an xarray "
                                f"Dataset, got {type(table).__name__}")
    return items


def _column_getter(columns):
    def get(name, si):
        unit, values = columns[name]
        try:
            values = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise InvalidStateError(f"table column {name}: expected numbers") from None
        if not unit:
            return values
        try:
            values = values * u.Unit(unit)
        except ValueError:
            raise InvalidStateError(f"table column {name}: cannot parse the unit "
                                    f"[{unit}]") from None
        return to_si(values, si or u.dimensionless_unscaled, name=f"table column {name}",
                     error=InvalidStateError)

    return get


# ============================================================================
# statistics
# ============================================================================
def diagnose_ensemble(ensemble: Ensemble) -> xr.Dataset:
    """Analytic torque-free diagnosis of every body (vectorised
    :func:`attitude.torquefree.diagnose_many`): a Dataset along ``body`` with ``regime``,
    the periods ``polhode precession rotation spin`` (s, NaN where absent),
    ``energy_ratio``, ``separatrix_distance``, ``nutation_min``/``nutation_max`` (rad)
    and ``valid``."""
    from .torquefree import diagnose_many

    ok = ensemble.valid
    n = len(ensemble)
    units = {"polhode": "s", "precession": "s", "rotation": "s", "spin": "s",
             "energy_ratio": "1", "separatrix_distance": "1", "nutation_min": "rad",
             "nutation_max": "rad"}
    data = {k: ("body", np.full(n, np.nan), {"units": v}) for k, v in units.items()}
    regime = np.full(n, "invalid", dtype=object)
    if ok.any():
        d = diagnose_many(ensemble.principal_moments[ok], ensemble.omega_principal()[ok])
        for k in units:
            data[k][1][ok] = d[k]
        regime[ok] = d["regime"]
    data["regime"] = ("body", regime.astype(str))
    data["valid"] = ("body", ok)
    return xr.Dataset(data, coords={"body": np.arange(len(ensemble))})


def regime_fractions(source) -> dict[str, float]:
    """Fraction of the valid bodies in each regime, largest first.

    ``source``: an :class:`Ensemble` (analytic torque-free regimes), the Dataset of
    :func:`diagnose_ensemble` or :func:`classify_ensemble`, or a batch
    :class:`~attitude.Ephemeris` (each body classified from its propagated motion by
    :func:`classify_ensemble`, which also sees regime changes under torques).  Bodies
    that are invalid or could not be classified are left out."""
    from .ephemeris import Ephemeris

    if isinstance(source, Ensemble):
        source = diagnose_ensemble(source)
    if isinstance(source, Ephemeris):
        source = classify_ensemble(source) if source.is_batch else xr.Dataset(
            {"regime": ("body", [_classify_one(source)])})
    regimes = np.asarray(source["regime"].values)
    regimes = regimes[(regimes != "invalid") & (regimes != "unclassified")]
    if regimes.size == 0:
        return {}
    names, counts = np.unique(regimes, return_counts=True)
    order = np.argsort(-counts, kind="stable")
    return {str(names[i]): float(counts[i] / regimes.size) for i in order}


def classify_ensemble(eph, **options) -> xr.Dataset:
    """:func:`attitude.classify` of every body of a batch ephemeris, one by one: a
    Dataset along ``body`` with ``regime`` (``"invalid"`` for bodies whose ``status`` is
    not 0, ``"unclassified"`` when the classification failed, e.g. a run shorter than a
    cycle), ``confidence``, ``margin`` and ``reason`` (why a body is not classified).
    One body that cannot be classified does not stop the others.  ``options`` go to
    :func:`attitude.classify` (default ``require_periods=False``); a dask-backed
    ephemeris is loaded first."""
    from .classify import classify
    from .ephemeris import Ephemeris

    if not eph.is_batch:
        raise InvalidStateError("classify_ensemble takes a batch ephemeris (dims body, "
                                "time); use attitude.classify for one body")
    ds = eph.dataset
    if any(hasattr(v.data, "dask") for v in ds.data_vars.values()):
        eph = Ephemeris(ds.load())
        ds = eph.dataset
    options.setdefault("require_periods", False)
    n = ds.sizes["body"]
    status = ds["status"].values if "status" in ds else np.zeros(n, dtype=np.int8)
    regime = np.full(n, "invalid", dtype=object)
    confidence, margin = np.full(n, np.nan), np.full(n, np.nan)
    reason = np.full(n, "", dtype=object)
    for i in range(n):
        if status[i] != STATUS_OK:
            reason[i] = "invalid input" if status[i] == STATUS_INVALID else \
                "propagation failed"
            continue
        try:
            c = classify(eph, body_index=i, **options)
        except AttitudeError as exc:
            regime[i], reason[i] = "unclassified", str(exc)
            continue
        regime[i], confidence[i], margin[i] = c.regime, c.confidence, c.margin
    return xr.Dataset({"regime": ("body", regime.astype(str)),
                       "confidence": ("body", confidence),
                       "margin": ("body", margin),
                       "reason": ("body", reason.astype(str))},
                      coords={"body": np.arange(n)})


def _classify_one(eph) -> str:
    from .classify import classify

    return classify(eph, require_periods=False).regime


def period_quantiles(source, q=(0.05, 0.5, 0.95)) -> xr.DataArray:
    """Quantiles of each period over the bodies that have it: a DataArray
    ``(period, quantile)`` in seconds, with the number of bodies that have each period
    as the coordinate ``bodies``.  ``source``: an :class:`Ensemble` or :func:`diagnose_ensemble`
    output."""
    d = diagnose_ensemble(source) if isinstance(source, Ensemble) else source
    keys = [k for k in ("polhode", "precession", "rotation", "spin")
            if np.isfinite(d[k].values).any()]
    q = np.atleast_1d(np.asarray(q, dtype=float))
    values = np.array([np.nanquantile(d[k].values, q) for k in keys]).reshape(len(keys),
                                                                               q.size)
    counts = [int(np.isfinite(d[k].values).sum()) for k in keys]
    return xr.DataArray(values, dims=("period", "quantile"),
                        coords={"period": keys, "quantile": q,
                                "bodies": ("period", counts)},
                        attrs={"units": "s", "long_name": "period quantiles over bodies"})


def attitude_spread(eph, nominal=0) -> xr.DataArray:
    """Angle (rad) between each body's attitude and the nominal's, ``(body, time)``:
    ``2 arccos |q . q_nominal|``, the angle of the rotation taking one to the other.

    ``nominal``: a body index of the batch (default 0, the nominal of
    :meth:`Ensemble.sample`) or a single-body :class:`~attitude.Ephemeris` on the same
    times.  Lazy (dask) when the ephemeris is."""
    from .ephemeris import Ephemeris

    q = eph.dataset["quaternion"]
    if isinstance(nominal, Ephemeris):
        qn = nominal.dataset["quaternion"]
        if qn.sizes["time"] != q.sizes["time"]:
            raise InvalidStateError("nominal: the ephemeris must have the same times")
        qn = qn.assign_coords(time=q["time"])
    else:
        qn = q.isel(body=int(nominal))
    dot = abs((q * qn).sum("quaternion_component"))
    angle = 2.0 * np.arccos(np.minimum(dot, 1.0))
    angle.attrs = {"units": "rad", "long_name": "angle from the nominal attitude"}
    return angle.rename("attitude_spread")


def spread_quantiles(eph, q=(0.5, 0.9, 0.99), nominal=0) -> xr.DataArray:
    """Quantiles over the bodies of :func:`attitude_spread` against time: ``(quantile,
    time)`` in rad (NaN bodies are skipped)."""
    spread = attitude_spread(eph, nominal)
    if hasattr(spread.data, "dask"):   # all bodies of an epoch in one chunk, epochs split
        spread = spread.chunk({"body": -1, "time": "auto"})
    out = spread.quantile(np.atleast_1d(q), dim="body", skipna=True)
    out.attrs = {"units": "rad", "long_name": "quantiles of the angle from the nominal"}
    return out


# ============================================================================
# propagation in chunks, locally or on dask
# ============================================================================
def _propagate_chunk(inertia, mass, moments, b2p, q0, w0, status, t, method, torques,
                     options):
    """The numpy kernel of one chunk of bodies: ``{"q", "w", "L", "E", "status"}``.

    Invalid rows come back NaN with their status; if the vectorised run fails, the
    bodies are run one by one and those that fail get :data:`STATUS_FAILED`."""
    from .ephemeris import momentum_and_energy

    n, T = inertia.shape[0], t.size
    out = {"q": np.full((n, T, 4), np.nan), "w": np.full((n, T, 3), np.nan),
           "L": np.full((n, T, 3), np.nan), "E": np.full((n, T), np.nan),
           "status": np.asarray(status, dtype=np.int8).copy()}
    ok = out["status"] == STATUS_OK

    def run(rows):
        q, w = _kernel(inertia[rows], mass[rows], moments[rows], b2p[rows], q0[rows],
                       w0[rows], t, method, torques, options)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(w))):
            raise FloatingPointError("non-finite result")
        return q, w

    idx = np.nonzero(ok)[0]
    if idx.size:
        try:
            results = [(idx, run(idx))]
        except (AttitudeError, FloatingPointError, ArithmeticError):
            results = []
            for i in idx:
                try:
                    results.append((np.array([i]), run(np.array([i]))))
                except (AttitudeError, FloatingPointError, ArithmeticError):
                    out["status"][i] = STATUS_FAILED
        for rows, (q, w) in results:
            q = _quat.canonical(q)
            L, E = momentum_and_energy(inertia[rows], q, w)
            out["q"][rows], out["w"][rows], out["L"][rows], out["E"][rows] = q, w, L, E
    return out


def _kernel(inertia, mass, moments, b2p, q0, w0, t, method, torques, options):
    if method == "exact":
        return exact_arrays(moments, b2p, q0, w0, t)
    bodies = [RigidBody(i, mass=m if np.isfinite(m) else None) for i, m in zip(inertia, mass)]
    if method == "splitting":
        from .splitting import integrate_splitting

        return integrate_splitting(bodies, q0, w0, t, torques=torques, **options)
    from .integrate import integrate_reference_batch

    return integrate_reference_batch(bodies, q0, w0, t, torques=torques, **options)


def exact_arrays(moments, b2p, q0, w0, t):
    """Torque-free closed form of N bodies given principal moments (N, 3), body ->
    principal quaternions (N, 4), attitudes (N, 4) and body rates (N, 3): ``q (N, T, 4),
    w (N, T, 3)`` in the body frames."""
    from .torquefree import free_rotation

    q_pb = _quat.conjugate(b2p)
    w0p = _quat.rotate(b2p, w0)
    q0p = _quat.multiply(q0, q_pb)                                      # principal -> inertial
    qp, wp = free_rotation(moments, w0p, q0p, t)                        # (N, T, 4), (N, T, 3)
    return _quat.multiply(qp, b2p[:, None, :]), _quat.rotate(q_pb[:, None, :], wp)


def _default_chunk(n: int, T: int) -> int:
    return int(max(1, min(n, _EPOCHS_PER_CHUNK // max(T, 1))))


def propagate_ensemble(ensemble: Ensemble, t: np.ndarray, *, method: str = "exact",
                       torques=(), options: Mapping | None = None, client=None,
                       chunks: int | None = None, title: str = "", source: str = ""):
    """Propagate an ensemble to ``t`` (s since its epoch); the engine of
    :func:`attitude.propagate` for ensembles.

    Without ``client`` and ``chunks`` the bodies run in this process, in chunks of
    about :data:`_EPOCHS_PER_CHUNK` epochs, into numpy arrays.  With ``chunks`` (bodies
    per chunk) or ``client`` (a ``dask.distributed.Client`` or a scheduler address) the
    chunks become tasks of a dask graph and the ephemeris is backed by dask arrays: it
    is computed when written (:meth:`~attitude.Ephemeris.to_netcdf`, chunk by chunk,
    never gathered in one process) or loaded.  A worker that dies is replaced and its
    tasks rerun by the dask scheduler; a body whose input is invalid gets
    ``status = 1`` and NaN, one whose propagation fails ``status = 2``.
    """
    from .ephemeris import Ephemeris, build_dataset

    options = dict(options or {})
    n, T = len(ensemble), t.size
    status = np.where(ensemble.valid, STATUS_OK, STATUS_INVALID).astype(np.int8)
    size = _default_chunk(n, T) if chunks is None else int(chunks)
    if size < 1:
        raise InvalidStateError(f"chunks: expected a positive number of bodies per chunk, "
                                f"got {chunks!r}")
    bounds = [(a, min(a + size, n)) for a in range(0, n, size)]

    def args(a, b):
        return (ensemble.inertia[a:b], ensemble.mass[a:b], ensemble.principal_moments[a:b],
                ensemble.body_to_principal[a:b], ensemble.quaternion[a:b],
                ensemble.omega_body[a:b], status[a:b], t, method, list(torques), options)

    if client is None and chunks is None:         # in place: the output and one chunk
        arrays = {"q": np.empty((n, T, 4)), "w": np.empty((n, T, 3)),
                  "L": np.empty((n, T, 3)), "E": np.empty((n, T)),
                  "status": np.empty(n, dtype=np.int8)}
        for a, b in bounds:
            for k, v in _propagate_chunk(*args(a, b)).items():
                arrays[k][a:b] = v
    else:
        arrays = _dask_arrays(bounds, args, T, client)
    extra = {"status": ("body", arrays.pop("status"), {
        "long_name": "propagation status of the body", "flag_values": np.array(
            [STATUS_OK, STATUS_INVALID, STATUS_FAILED], dtype=np.int8),
        "flag_meanings": _STATUS_MEANINGS})}
    attrs = {"ensemble_size": n}
    if ensemble.nominal is not None:
        attrs["nominal_body"] = ensemble.nominal
    if ensemble.invalid:
        attrs["invalid_bodies"] = "; ".join(f"{i}: {why}" for i, why in
                                            list(ensemble.invalid.items())[:100])
    for k, v in ensemble.parameters.items():
        extra[f"parameter_{k}"] = ("body", v, {"long_name": f"sampled parameter {k}",
                                               "units": MODEL_UNITS.get(k, "1")})
    ds = build_dataset(t, arrays["q"], arrays["w"], arrays["L"], arrays["E"],
                       inertia=ensemble.inertia, moments=ensemble.principal_moments,
                       names=ensemble.names, single=None, epoch=ensemble.epoch,
                       frame=ensemble.frame, title=title or "attitude ensemble ephemeris",
                       source=source, extra_attrs=attrs, extra_vars=extra)
    return Ephemeris(ds)


#: CF units of the sampled parameters stored with an ensemble ephemeris.
MODEL_UNITS = {k: {"rad/s": "rad s-1", "": "1"}.get(v, v)
               for spec in MODELS.values() for k, v in spec.items()}


def _dask_arrays(bounds, args, T, client):
    """The chunk tasks as dask arrays ``q w L E status`` along ``body``."""
    try:
        import dask
        import dask.array as da
    except ImportError:
        raise AttitudeError("client=/chunks= need the optional 'dask' package: pip install "
                            "'attitude[dask]'") from None

    if client is True or client == "local":
        client = _shared_local_client()
    elif isinstance(client, str):
        client = _client_for(client)
    shapes = {"q": (T, 4), "w": (T, 3), "L": (T, 3), "E": (T,), "status": ()}
    dtypes = {"status": np.int8}
    pieces = {k: [] for k in shapes}
    for a, b in bounds:
        part = dask.delayed(_propagate_chunk, pure=True)(*args(a, b))
        for k, shape in shapes.items():
            pieces[k].append(da.from_delayed(part[k], shape=(b - a,) + shape,
                                             dtype=dtypes.get(k, np.float64)))
    return {k: da.concatenate(v, axis=0) for k, v in pieces.items()}


_SHARED: dict = {}


def _shared_local_client():
    """``client="local"``: one LocalCluster for this process (a worker per available
    core), started on first use and closed at exit; it is the default dask client, so
    the lazy ephemerides are computed there."""
    if "client" not in _SHARED:
        import atexit
        import os

        cm = local_cluster(max(1, len(os.sched_getaffinity(0))))
        _SHARED["client"] = cm.__enter__()
        atexit.register(cm.__exit__, None, None, None)
    return _SHARED["client"]


def _client_for(address: str):
    """The current dask client if it is connected to ``address``, else a new one (which
    becomes the default, so the lazy ephemeris is computed there)."""
    try:
        from distributed import Client, default_client
    except ImportError:
        raise AttitudeError("client: a scheduler address needs the optional 'distributed' "
                            "package: pip install 'attitude[dask]'") from None
    try:
        current = default_client()
        if current.scheduler.address == address:
            return current
    except ValueError:
        pass
    try:
        return Client(address, timeout="10s")
    except OSError as exc:
        raise AttitudeError(f"client: cannot reach the dask scheduler at {address} "
                            f"({exc})") from None


@contextlib.contextmanager
def local_cluster(n_workers: int = 2, *, threads_per_worker: int = 1, **kwargs):
    """A dask ``LocalCluster`` of ``n_workers`` processes and a ``Client`` to it, for
    ``propagate(..., client=...)``; both are closed on exit::

        with att.ensemble.local_cluster(2) as client:
            eph = att.propagate(ensemble, times, client=client)
            eph.to_netcdf("cloud.nc")
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise AttitudeError("dask scale-out needs the optional 'distributed' package: "
                            "pip install 'attitude[dask]'") from None
    kwargs.setdefault("dashboard_address", ":0")     # any free port: no clash, no warning
    kwargs.setdefault("processes", True)
    with _glibc_mmap_threshold():
        try:
            cluster = LocalCluster(n_workers=n_workers, threads_per_worker=threads_per_worker,
                                   **kwargs)
        except RuntimeError as exc:
            raise AttitudeError(
                f"the dask LocalCluster did not start ({exc}); in a script, start it under "
                "'if __name__ == \"__main__\":' (its worker processes re-import the "
                "script)") from exc
        with cluster, Client(cluster) as client:     # restarted workers: same environment
            yield client


#: dask's default ``MALLOC_TRIM_THRESHOLD_`` for its worker processes.
_DASK_TRIM = "65536"


@contextlib.contextmanager
def _glibc_mmap_threshold():
    """Start workers without dask's default ``MALLOC_TRIM_THRESHOLD_=65536``.

    Setting it turns off glibc's dynamic mmap threshold, so every large numpy temporary
    of the propagation kernel (8-32 MB per 1000-body chunk) is mmapped and page-faulted
    afresh: measured, more than half of a worker's CPU time in the kernel and half the
    throughput of one plain process (``benchmarks/ensemble.py``).  A value the user set
    (other than dask's default) is kept."""
    import os

    import dask

    key = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
    if str(dask.config.get(key, None)) != _DASK_TRIM:
        yield
        return
    # a previous dask cluster in this process leaves the variable in os.environ
    inherited = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    if inherited == _DASK_TRIM:
        del os.environ["MALLOC_TRIM_THRESHOLD_"]
    try:
        with dask.config.set({key: None}):
            yield
    finally:
        if inherited == _DASK_TRIM:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = inherited
