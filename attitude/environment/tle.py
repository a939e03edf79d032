"""Orbits from two-line element sets, propagated by SGP4.

The ``sgp4`` package (Vallado's reference implementation, the one the catalogue's
element sets are fitted with) gives positions and velocities in TEME; they are turned
into the run's inertial frame with astropy (:mod:`attitude.environment.frames`) and
tabulated every ``spacing`` seconds, then interpolated with cubic Hermite polynomials
(position and velocity at each node).  With the default 20 s nodes in low Earth orbit the
interpolation error is below a millimetre, far below SGP4's own error (about a kilometre
a day from the element epoch).
"""

from __future__ import annotations

import numpy as np
from astropy.time import Time, TimeDelta

from ..foundations.errors import MissingDependencyError, OrbitError
from ..foundations.quantities import to_time
from .frames import check_frame, teme_to_inertial
from .tabulation import TimeTable

__all__ = ["TLEOrbit", "check_tle"]

_SGP4_ERRORS = {
    1: "mean eccentricity out of range",
    2: "mean motion below zero",
    3: "perturbed eccentricity out of range",
    4: "semi-latus rectum below zero",
    6: "the satellite has decayed",
}


def _checksum(line: str) -> int:
    return sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68]) % 10


def check_tle(line1: str, line2: str) -> tuple[str, str]:
    """Both lines, stripped, or an :class:`~attitude.foundations.errors.OrbitError` naming the
    defect.

    Checks the line numbers, the length (69 characters), the modulo-10 checksums and
    that both lines name the same catalogue number.

    Examples
    --------
    >>> l1 = "1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005"
    >>> l2 = "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537"
    >>> check_tle(l1, l2)[0][:7]
    '1 25544'
    """
    lines = []
    for number, line in ((1, line1), (2, line2)):
        key = f"tle[{number - 1}]"
        if not isinstance(line, str):
            raise OrbitError(f"expected line {number} of a two-line element set as a "
                             f"string, got {type(line).__name__}", key=key)
        line = line.rstrip()
        if len(line) != 69:
            raise OrbitError(f"line {number} must have 69 characters, got {len(line)}",
                             key=key)
        if line[0] != str(number):
            raise OrbitError(f"line {number} must start with '{number}', got "
                             f"{line[0]!r} (are the lines swapped?)", key=key)
        if not line[68].isdigit() or int(line[68]) != _checksum(line):
            raise OrbitError(f"checksum of line {number} is {line[68]!r}, the line sums "
                             f"to {_checksum(line)}: the element set is corrupted", key=key)
        lines.append(line)
    if lines[0][2:7] != lines[1][2:7]:
        raise OrbitError(f"the lines name different satellites ({lines[0][2:7]!r} and "
                         f"{lines[1][2:7]!r})", key="tle")
    return lines[0], lines[1]


