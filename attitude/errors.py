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
    """

    def __init__(self, message: str = "", *, key: str | None = None,
                 path: str | None = None):
        self.reason = str(message)
        self.key = key
        self.path = None if path is None else str(path)
        where = ": ".join(p for p in (self.path, key) if p)
        super().__init__(f"{where}: {self.reason}" if where else self.reason)


class InvalidInertiaError(AttitudeError, ValueError):
    """Non-physical mass properties (asymmetric, non-finite, not positive-definite,
    or violating the triangle inequality ``A + B >= C``)."""


class InvalidStateError(AttitudeError, ValueError):
    """An attitude state that cannot be propagated (NaN rates, non-unit quaternion,
    unknown frame, epoch without a time scale, ...)."""


class ShapeModelError(AttitudeError, ValueError):
    """A polyhedral shape model that cannot be a homogeneous solid (open mesh,
    inconsistent face orientation, degenerate faces, unreadable file)."""


class ScenarioError(AttitudeError, ValueError):
    """A malformed or non-physical scenario file.  ``str(err)`` is one line that
    names the file and the key."""


class QuantityError(AttitudeError, ValueError):
    """A number with a unit that cannot be read: unparseable text, a unit of the wrong
    dimension, the wrong shape, a non-finite or out-of-range value, a date that does not
    exist.  ``key`` names the field (``"propagation.step"``); the message says what was
    expected and how to write it (:func:`attitude.quantities.to_si`)."""


class PropagationError(AttitudeError, RuntimeError):
    """The propagator could not produce an ephemeris (integrator failure, ...)."""


class EphemerisFormatError(AttitudeError, ValueError):
    """An ephemeris file that does not follow the documented schema or format."""


class OrbitError(AttitudeError, ValueError):
    """Invalid orbital elements or path data; ``key`` names the element (``"e"``,
    ``"a"``, ...) so that scenario readers can prefix the path of its table."""


class TorqueConfigError(AttitudeError, ValueError):
    """A torque table (or constructor argument) that cannot be used; ``key`` is the key
    path inside the table (``"orbit.e"``), so that scenario readers can prefix the path of
    the table itself."""


class DiagnosticsError(AttitudeError, ValueError):
    """An ephemeris from which a diagnostic cannot be computed."""


class InsufficientDataError(DiagnosticsError):
    """The ephemeris is too short, too sparse or too coarse for the requested quantity
    (e.g. it covers less than one polhode period, so no period can be measured)."""


class ClassificationError(AttitudeError, ValueError):
    """Arguments that make a classification impossible (bad thresholds, a chaos test
    without the torques, ...)."""


class SpinOrbitError(AttitudeError, ValueError):
    """A spin-orbit problem that cannot be set up or solved: an orbit that is not a
    :class:`~attitude.orbit.KeplerOrbit`, a body without ``B > A``, a resonance whose
    periodic orbit does not converge, a bad ``[section]`` table."""


class MissingDependencyError(AttitudeError, ImportError):
    """An optional dependency is not installed; the message names the extra that
    installs it (``pip install "attitude-dynamics[spice]"``)."""


class PlotUnavailableError(MissingDependencyError):
    """matplotlib is not installed (``pip install 'attitude-dynamics[plot]'``)."""


class PhotometryError(AttitudeError, ValueError):
    """Photometric input that cannot give a lightcurve or a period (a zero or
    antiparallel Sun vector, an unknown scattering law, a negative albedo, a
    lightcurve too short for the requested periods, ...)."""


class LightcurveFormatError(AttitudeError, ValueError):
    """An observed lightcurve file (ALCDEF, CSV, netCDF) that does not follow its
    format; the message names the line."""


class WriterError(AttitudeError, RuntimeError):
    """An output writer used out of order (appending to a streaming writer that is not
    open, opening it twice) or a file that was not produced."""


class AttitudeWarning(UserWarning):
    """Base class of every warning issued by ``attitude``."""


class NearSeparatrixWarning(AttitudeWarning):
    """The state is so close to the separatrix that periods and the regime are
    ill-conditioned (the motion itself is still computed exactly)."""


class InvalidBodiesWarning(AttitudeWarning):
    """Some rows of an ensemble are not physical; they are propagated as NaN."""
