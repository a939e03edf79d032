"""Self-shadowing and self-hiding of non-convex shapes by ray casting.

A facet counts toward the lightcurve when its centroid sees the Sun and the observer
past the rest of the body.  :class:`ShadowCaster` builds an embree scene of the mesh
once (body frame) and, for a chunk of epochs, casts two occlusion rays per facet that
faces both the Sun and the observer, starting a small distance above the centroid.
The test is per facet (no partial shadows inside a facet): the error shrinks with the
facet size.

The rays go through :class:`attitude.model.raycast.Occluder`.  embree is an optional
dependency, installed by the ``shadows`` extra (``pip install
"attitude-dynamics[shadows]"``, which brings ``embreex``).
"""

from __future__ import annotations

import numpy as np

from attitude.model.raycast import OFFSET_RTOL, Occluder
from attitude.model.shape import Polyhedron

__all__ = ["ShadowCaster"]


class ShadowCaster:
    """Occlusion tests against a shape model, in the body frame.

    Parameters
    ----------
    shape : Polyhedron

    Raises
    ------
    MissingDependencyError
        When embreex is not installed (the message names the ``shadows`` extra).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from attitude.photometry.shadows import ShadowCaster
    >>> caster = ShadowCaster(att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=1))
    >>> mask = caster.visible(np.array([[0, 0, 1.0]]), np.array([[0, 0, 1.0]]))
    >>> bool(mask.any()), mask.shape          # a convex body shadows nothing
    (True, (1, 80))
    """

    def __init__(self, shape: Polyhedron):
        self._occluder = Occluder(shape.vertices[shape.faces])
        self._normals = shape.face_normals
        extent = float(np.ptp(shape.vertices, axis=0).max())
        self._origins = shape.face_centroids + OFFSET_RTOL * extent * self._normals

    def visible(self, sun, observer) -> np.ndarray:
        """``(n, n_faces)`` float mask: 1 where the facet is lit and seen, else 0.

        Parameters
        ----------
        sun, observer : ndarray, shape (n, 3)
            Unit vectors in the body frame.
        """
        mu0 = sun @ self._normals.T
        mu = observer @ self._normals.T
        candidate = (mu0 > 0) & (mu > 0)
        t_idx, f_idx = np.nonzero(candidate)
        mask = np.zeros(candidate.shape)
        if t_idx.size == 0:
            return mask
        origins = self._origins[f_idx]
        both = np.concatenate([origins, origins])
        dirs = np.concatenate([sun[t_idx], observer[t_idx]])
        hit = self._occluder.occluded(both, dirs)
        clear = ~(hit[: t_idx.size] | hit[t_idx.size:])
        mask[t_idx, f_idx] = clear
        return mask
