"""Scattering laws: the brightness of one facet seen under (i, e, alpha).

Every law gives the dimensionless facet brightness

    f(mu0, mu, alpha) = pi r(i, e, alpha) mu,

with ``r`` the bidirectional reflectance (1/sr, Hapke's convention: ``r`` contains
``mu0``), ``mu0 = cos i`` toward the Sun, ``mu = cos e`` toward the observer and
``alpha`` the phase angle.  A facet of area ``dA`` lit and seen sends ``F_sun f dA /
pi`` per steradian toward the observer; summing over facets and dividing by the
projected area ``pi R^2`` of the volume-equivalent sphere gives the *relative flux*,
which at zero phase is the geometric albedo of the body (2/3 for a Lambert sphere of
albedo 1, w/8 for a Lommel-Seeliger sphere).

Laws for asteroid regoliths: :class:`Lambert`, :class:`LommelSeeliger`,
:class:`LommelSeeligerLambert` (Kaasalainen's combination), :class:`Hapke`.
Diffuse + specular materials for spacecraft surfaces (glints): :class:`Phong` and
:class:`AshikhminShirley`.  :class:`FacetMaterials` assigns laws to facets.

References
----------
.. [1] J. H. Lambert, Photometria (1760).
.. [2] E. Lommel (1887); H. Seeliger (1888): the single-scattering law
   ``r = w/(4 pi) mu0/(mu0 + mu)``.
.. [3] M. Kaasalainen, J. Torppa, K. Muinonen, "Optimization methods for asteroid
   lightcurve inversion II", Icarus 153, 37-51 (2001), eq. (1) (LS + c L).
.. [4] B. Hapke, "Bidirectional reflectance spectroscopy 5. The coherent backscatter
   opposition effect and anisotropic scattering", Icarus 157, 523-534 (2002), eq. (13)
   (the H-function approximation); Theory of Reflectance and Emittance Spectroscopy,
   2nd ed., Cambridge (2012), ch. 9.
.. [5] B. T. Phong, "Illumination for computer generated pictures", Comm. ACM 18,
   311-317 (1975); E. P. Lafortune, Y. D. Willems, "Using the modified Phong
   reflectance model for physically based rendering", KU Leuven CW 197 (1994).
.. [6] M. Ashikhmin, P. Shirley, "An anisotropic Phong BRDF model", J. Graphics Tools
   5(2), 25-32 (2000); applied to space objects by C. J. Wetterer et al., "Refining
   space object radiation pressure modeling with bidirectional reflectance
   distribution functions", J. Guid. Control Dyn. 37, 185-196 (2014).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from attitude.foundations.errors import PhotometryError
from attitude.model.surface import Surface

__all__ = ["ScatteringLaw", "Lambert", "LommelSeeliger", "LommelSeeligerLambert", "Hapke",
           "Phong", "AshikhminShirley", "FacetMaterials", "LAWS", "scattering_law",
           "chandrasekhar_h"]

_TINY = 1e-300


def _check(name: str, value, lo=0.0, hi=None, lo_open=False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise PhotometryError(f"must be a number, got {value!r}", key=name) from None
    bad = not np.isfinite(x) or (x <= lo if lo_open else x < lo) or (hi is not None and x > hi)
    if bad:
        where = f"{'(' if lo_open else '['}{lo}, {hi if hi is not None else 'inf'}]"
        raise PhotometryError(f"must be in {where}, got {value!r}", key=name)
    return x


class ScatteringLaw:
    """Base of the scattering laws: ``law(mu0, mu, cos_alpha) -> f``.

    ``mu0`` and ``mu`` are arrays clamped at zero (a facet not lit or not seen gives
    0); ``cos_alpha`` broadcasts against them.  Laws may overwrite ``mu0`` and ``mu``
    (the hot path works in place): pass copies when you need them afterwards.

    Examples
    --------
    >>> law = scattering_law("lommel-seeliger")
    >>> isinstance(law, ScatteringLaw)
    True
    >>> mu0, mu = np.array([0.5, 1.0, 0.0]), np.array([0.5, 1.0, 0.7])
    >>> law(mu0.copy(), mu.copy(), 1.0).tolist()   # (w/4) mu0 mu / (mu0 + mu), 0 unlit
    [0.0625, 0.125, 0.0]
    >>> float(law.scale * law.kernel(mu0.copy(), mu.copy(), 1.0)[1])  # the hot path split
    0.125
    """

    name = "law"

    def __call__(self, mu0, mu, cos_alpha):
        return self.scale * self.kernel(mu0, mu, cos_alpha)

    @property
    def scale(self) -> float:
        """Constant factor of the law (the hot path applies it once, to the sum)."""
        return 1.0

    def kernel(self, mu0, mu, cos_alpha):  # pragma: no cover - abstract
        """The law without :attr:`scale`."""
        raise NotImplementedError


@dataclass(frozen=True)
class Lambert(ScatteringLaw):
    """The Lambert law, ``f = A mu0 mu``.

    Examples
    --------
    >>> from attitude.photometry.scattering import Lambert
    >>> float(Lambert(albedo=0.5)(np.array(0.5), np.array(1.0), 1.0))
    0.25
    """

    albedo: float = 1.0
    name = "lambert"

    def __post_init__(self):
        object.__setattr__(self, "albedo", _check("albedo", self.albedo))

    @property
    def scale(self) -> float:
        return self.albedo

    def kernel(self, mu0, mu, cos_alpha):
        return np.multiply(mu0, mu, out=mu0 if np.ndim(mu0) else None)


@dataclass(frozen=True)
class LommelSeeliger(ScatteringLaw):
    """The Lommel-Seeliger law, ``f = (w/4) mu0 mu / (mu0 + mu)``.

    Examples
    --------
    >>> from attitude.photometry.scattering import LommelSeeliger
    >>> float(LommelSeeliger(albedo=1.0)(np.array(1.0), np.array(1.0), 1.0))
    0.125
    """

    albedo: float = 1.0
    name = "lommel-seeliger"

    def __post_init__(self):
        object.__setattr__(self, "albedo", _check("albedo", self.albedo))

    @property
    def scale(self) -> float:
        return 0.25 * self.albedo

    def kernel(self, mu0, mu, cos_alpha):
        return _LOMMEL_SEELIGER_KERNEL.kernel(mu0, mu, cos_alpha)


@dataclass(frozen=True)
class LommelSeeligerLambert(ScatteringLaw):
    """Lommel-Seeliger plus ``c`` Lambert: ``f = (w/4) mu0 mu [1/(mu0 + mu) + c]``.

    Kaasalainen et al. (2001) use this combination (``c ~ 0.1``) in convex inversion.

    Examples
    --------
    >>> from attitude.photometry.scattering import LommelSeeligerLambert
    >>> float(LommelSeeligerLambert(c=0.1)(np.array(1.0), np.array(1.0), 1.0))
    0.15
    """

    c: float = 0.1
    albedo: float = 1.0
    name = "ls-lambert"

    def __post_init__(self):
        object.__setattr__(self, "c", _check("c", self.c))
        object.__setattr__(self, "albedo", _check("albedo", self.albedo))

    @property
    def scale(self) -> float:
        return 0.25 * self.albedo

    def kernel(self, mu0, mu, cos_alpha):
        # mu0 mu / (mu0 + mu) + c mu0 mu, in four in-place passes (the hot path)
        mu0 = np.asarray(mu0, dtype=float)
        mu = np.asarray(mu, dtype=float)
        if mu0.ndim == 0:
            return mu0 * mu * (1.0 / (mu0 + mu + _TINY) + self.c)
        prod = mu0 * mu
        ls = np.add(mu0, mu, out=mu0)
        ls += _TINY                        # 0/0 where neither lit nor seen
        np.divide(prod, ls, out=ls)
        if self.c:
            prod *= self.c
            ls += prod
        return ls



#: The Lommel-Seeliger kernel: LS + c Lambert with c = 0, built once (not per call).
_LOMMEL_SEELIGER_KERNEL = LommelSeeligerLambert(c=0.0)

def chandrasekhar_h(x, w):
    """Hapke's (2002) approximation of Chandrasekhar's H function, isotropic scatterers.

    ``H(x) = 1 / [1 - w x (r0 + (1 - 2 r0 x)/2 ln((1 + x)/x))]``, ``r0 = (1 - g)/(1 + g)``,
    ``g = sqrt(1 - w)``; relative error below 1 % (Hapke 2002, eq. 13).

    Examples
    --------
    >>> from attitude.photometry.scattering import chandrasekhar_h
    >>> round(float(chandrasekhar_h(1.0, 1.0)), 4)     # exact 2.9078
    2.8854
    """
    x = np.asarray(x, dtype=float)
    gamma = np.sqrt(1.0 - w)
    r0 = (1.0 - gamma) / (1.0 + gamma)
    with np.errstate(divide="ignore", invalid="ignore"):
        log = np.where(x > 0, np.log1p(1.0 / np.where(x > 0, x, 1.0)), 0.0)
    return 1.0 / (1.0 - w * x * (r0 + 0.5 * (1.0 - 2.0 * r0 * x) * log))


@dataclass(frozen=True)
class Hapke(ScatteringLaw):
    """Hapke's bidirectional reflectance without macroscopic roughness.

    ``r = w/(4 pi) mu0/(mu0 + mu) [(1 + B(alpha)) P(alpha) + H(mu0) H(mu) - 1]`` with a
    one-term Henyey-Greenstein phase function
    ``P = (1 - xi^2) / (1 + 2 xi cos alpha + xi^2)^(3/2)`` (``xi < 0`` backscattering),
    the shadow-hiding opposition surge ``B = B0 / (1 + tan(alpha/2) / h)`` and
    :func:`chandrasekhar_h`.  The macroscopic roughness correction is not included.

    Parameters
    ----------
    w : float
        Single-scattering albedo, [0, 1].
    xi : float
        Henyey-Greenstein asymmetry, (-1, 1); default -0.3.
    B0, h : float
        Opposition-surge amplitude (>= 0) and width (> 0); default 1.0, 0.05.

    Examples
    --------
    In the limit ``w -> 0`` with isotropic scattering and no surge, Hapke is
    Lommel-Seeliger:

    >>> from attitude.photometry.scattering import Hapke, LommelSeeliger
    >>> mu0, mu = np.array(0.6), np.array(0.8)
    >>> hapke = Hapke(w=1e-6, xi=0.0, B0=0.0)(mu0.copy(), mu.copy(), 0.9)
    >>> ls = LommelSeeliger(albedo=1e-6)(mu0.copy(), mu.copy(), 0.9)
    >>> bool(abs(hapke / ls - 1) < 1e-5)
    True
    """

    w: float = 0.3
    xi: float = -0.3
    B0: float = 1.0
    h: float = 0.05
    name = "hapke"

    def __post_init__(self):
        object.__setattr__(self, "w", _check("w", self.w, 0.0, 1.0))
        xi = _check("xi", self.xi, -1.0, 1.0)
        if abs(xi) >= 1.0:
            raise PhotometryError(f"must be in (-1, 1), got {self.xi!r}", key="xi")
        object.__setattr__(self, "xi", xi)
        object.__setattr__(self, "B0", _check("B0", self.B0))
        object.__setattr__(self, "h", _check("h", self.h, lo_open=True))

    def kernel(self, mu0, mu, cos_alpha):
        mu0 = np.asarray(mu0, dtype=float)
        mu = np.asarray(mu, dtype=float)
        cos_alpha = np.clip(cos_alpha, -1.0, 1.0)
        xi = self.xi
        P = (1.0 - xi**2) / (1.0 + 2.0 * xi * cos_alpha + xi**2) ** 1.5
        tan_half = np.sqrt((1.0 - cos_alpha) / (1.0 + cos_alpha + _TINY))
        B = self.B0 / (1.0 + tan_half / self.h)
        bracket = (1.0 + B) * P + chandrasekhar_h(mu0, self.w) * chandrasekhar_h(mu, self.w) - 1
        return 0.25 * self.w * mu0 * mu / (mu0 + mu + _TINY) * bracket


def _specular_geometry(mu0, mu, cos_alpha):
    """``(n.h, h.k)``: the normal against the half vector, the half vector against the
    Sun direction (``cos(alpha/2)``)."""
    cos_half = np.sqrt(0.5 * (1.0 + np.clip(cos_alpha, -1.0, 1.0)))
    n_h = (mu0 + mu) / (2.0 * cos_half + _TINY)
    return np.clip(n_h, 0.0, 1.0), cos_half


@dataclass(frozen=True)
class Phong(ScatteringLaw):
    """Diffuse + specular material, the (energy-normalised) Phong BRDF.

    ``rho = Rd/pi + Rs (n + 2)/(2 pi) cos^n(beta)``, ``beta`` the angle between the
    observer and the mirror direction of the Sun (``cos beta = 2 mu0 mu - cos alpha``
    projected on the facet plane's normal).

    Examples
    --------
    >>> from attitude.photometry.scattering import Phong
    >>> mirror = Phong(diffuse=0.0, specular=0.5, exponent=100)
    >>> f = mirror(np.array([0.8, 0.8]), np.array([0.8, 0.6]), np.array([0.28, 0.0]))
    >>> bool(f[0] > 10 * f[1])      # the glint at the mirror geometry
    True
    """

    diffuse: float = 0.2
    specular: float = 0.5
    exponent: float = 50.0
    name = "phong"

    def __post_init__(self):
        for key in ("diffuse", "specular"):
            object.__setattr__(self, key, _check(key, getattr(self, key), 0.0, 1.0))
        object.__setattr__(self, "exponent", _check("exponent", self.exponent))

    def kernel(self, mu0, mu, cos_alpha):
        mu0 = np.asarray(mu0, dtype=float)
        mu = np.asarray(mu, dtype=float)
        cos_beta = np.clip(2.0 * mu0 * mu - cos_alpha, 0.0, 1.0)
        lit = (mu0 > 0) & (mu > 0)
        spec = self.specular * 0.5 * (self.exponent + 2.0) * cos_beta**self.exponent
        return (self.diffuse + spec * lit) * mu0 * mu


@dataclass(frozen=True)
class AshikhminShirley(ScatteringLaw):
    """Diffuse + specular material, the isotropic Ashikhmin-Shirley BRDF.

    ``rho_s = (n + 1)/(8 pi) (n.h)^n / [(h.k) max(mu0, mu)] F(h.k)`` with Schlick's
    Fresnel ``F = Rs + (1 - Rs)(1 - h.k)^5``, and
    ``rho_d = 28 Rd / (23 pi) (1 - Rs) [1 - (1 - mu0/2)^5] [1 - (1 - mu/2)^5]``.
    The BRDF is reciprocal (symmetric in the Sun and the observer) and conserves
    energy.

    Examples
    --------
    >>> from attitude.photometry.scattering import AshikhminShirley
    >>> law = AshikhminShirley(diffuse=0.3, specular=0.6, exponent=200)
    >>> a = law(np.array(0.3), np.array(0.9), 0.2)
    >>> b = law(np.array(0.9), np.array(0.3), 0.2)
    >>> bool(abs(a - b) < 1e-15)          # reciprocity
    True
    """

    diffuse: float = 0.2
    specular: float = 0.5
    exponent: float = 50.0
    name = "ashikhmin-shirley"

    def __post_init__(self):
        for key in ("diffuse", "specular"):
            object.__setattr__(self, key, _check(key, getattr(self, key), 0.0, 1.0))
        object.__setattr__(self, "exponent", _check("exponent", self.exponent))

    def kernel(self, mu0, mu, cos_alpha):
        mu0 = np.asarray(mu0, dtype=float)
        mu = np.asarray(mu, dtype=float)
        Rd, Rs, n = self.diffuse, self.specular, self.exponent
        n_h, h_k = _specular_geometry(mu0, mu, cos_alpha)
        fresnel = Rs + (1.0 - Rs) * (1.0 - h_k) ** 5
        rho_s = (n + 1.0) / (8.0 * np.pi) * n_h**n / (h_k * np.maximum(mu0, mu) + _TINY) \
            * fresnel
        rho_d = 28.0 * Rd / (23.0 * np.pi) * (1.0 - Rs) \
            * (1.0 - (1.0 - 0.5 * mu0) ** 5) * (1.0 - (1.0 - 0.5 * mu) ** 5)
        return np.pi * (rho_s + rho_d) * mu0 * mu


#: Law names (scenario files, ``lightcurve(law=...)``) -> classes.
LAWS = {"lambert": Lambert, "lommel-seeliger": LommelSeeliger,
        "ls-lambert": LommelSeeligerLambert, "hapke": Hapke, "phong": Phong,
        "ashikhmin-shirley": AshikhminShirley}


def scattering_law(law, **parameters) -> ScatteringLaw:
    """A scattering law from its name (or the law itself) and parameters.

    Raises
    ------
    PhotometryError
        On an unknown name or parameter, or a parameter out of range (negative
        albedo, ...).

    Examples
    --------
    >>> from attitude.photometry import scattering_law
    >>> scattering_law("ls-lambert", c=0.2)
    LommelSeeligerLambert(c=0.2, albedo=1.0)
    """
    if isinstance(law, ScatteringLaw):
        if parameters:
            raise PhotometryError("parameters are given with a law object; set them on the "
                                  "object", key="law")
        return law
    if not isinstance(law, str) or law.lower() not in LAWS:
        raise PhotometryError(f"unknown scattering law {law!r}: use one of "
                              f"{', '.join(sorted(LAWS))}", key="law")
    cls = LAWS[law.lower()]
    try:
        return cls(**parameters)
    except TypeError:
        allowed = [f for f in cls.__dataclass_fields__]
        raise PhotometryError(f"unknown parameter for {law!r} among {sorted(parameters)}: "
                              f"allowed are {allowed}", key="law") from None


@dataclass(frozen=True, eq=False)
class FacetMaterials:
    """Scattering laws assigned to facets: ``laws[index[k]]`` is facet k's law.

    Parameters
    ----------
    laws : sequence of ScatteringLaw
    index : array_like of int, shape (n_faces,)

    Raises
    ------
    PhotometryError
        If an index does not name a law.

    Examples
    --------
    >>> from attitude.photometry.scattering import FacetMaterials, Lambert, Phong
    >>> mats = FacetMaterials([Lambert(0.1), Phong()], [0, 0, 1, 1])
    >>> [k.tolist() for k in mats.groups()]
    [[0, 1], [2, 3]]
    """

    laws: tuple
    index: np.ndarray = field(repr=False)

    def __post_init__(self):
        laws = tuple(scattering_law(law) for law in self.laws)
        index = np.asarray(self.index)
        if index.ndim != 1 or not np.issubdtype(index.dtype, np.integer) \
                or (index.size and (index.min() < 0 or index.max() >= len(laws))):
            raise PhotometryError(f"index must be integers in 0..{len(laws) - 1}, one per "
                                  "facet", key="materials")
        object.__setattr__(self, "laws", laws)
        object.__setattr__(self, "index", index)

    @classmethod
    def from_surface(cls, surface: Surface, law: str = "ashikhmin-shirley",
                     exponent: float = 100.0) -> FacetMaterials:
        """Diffuse + specular laws from a surface's optical properties.

        Each :class:`~attitude.model.surface.OpticalProperties` becomes a ``"phong"`` or
        ``"ashikhmin-shirley"`` law with ``diffuse = rho_d`` and ``specular = rho_s``
        (the fractions the solar-radiation-pressure model uses), and the given
        specular exponent (the glint's sharpness, which the fractions do not fix).

        Examples
        --------
        >>> import attitude as att
        >>> from attitude.model.surface import OpticalProperties, Surface
        >>> from attitude.photometry.scattering import FacetMaterials
        >>> shape = att.Polyhedron.ellipsoid(1, 1, 1, subdivisions=0)
        >>> surf = Surface.uniform(shape, OpticalProperties(specular=0.6, diffuse=0.2))
        >>> FacetMaterials.from_surface(surf, "phong", exponent=40).laws
        (Phong(diffuse=0.2, specular=0.6, exponent=40.0),)
        """
        if law not in ("phong", "ashikhmin-shirley"):
            raise PhotometryError(f"a surface maps to 'phong' or 'ashikhmin-shirley', got "
                                  f"{law!r}", key="law")
        laws = [scattering_law(law, diffuse=p.diffuse, specular=p.specular,
                               exponent=exponent) for p in surface.properties]
        return cls(laws, np.asarray(surface.index))

    def groups(self) -> list[np.ndarray]:
        """Facet indices of each law, in the order of :attr:`laws`."""
        return [np.flatnonzero(self.index == k) for k in range(len(self.laws))]

