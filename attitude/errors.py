"""Exceptions and warnings of the ``attitude`` package.

Every exception derives from :class:`AttitudeError` *and* from the builtin that
best describes it, so callers can catch either (the astropy pattern)::

    try:
        body = att.RigidBody.from_principal_moments([1.0, 1.0, 3.0])
    except ValueError as err:      # or att.InvalidInertiaError
        print(err)

Messages name the offending value and say what would fix it.
"""

from __future__ import annotations

__all__ = [
    "AttitudeError",
    "InvalidInertiaError",
    "InvalidStateError",
    "ShapeModelError",
    "ScenarioError",
    "PropagationError",
    "EphemerisFormatError",
    "AttitudeWarning",
    "NearSeparatrixWarning",
]


class AttitudeError(Exception):
    """Base class of every error raised by ``attitude``."""


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

    def __init__(self, message: str, *, path: str | None = None, key: str | None = None):
        self.path = path
        self.key = key
        where = ": ".join(p for p in (path, key) if p)
        super().__init__(f"{where}: {message}" if where else message)


class PropagationError(AttitudeError, RuntimeError):
    """The propagator could not produce an ephemeris (integrator failure, ...)."""


class EphemerisFormatError(AttitudeError, ValueError):
    """An ephemeris file that does not follow the documented schema or format."""


class AttitudeWarning(UserWarning):
    """Base class of every warning issued by ``attitude``."""


class NearSeparatrixWarning(AttitudeWarning):
    """The state is so close to the separatrix that periods and the regime are
    ill-conditioned (the motion itself is still computed exactly)."""