class TLEOrbit:
    """A satellite's orbit from a two-line element set (SGP4), inertial, about the Earth.

    Parameters
    ----------
    line1, line2 : str
        The element set.
    epoch : astropy Time, optional
        Time ``t = 0`` of the run (``position(t)`` takes seconds since it, in this
        epoch's time scale); default the element set's own epoch.
    frame : str
        Inertial frame of the positions: ``"GCRF"`` (default), ``"ICRF"`` (same axes),
        ``"EME2000"`` or ``"TEME"``.
    spacing : float
        Node spacing of the tabulation, s (see the module docstring).

    Raises
    ------
    OrbitError
        On a malformed element set, an unknown frame, or when SGP4 fails at a requested
        time (decayed satellite, eccentricity out of range), naming the time.
    MissingDependencyError
        If the ``sgp4`` package is absent (the ``environment`` extra).

    Examples
    --------
    >>> l1 = "1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005"
    >>> l2 = "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537"
    >>> iss = TLEOrbit(l1, l2)
    >>> iss.epoch.utc.isot
    '2024-03-01T12:00:00.000'
    >>> r = float(np.linalg.norm(iss.position(600.0)))
    >>> 6.6e6 < r < 6.9e6
    True
    """

    def __init__(self, line1: str, line2: str, *, epoch=None, frame: str = "GCRF",
                 spacing: float = 20.0):
        try:
            from sgp4.api import Satrec  # optional dependency (the environment extra)
        except ImportError:
            raise MissingDependencyError(
                "TLE orbits need the sgp4 package: pip install "
                "\"attitude-dynamics[environment]\"") from None
        self.lines = check_tle(line1, line2)
        self.frame = check_frame(frame)
        self._satrec = Satrec.twoline2rv(*self.lines)
        if self._satrec.error:
            raise OrbitError(f"SGP4 cannot initialise this element set: "
                             f"{_SGP4_ERRORS.get(self._satrec.error, 'error')} "
                             f"(code {self._satrec.error})", key="tle")
        self.element_epoch = Time(self._satrec.jdsatepoch, self._satrec.jdsatepochF,
                                  format="jd", scale="utc")
        self.epoch = (self.element_epoch if epoch is None
                      else to_time(epoch, key="epoch", error=OrbitError))
        self._table = TimeTable(self._evaluate, spacing=spacing, segment=4320 * spacing,
                                derivative=True)

    def _evaluate(self, t: np.ndarray):
        times = (self.epoch + TimeDelta(t, format="sec")).utc
        err, r, v = self._satrec.sgp4_array(times.jd1, times.jd2)
        bad = np.flatnonzero(err)
        if bad.size:
            code = int(err[bad[0]])
            raise OrbitError(f"SGP4 fails at t = {t[bad[0]]:.0f} s "
                             f"({times[bad[0]].isot} UTC): "
                             f"{_SGP4_ERRORS.get(code, 'error')} (code {code})", key="tle")
        m = teme_to_inertial(times, self.frame)
        # km -> m; the TEME -> inertial rotation turns by ~1e-11 rad/s, so the velocity
        # rotates with the same matrix (the omitted term is below 1e-4 m/s in LEO).
        return (np.einsum("nij,nj->ni", m, r) * 1e3, np.einsum("nij,nj->ni", m, v) * 1e3)

    @property
    def mean_motion(self) -> float:
        """Kozai mean motion of the element set, rad/s."""
        return self._satrec.no_kozai / 60.0

    @property
    def period(self) -> float:
        """Orbital period from the mean motion, s."""
        return 2 * np.pi / self.mean_motion

    def compiled_parameters(self, t_span=None) -> tuple[str, dict] | None:
        """``("piecewise_cubic", {breakpoints, coefficients})``: the tabulated orbit over
        ``t_span = (t0, t1)`` (s) for a compiled kernel (:meth:`TimeTable.piecewise`), or
        None without a span.

        Examples
        --------
        >>> l1 = "1 25544U 98067A   24061.50000000  .00016717  00000-0  10270-3 0  9005"
        >>> l2 = "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537"
        >>> kind, values = TLEOrbit(l1, l2).compiled_parameters((0.0, 600.0))
        >>> kind, values["coefficients"].shape
        ('piecewise_cubic', (4, 4320, 3))
        """
        return self._table.compiled_parameters(t_span)

    def position(self, t) -> np.ndarray:
        """Position relative to the Earth's centre, inertial, m; shape ``t.shape + (3,)``."""
        return self._table(t)

    def velocity(self, t) -> np.ndarray:
        """Velocity, inertial, m/s; shape ``t.shape + (3,)``."""
        return self._table.rate(t)

    def state(self, t) -> tuple[np.ndarray, np.ndarray]:
        """``(position, velocity)`` at ``t``."""
        return self.position(t), self.velocity(t)

    def __repr__(self) -> str:
        return (f"TLEOrbit(catalogue {self.lines[0][2:7].strip()}, element epoch "
                f"{self.element_epoch.utc.isot}, frame {self.frame!r})")


