"""Exceptions and warnings of the ``attitude`` package.

Every exception derives from :class:`AttitudeError` *and* from the builtin that
best describes it, so callers can catch either (the astropy pattern)::

    try:
        body = att.RigidBody.from_principal_moments([1.0, 1.0, 3.0])
    except ValueError as err:      # or att.InvalidInertiaError
        print(err)

Messages name the offending value and say what would fix it.  Every error takes one
shape, ``SomeError(message, key=..., path=...)``: ``key`` names the offending field (a
scenario key such as ``"torques[0].orbit.e"``, an element ``"e"``, a table column),
``path`` the file it came from, and ``str(err)`` is the one line
``"path: key: message"`` (``err.reason`` is the message alone), so that a reader of a
nested table can re-raise the error under the longer key.
"""

from __future__ import annotations

__all__ = [
    "AttitudeError",
    "InvalidInertiaError",
    "InvalidStateError",
    "ShapeModelError",
    "ScenarioError",
    "QuantityError",
    "PropagationError",
    "EphemerisFormatError",
    "OrbitError",
    "TorqueConfigError",
    "DiagnosticsError",
    "InsufficientDataError",
    "BinarySystemError",
    "ClassificationError",
    "SpinOrbitError",
    "MissingDependencyError",
    "PhotometryError",
    "LightcurveFormatError",
    "PlotUnavailableError",
    "WriterError",
    "AttitudeWarning",
    "NearSeparatrixWarning",
    "InvalidBodiesWarning",
]


class AttitudeError(Exception):
    """Base class of every error raised by ``attitude``.

    Parameters
    ----------
    message : str
        What is wrong and how to fix it.
    key : str, optional
        The offending field (scenario key, element, column), prefixed to the message.
    path : str, optional
        The file it came from, prefixed to the key.

    Examples
    --------
    >>> err = AttitudeError("must be in [0, 1), got 1.2", key="orbit.e", path="leo.toml")
    >>> str(err), err.key, err.reason
    ('leo.toml: orbit.e: must be in [0, 1), got 1.2', 'orbit.e', 'must be in [0, 1), got 1.2')
    >>> str(AttitudeError("rtol: must be in (0, 1)", key="rtol"))  # the key said once
    'rtol: must be in (0, 1)'
    """

    def __init__(self, message: str = "", *, key: str | None = None,
                 path: str | None = None):
        self.reason = _without_key(str(message), key)
        self.key = key
        self.path = None if path is None else str(path)
        where = ": ".join(p for p in (self.path, key) if p)
        super().__init__(f"{where}: {self.reason}" if where else self.reason)


def _without_key(reason: str, key: str | None) -> str:
    """``reason`` without a leading ``"KEY: "`` (the key, or its last part) that the line
    ``path: key: reason`` already shows, so that every message names its key once
    (``"rtol: rtol: expected ..."`` was the symptom)."""
    if key:
        for prefix in dict.fromkeys((key, key.rsplit(".", 1)[-1])):
            if reason.startswith(f"{prefix}: "):
                return reason[len(prefix) + 2:]
    return reason


class InvalidInertiaError(AttitudeError, ValueError):
    """Non-physical mass properties (asymmetric, non-finite, not positive-definite,
    or violating the triangle inequality ``A + B >= C``).

    Examples
    --------
    >>> import attitude as att
    >>> try:
    ...     att.RigidBody.from_principal_moments([1.0, 1.0, 3.0])
    ... except InvalidInertiaError as err:
    ...     print(err.reason[:60])
    principal moments A = 1, B = 1, C = 3 kg m^2 violate the tri
    >>> issubclass(InvalidInertiaError, ValueError)
    True
    """


class InvalidStateError(AttitudeError, ValueError):
    """An attitude state that cannot be propagated (NaN rates, non-unit quaternion,
    unknown frame, epoch without a time scale, ...).

    Examples
    --------
    >>> import attitude as att
    >>> try:
    ...     att.AttitudeState.from_quaternion([0, 0, 0, 0], epoch="2025-01-01",
    ...                                       omega_body=[0, 0, 1])
    ... except InvalidStateError as err:
    ...     print(err.reason[:46])
    quaternion [0.0, 0.0, 0.0, 0.0] has norm 0, no
    """


class ShapeModelError(AttitudeError, ValueError):
    """A polyhedral shape model that cannot be a homogeneous solid (open mesh,
    inconsistent face orientation, degenerate faces, unreadable file).

    Examples
    --------
    >>> import attitude as att
    >>> try:                     # three coincident vertices: a face of zero area
    ...     att.Polyhedron([[0, 0, 0]] * 3, [[0, 1, 2]])
    ... except ShapeModelError as err:
    ...     print(err.reason[:26])
    1 face is degenerate (zero
    """


