"""The binary wing: two rigid bodies that torque each other (the full two-body problem).

Modules: ``integrals`` (each body's inertia integrals to order N), ``mutual`` (the
mutual potential, force and torques), ``system`` (:class:`BinarySystem`,
:class:`BinaryState`, :class:`Impulse`), ``dynamics`` (equations of motion, DOP853),
``propagate`` (the ephemeris of a binary), ``diagnostics`` (periods, libration, regime:
:func:`diagnose`), ``chaos`` (the finite-time Lyapunov exponent), ``ensembles`` (many
systems in one call, in this process or on dask: :func:`ensemble`, :func:`sample_dart`),
``encounter`` (a planet's flyby of a tumbling body and its ensemble:
:func:`close_encounter`, :func:`sample_encounter`, :func:`encounter_ensemble`).
"""

from __future__ import annotations

from attitude.binary.chaos import BinaryLyapunov, lyapunov_exponent
from attitude.binary.diagnostics import (
    BinaryDiagnosis,
    PeriodChange,
    diagnose,
    libration_angle,
    period_change,
)
from attitude.binary.encounter import (
    close_encounter,
    encounter_ensemble,
    hyperbola,
    sample_encounter,
)
from attitude.binary.ensembles import ensemble, sample_dart
from attitude.binary.integrals import InertiaIntegrals, inertia_integrals, multi_indices, rotated
from attitude.binary.mutual import MutualForces, MutualGravity
from attitude.binary.propagate import propagate_binary
from attitude.binary.system import BODIES, BinaryState, BinarySystem, Impulse
from attitude.foundations.constants import G

__all__ = ["InertiaIntegrals", "inertia_integrals", "multi_indices", "rotated", "MutualForces",
           "MutualGravity", "BinarySystem", "BinaryState", "Impulse", "BODIES",
           "propagate_binary", "G", "BinaryDiagnosis", "PeriodChange", "diagnose",
           "libration_angle", "period_change", "BinaryLyapunov", "lyapunov_exponent",
           "ensemble", "sample_dart", "hyperbola", "close_encounter", "sample_encounter",
           "encounter_ensemble"]
