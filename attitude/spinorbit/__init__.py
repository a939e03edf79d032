"""The spin-orbit wing: moons and other bodies on orbits about a primary.

:class:`SpinOrbit` (a body on a :class:`~attitude.model.orbit.KeplerOrbit`) holds the planar
problem and the 3-D problem with the gravity-gradient torque; the p:q resonances with
their widths (:mod:`~attitude.spinorbit.resonances`), the forced libration in longitude
(:mod:`~attitude.spinorbit.libration`), surfaces of section classified by the
finite-time Lyapunov test (:mod:`~attitude.spinorbit.planar`), the tidal despinning time
(:mod:`~attitude.spinorbit.tides`) and the ``[section]`` table of scenario files
(:mod:`~attitude.spinorbit.section`).  docs/spinorbit.md has the physics.
"""

from __future__ import annotations

from .libration import (
    LibrationMeasurement,
    forced_libration_amplitude,
    long_axis_angle,
    measure_libration,
    orbit_basis,
)
from .model import SpinOrbit, Stability
from .planar import periodic_orbit, planar_rhs, stroboscopic_map
from .resonances import (
    Resonance,
    cayley_coefficient,
    cayley_series,
    overlap_parameter,
    resonance_list,
)
from .tides import despinning_time, love_number_k2

__all__ = [
    "SpinOrbit", "Stability", "Resonance", "LibrationMeasurement",
    "cayley_coefficient", "cayley_series", "resonance_list", "overlap_parameter",
    "forced_libration_amplitude", "measure_libration", "long_axis_angle", "orbit_basis",
    "planar_rhs", "stroboscopic_map", "periodic_orbit",
    "despinning_time", "love_number_k2",
]
