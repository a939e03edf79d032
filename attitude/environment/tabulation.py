"""Quantities along time that do not depend on the attitude: tabulate once, interpolate.

An orbit, the field along it and the Sun's direction are the same whatever the body
does, but the models that give them (SGP4 with an astropy frame rotation, IGRF's
spherical harmonics, an ephemeris of the Sun) cost milliseconds per call, and a
propagation asks for them at every step.  :class:`TimeTable` evaluates the model on a
uniform grid, one segment of the time line at a time (segments are computed when a
time inside them is first asked for, then kept), and interpolates between the nodes:
a cubic Hermite polynomial when the model also gives the derivative (an orbit's
velocity), else a cubic spline.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.interpolate import CubicHermiteSpline, CubicSpline

from attitude.foundations.cubic import cubic_rate, cubic_value

from ..foundations.errors import QuantityError

__all__ = ["TimeTable"]


class TimeTable:
    """A vector function of time, tabulated per segment and interpolated.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(t) -> values`` for a 1-D array of times (s since the epoch of the
        caller), values of shape ``(n, k)``; or ``(values, derivatives)`` when
        ``derivative=True``.
    spacing : float
        Node spacing, s.  The interpolation error of a cubic is about
        ``(spacing * rate)^4 / 384`` of the amplitude for a signal of angular rate
        ``rate``; choose the spacing from the fastest rate of the model.
    segment : float
        Length of one segment of nodes, s (a whole multiple of ``spacing``).
    derivative : bool
        Whether ``evaluate`` also returns the time derivative (Hermite interpolation).

    Examples
    --------
    >>> import numpy as np
    >>> table = TimeTable(lambda t: np.stack([np.sin(t / 100), np.cos(t / 100)], axis=-1),
    ...                   spacing=10.0, segment=1000.0)
    >>> err = table(np.array([123.4, -50.0])) - [[np.sin(1.234), np.cos(1.234)],
    ...                                         [np.sin(-0.5), np.cos(-0.5)]]
    >>> bool(np.abs(err).max() < 1e-6)
    True
    """

    def __init__(self, evaluate: Callable, *, spacing: float, segment: float,
                 derivative: bool = False):
        if not (np.isfinite(spacing) and spacing > 0):
            raise QuantityError(f"the node spacing must be a positive finite number of "
                                f"seconds, got {spacing!r}", key="spacing")
        n = round(segment / spacing) if np.isfinite(segment) else 0
        if not (n >= 4 and abs(n * spacing - segment) <= 1e-9 * segment):
            raise QuantityError(f"the segment ({segment} s) must hold a whole number >= 4 "
                                f"of node spacings ({spacing} s); choose a segment of 4 "
                                "or more spacings", key="segment")
        self._evaluate = evaluate
        self.spacing = float(spacing)
        self.segment = float(segment)
        self.derivative = derivative
        self._nodes = n
        self._splines: dict[int, Callable] = {}
        self._last: dict[int, tuple] = {}        # derivative order -> (t, value)

    def _spline(self, k: int) -> Callable:
        spline = self._splines.get(k)
        if spline is None:
            t = k * self.segment + self.spacing * np.arange(self._nodes + 1)
            if self.derivative:
                values, rates = self._evaluate(t)
                spline = CubicHermiteSpline(t, values, rates, axis=0)
            else:
                spline = CubicSpline(t, self._evaluate(t), axis=0)
            self._splines[k] = spline
        return spline

    def piecewise(self, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
        """The interpolant over ``[t0, t1]`` as one piecewise cubic: the breakpoints
        ``(N,)`` of the segments that cover the span and the coefficients ``(4, N - 1,
        k)`` (highest power first, in powers of ``t - breakpoint``), the segments'
        own (a compiled kernel evaluates them with the Horner rule of :meth:`__call__`).

        Examples
        --------
        >>> import numpy as np
        >>> table = TimeTable(lambda t: np.stack([t, t * t], axis=-1), spacing=10.0,
        ...                   segment=40.0)
        >>> x, c = table.piecewise(5.0, 50.0)      # segments [0, 40] and [40, 80]
        >>> x.tolist(), c.shape
        ([0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0], (4, 8, 2))
        """
        if not (np.isfinite(t0) and np.isfinite(t1) and t0 <= t1):
            raise QuantityError(f"expected finite times t0 <= t1, got {t0}, {t1}",
                                key="t_span")
        first, last = int(np.floor(t0 / self.segment)), int(np.floor(t1 / self.segment))
        splines = [self._spline(k) for k in range(first, last + 1)]
        x = np.concatenate([s.x[:-1] for s in splines] + [splines[-1].x[-1:]])
        return x, np.concatenate([s.c for s in splines], axis=1)

    def compiled_parameters(self, t_span) -> tuple[str, dict] | None:
        """``("piecewise_cubic", {breakpoints, coefficients})``: the table over
        ``t_span = (t0, t1)`` as :meth:`piecewise` gives it, the form a compiled kernel
        reads for every tabulated path and field; None without a span.

        Examples
        --------
        >>> import numpy as np
        >>> table = TimeTable(lambda t: np.stack([t, t * t], axis=-1), spacing=10.0,
        ...                   segment=40.0)
        >>> kind, values = table.compiled_parameters((5.0, 50.0))
        >>> kind, values["breakpoints"].shape, values["coefficients"].shape
        ('piecewise_cubic', (9,), (4, 8, 2))
        >>> table.compiled_parameters(None) is None
        True
        """
        if t_span is None:
            return None
        x, c = self.piecewise(*t_span)
        return ("piecewise_cubic", {"breakpoints": x, "coefficients": c})

    def _horner(self, k: int, x: float, nu: int) -> np.ndarray:
        """The spline of segment ``k`` (or its derivative) at one time: the cubic of the
        node interval by Horner's rule (scipy's ``PPoly.__call__`` costs ~20 us)."""
        spline = self._spline(k)
        nodes, c = spline.x, spline.c                   # c: (4, intervals, values)
        i = min(max(int((x - nodes[0]) / self.spacing), 0), c.shape[1] - 1)
        d = x - nodes[i]
        if nu == 0:
            return cubic_value(c[0, i], c[1, i], c[2, i], c[3, i], d)
        return cubic_rate(c[0, i], c[1, i], c[2, i], d)

    def _call(self, t, nu: int) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if t.ndim == 0:                  # one epoch (an integrator's stage): no masks
            x = float(t)
            last = self._last.get(nu)
            if last is not None and last[0] == x:   # several torques ask at one stage
                return last[1].copy()
            if not np.isfinite(x):
                raise QuantityError(f"times must be finite, got {x}", key="t")
            value = self._horner(int(np.floor(x / self.segment)), x, nu)
            self._last[nu] = (x, value)
            return value.copy()
        flat = t.reshape(-1)
        if not np.all(np.isfinite(flat)):
            raise QuantityError("times must be finite, got "
                                f"{int(np.count_nonzero(~np.isfinite(flat)))} that are not",
                                key="t")
        k = np.floor(flat / self.segment).astype(int)
        out = None
        for seg in np.unique(k):
            mask = k == seg
            part = self._spline(int(seg))(flat[mask], nu)
            if out is None:
                out = np.empty((flat.size,) + part.shape[1:])
            out[mask] = part
        return out.reshape(t.shape + out.shape[1:])

    def __call__(self, t) -> np.ndarray:
        """Interpolated values at ``t`` (s), shape ``t.shape + (k,)``."""
        return self._call(t, 0)

    def rate(self, t) -> np.ndarray:
        """Interpolated time derivative at ``t`` (s), shape ``t.shape + (k,)``."""
        return self._call(t, 1)
