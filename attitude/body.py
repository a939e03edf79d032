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

from .errors import InvalidInertiaError
from .quantities import to_si
from .shape import Polyhedron

__all__ = [
    "MassProperties",
    "RigidBody",
    "SYMMETRY_RTOL",
    "TRIANGLE_RTOL",
    "SYMMETRIC_TENSOR_RTOL",
    "diagonal_inertia",
]

#: Two principal moments are treated as equal (axisymmetric body) when they differ by
#: at most ``SYMMETRY_RTOL * C``; all three equal (spherical body) likewise.  Used by
#: :attr:`RigidBody.symmetry` and by the propagators to pick the axisymmetric branch.
SYMMETRY_RTOL = 1e-12

#: Allowed violation of the triangle inequality ``A + B >= C``, relative to ``C``.
#: A thin plate sits exactly on the equality, so rounding must not reject it.
TRIANGLE_RTOL = 1e-10

#: Allowed asymmetry of an input tensor, relative to its largest element.
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
    if not np.all(np.isfinite(inertia)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(inertia))[0])
        raise InvalidInertiaError(
            f"{name}[{bad[0]}][{bad[1]}] = {float(inertia[bad])}: every element must be finite")
    scale = np.max(np.abs(inertia))
    asym = np.abs(inertia - inertia.T)
    if np.any(asym > SYMMETRIC_TENSOR_RTOL * scale):
        i, j = (int(k) for k in np.unravel_index(np.argmax(asym), asym.shape))
        raise InvalidInertiaError(
            f"{name} is not symmetric: [{i}][{j}] = {float(inertia[i, j])} but [{j}][{i}] = "
            f"{float(inertia[j, i])}; an inertia tensor equals its transpose (products of "
            "inertia appear twice with the same sign)")
    return 0.5 * (inertia + inertia.T)


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
        return MassProperties(self.mass, offset + rot @ self.center_of_mass,
                              rot @ self.inertia @ rot.T)

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
        return cls(m, np.zeros(3), np.eye(3) * 0.4 * m * r**2)

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
                                                                  a**2 + b**2])))

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


def _principal_frame(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted principal moments and the right-handed matrix whose columns are the
    principal axes in the body frame (``v_body = V @ v_principal``)."""
    if np.count_nonzero(inertia - np.diag(np.diag(inertia))) == 0:
        # Diagonal input: an exact permutation, no eigen-solver rounding.
        order = np.argsort(np.diag(inertia), kind="stable")
        moments, axes = np.diag(inertia)[order], np.eye(3)[:, order]
    else:
        moments, axes = np.linalg.eigh(inertia)
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return moments, axes


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
    attitude.errors.InvalidInertiaError: principal moments A = 1, B = 1, C = 3 kg m^2 violate ...
    """

    inertia: np.ndarray
    mass: float | None = None
    center_of_mass: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = ""
    principal_moments: np.ndarray = field(init=False, repr=False)
    principal_axes: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        inertia = _tensor(self.inertia)
        moments, axes = _principal_frame(inertia)
        A, B, C = moments
        if not A > 0:
            raise InvalidInertiaError(
                f"inertia is not positive-definite: smallest principal moment "
                f"A = {A:.6g} kg m^2; every rigid body with extent in three dimensions has "
                "A > 0 (a thin rod or collinear point masses has A = 0: give it a radius "
                "or add the mass it is attached to)")
        if A + B < C * (1 - TRIANGLE_RTOL):
            raise InvalidInertiaError(
                f"principal moments A = {A:.6g}, B = {B:.6g}, C = {C:.6g} kg m^2 violate the "
                f"triangle inequality A + B >= C (A + B = {A + B:.6g}); no mass distribution "
                "has them: check the units and that the moments are about the centre of mass")
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
                   name=name)

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
        mass, com, inertia = Polyhedron.from_obj(path, length_unit=length_unit
                                                 ).mass_properties(density)
        return cls(inertia, mass=mass, center_of_mass=com, name=name)

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
