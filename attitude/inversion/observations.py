"""Lightcurves with their viewing geometry: the input of an inversion.

An inversion compares, point by point, an observed brightness with the brightness of a
model seen from where the observer was, lit from where the Sun was.  The data come as
:class:`~attitude.photometry.observations.LightcurveObservations`, the one type of a
lightcurve with its geometry (fitting reads it too): from :func:`read_damit_lightcurves`,
or from :func:`attitude.read_lightcurve` with ``geometry=`` (ALCDEF, CSV).
:class:`ObservedLightcurve` is the form the convex engine works in, one lightcurve (one
night, one session) in intensity units at the epochs at the body (light-time
corrected), with a :class:`~attitude.photometry.Geometry` of the directions from the
body toward the Sun and toward the observer, one per point; :func:`engine_blocks`
turns any observations into it.

A lightcurve is *relative* (only the shape of the curve counts: each lightcurve is
divided by its mean, model and data alike) or *calibrated* (the brightness reduced to
unit distances, comparable between nights: its level constrains the phase function).

:func:`read_damit_lightcurves` reads the lightcurve files of DAMIT's ``convexinv``
(Kaasalainen & Torppa 2001; the format of the Database of Asteroid Models from
Inversion Techniques): the number of lightcurves, then for each a line ``N flag`` (0
relative, 1 calibrated) and ``N`` lines ``JD brightness xs ys zs xe ye ze``, the epoch
light-time corrected, the brightness in intensity units and the asteroid-centric
ecliptic (J2000) vectors to the Sun and to the Earth, au.
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

import numpy as np
from astropy.time import Time, TimeDelta

from attitude.foundations.constants import AU
from attitude.foundations.errors import LightcurveFormatError, PhotometryError
from attitude.photometry.geometry import Geometry
from attitude.photometry.observations import MAGNITUDE_PER_LN, LightcurveObservations

__all__ = ["LightcurveObservations", "ObservedLightcurve", "engine_blocks",
           "read_damit_lightcurves"]

#: The frame of DAMIT's vectors: ecliptic and mean equinox of J2000.
DAMIT_FRAME = "ECLIPJ2000"


class ObservedLightcurve(LightcurveObservations):
    """One lightcurve in intensities at the body's epochs: the convex engine's block.

    A :class:`~attitude.photometry.observations.LightcurveObservations` (the one type of
    a lightcurve with its geometry, which :func:`attitude.fitting.fit` reads too) built
    from what an inversion works in: intensities and the epochs at the body.  Its
    ``sigma`` is the uncertainty of the *intensity* (the unit of
    :class:`~attitude.inversion.convex.ConvexModel`); ``magnitude_sigma`` that of the
    magnitude, as for every observations object.  :func:`engine_blocks` turns any
    observations into these blocks.

    Parameters
    ----------
    epoch : astropy.time.Time
        Reference epoch of ``time``.
    time : (n,) array
        Seconds since ``epoch`` at the body (light-time corrected), increasing.
    brightness : (n,) array
        Brightness in intensity units (``10**(-0.4 m)``), positive.
    geometry : Geometry
        Sun and observer directions from the body, one per point (or constant), in
        the inertial frame of the inversion (ecliptic J2000 for DAMIT files).
    sigma : (n,) array or float, optional
        Uncertainty of ``brightness`` (same units); default 1 (equal weights).
    calibrated : bool
        True when the brightness is reduced to unit distances and comparable between
        lightcurves; False (default) for a relative lightcurve.
    name : str
        Where the lightcurve came from (file and block), for messages.

    Raises
    ------
    PhotometryError
        On an empty, non-finite, non-positive or decreasing input, naming ``name``.

    Examples
    --------
    >>> import numpy as np
    >>> from astropy.time import Time
    >>> from attitude.photometry import Geometry
    >>> obs = ObservedLightcurve(Time("2026-01-01", scale="tdb"),
    ...                              np.arange(4) * 600.0, np.ones(4),
    ...                              Geometry(sun=[1, 0, 0], observer=[1, 0.1, 0]))
    >>> len(obs), obs.calibrated, obs.magnitudes.tolist()
    (4, False, [-0.0, -0.0, -0.0, -0.0])
    >>> isinstance(obs, LightcurveObservations)
    True
    """

    def __init__(self, epoch: Time, time, brightness, geometry: Geometry,
                 sigma=1.0, calibrated: bool = False, name: str = "lightcurve"):
        t = np.array(time, dtype=float).ravel()
        y = np.array(brightness, dtype=float).ravel()
        s = np.broadcast_to(np.array(sigma, dtype=float), y.shape).copy()
        where = name
        if t.shape != y.shape or t.size == 0:
            raise PhotometryError(f"{where}: time and brightness must be non-empty and of "
                                  f"one length, got {t.size} and {y.size}", key="brightness")
        if not (np.isfinite(t).all() and np.isfinite(y).all() and np.isfinite(s).all()):
            raise PhotometryError(f"{where}: a time, brightness or sigma is not finite",
                                  key="brightness")
        if np.any(y <= 0.0) or np.any(s <= 0.0):
            raise PhotometryError(f"{where}: brightness and sigma must be positive "
                                  "(intensity units, 10**(-0.4 mag))", key="brightness")
        if np.any(np.diff(t) < 0.0):
            raise PhotometryError(f"{where}: the times must not decrease", key="time")
        if not isinstance(geometry, Geometry):
            raise PhotometryError(f"{where}: expected an attitude.photometry.Geometry",
                                  key="geometry")
        if geometry.n_time not in (None, t.size):
            raise PhotometryError(f"{where}: the geometry has {geometry.n_time} directions "
                                  f"for {t.size} points", key="geometry")
        epoch = Time(epoch).tdb
        # the times at the observer: the body's plus the light time, when known
        delay = 0.0 if geometry.light_time is None else geometry.light_time
        super().__init__(epoch + TimeDelta(t + delay, format="sec"), -2.5 * np.log10(y),
                         MAGNITUDE_PER_LN * s / y, geometry, epoch=epoch,
                         calibrated=calibrated, name=name)
        for key, value in (("_body_time", t), ("sigma", s), ("_brightness", y)):
            value.setflags(write=False)
            object.__setattr__(self, key, value)

    @property
    def time(self) -> np.ndarray:
        """Seconds since ``epoch`` at the body, as given."""
        return self._body_time

    @property
    def brightness(self) -> np.ndarray:
        """Intensities, as given."""
        return self._brightness

    @property
    def brightness_sigma(self) -> np.ndarray:
        """Uncertainty of the intensities (``sigma``)."""
        return self.sigma


def engine_blocks(observations) -> list[ObservedLightcurve]:
    """The convex engine's blocks of any observations: one per session, in intensities
    at the body's epochs, all on the clock of the first one's epoch.

    Parameters
    ----------
    observations : LightcurveObservations or list of them
        From :func:`read_damit_lightcurves`, :func:`attitude.read_lightcurve` with
        ``geometry=``, or built by hand (with an ``epoch`` or Time ``times``).

    Returns
    -------
    list of ObservedLightcurve
        The blocks (an ObservedLightcurve passes through).

    Raises
    ------
    PhotometryError
        On an empty list or an item that is not observations.

    Examples
    --------
    >>> import numpy as np
    >>> from astropy.time import Time
    >>> from attitude.photometry import Geometry
    >>> obs = LightcurveObservations(Time(["2026-01-01T00:00", "2026-01-01T01:00",
    ...                                     "2026-01-02T00:00"], scale="tdb"),
    ...                              [0.0, 0.1, 0.2], 0.01,
    ...                              Geometry(sun=[1, 0, 0], observer=[1, 0.1, 0]),
    ...                              sessions=[1, 1, 2])
    >>> [(b.time.tolist(), b.brightness.round(4).tolist()) for b in engine_blocks(obs)]
    [([0.0, 3600.0], [1.0, 0.9120]), ([86400.0], [0.8318])]
    """
    items = [observations] if isinstance(observations, LightcurveObservations) \
        else list(observations)
    if not items:
        raise PhotometryError("no lightcurves to invert", key="observations")
    blocks = []
    for item in items:
        if not isinstance(item, LightcurveObservations):
            raise PhotometryError(f"expected lightcurve observations (read_damit_lightcurves,"
                                  f" read_lightcurve with geometry=), got {type(item).__name__}",
                                  key="observations")
        if isinstance(item, ObservedLightcurve):
            blocks.append(item)
            continue
        for part in item.split_sessions():
            blocks.append(ObservedLightcurve(part.epoch, part.time, part.brightness,
                                             part.geometry, sigma=part.brightness_sigma,
                                             calibrated=part.calibrated, name=part.name))
    return blocks


def read_damit_lightcurves(path: str | PathLike, *, time_scale: str = "utc",
                           epoch: Time | None = None) -> list[ObservedLightcurve]:
    """Read a DAMIT / ``convexinv`` lightcurve file.

    Parameters
    ----------
    path : str or path
        The file: the number of lightcurves, then per lightcurve a line ``N flag``
        (0 relative, 1 calibrated) and ``N`` lines ``JD brightness xs ys zs xe ye ze``
        (the Julian date light-time corrected, the brightness in intensity units, the
        asteroid-centric ecliptic J2000 vectors toward the Sun and the Earth, au).
    time_scale : str
        Time scale of the Julian dates (DAMIT's are UTC); the times are seconds of TDB
        since ``epoch`` (leap seconds counted).
    epoch : Time, optional
        Reference epoch of every lightcurve's ``time`` (default: the first point of the
        file), so that all lightcurves share one clock; kept in TDB.

    Returns
    -------
    list of ObservedLightcurve
        One per lightcurve, in file order, named ``"<file>: lightcurve k (line j)"``; the
        geometry in ``ECLIPJ2000`` with the distances in metres.

    Raises
    ------
    LightcurveFormatError
        On a malformed file: the message names the line and what was expected.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "lcs"
    >>> _ = path.write_text('''1
    ... 2 0
    ... 2451545.0  1.00  1 0 0  1 0.1 0
    ... 2451545.01 1.05  1 0 0  1 0.1 0
    ... ''')
    >>> [obs] = read_damit_lightcurves(path)
    >>> au = 1.495978707e11
    >>> obs.time.tolist(), obs.calibrated, round(float(obs.geometry.sun_distance[0] / au), 12)
    ([0.0, 864.0], False, 1.0)
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="ascii")
    except UnicodeDecodeError:
        raise LightcurveFormatError("is not a text file of numbers (non-ASCII bytes)",
                                    path=path) from None
    except OSError as err:
        raise LightcurveFormatError(f"cannot be read: {err.strerror or err}",
                                    path=path) from None
    lines = [(k + 1, line.split()) for k, line in enumerate(text.splitlines())
             if line.strip()]
    blocks = _blocks(lines, path)
    if not blocks:
        raise LightcurveFormatError("holds no lightcurve", path=path)
    if epoch is None:
        epoch = Time(blocks[0][2][0, 0], format="jd", scale=time_scale)
    ref = Time(epoch).tdb
    observations = []
    for k, (line_no, calibrated, rows) in enumerate(blocks):
        # seconds of TDB since the epoch (leap seconds counted), the JD split in two
        when = Time(rows[:, 0], format="jd", scale=time_scale).tdb
        time = ((when.jd1 - ref.jd1) + (when.jd2 - ref.jd2)) * 86400.0
        sun, earth = rows[:, 2:5] * AU, rows[:, 5:8] * AU
        name = f"{path.name}: lightcurve {k + 1} (line {line_no})"
        try:
            geometry = Geometry(sun=sun, observer=earth, frame=DAMIT_FRAME)
            observations.append(ObservedLightcurve(ref, time, rows[:, 1], geometry,
                                                       calibrated=calibrated, name=name))
        except PhotometryError as err:
            raise LightcurveFormatError(err.reason, path=path, key=f"line {line_no}") from None
    return observations


