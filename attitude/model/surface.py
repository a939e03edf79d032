"""Surface optical properties of a shape model, facet by facet.

Sunlight on a facet is absorbed, reflected specularly or reflected diffusely; the
fractions are the facet's :class:`OpticalProperties`.  The same numbers drive two
models: the brightness of the facet (photometry: a diffuse + specular BRDF,
:meth:`attitude.photometry.scattering.FacetMaterials.from_surface`) and the force of
the light on it (solar radiation pressure, the classic flat-plate model
``F = -P A cos(theta) [(1 - rho_s) s + 2 (rho_s cos(theta) + rho_d / 3) n]``,
Montenbruck & Gill 2000, eq. 3.73).  :class:`Surface` assigns properties to the facets of
a :class:`~attitude.model.shape.Polyhedron`.

References
----------
.. [1] O. Montenbruck, E. Gill, *Satellite Orbits*, Springer (2000), sec. 3.4.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from attitude.foundations.errors import ShapeModelError
from attitude.model.shape import Polyhedron

__all__ = ["OpticalProperties", "Surface"]


@dataclass(frozen=True)
class OpticalProperties:
    """Fractions of the incident light reflected specularly and diffusely.

    Parameters
    ----------
    specular : float
        ``rho_s``, in [0, 1].
    diffuse : float
        ``rho_d``, in [0, 1], with ``rho_s + rho_d <= 1``.
    name : str, optional
        A label ("MLI", "solar cell", ...).

    Raises
    ------
    ShapeModelError
        If a fraction is outside [0, 1] or they add up to more than 1.

    Examples
    --------
    >>> from attitude.model.surface import OpticalProperties
    >>> aluminium = OpticalProperties(specular=0.6, diffuse=0.2, name="aluminium")
    >>> round(aluminium.absorbed, 12)
    0.2
    """

    specular: float = 0.0
    diffuse: float = 0.0
    name: str = ""

    def __post_init__(self):
        for key in ("specular", "diffuse"):
            value = getattr(self, key)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ShapeModelError(f"must be a number, got {value!r}", key=key) from None
            if not (np.isfinite(value) and 0.0 <= value <= 1.0):
                raise ShapeModelError(f"must be in [0, 1], got {value!r}", key=key)
            object.__setattr__(self, key, value)
        if self.specular + self.diffuse > 1.0 + 1e-12:
            raise ShapeModelError(f"specular + diffuse = {self.specular + self.diffuse:g} "
                                  "exceeds 1: a surface cannot reflect more light than it "
                                  "receives", key="diffuse")

    @property
    def absorbed(self) -> float:
        """``1 - rho_s - rho_d``."""
        return 1.0 - self.specular - self.diffuse


@dataclass(frozen=True, eq=False)
class Surface:
    """A shape model with optical properties per facet.

    Parameters
    ----------
    shape : Polyhedron
    properties : sequence of OpticalProperties
    index : array_like of int, shape (n_faces,)
        ``properties[index[k]]`` belongs to face ``k``.

    Raises
    ------
    ShapeModelError
        On an index of the wrong length or out of range.

    Examples
    --------
    >>> import attitude as att
    >>> from attitude.model.surface import OpticalProperties, Surface
    >>> cube = att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=0)
    >>> surf = Surface.uniform(cube, OpticalProperties(0.1, 0.3))
    >>> surf.diffuse[:3]
    array([0.3, 0.3, 0.3])
    """

    shape: Polyhedron
    properties: tuple
    index: np.ndarray = field(repr=False)

    def __post_init__(self):
        props = tuple(self.properties)
        if not all(isinstance(p, OpticalProperties) for p in props):
            raise ShapeModelError("properties must be OpticalProperties", key="properties")
        index = np.asarray(self.index)
        n = len(self.shape.faces)
        if index.shape != (n,) or not np.issubdtype(index.dtype, np.integer) \
                or index.min() < 0 or index.max() >= len(props):
            raise ShapeModelError(f"index must hold one integer in 0..{len(props) - 1} per "
                                  f"face ({n} faces)", key="index")
        index = index.copy()
        index.setflags(write=False)
        object.__setattr__(self, "properties", props)
        object.__setattr__(self, "index", index)

    @classmethod
    def uniform(cls, shape: Polyhedron, properties: OpticalProperties) -> Surface:
        """Every facet with the same properties."""
        return cls(shape, (properties,), np.zeros(len(shape.faces), dtype=int))

    @property
    def specular(self) -> np.ndarray:
        """``rho_s`` per face, shape (n_faces,)."""
        return np.array([p.specular for p in self.properties])[self.index]

    @property
    def diffuse(self) -> np.ndarray:
        """``rho_d`` per face, shape (n_faces,)."""
        return np.array([p.diffuse for p in self.properties])[self.index]
