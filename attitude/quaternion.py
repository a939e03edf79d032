"""Quaternion arithmetic on numpy arrays (scalar-last ``(x, y, z, w)``, like scipy).

Hot paths build quaternions with these broadcasting kernels and wrap them in a scipy
``Rotation`` once at the end (a ``Rotation`` per epoch costs more than the physics).
"""

from __future__ import annotations

import numpy as np

__all__ = ["multiply", "rotate", "conjugate", "canonical"]


def multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p q`` (the rotation ``q`` first, then ``p``), broadcasting."""
    pv, pw = p[..., :3], p[..., 3:]
    qv, qw = q[..., :3], q[..., 3:]
    v = pw * qv + qw * pv + np.cross(pv, qv)
    w = pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)
    return np.concatenate([v, w], axis=-1)


def conjugate(q: np.ndarray) -> np.ndarray:
    """Inverse of a unit quaternion."""
    return np.concatenate([-q[..., :3], q[..., 3:]], axis=-1)


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Apply the rotation of unit quaternion ``q`` to vectors ``v`` (broadcasting):
    ``v' = v + 2 w (u x v) + 2 u x (u x v)`` with ``q = (u, w)``."""
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def canonical(q: np.ndarray) -> np.ndarray:
    """Unit quaternions with the sign chosen so that ``w >= 0`` (scipy's canonical form)."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., 3:] < 0, -q, q)
