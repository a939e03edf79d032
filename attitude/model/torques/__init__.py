"""Perturbation torques: the hook and the built-in models.

The protocol
------------
A torque model is any callable

.. code-block:: python

    torque(t, quaternion, omega_body, body) -> (..., 3) ndarray   # body frame, N m

with

``t``
    seconds since the epoch (float, or an array for a vectorised call);
``quaternion``
    the attitude, body -> inertial, scalar-last ``(x, y, z, w)``, shape ``(..., 4)``
    (the built-in models also take a scipy ``Rotation`` stack and tolerate a
    quaternion that is not exactly unit: integrators pass their raw stage values);
``omega_body``
    body-frame angular velocity, rad/s, shape ``(..., 3)``;
``body``
    the :class:`~attitude.model.body.RigidBody` (the built-in models also take a sequence
    of bodies, one per leading element, or an inertia array ``(..., 3, 3)``).

Leading axes broadcast: a scalar ``t`` with a ``(4,)`` quaternion gives ``(3,)``; arrays
``(n,)``, ``(n, 4)``, ``(n, 3)`` give ``(n, 3)``.  The integrators add the returned torque
to Euler's equations ``I dω/dt = (I ω) x ω + M``.

A plain Python function with this signature is a valid model.  Models derived from
:class:`TorqueModel` add with ``+`` (``GravityGradient(...) + EnergyDissipation(...)``
is a :class:`SumTorque`); :func:`as_torque_model` wraps a plain function so that it can
take part in a sum.  Each model says whether it depends on the angular velocity
(:attr:`TorqueModel.velocity_dependent`): splitting integrators may treat
velocity-independent (conservative) torques as pure kicks; whether it is internal
(:attr:`TorqueModel.internal`: exerted by one part of the body on another, so that the
integrators keep the inertial angular momentum fixed); its own time scale
(:meth:`TorqueModel.characteristic_rate`, from which the splitting integrator builds its
default step) and how to move its time origin (:meth:`TorqueModel.shifted`, for runs
restarted mid-way).  The integrators and the Lyapunov test use nothing else, so a
user's subclass is treated like the built-in models.

Built-in models
---------------
============================  ========================================================
:class:`GravityGradient`      point-mass primary, ``3 mu / r^5 (r x I r)``
:class:`ConstantTorque`       fixed torque in body or inertial axes
:class:`EnergyDissipation`    internal energy sink (damper, inelastic asteroid): keeps
                              the inertial ``L``, bleeds kinetic energy toward ``L^2 / 2C``
                              in a time constant (:func:`damping_timescale` for asteroids)
:class:`EddyCurrentDamping`   ``(M (ω x B)) x B`` in a uniform or tilted-dipole field
:class:`MagneticDipole`       a body-fixed (residual) magnetic moment: ``m x B``
:class:`HeavyTopPivot`        uniform gravity about a fixed pivot (the heavy top)
============================  ========================================================

:func:`from_config` builds any of them from a scenario ``[[torques]]`` table.

Modules
-------
One concept per module; this package re-exports their public names.

- :mod:`.base`: the protocol (:class:`TorqueModel`, :class:`SumTorque`,
  :class:`FunctionTorque`, :func:`as_torque_model`, :func:`internal_rate`);
- one module per built-in model: :mod:`.gravity_gradient`, :mod:`.constant`,
  :mod:`.dissipation` (with :func:`damping_timescale`), :mod:`.eddy_current`,
  :mod:`.magnetic_dipole`, :mod:`.heavy_top`; a new built-in model is one class in one
  module, re-exported here, with its ``[[torques]]`` table and builder in :mod:`.registry`;
- :mod:`.fields`: the magnetic field models (:class:`UniformField`,
  :class:`TiltedDipoleField`);
- :mod:`.registry`: the scenario tables and builders (:func:`from_config`,
  :class:`BuildContext`, :func:`register_torque_type`);
- :mod:`.common`: the small array kernels and argument readers the models share.

The physical constants (``EARTH_MU``, ...) live in :mod:`attitude.foundations.constants`
and are re-exported here for the names this module always offered.
"""

from __future__ import annotations

from ...foundations.constants import (
    EARTH_DIPOLE_MOMENT,
    EARTH_DIPOLE_POLE_LONGITUDE,
    EARTH_DIPOLE_TILT,
    EARTH_MU,
    EARTH_ROTATION_RATE,
    STANDARD_GRAVITY,
)

# names the single-module torques offered besides its own (kept for code importing them
# from here, e.g. ``from attitude.model.torques import TorqueConfigError``)
from ...foundations.errors import OrbitError, TorqueConfigError  # noqa: F401
from ...foundations.quantities import to_si  # noqa: F401
from ...foundations.spec import SYNONYMS, Key, Table, json_schema, validate  # noqa: F401
from ..body import SYMMETRY_RTOL, RigidBody  # noqa: F401
from ..orbit import KeplerOrbit, as_path  # noqa: F401
from .base import FunctionTorque, SumTorque, TorqueModel, as_torque_model, internal_rate
from .constant import ConstantTorque
from .dissipation import EnergyDissipation, damping_timescale
from .eddy_current import EddyCurrentDamping
from .fields import TiltedDipoleField, UniformField
from .gravity_gradient import GravityGradient
from .heavy_top import HeavyTopPivot
from .magnetic_dipole import MagneticDipole
from .registry import (  # noqa: F401 - ORBIT_TABLE, ... are read by the wings
    FIELD_SOURCES,
    ORBIT_SOURCES,
    ORBIT_TABLE,
    TORQUE_TABLES,
    TORQUE_TYPES,
    BuildContext,
    from_config,
    register_torque_type,
)

__all__ = [
    "TorqueModel",
    "SumTorque",
    "FunctionTorque",
    "as_torque_model",
    "GravityGradient",
    "ConstantTorque",
    "EnergyDissipation",
    "internal_rate",
    "damping_timescale",
    "EddyCurrentDamping",
    "MagneticDipole",
    "HeavyTopPivot",
    "UniformField",
    "TiltedDipoleField",
    "from_config",
    "TORQUE_TYPES",
    "BuildContext",
    "register_torque_type",
    "EARTH_MU",
    "EARTH_DIPOLE_MOMENT",
    "EARTH_DIPOLE_TILT",
    "EARTH_DIPOLE_POLE_LONGITUDE",
    "EARTH_ROTATION_RATE",
    "STANDARD_GRAVITY",
]