class ScenarioError(AttitudeError, ValueError):
    """A malformed or non-physical scenario file.  ``str(err)`` is one line that
    names the file and the key.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.app.scenario import load_scenario
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "sat.toml"
    >>> _ = path.write_text('''
    ... [body]
    ... principal_moments = [1.0, 2.0, 3.0]
    ... [state]
    ... epoch = "2024-01-01"
    ... omega_body = [0, 0, 1]
    ... [propagation]
    ... duration = "-1 h"
    ... step = "1 min"
    ... ''')
    >>> try:
    ...     load_scenario(path)
    ... except ScenarioError as err:
    ...     print(err.key, "|", err.reason, "|", pathlib.Path(err.path).name)
    propagation.duration | must be positive, got -3600 s | sat.toml
    """


class QuantityError(AttitudeError, ValueError):
    """A number with a unit that cannot be read: unparseable text, a unit of the wrong
    dimension, the wrong shape, a non-finite or out-of-range value, a date that does not
    exist.  ``key`` names the field (``"propagation.step"``); the message says what was
    expected and how to write it (:func:`attitude.foundations.quantities.to_si`).

    Examples
    --------
    >>> from attitude.foundations.quantities import to_si
    >>> try:
    ...     to_si("2 m", "rad/s", key="state.omega")
    ... except QuantityError as err:
    ...     print(err.key, "|", err.reason[:40])
    state.omega | unit 'm' cannot be converted to 'rad / s
    """


class PropagationError(AttitudeError, RuntimeError):
    """The propagator could not produce an ephemeris (integrator failure, ...).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> def undefined(t, q, w, body):                  # an event function that gives NaN
    ...     return float("nan")
    >>> try:
    ...     att.propagate(body, state, [0.0, 10.0], events=[undefined])
    ... except PropagationError as err:
    ...     print(err.reason.split(";")[0])
    event 'undefined' returned array(nan) at t = 0 s
    >>> issubclass(PropagationError, RuntimeError)
    True
    """


class EphemerisFormatError(AttitudeError, ValueError):
    """An ephemeris file that does not follow the documented schema or format.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.formats.aem import read_aem
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "bad.aem"
    >>> _ = path.write_text("hello")
    >>> try:
    ...     read_aem(path)
    ... except EphemerisFormatError as err:
    ...     print(err.key, "|", err.reason)
    CCSDS_AEM_VERS | the first non-blank line must be 'CCSDS_AEM_VERS = 2.0': found 'hello'
    """


class OrbitError(AttitudeError, ValueError):
    """Invalid orbital elements or path data; ``key`` names the element (``"e"``,
    ``"a"``, ...) so that scenario readers can prefix the path of its table.

    Examples
    --------
    >>> from attitude.model.orbit import KeplerOrbit
    >>> try:
    ...     KeplerOrbit(mu=3.986e14, a=7e6, e=1.5)
    ... except OrbitError as err:
    ...     print(err.key, "|", err.reason.split(";")[0])
    e | must be in [0, 1), got 1.5
    """


class TorqueConfigError(AttitudeError, ValueError):
    """A torque table (or constructor argument) that cannot be used; ``key`` is the key
    path inside the table (``"orbit.e"``), so that scenario readers can prefix the path of
    the table itself.

    Examples
    --------
    >>> from attitude.model.torques import from_config
    >>> try:
    ...     from_config({"type": "constant", "torq": [0, 0, 1e-6]})
    ... except TorqueConfigError as err:
    ...     print(err.key, "|", err.reason.split(" (")[0])
    torq | unknown key; did you mean 'torque'?
    """


class DiagnosticsError(AttitudeError, ValueError):
    """An ephemeris from which a diagnostic cannot be computed.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.analysis.diagnostics import measure_periods
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> try:
    ...     measure_periods(eph, reference_axis=2)
    ... except DiagnosticsError as err:
    ...     print(err)
    reference_axis must be 1 (A) or 3 (C), got 2
    """


class InsufficientDataError(DiagnosticsError):
    """The ephemeris is too short, too sparse or too coarse for the requested quantity
    (e.g. it covers less than one polhode period, so no period can be measured).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2024-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.analysis.diagnostics import measure_periods
    >>> try:
    ...     measure_periods(att.propagate(body, state, [0.0, 5.0, 10.0]))
    ... except InsufficientDataError as err:
    ...     print(err)
    3 samples: at least 6 are needed to measure a period
    >>> issubclass(InsufficientDataError, DiagnosticsError)
    True
    """


class ClassificationError(AttitudeError, ValueError):
    """Arguments that make a classification impossible (bad thresholds, a chaos test
    without the torques, ...).

    Examples
    --------
    >>> from attitude.model.regimes import Thresholds
    >>> try:
    ...     Thresholds(softness=0)
    ... except ClassificationError as err:
    ...     print(err)
    thresholds.softness must be > 0
    """