def _blocks(lines, path):
    """The lightcurve blocks of a DAMIT file: ``(line, calibrated, (N, 8) rows)``."""
    def fail(message, line):
        raise LightcurveFormatError(message, path=path, key=f"line {line}")

    if not lines:
        fail("is empty: expected the number of lightcurves on the first line", 1)
    head_no, head = lines[0]
    count = _integer(head, 1, head_no, "the number of lightcurves", fail)
    pos, blocks = 1, []
    for k in range(count):
        if pos >= len(lines):
            fail(f"ends after {k} of the {count} lightcurves it announces",
                 lines[-1][0])
        line_no, fields = lines[pos]
        n = _integer(fields[:1], 1, line_no, f"the number of points of lightcurve {k + 1}",
                     fail)
        if len(fields) != 2 or fields[1] not in ("0", "1"):
            fail(f"lightcurve {k + 1}: expected 'N flag' with flag 0 (relative) or 1 "
                 f"(calibrated), got {' '.join(fields)!r}", line_no)
        rows = lines[pos + 1:pos + 1 + n]
        if len(rows) < n:
            fail(f"lightcurve {k + 1} announces {n} points, the file ends after "
                 f"{len(rows)}", lines[-1][0])
        values = np.empty((n, 8))
        for j, (row_no, row) in enumerate(rows):
            if len(row) != 8:
                fail(f"expected 8 numbers (JD, brightness, Sun xyz, Earth xyz), got "
                     f"{len(row)}", row_no)
            try:
                values[j] = [float(x) for x in row]
            except ValueError:
                fail(f"expected 8 numbers, got {' '.join(row)!r}", row_no)
            if not np.isfinite(values[j]).all():
                fail("a value is not finite", row_no)
            if values[j, 1] <= 0.0:
                fail(f"the brightness must be positive (intensity units, 10**(-0.4 mag)), "
                     f"got {row[1]}", row_no)
            if not (values[j, 2:5].any() and values[j, 5:8].any()):
                fail("a zero Sun or Earth vector: give the asteroid-centric ecliptic "
                     "vectors toward them, au", row_no)
        blocks.append((line_no, fields[1] == "1", values))
        pos += 1 + n
    if pos < len(lines):
        fail(f"has {len(lines) - pos} lines after the {count} lightcurves it announces",
             lines[pos][0])
    return blocks


def _integer(fields, at_least, line, what, fail):
    """A positive integer from the first field of a line."""
    try:
        value = int(fields[0])
    except (IndexError, ValueError):
        fail(f"expected {what} (an integer), got {' '.join(fields)!r}", line)
    if value < at_least:
        fail(f"{what} must be at least {at_least}, got {value}", line)
    return value
