"""The photometry wing: synthetic lightcurves and period analysis.

From a shape, an attitude ephemeris and the Sun/observer geometry to a lightcurve
(:func:`lightcurve`), and from a lightcurve, synthetic or observed
(:func:`read_lightcurve`), back to its periods (:func:`fit_periods`).

Modules: ``geometry`` (Sun and observer directions), ``scattering`` (the laws),
``brightness`` (disk integration over facets), ``shadows`` (ray casting, optional
embree), ``lightcurve`` (the dataset and its netCDF file), ``periods`` (Lomb-Scargle
and the two-period Fourier series), ``readers`` (ALCDEF and CSV), ``observations``
(a lightcurve with its geometry, what fits and inversions read), ``config`` (the
``[photometry]`` table of scenario files) and ``plot`` (figures).
"""

from __future__ import annotations

from attitude.photometry.brightness import facet_brightness, lightcurve
from attitude.photometry.dataset import Lightcurve
from attitude.photometry.geometry import Geometry, OrbitGeometry, phase_angle, reduced_magnitude
from attitude.photometry.observations import LightcurveObservations
from attitude.photometry.periods import PeriodFit, fit_periods, lattice_combination
from attitude.photometry.readers import read_alcdef, read_csv, read_lightcurve
from attitude.photometry.scattering import (
    LAWS,
    AshikhminShirley,
    FacetMaterials,
    Hapke,
    Lambert,
    LommelSeeliger,
    LommelSeeligerLambert,
    Phong,
    ScatteringLaw,
    scattering_law,
)

__all__ = ["Geometry", "OrbitGeometry", "LightcurveObservations", "phase_angle",
           "reduced_magnitude", "Lightcurve", "lightcurve",
           "facet_brightness", "LAWS", "ScatteringLaw", "Lambert", "LommelSeeliger",
           "LommelSeeligerLambert", "Hapke", "Phong", "AshikhminShirley", "FacetMaterials",
           "scattering_law", "PeriodFit", "fit_periods", "lattice_combination",
           "read_lightcurve", "read_alcdef", "read_csv"]
