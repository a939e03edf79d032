"""Mass properties of rigid bodies.

Two value types:

:class:`MassProperties`
    mass, centre of mass and inertia tensor of a *part* (a primitive solid, a set
    of point masses, a polyhedral shape model).  Parts can be placed at an offset and
    orientation and added; the sum uses the parallel-axis theorem.  A part may be
    degenerate (a thin rod has a zero moment), so it is only checked for being
    symmetric, finite and positive semi-definite.

:class:`RigidBody`
    the validated inertia tensor of a whole body about its centre of mass, with its
    principal moments ``A <= B <= C`` and the rotation into the right-handed principal
    frame.  This is what the propagators take.

Conventions: SI units (kg, m, kg m^2) for plain numbers, astropy Quantities or
strings accepted at the boundary; inertia tensors are about the centre of mass and
expressed in the frame of the object that holds them; an ``orientation`` is a scipy
``Rotation`` mapping the part's frame into the parent frame
(``v_parent = orientation.apply(v_part)``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from os import PathLike

import numpy as np
from scipy.spatial.transform import Rotation

from ..foundations import quaternion as quat
from ..foundations.errors import InvalidInertiaError, InvalidStateError
from ..foundations.quantities import to_si
from .shape import Polyhedron

__all__ = [
    "MassDistribution",
    "MassProperties",
    "RigidBody",
    "SYMMETRY_RTOL",
    "TRIANGLE_RTOL",
    "SYMMETRIC_TENSOR_RTOL",
    "diagonal_inertia",
    "check_inertia",
    "principal_quaternions",
    "to_principal_frame",
    "to_body_frame",
    "BodyBatch",
    "as_bodies",
]

#: Two principal moments are treated as equal (axisymmetric body) when they differ by
#: at most ``SYMMETRY_RTOL * C``; all three equal (spherical body) likewise.  Used by
#: :attr:`RigidBody.symmetry` and by the propagators to pick the axisymmetric branch.
SYMMETRY_RTOL = 1e-12

#: Allowed violation of the triangle inequality ``A + B >= C``, relative to ``C``.
#: A thin plate sits exactly on the equality, so rounding must not reject it.
TRIANGLE_RTOL = 1e-10

#: Allowed asymmetry ``|I_ij - I_ji|`` of an input tensor, relative to its largest
#: element; the one symmetry tolerance of every inertia check (:func:`check_inertia`:
#: ``RigidBody``, ``MassProperties``, the rows of an ensemble).  Relative, because
#: tensors come in any unit and scale (kg m^2 of a cubesat, of an asteroid).  Tensors
#: that were computed (rotated as ``R I R^T``, summed over parts, integrated over a
#: shape model) carry a rounding asymmetry of a few ulp per term, far below 1e-10;
#: a real error (a product of inertia with the wrong sign or a transposed entry) is
#: O(1) relative, far above it.
SYMMETRIC_TENSOR_RTOL = 1e-10


def diagonal_inertia(moments) -> np.ndarray:
    """(N, 3, 3) inertia tensors of bodies whose frame is their principal frame.

    Examples
    --------
    >>> diagonal_inertia([[1.0, 2.0, 3.0]])[0]
    array([[1., 0., 0.],
           [0., 2., 0.],
           [0., 0., 3.]])
    """
    return np.asarray(moments, dtype=float)[:, :, None] * np.eye(3)


def _copy(a) -> np.ndarray:
    # A private copy.  Not flagged read-only: scipy's Rotation.apply refuses read-only
    # buffers, and users rotate these vectors all the time.
    return np.array(a, dtype=float)


def _vector(value, unit: str, name: str) -> np.ndarray:
    v = np.asarray(to_si(value, unit, name=name, finite=False,
                         error=InvalidInertiaError), dtype=float)
    if v.shape != (3,):
        raise InvalidInertiaError(f"{name}: expected 3 components, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InvalidInertiaError(f"{name}: components must be finite, got {v.tolist()}")
    return v


def _positive(value, unit: str, name: str, *, allow_zero: bool = False) -> float:
    x = to_si(value, unit, name=name, finite=False, error=InvalidInertiaError)
    if np.ndim(x) != 0:
        raise InvalidInertiaError(f"{name}: expected a scalar, got shape {np.shape(x)}")
    x = float(x)
    if not np.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        raise InvalidInertiaError(
            f"{name} = {x!r} {unit}: must be a finite, positive number")
    return x


def _tensor(value, name: str = "inertia") -> np.ndarray:
    """Convert, check shape, finiteness and symmetry; return the symmetrised tensor."""
    inertia = np.asarray(to_si(value, "kg m2", name=name, finite=False,
                               error=InvalidInertiaError))
    if inertia.shape != (3, 3):
        raise InvalidInertiaError(f"{name}: expected a 3x3 tensor, got shape {inertia.shape}")
    invalid = _tensor_problems(inertia[None], name)
    if invalid:
        raise InvalidInertiaError(invalid[0])
    return 0.5 * (inertia + inertia.T)


def _tensor_problems(inertia: np.ndarray, name: str = "inertia") -> dict[int, str]:
    """Rows of an (N, 3, 3) stack that are not finite or not symmetric: ``{i: reason}``."""
    invalid: dict[int, str] = {}
    finite = np.all(np.isfinite(inertia), axis=(1, 2))
    for i in np.flatnonzero(~finite):
        a, b = (int(k) for k in np.argwhere(~np.isfinite(inertia[i]))[0])
        invalid[int(i)] = (f"{name}[{a}][{b}] = {float(inertia[i, a, b])}: every element "
                           "must be finite")
    safe = np.where(finite[:, None, None], inertia, 0.0)
    scale = np.abs(safe).max(axis=(1, 2))
    asym = np.abs(safe - safe.transpose(0, 2, 1))
    for i in np.flatnonzero(finite & (asym.max(axis=(1, 2)) > SYMMETRIC_TENSOR_RTOL * scale)):
        a, b = (int(k) for k in np.unravel_index(np.argmax(asym[i]), (3, 3)))
        invalid[int(i)] = (
            f"{name} is not symmetric: [{a}][{b}] = {float(inertia[i, a, b])} but [{b}][{a}] = "
            f"{float(inertia[i, b, a])}; an inertia tensor equals its transpose (products "
            "of inertia appear twice with the same sign)")
    return invalid


def check_inertia(inertia) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
    """Validate and diagonalise a stack of inertia tensors (vectorised).

    The one inertia validator: :class:`RigidBody` calls it on one tensor and raises on
    its reason, an ensemble on all rows and records the invalid ones.

    Parameters
    ----------
    inertia : (N, 3, 3) array_like
        Tensors about the centres of mass, kg m^2.

    Returns
    -------
    moments : (N, 3) ndarray
        Principal moments sorted ``A <= B <= C`` (NaN on invalid rows).
    axes : (N, 3, 3) ndarray
        Right-handed principal axes as columns (``v_body = axes @ v_principal``);
        exact permutations for diagonal tensors, the identity on invalid rows.
    invalid : dict
        ``{row: reason}`` for tensors that are not finite, not symmetric (beyond
        :data:`SYMMETRIC_TENSOR_RTOL`), not positive-definite, or that violate the
        triangle inequality ``A + B >= C`` (beyond :data:`TRIANGLE_RTOL`); the reason
        names the problem and the fix.

    Examples
    --------
    >>> import numpy as np
    >>> moments, axes, invalid = check_inertia([np.diag([3.0, 1.0, 2.0]),
    ...                                         np.diag([1.0, 1.0, 3.0])])
    >>> moments[0], axes[0] @ [0.0, 0.0, 1.0]        # C = 3 is about body x
    (array([1., 2., 3.]), array([1., 0., 0.]))
    >>> invalid[1][:48]
    'principal moments A = 1, B = 1, C = 3 kg m^2 vio'
    """
    inertia = np.array(inertia, dtype=float, ndmin=3)
    if inertia.shape[1:] != (3, 3):
        raise InvalidInertiaError(f"inertia: expected (N, 3, 3) tensors, got {inertia.shape}")
    n = inertia.shape[0]
    invalid = _tensor_problems(inertia)
    good = np.ones(n, dtype=bool)
    good[list(invalid)] = False
    safe = np.where(good[:, None, None], inertia, np.eye(3))
    safe = 0.5 * (safe + safe.transpose(0, 2, 1))
    moments = np.empty((n, 3))
    axes = np.empty((n, 3, 3))
    diag = np.einsum("nii->ni", safe)
    diagonal = np.count_nonzero(safe - diag[:, :, None] * np.eye(3), axis=(1, 2)) == 0
    if diagonal.any():      # an exact permutation, no eigen-solver rounding
        order = np.argsort(diag[diagonal], axis=1, kind="stable")
        moments[diagonal] = np.take_along_axis(diag[diagonal], order, axis=1)
        axes[diagonal] = np.eye(3)[:, order].transpose(1, 0, 2)
    if (~diagonal).any():
        moments[~diagonal], axes[~diagonal] = np.linalg.eigh(safe[~diagonal])
    axes[:, :, 2] *= np.where(np.linalg.det(axes) < 0, -1.0, 1.0)[:, None]
    A, B, C = moments[:, 0], moments[:, 1], moments[:, 2]
    for i in np.flatnonzero(good & ~(A > 0)):
        invalid[int(i)] = (
            f"inertia is not positive-definite: smallest principal moment A = {A[i]:.6g} "
            "kg m^2; every rigid body with extent in three dimensions has A > 0 (a thin rod "
            "or collinear point masses has A = 0: give it a radius or add the mass it is "
            "attached to)")
    for i in np.flatnonzero(good & (A > 0) & (A + B < C * (1 - TRIANGLE_RTOL))):
        invalid[int(i)] = (
            f"principal moments A = {A[i]:.6g}, B = {B[i]:.6g}, C = {C[i]:.6g} kg m^2 violate "
            f"the triangle inequality A + B >= C (A + B = {A[i] + B[i]:.6g}); no mass "
            "distribution has them: check the units and that the moments are about the "
            "centre of mass")
    bad = np.zeros(n, dtype=bool)
    bad[list(invalid)] = True
    moments[bad] = np.nan
    axes[bad] = np.eye(3)
    return moments, axes, dict(sorted(invalid.items()))


@dataclass(frozen=True, eq=False)
class MassDistribution:
    """Where a homogeneous body's mass lies, beyond its inertia tensor: what the mutual
    gravity of two bodies needs to every order (:mod:`attitude.binary`).

    Parameters
    ----------
    kind : {"sphere", "ellipsoid", "polyhedron"}
    mass : float
        kg.
    semi_axes : (3,) array, optional
        m, along the part's x, y, z (sphere: three equal radii), centred on the origin.
    shape : Polyhedron, optional
        The solid (vertices in m, in the body frame), of uniform density.

    Examples
    --------
    >>> from attitude import MassProperties
    >>> MassProperties.solid_ellipsoid(2.0, [3.0, 2.0, 1.0]).distribution.kind
    'ellipsoid'
    """

    kind: str
    mass: float
    semi_axes: np.ndarray | None = None
    shape: Polyhedron | None = None

    def __post_init__(self):
        if self.kind not in ("sphere", "ellipsoid", "polyhedron"):
            raise InvalidInertiaError(f"distribution: unknown kind {self.kind!r}; expected "
                                      "sphere, ellipsoid or polyhedron")
        if (self.shape is None) == (self.kind == "polyhedron"):
            raise InvalidInertiaError("distribution: a polyhedron needs its shape, and "
                                      "only a polyhedron has one")
        if self.semi_axes is not None:
            object.__setattr__(self, "semi_axes", _copy(np.asarray(self.semi_axes, float)))

    @property
    def center_of_mass(self) -> np.ndarray:
        """m, in the body frame."""
        return np.zeros(3) if self.shape is None else self.shape.centroid


def _parallel_axis(mass: float, r: np.ndarray) -> np.ndarray:
    """Steiner term ``m (|r|^2 1 - r r^T)``: inertia of a point mass at ``r``."""
    return mass * (np.dot(r, r) * np.eye(3) - np.outer(r, r))


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass, centre of mass and inertia of a part (possibly degenerate).

    Parameters
    ----------
    mass : float or Quantity
        kg.
    center_of_mass : (3,) array-like or Quantity
        Position of the centre of mass in the part's frame, m.
    inertia : (3, 3) array-like or Quantity
        Inertia tensor about the centre of mass in the part's frame, kg m^2.

    Examples
    --------
    A bus with two solar panels, summed with the parallel-axis theorem:

    >>> from attitude import MassProperties, RigidBody
    >>> bus = MassProperties.solid_box(mass=500.0, size=[1.0, 1.0, 2.0])
    >>> panel = MassProperties.thin_plate(mass=20.0, size=[3.0, 1.0])
    >>> body = RigidBody.from_parts([bus, panel.placed(offset=[2.0, 0, 0]),
    ...                              panel.placed(offset=[-2.0, 0, 0])])
    >>> body.mass
    540.0
    >>> body.principal_moments.round(3)
    array([211.667, 276.667, 398.333])
    """

    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    #: How the mass lies (a homogeneous primitive or shape), where known: what the
    #: mutual gravity of a binary needs beyond order 2.  A placed or composite part
    #: has none.
    distribution: MassDistribution | None = field(default=None, repr=False)

    def __post_init__(self):
        mass = _positive(self.mass, "kg", "mass")
        com = _vector(self.center_of_mass, "m", "center_of_mass")
        inertia = _tensor(self.inertia)
        eig = np.linalg.eigvalsh(inertia)
        if eig[0] < -1e-12 * max(eig[-1], 0.0) or eig[-1] < 0:
            raise InvalidInertiaError(
                f"inertia has a negative principal moment ({eig[0]!r} kg m^2); "
                "the inertia of any mass distribution is positive semi-definite")
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "center_of_mass", _copy(com))
        object.__setattr__(self, "inertia", _copy(inertia))

    # --- composition -------------------------------------------------------------
    def placed(self, offset=(0.0, 0.0, 0.0), orientation: Rotation | None = None
               ) -> MassProperties:
        """The same part expressed in a parent frame.

        Parameters
        ----------
        offset : (3,) array-like or Quantity
            Position of the part's frame origin in the parent frame, m.
        orientation : scipy Rotation, optional
            Maps part-frame vectors into the parent frame.  Identity if omitted.
        """
        offset = _vector(offset, "m", "offset")
        rot = np.eye(3) if orientation is None else _single_rotation(orientation).as_matrix()
        unmoved = not offset.any() and np.array_equal(rot, np.eye(3))
        return MassProperties(self.mass, offset + rot @ self.center_of_mass,
                              rot @ self.inertia @ rot.T,
                              self.distribution if unmoved else None)

    def inertia_about(self, point=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Inertia tensor about ``point`` (parallel-axis theorem), kg m^2."""
        r = self.center_of_mass - _vector(point, "m", "point")
        return self.inertia + _parallel_axis(self.mass, r)

    def __add__(self, other: MassProperties) -> MassProperties:
        if not isinstance(other, MassProperties):
            return NotImplemented
        return MassProperties.from_parts([self, other])

    @classmethod
    def from_parts(cls, parts: Iterable[MassProperties]) -> MassProperties:
        """Sum parts already expressed in a common frame (parallel-axis theorem)."""
        parts = list(parts)
        if not parts:
            raise InvalidInertiaError("parts: at least one part is needed")
        for i, p in enumerate(parts):
            if not isinstance(p, MassProperties):
                raise InvalidInertiaError(
                    f"parts[{i}]: expected MassProperties, got {type(p).__name__}")
        mass = sum(p.mass for p in parts)
        com = sum(p.mass * p.center_of_mass for p in parts) / mass
        inertia = sum(p.inertia + _parallel_axis(p.mass, p.center_of_mass - com)
                      for p in parts)
        return cls(mass, com, inertia)

    # --- primitives (centre of mass at the origin, symmetry axes along x, y, z) ---
    @classmethod
    def solid_box(cls, mass, size) -> MassProperties:
        """Homogeneous box with edge lengths ``size = (a, b, c)`` along x, y, z."""
        m = _positive(mass, "kg", "mass")
        a, b, c = _lengths(size, 3, "size")
        return cls(m, np.zeros(3), np.diag(m / 12 * np.array([b**2 + c**2, a**2 + c**2,
                                                                   a**2 + b**2])))

    @classmethod
    def solid_cylinder(cls, mass, radius, length) -> MassProperties:
        """Homogeneous solid cylinder, axis along z."""
        return cls.hollow_cylinder(mass, outer_radius=radius, length=length, inner_radius=0.0)

    @classmethod
    def hollow_cylinder(cls, mass, outer_radius, length, inner_radius=0.0) -> MassProperties:
        """Homogeneous thick-walled tube, axis along z (``inner_radius = 0``: solid)."""
        m = _positive(mass, "kg", "mass")
        r2 = _positive(outer_radius, "m", "outer_radius")
        r1 = _positive(inner_radius, "m", "inner_radius", allow_zero=True)
        h = _positive(length, "m", "length", allow_zero=True)
        if r1 > r2:
            raise InvalidInertiaError(
                f"inner_radius = {r1} m exceeds outer_radius = {r2} m; swap them")
        rr = r1**2 + r2**2
        t = m * (3 * rr + h**2) / 12
        return cls(m, np.zeros(3), np.diag([t, t, m * rr / 2]))

    @classmethod
    def solid_sphere(cls, mass, radius) -> MassProperties:
        """Homogeneous solid ball: ``2/5 m r^2``."""
        m = _positive(mass, "kg", "mass")
        r = _positive(radius, "m", "radius")
        return cls(m, np.zeros(3), np.eye(3) * 0.4 * m * r**2,
                   MassDistribution("sphere", m, semi_axes=[r, r, r]))

    @classmethod
    def spherical_shell(cls, mass, radius, inner_radius=None) -> MassProperties:
        """Spherical shell: thin (``2/3 m r^2``) when ``inner_radius`` is None, else the
        thick shell ``2/5 m (r2^5 - r1^5)/(r2^3 - r1^3)``."""
        m = _positive(mass, "kg", "mass")
        r2 = _positive(radius, "m", "radius")
        if inner_radius is None:
            return cls(m, np.zeros(3), np.eye(3) * 2 / 3 * m * r2**2)
        r1 = _positive(inner_radius, "m", "inner_radius", allow_zero=True)
        if r1 >= r2:
            raise InvalidInertiaError(
                f"inner_radius = {r1} m must be smaller than radius = {r2} m")
        x = r1 / r2  # (r2^5 - r1^5)/(r2^3 - r1^3) without cancellation for thin shells
        ratio = r2**2 * (1 + x + x**2 + x**3 + x**4) / (1 + x + x**2)
        return cls(m, np.zeros(3), np.eye(3) * 0.4 * m * ratio)

    @classmethod
    def solid_ellipsoid(cls, mass, semi_axes) -> MassProperties:
        """Homogeneous ellipsoid with semi-axes ``(a, b, c)`` along x, y, z."""
        m = _positive(mass, "kg", "mass")
        a, b, c = _lengths(semi_axes, 3, "semi_axes")
        return cls(m, np.zeros(3), np.diag(m / 5 * np.array([b**2 + c**2, a**2 + c**2,
                                                                  a**2 + b**2])),
                   MassDistribution("ellipsoid", m, semi_axes=[a, b, c]))

    @classmethod
    def thin_rod(cls, mass, length) -> MassProperties:
        """Thin rod along z: ``m L^2 / 12`` about x and y, zero about z."""
        m = _positive(mass, "kg", "mass")
        h = _positive(length, "m", "length")
        t = m * h**2 / 12
        return cls(m, np.zeros(3), np.diag([t, t, 0.0]))

    @classmethod
    def thin_plate(cls, mass, size) -> MassProperties:
        """Thin rectangular plate ``size = (a, b)`` in the x-y plane (normal along z)."""
        m = _positive(mass, "kg", "mass")
        a, b = _lengths(size, 2, "size")
        return cls(m, np.zeros(3), np.diag(m / 12 * np.array([b**2, a**2, a**2 + b**2])))

    @classmethod
    def point_masses(cls, masses, positions) -> MassProperties:
        """A set of point masses (kg) at ``positions`` (n, 3) m."""
        ms = np.atleast_1d(np.asarray(to_si(masses, "kg", name="masses",
                                            error=InvalidInertiaError), dtype=float))
        pos = np.asarray(to_si(positions, "m", name="positions", error=InvalidInertiaError),
                         dtype=float).reshape(-1, 3)
        if ms.shape != (len(pos),):
            raise InvalidInertiaError(
                f"masses: expected {len(pos)} masses for {len(pos)} positions, got {ms.size}")
        if not (np.all(np.isfinite(ms)) and np.all(ms > 0) and np.all(np.isfinite(pos))):
            raise InvalidInertiaError("masses must be positive and positions finite")
        return cls.from_parts(cls(m, p, np.zeros((3, 3))) for m, p in zip(ms, pos))

    PRIMITIVES = ("solid_box", "solid_cylinder", "hollow_cylinder", "solid_sphere",
                  "spherical_shell", "solid_ellipsoid", "thin_rod", "thin_plate",
                  "point_masses")

    @classmethod
    def from_primitive(cls, primitive: str, **parameters) -> MassProperties:
        """Build a primitive by name (``"solid_box"``, ``"box"`` ...), as scenario files do."""
        name = {"box": "solid_box", "cylinder": "solid_cylinder", "sphere": "solid_sphere",
                "ellipsoid": "solid_ellipsoid", "rod": "thin_rod", "plate": "thin_plate",
                "shell": "spherical_shell", "tube": "hollow_cylinder"}.get(primitive, primitive)
        if name not in cls.PRIMITIVES:
            raise InvalidInertiaError(
                f"primitive {primitive!r} is unknown; choose one of {', '.join(cls.PRIMITIVES)}")
        try:
            return getattr(cls, name)(**parameters)
        except TypeError as exc:
            raise InvalidInertiaError(f"primitive {primitive!r}: {exc}") from None


def _lengths(values, n: int, name: str) -> tuple[float, ...]:
    v = np.atleast_1d(np.asarray(to_si(values, "m", name=name, error=InvalidInertiaError),
                                 dtype=float))
    if v.shape != (n,):
        raise InvalidInertiaError(f"{name}: expected {n} lengths, got shape {v.shape}")
    if not (np.all(np.isfinite(v)) and np.all(v > 0)):
        raise InvalidInertiaError(f"{name} = {v.tolist()} m: lengths must be positive")
    return tuple(float(x) for x in v)


def _single_rotation(rotation) -> Rotation:
    if not isinstance(rotation, Rotation) or not rotation.single:
        raise InvalidInertiaError(
            f"orientation: expected a single scipy Rotation, got {type(rotation).__name__}")
    return rotation


@dataclass(frozen=True, eq=False)
class RigidBody:
    """A rigid body's inertia about its centre of mass, validated and diagonalised.

    Parameters
    ----------
    inertia : (3, 3) array-like or Quantity
        Inertia tensor about the centre of mass, in the body frame, kg m^2.
    mass : float or Quantity, optional
        kg.  Not needed for torque-free motion; needed by some torque models.
    center_of_mass : (3,) array-like, optional
        Position of the centre of mass in the body frame, m (default origin).
    name : str, optional
        A label carried into outputs.

    Raises
    ------
    InvalidInertiaError
        If the tensor is not 3x3, not finite, not symmetric, not positive-definite, or
        violates the triangle inequality ``A + B >= C`` (beyond ``TRIANGLE_RTOL``).

    Notes
    -----
    Principal moments are sorted ``A <= B <= C``: ``A`` about the long axis, ``C``
    about the short axis.  :attr:`body_to_principal` maps body-frame vectors into
    the right-handed principal frame whose x, y, z axes carry ``A, B, C``.

    Examples
    --------
    >>> import numpy as np
    >>> from attitude import RigidBody
    >>> body = RigidBody.from_principal_moments([3.0, 1.0, 2.0])
    >>> body.principal_moments
    array([1., 2., 3.])
    >>> body.body_to_principal.apply([1.0, 0.0, 0.0]).round(12)   # body x carries C
    array([0., 0., 1.])
    >>> RigidBody(np.diag([1.0, 1.0, 3.0]))
    Traceback (most recent call last):
    ...
    attitude.foundations.errors.InvalidInertiaError: principal moments A = 1, B = 1, C = 3 ...
    """

    inertia: np.ndarray
    mass: float | None = None
    center_of_mass: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = ""
    #: How the mass lies (:class:`MassDistribution`), where the body was made from a
    #: primitive or a shape model; ``None`` for a body known by its moments.
    distribution: MassDistribution | None = field(default=None, repr=False)
    principal_moments: np.ndarray = field(init=False, repr=False)
    principal_axes: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        inertia = _tensor(self.inertia)
        moments, axes, invalid = check_inertia(inertia)
        if invalid:
            raise InvalidInertiaError(invalid[0])
        moments, axes = moments[0], axes[0]
        object.__setattr__(self, "inertia", _copy(inertia))
        object.__setattr__(self, "principal_moments", _copy(moments))
        object.__setattr__(self, "principal_axes", _copy(axes))
        if self.mass is not None:
            object.__setattr__(self, "mass", _positive(self.mass, "kg", "mass"))
        object.__setattr__(self, "center_of_mass",
                           _copy(_vector(self.center_of_mass, "m", "center_of_mass")))

    # --- constructors ---------------------------------------------------------
    @classmethod
    def from_principal_moments(cls, moments: Sequence[float], *, mass=None, name: str = ""
                               ) -> RigidBody:
        """A body whose frame is a principal frame: ``inertia = diag(moments)``.

        ``moments`` may come in any order (and as a Quantity); the body frame keeps that
        order, and :attr:`principal_moments` is sorted.
        """
        m = np.atleast_1d(np.asarray(to_si(moments, "kg m2", name="principal_moments",
                                           error=InvalidInertiaError), dtype=float))
        if m.shape != (3,):
            raise InvalidInertiaError(
                f"principal_moments: expected 3 values, got shape {m.shape}")
        if not np.all(np.isfinite(m)):
            raise InvalidInertiaError(
                f"principal_moments = {m.tolist()}: every moment must be finite")
        return cls(np.diag(m), mass=mass, name=name)

    @classmethod
    def from_mass_properties(cls, props: MassProperties, *, name: str = "") -> RigidBody:
        """The body of a (composite) part, about its centre of mass."""
        return cls(props.inertia, mass=props.mass, center_of_mass=props.center_of_mass,
                   name=name, distribution=props.distribution)

    @classmethod
    def from_parts(cls, parts: Iterable[MassProperties], *, name: str = "") -> RigidBody:
        """Sum parts placed in a common body frame (see :meth:`MassProperties.placed`)."""
        return cls.from_mass_properties(MassProperties.from_parts(parts), name=name)

    @classmethod
    def from_obj(cls, path: str | PathLike, *, density, length_unit="m", name: str = ""
                 ) -> RigidBody:
        """A homogeneous body from a Wavefront OBJ shape model.

        Parameters
        ----------
        path : path-like
            The ``.obj`` file (a closed, consistently oriented triangle/polygon mesh).
        density : float (kg/m^3) or Quantity / str (``"2.6 g/cm3"``)
        length_unit : str or astropy unit
            Unit of the vertex coordinates (asteroid models are usually in ``"km"``).
        """
        shape = Polyhedron.from_obj(path, length_unit=length_unit)
        mass, com, inertia = shape.mass_properties(density)
        return cls(inertia, mass=mass, center_of_mass=com, name=name,
                   distribution=MassDistribution("polyhedron", mass, shape=shape))

    # --- derived --------------------------------------------------------------
    @property
    def body_to_principal(self) -> Rotation:
        """Rotation mapping body-frame vectors into the principal frame."""
        return Rotation.from_matrix(self.principal_axes.T)

    @property
    def symmetry(self) -> str:
        """``"spherical"``, ``"oblate"`` (A = B < C), ``"prolate"`` (A < B = C) or
        ``"triaxial"``, with moments equal within ``SYMMETRY_RTOL * C``."""
        return symmetry_of(self.principal_moments)

    def with_name(self, name: str) -> RigidBody:
        return dataclasses.replace(self, name=name)

    def __repr__(self) -> str:
        A, B, C = self.principal_moments
        mass = "" if self.mass is None else f", mass={self.mass:.6g} kg"
        label = f"{self.name!r}, " if self.name else ""
        return f"RigidBody({label}A={A:.6g}, B={B:.6g}, C={C:.6g} kg m^2{mass})"


def symmetry_of(moments, rtol: float = SYMMETRY_RTOL) -> str:
    """Classify sorted principal moments as spherical / oblate / prolate / triaxial."""
    A, B, C = moments
    tol = rtol * C
    if C - A <= tol:
        return "spherical"
    if B - A <= tol:
        return "oblate"
    if C - B <= tol:
        return "prolate"
    return "triaxial"


# ===========================================================================
# batches of bodies and the body <-> principal frames
# ===========================================================================
def principal_quaternions(axes) -> np.ndarray:
    """Body -> principal quaternions (N, 4), scalar-last, from principal axes (N, 3, 3)
    (columns, as :attr:`RigidBody.principal_axes`), with one scipy call for the stack.

    Examples
    --------
    >>> body = RigidBody.from_principal_moments([3.0, 1.0, 2.0])
    >>> q = principal_quaternions([body.principal_axes])
    >>> bool(np.allclose(q[0], body.body_to_principal.as_quat()))
    True
    """
    axes = np.array(axes, dtype=float, ndmin=3)
    return Rotation.from_matrix(axes.transpose(0, 2, 1)).as_quat()


def to_principal_frame(quaternion, omega, body_to_principal):
    """Attitudes and rates of bodies -> the same motion seen in their principal frames.

    Parameters
    ----------
    quaternion : (..., 4) array_like
        Body -> inertial, scalar-last.
    omega : (..., 3) array_like
        Body-frame angular velocity, rad/s.
    body_to_principal : (..., 4) array_like
        Body -> principal quaternions (:func:`principal_quaternions`), broadcasting.

    Returns
    -------
    quaternion : (..., 4) ndarray
        Principal -> inertial.
    omega : (..., 3) ndarray
        Principal-frame rates.

    Examples
    --------
    >>> body = RigidBody.from_principal_moments([3.0, 1.0, 2.0])
    >>> q_bp = body.body_to_principal.as_quat()
    >>> q_p, w_p = to_principal_frame([0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0], q_bp)
    >>> w_p.round(12) + 0.0                   # body x carries C: the third principal axis
    array([0., 0., 1.])
    >>> q_b, w_b = to_body_frame(q_p, w_p, q_bp)
    >>> w_b.round(12) + 0.0
    array([1., 0., 0.])
    """
    q_bp = np.asarray(body_to_principal, dtype=float)
    return (quat.multiply(quaternion, quat.conjugate(q_bp)),
            quat.rotate(q_bp, omega))


def to_body_frame(quaternion, omega, body_to_principal):
    """The inverse of :func:`to_principal_frame`: principal -> inertial quaternions and
    principal-frame rates back to body -> inertial and body-frame rates.

    Examples
    --------
    >>> to_body_frame([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0])[1]
    array([0., 0., 1.])
    """
    return (quat.multiply(quaternion, body_to_principal),
            quat.rotate(body_to_principal, omega, inverse=True))


class BodyBatch(tuple):
    """The bodies of a batch: a tuple of :class:`RigidBody` (``batch[i]``, ``len``) that
    also carries their stacked arrays, computed once: ``inertia`` (N, 3, 3),
    ``principal_moments`` (N, 3), ``body_to_principal`` (N, 4) body -> principal
    quaternions (one scipy call for the whole stack), ``mass`` (N,) (``None`` if a
    body has no mass) and ``names``.  Torque models receive it, so vectorised models
    read the arrays.

    Examples
    --------
    >>> batch = BodyBatch([RigidBody.from_principal_moments([1.0, 2.0, 3.0])] * 2)
    >>> len(batch), batch.principal_moments.shape, batch.body_to_principal.shape
    (2, (2, 3), (2, 4))
    """

    def __new__(cls, bodies):
        self = super().__new__(cls, bodies)
        # np.array on a list of equal-shape arrays: ~3x faster than np.stack here
        self.inertia = np.array([b.inertia for b in self], dtype=float)
        self.principal_moments = np.array([b.principal_moments for b in self], dtype=float)
        self.body_to_principal = principal_quaternions(
            np.array([b.principal_axes for b in self], dtype=float))
        masses = [b.mass for b in self]
        self.mass = None if any(m is None for m in masses) else np.asarray(masses, float)
        self.names = tuple(b.name for b in self)
        return self


def as_bodies(bodies, *, moments: bool = True, error=InvalidStateError
              ) -> tuple[BodyBatch, bool]:
    """The one batch normaliser of bodies: a body, a sequence of bodies or (with
    ``moments=True``) principal moments (3,) / (N, 3) -> a :class:`BodyBatch` and
    whether a single body was given.

    Raises ``error`` naming the index of an entry that is not a body.

    Examples
    --------
    >>> batch, single = as_bodies([[1.0, 2.0, 3.0], [1.0, 1.5, 2.0]])
    >>> len(batch), single
    (2, False)
    >>> as_bodies(RigidBody.from_principal_moments([1.0, 2.0, 3.0]))[1]
    True
    """
    if isinstance(bodies, RigidBody):
        return BodyBatch([bodies]), True
    if moments and (isinstance(bodies, np.ndarray) or (
            isinstance(bodies, Sequence) and len(bodies) > 0
            and not isinstance(bodies[0], RigidBody))):
        m = np.asarray(bodies, dtype=float)
        if m.shape == (3,):
            return BodyBatch([RigidBody.from_principal_moments(m)]), True
        if m.ndim == 2 and m.shape[1] == 3 and m.shape[0] > 0:
            return BodyBatch([RigidBody.from_principal_moments(row) for row in m]), False
        raise error(f"bodies: expected a RigidBody, a sequence of them or principal "
                    f"moments (3,) / (N, 3), got shape {m.shape}")
    if isinstance(bodies, BodyBatch):
        return bodies, False
    bodies = list(bodies)
    if not bodies:
        raise error("bodies: empty sequence")
    for i, b in enumerate(bodies):
        if not isinstance(b, RigidBody):
            raise error(f"bodies[{i}]: expected a RigidBody, got {type(b).__name__}")
    return BodyBatch(bodies), False
