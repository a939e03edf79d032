"""The motion at the times a picture shows: frames chosen from the motion's periods, the
attitude interpolated between samples (slerp) and the rate put back on its polhode.

A movie should show a few turns of the slowest angle, each turn of the fastest in many
frames: :func:`frame_times` takes the shortest and longest periods of the ephemeris
(:func:`characteristic_periods`: the measured polhode, precession and rotation periods,
else the osculating polhode period and the spin time ``2 pi / |omega|``) and spaces the
frames evenly, whatever the sampling.  :func:`sample_motion` gives the attitude, the
rates, ``E`` and ``|L|`` at any times inside the ephemeris: at a sample time the sample
itself, between samples the rate interpolated linearly and projected onto the polhode of
the interpolated ``(E, |L|)`` (:func:`attitude.pictures.poinsot.on_polhode`) and the
slerp of the attitude turned by the least rotation that makes ``R I omega`` point along
the interpolated ``L`` (:func:`align`), so that every drawn point obeys the construction
to round-off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ..analysis.angles import (
    momentum_frame_angles,
    osculating_polhode_period,
    principal_series,
    reference_axis_for,
)
from ..analysis.periods import measure_periods
from ..foundations import quaternion as quat
from ..foundations.errors import AttitudeError, EphemerisFormatError
from ..model.shape import Polyhedron
from .poinsot import ellipsoid_surface, equivalent_ellipsoid_axes, on_polhode, surface_quads

__all__ = ["Motion", "characteristic_periods", "frame_times", "sample_motion",
           "ephemeris_inertia", "nutation_series", "align", "body_polygons"]

#: Frames per shortest period, turns of the longest period shown, and the longest movie
#: (frames) when neither a duration nor a span is given.
FRAMES_PER_PERIOD = 24
CYCLES = 3.0
MAX_FRAMES = 600


@dataclass(frozen=True)
class Motion:
    """One body's motion at given times.

    Attributes
    ----------
    time : (n,) ndarray
        Seconds since the ephemeris epoch.
    quaternion : (n, 4) ndarray
        Body -> inertial, scalar-last.
    omega : (n, 3) ndarray
        Body-frame rates, rad/s (on the polhode of ``energy``, ``momentum``).
    inertia : (3, 3) ndarray or None
        Body-frame inertia tensor (None: the ephemeris carries none).
    energy, momentum : (n,) ndarray or None
        ``E`` (J) and ``|L|`` (kg m^2/s).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
    >>> m = sample_motion(eph, [0.0, 15.0, 300.0])
    >>> m.quaternion.shape, m.angular_momentum.shape
    ((3, 4), (3, 3))
    """

    time: np.ndarray
    quaternion: np.ndarray
    omega: np.ndarray
    inertia: np.ndarray | None
    energy: np.ndarray | None
    momentum: np.ndarray | None

    @property
    def angular_momentum(self) -> np.ndarray:
        """``L = R I omega``, inertial, kg m^2/s (n, 3)."""
        if self.inertia is None:
            raise EphemerisFormatError("attribute inertia is missing: no angular momentum")
        return quat.rotate(self.quaternion, self.omega @ self.inertia.T)

    @property
    def omega_inertial(self) -> np.ndarray:
        """``R omega``: the herpolhode point, rad/s (n, 3)."""
        return quat.rotate(self.quaternion, self.omega)


def ephemeris_inertia(eph, body_index: int | None = None) -> np.ndarray | None:
    """The body-frame inertia tensor of an ephemeris (of body ``body_index`` of a batch),
    or None when it carries none (a CCSDS AEM read without a body).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 0.1])
    >>> np.diag(ephemeris_inertia(att.propagate(body, state, [0.0, 1.0]))).tolist()
    [1.0, 2.0, 3.0]
    """
    ds = eph.dataset
    if eph.is_batch:
        if "inertia" not in ds:
            return None
        value = np.asarray(ds["inertia"].values[body_index or 0], dtype=float)
    else:
        if "inertia" not in ds.attrs:
            return None
        value = np.asarray(ds.attrs["inertia"], dtype=float)
    return value.reshape(3, 3) if np.all(np.isfinite(value)) else None


def _arrays(eph, body_index):
    ds = eph.dataset
    t = np.asarray(eph.time, dtype=float)
    q = np.asarray(ds["quaternion"].values, dtype=float)
    w = np.asarray(ds["angular_velocity"].values, dtype=float)
    if eph.is_batch:
        q, w = q[body_index or 0], w[body_index or 0]
    if t.size < 2:
        raise EphemerisFormatError(f"{t.size} sample: a picture needs at least two epochs",
                                   key="time")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(w))):
        raise EphemerisFormatError("quaternion or angular_velocity holds NaN (an invalid "
                                   "body of an ensemble?): choose another body_index")
    if not np.all(np.diff(t) > 0):
        raise EphemerisFormatError("time must increase strictly", key="time")
    return t, q / np.linalg.norm(q, axis=-1, keepdims=True), w


def characteristic_periods(eph, body_index: int | None = None) -> tuple[float, float]:
    """``(shortest, longest)`` period of the motion, s: the measured polhode, precession,
    rotation (or spin) periods where the ephemeris holds a cycle of them, always with the
    spin time ``2 pi / max |omega|``; else the osculating polhode period.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> short, long = characteristic_periods(eph)
    >>> P = att.diagnose(body, state).periods
    >>> bool(short <= 2 * np.pi / 0.1 and abs(long / max(P.values()) - 1) < 1e-6)
    True
    """
    t, q, w = _arrays(eph, body_index)
    rate = float(np.max(np.linalg.norm(w, axis=-1)))
    periods = [2 * math.pi / rate] if rate > 0 else []
    inertia = ephemeris_inertia(eph, body_index)
    if inertia is not None and rate > 0:
        try:
            found = measure_periods(eph, body_index=(body_index or 0) if eph.is_batch else None)
            periods += [float(p.value) for p in found.values() if np.isfinite(p.value)]
        except AttitudeError:           # less than a cycle sampled: the osculating period
            series = principal_series(eph, (body_index or 0) if eph.is_batch else None)
            P = osculating_polhode_period(series.omega[:1], series.moments)
            periods += [float(p) for p in np.ravel(P) if np.isfinite(p) and p > 0]
    if not periods:
        span = float(t[-1] - t[0])
        return span, span
    return min(periods), max(periods)


def frame_times(eph, *, fps: float = 20.0, duration: float | None = None,
                span: tuple[float, float] | None = None, body_index: int | None = None,
                frames_per_period: int = FRAMES_PER_PERIOD, cycles: float = CYCLES,
                max_frames: int = MAX_FRAMES) -> np.ndarray:
    """Evenly spaced frame times (s since the epoch) for a movie of the ephemeris.

    Parameters
    ----------
    fps : float
        Frames per second of the movie.
    duration : float, optional
        Length of the movie, s: ``round(fps * duration)`` frames over the span.  Default:
        :data:`FRAMES_PER_PERIOD` frames per shortest period, at most ``max_frames``.
    span : (start, stop), optional
        Times shown, s since the epoch.  Default: from the first sample, ``cycles`` turns
        of the longest period (:func:`characteristic_periods`), within the ephemeris.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 3000.0, 1501))
    >>> t = frame_times(eph, fps=10, duration=4.0)
    >>> t.size, float(t[0])                 # three turns of the longest period
    (40, 0.0)
    >>> bool(abs(t[-1] - 3 * characteristic_periods(eph)[1]) < 1e-9)
    True
    """
    t = np.asarray(eph.time, dtype=float)
    if span is None:
        short, long = characteristic_periods(eph, body_index)
        start, stop = t[0], min(t[-1], t[0] + cycles * long)
    else:
        start, stop = (float(s) for s in span)
        if not (t[0] <= start < stop <= t[-1]):
            raise EphemerisFormatError(f"span ({start}, {stop}) s is not inside the "
                                       f"ephemeris ({t[0]}, {t[-1]}) s", key="span")
        short = characteristic_periods(eph, body_index)[0]
    if duration is not None:
        n = int(round(fps * float(duration)))
    else:
        n = int(math.ceil((stop - start) / short * frames_per_period)) + 1
        n = min(n, max_frames)
    if n < 2:
        raise EphemerisFormatError(f"{n} frame: give a longer duration or a higher fps",
                                   key="duration")
    return np.linspace(start, stop, n)


def sample_motion(eph, times, *, body_index: int | None = None) -> Motion:
    """The motion at ``times`` (s since the epoch, inside the ephemeris): samples where
    the times are sample times, slerp and the polhode projection between them.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from attitude.pictures.poinsot import energy_residual
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
    >>> m = sample_motion(eph, [5.0, 12.5])
    >>> bool(np.all(np.abs(energy_residual(m.omega, m.inertia, m.energy)) < 1e-14))
    True
    """
    t, q, w = _arrays(eph, body_index)
    x = np.atleast_1d(np.asarray(times, dtype=float))
    if x.min() < t[0] or x.max() > t[-1]:
        raise EphemerisFormatError(f"times {x.min()}..{x.max()} s outside the ephemeris "
                                   f"({t[0]}..{t[-1]} s)", key="time")
    k = np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 2)
    exact_left, exact_right = x == t[k], x == t[k + 1]
    slerped = Slerp(t, Rotation.from_quat(q))(x).as_quat()
    qx = np.where(exact_left[:, None], q[k], np.where(exact_right[:, None], q[k + 1],
                                                      slerped))
    s = ((x - t[k]) / (t[k + 1] - t[k]))[:, None]
    wx = (1 - s) * w[k] + s * w[k + 1]
    inertia = ephemeris_inertia(eph, body_index)
    energy = momentum = None
    if inertia is not None:
        Iw = w @ inertia.T
        E_s = 0.5 * np.sum(w * Iw, -1)
        L_s = np.linalg.norm(Iw, axis=-1)
        energy = (1 - s[:, 0]) * E_s[k] + s[:, 0] * E_s[k + 1]
        momentum = (1 - s[:, 0]) * L_s[k] + s[:, 0] * L_s[k + 1]
        between = ~(exact_left | exact_right) & (momentum > 0)
        if np.any(between):
            wx[between] = on_polhode(wx[between], inertia, energy[between],
                                     momentum[between])
            L_s = quat.rotate(q, Iw)                         # inertial L at the samples
            target = (1 - s) * L_s[k] + s * L_s[k + 1]
            qx[between] = align(qx[between], wx[between] @ inertia.T, target[between])
    wx = np.where(exact_left[:, None], w[k], np.where(exact_right[:, None], w[k + 1], wx))
    return Motion(x, quat.canonical(qx), wx, inertia, energy, momentum)


def align(quaternion, body_vector, inertial_direction) -> np.ndarray:
    """The attitudes turned by the least rotation that takes ``R body_vector`` onto
    ``inertial_direction``: a slerped attitude made to carry the interpolated angular
    momentum, so that the drawn ``L = R I omega`` is the ephemeris's (the rotation is of
    the order of the slerp error).

    Examples
    --------
    >>> q = align([0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0])
    >>> quat.rotate(q, [1.0, 0.0, 0.0]).round(15).tolist()
    [0.0, 1.0, 0.0]
    """
    q = np.asarray(quaternion, dtype=float)
    a = quat.rotate(q, np.asarray(body_vector, dtype=float))
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = np.asarray(inertial_direction, dtype=float)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    turn = np.concatenate([np.cross(a, b), 1.0 + np.sum(a * b, -1, keepdims=True)], -1)
    turn /= np.linalg.norm(turn, axis=-1, keepdims=True)
    return quat.multiply(turn, q)


def body_polygons(eph, shape=None, body_index: int | None = None) -> np.ndarray:
    """The body as polygons (k, m, 3) in the body frame, scaled to a largest extent of 1:
    the faces of ``shape`` (a Polyhedron) or of the OBJ named by the ephemeris attribute
    ``shape_model`` (with ``shape_length_unit``), else the uniform ellipsoid of the
    principal moments, else (no inertia) a flat ellipsoid that shows the axes.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 0.1])
    >>> polys = body_polygons(att.propagate(body, state, [0.0, 1.0]))
    >>> polys.shape, float(np.abs(polys[..., 0]).max().round(12))      # long axis x
    ((200, 4, 3), 1.0)
    """
    if shape is None and not eph.is_batch and "shape_model" in eph.dataset.attrs:
        path = Path(str(eph.dataset.attrs["shape_model"]))
        if path.is_file():
            shape = Polyhedron.from_obj(path, length_unit=str(
                eph.dataset.attrs.get("shape_length_unit", "m")))
    if shape is not None:
        v = np.asarray(shape.vertices, dtype=float)
        v = v - v.mean(axis=0)
        return v[np.asarray(shape.faces)] / np.linalg.norm(v, axis=-1).max()
    inertia = ephemeris_inertia(eph, body_index)
    if inertia is None:                       # no mass properties: a flat box for the axes
        return surface_quads(*ellipsoid_surface([0.9, 0.6, 0.3], n_lat=6, n_lon=8))
    moments, axes = np.linalg.eigh(inertia)
    return surface_quads(*ellipsoid_surface(equivalent_ellipsoid_axes(moments), axes,
                                     n_lat=10, n_lon=20))


def nutation_series(eph, body_index: int | None = None) -> np.ndarray | None:
    """The nutation angle (rad) at the samples (3-1-3 about ``L``,
    :func:`attitude.analysis.angles.momentum_frame_angles`), or None without inertia.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([1.0, 2.0, 3.0])
    >>> state = att.AttitudeState("2030-01-01", Rotation.identity(), [0, 0, 0.1])
    >>> nutation_series(att.propagate(body, state, [0.0, 1.0])).tolist()
    [0.0, 0.0]
    """
    if ephemeris_inertia(eph, body_index) is None:
        return None
    series = principal_series(eph, (body_index or 0) if eph.is_batch else None)
    dyn = np.sum((series.omega * series.moments) ** 2, -1) / np.maximum(
        np.sum(series.omega ** 2 * series.moments, -1), np.finfo(float).tiny)
    ref = reference_axis_for(series.moments, dyn)
    return momentum_frame_angles(series, ref)["nutation"]
