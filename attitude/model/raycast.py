"""Occlusion of rays by a triangle mesh: the ray casting behind self-shadowing.

:class:`Occluder` builds an embree scene of triangles once (body frame) and answers, for
a batch of rays, whether each one meets a triangle.  Photometry
(:mod:`attitude.photometry.shadows`) and radiation pressure
(:class:`attitude.environment.SolarRadiationPressure` with ``self_shadowing=True``) both
cast their rays through it.  Positions are rounded to float32 inside embree (~1e-7
relative): rays start a little above the surface they leave (:data:`OFFSET_RTOL`).

embree is an optional dependency, installed by the ``shadows`` extra
(``pip install "attitude-dynamics[shadows]"``, which brings ``embreex``).
"""

from __future__ import annotations

import numpy as np

from ..foundations.errors import MissingDependencyError

__all__ = ["Occluder", "load_embree", "OFFSET_RTOL"]

#: Rays start this fraction of the model's extent above the surface they leave, so that
#: a facet does not occlude itself (float32 inside embree: ~1e-7 relative rounding).
OFFSET_RTOL = 1e-5


def load_embree(key: str = "shadows", switch: str = "shadows = false"):
    """embreex's ``rtcore_scene`` and ``TriangleMesh``, or the error naming the extra.

    Parameters
    ----------
    key : str
        The setting that asked for ray casting (the error's key).
    switch : str
        How to turn it off, quoted in the message.

    Raises
    ------
    MissingDependencyError
        When embreex is not installed: ``pip install "attitude-dynamics[shadows]"``.

    Examples
    --------
    >>> rtcore_scene, TriangleMesh = load_embree()
    >>> TriangleMesh.__name__
    'TriangleMesh'
    """
    try:
        # optional dependency (the "shadows" extra): imported only when shadows are asked
        from embreex import rtcore_scene  # optional: the "shadows" extra
        from embreex.mesh_construction import TriangleMesh  # optional: "shadows" extra
    except ImportError:
        raise MissingDependencyError(
            "self-shadowing needs embree: pip install \"attitude-dynamics[shadows]\" "
            f"(installs embreex), or set {switch}", key=key) from None
    return rtcore_scene, TriangleMesh


class Occluder:
    """Occlusion tests of rays against triangles (both sides of each triangle block).

    Parameters
    ----------
    triangles : array_like, shape (m, 3, 3)
        The corners of each triangle, m.
    key, switch : str
        For the error when embree is missing (:func:`load_embree`).

    Raises
    ------
    MissingDependencyError
        When embreex is not installed (the message names the ``shadows`` extra).

    Examples
    --------
    A unit triangle in the plane z = 0 blocks a ray going down through it, not one
    going up, nor one beside it.

    >>> tri = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]
    >>> occluder = Occluder(tri)
    >>> occluder.occluded([[0.2, 0.2, 1.0], [0.2, 0.2, 1.0], [2.0, 2.0, 1.0]],
    ...                   [[0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    array([ True, False, False])

    It can be pickled (the scene is built again on loading):

    >>> import pickle
    >>> pickle.loads(pickle.dumps(occluder)).occluded([[0.2, 0.2, 1.0]], [[0, 0, -1.0]])
    array([ True])
    """

    def __init__(self, triangles, *, key: str = "shadows", switch: str = "shadows = false"):
        triangles = np.asarray(triangles, dtype=float)
        self._setup = (np.ascontiguousarray(triangles, dtype=np.float32), key, switch)
        self._scene = self._build(*self._setup)
        #: The largest edge of the triangles' bounding box, m.
        self.extent = float(np.ptp(triangles.reshape(-1, 3), axis=0).max())

    @staticmethod
    def _build(triangles: np.ndarray, key: str, switch: str):
        rtcore_scene, TriangleMesh = load_embree(key, switch)
        scene = rtcore_scene.EmbreeScene()
        TriangleMesh(scene, triangles)
        return scene

    def __getstate__(self) -> dict:
        # the embree scene cannot be pickled (dask workers, processes): rebuilt on load
        return {"setup": self._setup, "extent": self.extent}

    def __setstate__(self, state: dict):
        self._setup, self.extent = state["setup"], state["extent"]
        self._scene = self._build(*self._setup)

    def occluded(self, origins, directions) -> np.ndarray:
        """``(k,)`` bool: True where the ray from ``origins`` along ``directions`` meets
        a triangle.

        Parameters
        ----------
        origins, directions : array_like, shape (k, 3)
            Body frame; the directions need not be unit vectors.
        """
        origins = np.ascontiguousarray(origins, dtype=np.float32)
        if origins.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        directions = np.ascontiguousarray(directions, dtype=np.float32)
        return np.asarray(self._scene.run(origins, directions, query="OCCLUDED")) != -1
