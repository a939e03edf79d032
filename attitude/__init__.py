"""attitude: rotation-state analysis of spacecraft and small bodies.

Mass properties in, time-tagged attitude ephemerides out::

    import attitude as att
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState(epoch, attitude, omega_body)
    eph = att.propagate(body, state, times)
    eph.to_netcdf("out.nc")

See ``API.md``-level names in ``__all__``.
"""

from __future__ import annotations

from . import (
    _units,  # noqa: F401  (registers the 'rev' and 'rpm' units with astropy)
    ensemble,  # noqa: F401  (att.ensemble.regime_fractions, ...)
    torques,  # noqa: F401  (att.torques.GravityGradient, ...)
)
from .body import SYMMETRY_RTOL, TRIANGLE_RTOL, MassProperties, RigidBody
from .classify import Classification, ClassificationError, classify
from .diagnostics import DiagnosticsError, InsufficientDataError
from .ensemble import Ensemble, InvalidBodiesWarning
from .ephemeris import Ephemeris
from .errors import (
    AttitudeError,
    AttitudeWarning,
    EphemerisFormatError,
    InvalidInertiaError,
    InvalidStateError,
    NearSeparatrixWarning,
    PropagationError,
    ScenarioError,
    ShapeModelError,
)
from .events import Event, event_table, nutation_crossing
from .orbit import KeplerOrbit, OrbitError
from .propagate import propagate
from .state import INERTIAL_FRAMES, AttitudeState
from .torques import TorqueConfigError

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "RigidBody",
    "MassProperties",
    "AttitudeState",
    "Ephemeris",
    "Ensemble",
    "Event",
    "nutation_crossing",
    "event_table",
    "KeplerOrbit",
    "torques",
    "propagate",
    "diagnose",
    "classify",
    "Classification",
    "INERTIAL_FRAMES",
    "SYMMETRY_RTOL",
    "TRIANGLE_RTOL",
    "AttitudeError",
    "InvalidInertiaError",
    "InvalidStateError",
    "ShapeModelError",
    "ScenarioError",
    "PropagationError",
    "EphemerisFormatError",
    "OrbitError",
    "TorqueConfigError",
    "DiagnosticsError",
    "InsufficientDataError",
    "ClassificationError",
    "AttitudeWarning",
    "NearSeparatrixWarning",
    "InvalidBodiesWarning",
]


def __getattr__(name):
    # The exact torque-free module is imported on first use (it pulls in scipy.special).
    if name == "diagnose":
        from .torquefree import diagnose

        return diagnose
    raise AttributeError(f"module 'attitude' has no attribute {name!r}")
