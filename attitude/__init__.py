"""attitude: rotation-state analysis of spacecraft and small bodies.

Mass properties in, time-tagged attitude ephemerides out::

    import attitude as att
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState(epoch, attitude, omega_body)
    eph = att.propagate(body, state, times)
    eph.to_netcdf("out.nc")

The package follows the pipeline *mass properties -> state -> propagation -> ephemeris
-> analysis -> formats / CLI* (docs/architecture.md): model modules at the top level
(``body``, ``shape``, ``state``, ``orbit``, ``torques``, ``ephemeris``, ``population``),
the propagation wing (``attitude.propagation``), the analysis modules (``diagnostics``,
``classify``, ``lyapunov``, ``statistics``), the file-format wing (``attitude.formats``)
and the application layer (``scenario``, ``cli``, ``plot``).  The public names are in
``__all__``.
"""

from __future__ import annotations

import sys

from . import (
    ensemble,  # noqa: F401  (att.ensemble.regime_fractions, ...)
    errors,
    quantities,  # noqa: F401  (registers the 'rev' and 'rpm' units with astropy)
    torques,  # noqa: F401  (att.torques.GravityGradient, ...)
)
from .body import SYMMETRY_RTOL, TRIANGLE_RTOL, MassProperties, RigidBody
from .classify import Classification, classify
from .deprecation import MOVED_MODULES, install
from .environment import IGRF, TLEOrbit
from .ephemeris import Ephemeris
from .errors import *  # noqa: F403  (every exception and warning: errors.__all__)
from .fitting import (
    AngularVelocityObservations,
    AttitudeObservations,
    LightcurveObservations,
    PeriodObservations,
    fit,
    sample_posterior,
)
from .freebody import diagnose
from .orbit import KeplerOrbit
from .photometry import Geometry, Lightcurve, PeriodFit, fit_periods, lightcurve, read_lightcurve
from .population import Ensemble
from .propagation.events import Event, event_table, nutation_crossing
from .propagation.propagator import propagate
from .shape import Polyhedron
from .spinorbit import SpinOrbit
from .state import INERTIAL_FRAMES, AttitudeState
from .version import __version__

install()   # the module paths of earlier releases (attitude.splitting, ...) as aliases


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
    "fit",
    "sample_posterior",
    "AttitudeObservations",
    "AngularVelocityObservations",
    "PeriodObservations",
    "LightcurveObservations",
    "TLEOrbit",
    "IGRF",
    "SpinOrbit",
    "torques",
    "propagate",
    "diagnose",
    "classify",
    "Classification",
    "INERTIAL_FRAMES",
    "SYMMETRY_RTOL",
    "TRIANGLE_RTOL",
    # photometry (issue 15)
    "Polyhedron",
    "Geometry",
    "Lightcurve",
    "lightcurve",
    "fit_periods",
    "PeriodFit",
    "read_lightcurve",
    *errors.__all__,          # every exception and warning
]


def __getattr__(name):
    # att.splitting, att.aem, ...: the deprecated aliases of moved modules
    old = f"{__name__}.{name}"
    if old in MOVED_MODULES:
        return sys.modules[old]
    raise AttributeError(f"module 'attitude' has no attribute {name!r}")
