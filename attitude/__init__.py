"""attitude: rotation-state analysis of spacecraft and small bodies.

Mass properties in, time-tagged attitude ephemerides out::

    import attitude as att
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState(epoch, attitude, omega_body)
    eph = att.propagate(body, state, times)
    eph.to_netcdf("out.nc")

The package is laid out in layers (docs/architecture.md): ``attitude.foundations``
(errors, quantities and epochs, quaternions, elliptic functions, constants, table specs),
``attitude.model`` (bodies, shapes, states, orbits, torques, ephemerides, populations),
``attitude.propagation``, ``attitude.analysis`` (diagnostics, classification, Lyapunov
exponents, statistics), the wings (``formats``, ``photometry``, ``fitting``,
``environment``, ``spinorbit``, ``inversion``, ``pictures``, ``binary``) and
``attitude.app`` (scenario files, the CLI, plots).

The public names are in ``__all__``; each is imported on first use, so that
``import attitude`` (and ``attitude --help``) loads no more than the exceptions.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys

from .deprecation import MOVED_MODULES, install
from .foundations.errors import *  # noqa: F403  (every exception and warning: errors.__all__)
from .foundations.errors import __all__ as _error_names
from .foundations.lazy import owned_attribute
from .version import __version__

#: The runtime dependencies (import name -> distribution): none is imported here, but a
#: missing one is named now rather than at the first use of a name.
_DEPENDENCIES = {"numpy": "numpy", "scipy": "scipy", "astropy": "astropy", "erfa": "pyerfa",
                 "xarray": "xarray", "netCDF4": "netCDF4"}
_missing = [dist for name, dist in _DEPENDENCIES.items() if importlib.util.find_spec(name) is None]
if _missing:
    raise ImportError(f"attitude needs {', '.join(_missing)}: pip install attitude-dynamics "
                      f"(or pip install {' '.join(_missing)})")

install()   # the module paths of earlier releases (attitude.splitting, ...) as aliases

#: Public name -> the module that owns it (imported on first use, PEP 562).
_OWNERS = {
    "RigidBody": "model.body", "MassProperties": "model.body",
    "SYMMETRY_RTOL": "model.body", "TRIANGLE_RTOL": "model.body",
    "AttitudeState": "model.state", "INERTIAL_FRAMES": "model.state",
    "Ephemeris": "model.ephemeris", "Ensemble": "model.population",
    "KeplerOrbit": "model.orbit", "Polyhedron": "model.shape",
    "diagnose": "model.freebody",
    "Event": "propagation.events", "nutation_crossing": "propagation.events",
    "event_table": "propagation.events", "propagate": "propagation.propagator",
    "classify": "analysis.classification", "Classification": "analysis.classification",
    "fit": "fitting", "sample_posterior": "fitting",
    "AttitudeObservations": "fitting", "AngularVelocityObservations": "fitting",
    "PeriodObservations": "fitting", "LightcurveObservations": "fitting",
    "TLEOrbit": "environment", "IGRF": "environment", "SpinOrbit": "spinorbit",
    "Geometry": "photometry", "Lightcurve": "photometry", "lightcurve": "photometry",
    "fit_periods": "photometry", "PeriodFit": "photometry",
    "read_lightcurve": "photometry",
    "invert": "inversion", "period_scan": "inversion", "read_damit_lightcurves": "inversion",
    "InversionResult": "inversion",
    "BinarySystem": "binary", "BinaryState": "binary", "Impulse": "binary",
}

#: Namespaces of the public API that are modules (``att.torques.GravityGradient``).
_NAMESPACES = ("torques", "ensemble", "spindown", "binary")

__all__ = ["__version__", *_OWNERS, "torques", *_error_names]


def __getattr__(name):
    if name in _NAMESPACES:
        value = globals()[name] = importlib.import_module(f"{__name__}.{name}")
        return value
    if name not in _OWNERS and f"{__name__}.{name}" in MOVED_MODULES:
        return sys.modules[f"{__name__}.{name}"]    # att.splitting, att.aem: warn on use
    return owned_attribute(__name__, _OWNERS, name, globals())


def __dir__():
    return sorted(set(globals()) | set(__all__) | set(_NAMESPACES))