class SpinOrbitError(AttitudeError, ValueError):
    """A spin-orbit problem that cannot be set up or solved: an orbit that is not a
    :class:`~attitude.model.orbit.KeplerOrbit`, a body without ``B > A``, a resonance whose
    periodic orbit does not converge, a bad ``[section]`` table.

    Examples
    --------
    >>> from attitude.spinorbit.resonances import resonance_list
    >>> try:
    ...     resonance_list(0.5, 1.2)      # eccentricity 1.2
    ... except SpinOrbitError as err:
    ...     print(err)
    e: must be in [0, 1), got 1.2
    """


class BinarySystemError(AttitudeError, ValueError):
    """A binary system that cannot be set up: a body without a mass, a mutual potential
    asked beyond order 2 of a body known only by its moments, an impulse on an unknown
    body, colliding bodies.

    Examples
    --------
    >>> import attitude as att
    >>> try:
    ...     att.BinarySystem(att.RigidBody.from_principal_moments([1.0, 2.0, 2.5], mass=3.0),
    ...                      att.RigidBody.from_principal_moments([1.0, 1.0, 1.0], mass=1.0),
    ...                      order=4)
    ... except BinarySystemError as err:
    ...     print(str(err)[:60])
    primary: a body known only by its moments has no mutual pote
    """


class MissingDependencyError(AttitudeError, ImportError):
    """An optional dependency is not installed; the message names the extra that
    installs it (``pip install "attitude-dynamics[spice]"``).

    Examples
    --------
    >>> err = MissingDependencyError('writing SPICE kernels needs spiceypy: '
    ...                              'pip install "attitude-dynamics[spice]"')
    >>> isinstance(err, ImportError), "[spice]" in str(err)
    (True, True)
    """


class PlotUnavailableError(MissingDependencyError):
    """matplotlib is not installed (``pip install 'attitude-dynamics[plot]'``).

    Examples
    --------
    >>> issubclass(PlotUnavailableError, MissingDependencyError)
    True
    >>> isinstance(PlotUnavailableError("pip install 'attitude-dynamics[plot]'"), ImportError)
    True
    """


class PhotometryError(AttitudeError, ValueError):
    """Photometric input that cannot give a lightcurve or a period (a zero or
    antiparallel Sun vector, an unknown scattering law, a negative albedo, a
    lightcurve too short for the requested periods, ...).

    Examples
    --------
    >>> from attitude.photometry.scattering import scattering_law
    >>> try:
    ...     scattering_law("lambert", albedo=-0.1)
    ... except PhotometryError as err:
    ...     print(err)
    albedo: must be in [0.0, inf], got -0.1
    """


class LightcurveFormatError(AttitudeError, ValueError):
    """An observed lightcurve file (ALCDEF, CSV, netCDF) that does not follow its
    format; the message names the line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from attitude.photometry.readers import read_lightcurve
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "notes.txt"
    >>> _ = path.write_text("hello")
    >>> try:
    ...     read_lightcurve(path)
    ... except LightcurveFormatError as err:
    ...     print(err.reason[:22])
    cannot tell the format
    """


class WriterError(AttitudeError, RuntimeError):
    """An output writer used out of order (appending to a streaming writer that is not
    open, opening it twice) or a file that was not produced.

    Examples
    --------
    >>> from attitude.model.ephemeris import AtomicFiles
    >>> try:
    ...     AtomicFiles("out.nc", "out.nc")
    ... except WriterError as err:
    ...     print(err)
    the same destination twice in ['out.nc', 'out.nc']
    """


class AttitudeWarning(UserWarning):
    """Base class of every warning issued by ``attitude``.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warnings.warn("near the separatrix", NearSeparatrixWarning)
    >>> issubclass(caught[0].category, AttitudeWarning)
    True
    """


class NearSeparatrixWarning(AttitudeWarning):
    """The state is so close to the separatrix that periods and the regime are
    ill-conditioned (the motion itself is still computed exactly).

    Examples
    --------
    >>> import warnings, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> omega = [3 ** 0.5, 0.0, 1.0]   # |L|^2 = 2 E B to rounding: on the separatrix
    >>> state = att.AttitudeState("2025-01-01", Rotation.identity(), omega)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     _ = att.diagnose(body, state)
    >>> any(w.category is NearSeparatrixWarning for w in caught)
    True
    """


class InvalidBodiesWarning(AttitudeWarning):
    """Some rows of an ensemble are not physical; they are propagated as NaN.

    Examples
    --------
    >>> import warnings, attitude as att
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     ens = att.Ensemble.from_arrays(                     # row 1: A + B < C
    ...         principal_moments=[[1.0, 2.0, 3.0], [1.0, 1.0, 3.0]],
    ...         omega_body=[[0, 0, 1.0], [0, 0, 1.0]], epoch="2024-01-01")
    >>> [w.category.__name__ for w in caught], sorted(ens.invalid)
    (['InvalidBodiesWarning'], [1])
    """
