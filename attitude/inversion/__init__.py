"""The inversion wing: shape, pole and rotation state from photometry alone.

Modules: ``observations`` (lightcurves with their geometry, DAMIT's file format),
``gaussian_image`` (the convex shape as facet areas over fixed normals), ``convex``
(the principal-axis model and its least-squares fit), ``tumbler`` (the same shape with
the exact torque-free attitude of a non-principal-axis rotator).
"""

from __future__ import annotations

from attitude.inversion.convex import ConvexFit, ConvexModel, fit_convex, spin_to_body
from attitude.inversion.gaussian_image import GaussianImage, real_harmonics, sphere_triangulation
from attitude.inversion.invert import (
    InversionResult,
    PeriodScan,
    invert,
    period_grid,
    period_scan,
    pole_starts,
)
from attitude.inversion.minkowski import facet_mesh, polyhedron_from_areas, support_polyhedron
from attitude.inversion.observations import (
    LightcurveObservations,
    ObservedLightcurve,
    engine_blocks,
    read_damit_lightcurves,
)
from attitude.inversion.tumbler import TumblerFit, fit_tumbler

__all__ = ["LightcurveObservations", "ObservedLightcurve", "engine_blocks",
           "read_damit_lightcurves", "GaussianImage",
           "real_harmonics", "sphere_triangulation", "ConvexModel", "ConvexFit", "fit_convex",
           "spin_to_body", "invert", "period_scan", "period_grid", "pole_starts",
           "InversionResult", "PeriodScan", "polyhedron_from_areas", "support_polyhedron",
           "facet_mesh", "TumblerFit", "fit_tumbler"]
