"""What the torque models share: small numpy kernels (the integrators call a model once
per stage, so the overhead is kept low), the readers of their constructor arguments and of
the paths they follow."""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Mapping, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from ...foundations.errors import TorqueConfigError
from ...foundations.quantities import to_si
from ...foundations.spec import SYNONYMS
from ..body import RigidBody
from ..orbit import KeplerOrbit

#: Nothing public: these helpers serve the torque modules of this package only.
__all__ = []


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product over the last axis, ``(...)`` (a scalar for two ``(3,)`` vectors)."""
    if a.ndim == 1 and b.ndim == 1:
        return np.dot(a, b)
    return np.sum(a * b, axis=-1)


def unit_quaternion(quaternion) -> np.ndarray:
    """A scalar-last quaternion ``(..., 4)`` (or a scipy ``Rotation``) normalised: the
    integrators pass their raw stage values, not exactly unit."""
    if isinstance(quaternion, Rotation):
        return quaternion.as_quat()
    q = np.asarray(quaternion, dtype=float)
    if q.shape[-1:] != (4,):
        raise ValueError(f"quaternion: expected shape (..., 4) scalar-last, got {q.shape}")
    if q.ndim == 1:
        return q / np.sqrt(np.dot(q, q))
    return q / np.sqrt(np.sum(q * q, axis=-1, keepdims=True))


def inertia_of(body) -> np.ndarray:
    """Inertia ``(3, 3)`` of a body, or ``(n, 3, 3)`` of a sequence of bodies."""
    if isinstance(body, RigidBody):
        return body.inertia
    if isinstance(body, np.ndarray):
        if body.shape[-2:] != (3, 3):
            raise ValueError(f"body: expected an inertia array (..., 3, 3), got {body.shape}")
        return body
    if hasattr(body, "inertia"):
        return np.asarray(body.inertia, dtype=float)
    if isinstance(body, Sequence) and len(body) > 0:
        return np.stack([inertia_of(b) for b in body])
    raise TypeError(f"body: expected a RigidBody, a sequence of them or an inertia array, "
                    f"got {type(body).__name__}")


def moments_of(body) -> np.ndarray:
    """Sorted principal moments, ``(3,)`` or ``(n, 3)``."""
    if isinstance(body, RigidBody):
        return body.principal_moments
    if isinstance(body, np.ndarray) or hasattr(body, "inertia"):
        return np.linalg.eigvalsh(inertia_of(body))
    return np.stack([moments_of(b) for b in body])


def mass_of(body) -> np.ndarray | float | None:
    """Mass of a body (kg), ``(n,)`` of a sequence of them, or None where one has none."""
    if isinstance(body, RigidBody) or hasattr(body, "mass"):
        return body.mass
    if isinstance(body, Sequence) and not isinstance(body, np.ndarray):
        masses = [mass_of(b) for b in body]
        return None if any(m is None for m in masses) else np.asarray(masses, dtype=float)
    return None


def matvec(inertia: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``I v`` over the leading axes, ``(..., 3)``."""
    if inertia.ndim == 2:
        return v @ inertia.T
    return np.einsum("...ij,...j->...i", inertia, v)


def matvec_parts(m, v) -> tuple:
    """``M v`` in component form: ``m`` the nine entries of ``M`` row-major (any indexable:
    a tuple of floats or of arrays, a slice of the compiled kernels' ``params``), ``v``
    the components ``(x, y, z)`` (floats or arrays).  The one source of the products of a
    tensor and a vector in the torque formulas (numba compiles it on floats)."""
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z,
            m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)


def dot_parts(a, b):
    """``a . b`` in component form (floats or arrays), summed in order ``x, y, z``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def parts(v: np.ndarray) -> tuple:
    """The components ``(x, y, z)`` of ``(..., 3)`` vectors: plain floats for one vector
    (a formula on floats is ~10x faster than numpy on three elements), else arrays."""
    if v.ndim == 1:
        return tuple(v.tolist())
    return (v[..., 0], v[..., 1], v[..., 2])


def entries(matrix: np.ndarray) -> tuple:
    """The nine entries of ``(..., 3, 3)`` matrices, row-major (floats for one matrix),
    as :func:`matvec_parts` takes them."""
    if matrix.ndim == 2:
        return tuple(matrix.ravel().tolist())
    return tuple(matrix[..., i, j] for i in range(3) for j in range(3))


def stacked(components) -> np.ndarray:
    """``(..., 3)`` vectors from their components (floats or arrays that broadcast)."""
    x, y, z = components
    if np.ndim(x) == 0 and np.ndim(y) == 0 and np.ndim(z) == 0:
        return np.array([x, y, z], dtype=float)
    return np.stack(np.broadcast_arrays(x, y, z), axis=-1)


def orbit_rate(path) -> float:
    """Largest angular rate of the body's position about the primary, rad/s (at
    periapsis for a Keplerian orbit, at ``t = 0`` for a path with a velocity, else 0)."""
    if isinstance(path, KeplerOrbit):
        e = path.e
        return path.mean_motion * (1.0 + e) ** 2 / (1.0 - e * e) ** 1.5
    velocity = getattr(path, "velocity", None)
    if callable(velocity):
        try:
            r = np.asarray(path.position(0.0), dtype=float)
            v = np.asarray(velocity(0.0), dtype=float)
            return float(np.linalg.norm(np.cross(r, v)) / np.dot(r, r))
        except Exception:  # noqa: BLE001 - a path without a usable velocity
            return 0.0
    return 0.0


def min_radius(path) -> float:
    """Periapsis distance of a Keplerian orbit, else ``|r(0)|``, m."""
    if isinstance(path, KeplerOrbit):
        return path.periapsis
    return float(np.linalg.norm(np.asarray(path.position(0.0), dtype=float)))


def advance(orbit: KeplerOrbit, dt: float) -> KeplerOrbit:
    """The same Keplerian orbit with its time origin moved ``dt`` seconds later."""
    M = math.fmod(orbit.mean_anomaly + orbit.mean_motion * dt, 2.0 * math.pi)
    return dataclasses.replace(orbit, mean_anomaly=M)


# --- conversions of constructor arguments ----------------------------------------------


def si_value(value, unit: str, key: str, *, shape: tuple | None = ()):
    """A number (SI), a string parsed by astropy, a Quantity, or ``{value, unit}``
    (:func:`attitude.foundations.quantities.to_si`, raising :class:`TorqueConfigError`)."""
    return to_si(value, unit, key=key, shape=shape, error=TorqueConfigError)


def si_positive(value, unit: str, key: str) -> float:
    """:func:`si_value` of a scalar that must be positive."""
    return to_si(value, unit, key=key, shape=(), positive=True, error=TorqueConfigError)


def check_keys(table: Mapping, allowed: Sequence[str], where: str) -> None:
    """Raise :class:`TorqueConfigError` at ``where.key`` for a key of ``table`` not in
    ``allowed``, with a did-you-mean suggestion."""
    for key in table:
        if key not in allowed:
            path = f"{where}.{key}" if where else str(key)
            hint = SYNONYMS.get(str(key).lower())
            if hint not in allowed:
                near = difflib.get_close_matches(str(key), list(allowed), n=1)
                hint = near[0] if near else None
            did = f"did you mean {hint!r}? " if hint else ""
            raise TorqueConfigError(f"unknown key; {did}allowed keys: "
                                    f"{', '.join(allowed)}", key=path)
