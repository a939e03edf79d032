"""Disk-integrated brightness of a faceted body: the synthetic lightcurve.

For each epoch the Sun and observer directions are rotated into the body frame
(``s_b = R^T s``), each facet's ``mu0 = n . s_b`` and ``mu = n . o_b`` are formed by one
matrix product per chunk of epochs, the scattering law gives each facet's brightness
and the facet areas sum them (a matrix-vector product):

    flux(t) = sum_k A_k f(mu0_k, mu_k, alpha) / (pi R^2)

with ``R`` the radius of the volume-equivalent sphere (so that a sphere's flux at zero
phase is its geometric albedo).  A facet counts when it is lit (``mu0 > 0``) and seen
(``mu > 0``); for a convex body that is exact.  For a non-convex body
``shadows=True`` also removes facets whose centroid is shadowed or hidden by another
part of the body (ray casting, :mod:`attitude.photometry.shadows`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from attitude.foundations.errors import PhotometryError
from attitude.model.shape import Polyhedron
from attitude.photometry.dataset import Lightcurve
from attitude.photometry.geometry import Geometry
from attitude.photometry.periods import blas_single_thread
from attitude.photometry.scattering import FacetMaterials, scattering_law
from attitude.photometry.shadows import ShadowCaster

__all__ = ["lightcurve", "facet_brightness"]

#: Values per chunk of the (epochs x facets) work arrays: 2^18 float64 = 2 MiB, which
#: keeps the in-place passes in the cache of this machine's cores.
CHUNK_ELEMENTS = 1 << 18


def lightcurve(ephemeris, shape: Polyhedron, geometry: Geometry, law="lommel-seeliger", *,
               shadows: bool = False, facet_contributions: bool = False,
               chunk_elements: int = CHUNK_ELEMENTS) -> Lightcurve:
    """The synthetic lightcurve of a body on an attitude ephemeris.

    Parameters
    ----------
    ephemeris : Ephemeris
        A single-body ephemeris (body -> inertial quaternions).
    shape : Polyhedron
        The shape model in the ephemeris's body frame, m.
    geometry : Geometry
        Sun and observer directions (constant or one per epoch of the ephemeris).
    law : str, ScatteringLaw or FacetMaterials, optional
        ``"lambert"``, ``"lommel-seeliger"`` (default), ``"ls-lambert"``, ``"hapke"``,
        ``"phong"``, ``"ashikhmin-shirley"``, a law object with its parameters, or
        :class:`~attitude.photometry.scattering.FacetMaterials` (a law per facet).
    shadows : bool, optional
        Ray-cast self-shadowing and self-hiding (needs the ``shadows`` extra, embree).
    facet_contributions : bool, optional
        Also store each facet's flux (``facet_flux``, dims time x face); memory grows
        as epochs x facets.
    chunk_elements : int, optional
        Epochs x facets per chunk of work.

    Returns
    -------
    Lightcurve
        ``time`` as the ephemeris; ``flux`` (relative), ``magnitude`` (``-2.5 log10
        flux``: reduced to unit distances), ``phase_angle`` (rad), and the distances and
        light time when the geometry has them.

    Raises
    ------
    PhotometryError
        On a batch ephemeris, a geometry with another number of epochs, an unknown law
        or a bad parameter.
    MissingDependencyError
        ``shadows=True`` without embree installed.

    Examples
    --------
    A Lambert sphere at zero phase has geometric albedo 2/3:

    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.photometry import Geometry, lightcurve
    >>> body = att.RigidBody.from_principal_moments([1.0, 1.0, 1.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 1e-3])
    >>> eph = att.propagate(body, state, [0.0, 100.0])
    >>> sphere = att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=5)
    >>> lc = lightcurve(eph, sphere, Geometry(sun=[1, 0, 0], observer=[1, 0, 0]),
    ...                 law="lambert")
    >>> np.round(lc.dataset.flux.values, 3)
    array([0.667, 0.667])
    """
    ds = ephemeris.dataset
    if "body" in ds.quaternion.dims:
        raise PhotometryError("a lightcurve needs a single-body ephemeris; select one body "
                              "(eph.dataset.isel(body=k))", key="ephemeris")
    if not isinstance(shape, Polyhedron):
        raise PhotometryError(f"shape must be a Polyhedron, got {type(shape).__name__}",
                              key="shape")
    if geometry.frame and geometry.frame != ephemeris.frame:
        raise PhotometryError(f"the geometry is in frame {geometry.frame!r} but the "
                              f"ephemeris in {ephemeris.frame!r}", key="geometry.frame")
    time = np.asarray(ds.time.values, dtype=float)
    rotation = Rotation.from_quat(np.asarray(ds.quaternion.values, dtype=float))
    sun, obs = geometry.broadcast(len(time))
    flux, facet = facet_brightness(shape, rotation.inv().apply(sun),
                                   rotation.inv().apply(obs), law, shadows=shadows,
                                   facet_contributions=facet_contributions,
                                   chunk_elements=chunk_elements)
    return Lightcurve.from_arrays(
        time, flux, phase_angle=np.broadcast_to(geometry.phase_angle, time.shape),
        epoch=ephemeris.epoch, frame=ephemeris.frame, law=_law_label(law),
        sun_distance=geometry.sun_distance, observer_distance=geometry.observer_distance,
        light_time=geometry.light_time, facet_flux=facet)


def facet_brightness(shape: Polyhedron, sun_body, observer_body, law="lommel-seeliger", *,
                     shadows: bool = False, facet_contributions: bool = False,
                     chunk_elements: int = CHUNK_ELEMENTS):
    """Relative flux from body-frame unit vectors toward the Sun and the observer.

    Parameters
    ----------
    shape : Polyhedron
    sun_body, observer_body : array_like, shape (n, 3)
        Unit vectors in the body frame.
    law, shadows, facet_contributions, chunk_elements
        As in :func:`lightcurve`.

    Returns
    -------
    flux : ndarray, shape (n,)
    facet_flux : ndarray, shape (n, n_faces), or None

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from attitude.photometry import facet_brightness
    >>> cube = att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=0)
    >>> flux, _ = facet_brightness(cube, [[0, 0, 1.0]], [[0, 0, 1.0]], "lommel-seeliger")
    >>> round(float(flux[0]), 3)      # w/8 for a sphere; an icosahedron is close
    0.13
    """
    s = np.ascontiguousarray(sun_body, dtype=float).reshape(-1, 3)
    o = np.ascontiguousarray(observer_body, dtype=float).reshape(-1, 3)
    cos_alpha = np.einsum("ij,ij->i", s, o)[:, None]
    normals, areas = shape.face_normals, shape.face_areas
    r_eq = (3.0 * shape.volume / (4.0 * np.pi)) ** (1.0 / 3.0)
    areas = areas / (np.pi * r_eq**2)
    if isinstance(law, FacetMaterials):
        if len(law.index) != len(normals):
            raise PhotometryError(f"materials index has {len(law.index)} entries but the "
                                  f"shape has {len(normals)} faces", key="materials")
        groups = [(lw, idx) for lw, idx in zip(law.laws, law.groups()) if idx.size]
    else:
        groups = [(scattering_law(law), None)]
    caster = ShadowCaster(shape) if shadows else None
    with blas_single_thread():
        return _facet_loop(s, o, cos_alpha, normals, areas, groups, caster,
                           facet_contributions, chunk_elements)


def _facet_loop(s, o, cos_alpha, normals, areas, groups, caster, facet_contributions,
                chunk_elements):
    n, n_faces = len(s), len(normals)
    flux = np.zeros(n)
    facet = np.zeros((n, n_faces)) if facet_contributions else None
    step = max(1, int(chunk_elements) // max(n_faces, 1))
    for lo in range(0, n, step):
        hi = min(n, lo + step)
        mask = caster.visible(s[lo:hi], o[lo:hi]) if caster is not None else None
        for law_k, idx in groups:
            nk = normals if idx is None else normals[idx]
            ak = areas if idx is None else areas[idx]
            mu0 = s[lo:hi] @ nk.T                       # (chunk, faces): cos i
            mu = o[lo:hi] @ nk.T                        # cos e
            np.maximum(mu0, 0.0, out=mu0)
            np.maximum(mu, 0.0, out=mu)
            if mask is not None:
                mu0 *= mask if idx is None else mask[:, idx]
            f = law_k.kernel(mu0, mu, cos_alpha[lo:hi])
            flux[lo:hi] += law_k.scale * (f @ ak)
            if facet is not None:
                cols = slice(None) if idx is None else idx
                facet[lo:hi, cols] = f * (law_k.scale * ak)
    return flux, facet


def _law_label(law) -> str:
    if isinstance(law, FacetMaterials):
        return "materials: " + ", ".join(repr(lw) for lw in law.laws)
    return repr(scattering_law(law)) if not isinstance(law, str) else law
