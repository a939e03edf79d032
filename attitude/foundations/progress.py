"""Progress of long work, on stderr: one module for every layer.

A step that may last more than a second or two (a splitting propagation, the MCMC steps
of a posterior, the dask tasks of an ensemble, the orbits of a surface of section, the
first compile of the kernels) reports through :class:`Progress` (or :func:`track` over
a loop, :func:`activity` for work without a count).  What the user sees depends on
where stderr goes:

- a terminal: a ``rich`` progress bar when rich is installed (the ``cli`` extra), else
  one line rewritten in place (``\\r``); the bar is removed when the work ends;
- not a terminal (a pipe, a log file): plain lines, the first after :data:`DELAY`
  seconds, then one every :data:`INTERVAL` seconds, and one when the work ends (if any
  line was written), so that a log says what ran and how long it took;
- nothing at all when the display is off: the default of the library, and the
  ``--quiet`` of the ``attitude`` command (:func:`showing`).

Whether a report is shown is the caller's ``show=`` when it is a bool (the ``progress=``
of :func:`attitude.propagate`), else the setting of :func:`showing` (the command line
turns it on unless ``--quiet``).  Only the outermost report is drawn: work nested in
another's (a propagation inside a fit) says nothing of its own.  Nothing here touches
stdout, so a command's output is the same with and without progress.

rich is imported when a bar is drawn, never when this module loads (``attitude --help``
must answer without it).
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time

#: Nothing public: the layers and the commands use it (tests/foundations/test_progress.py
#: and tests/app/test_progress.py test it).
__all__ = []

#: Seconds of work before anything is shown (short work says nothing).
DELAY = 1.0
#: Seconds between two plain lines when stderr is not a terminal.
INTERVAL = 10.0
#: Seconds between two rewrites of the in-place line (a terminal without rich).
REFRESH = 0.5

_state = {"show": False}
_lock = threading.Lock()
_active: list = []        # the report being drawn (at most one)


def showing_now() -> bool:
    """Whether reports that do not say (``show=None``) are shown.

    Examples
    --------
    >>> showing_now()
    False
    """
    return _state["show"]


@contextlib.contextmanager
def showing(show: bool = True):
    """A context in which reports with ``show=None`` are shown (or not); the previous
    setting comes back after it.  The ``attitude`` command runs every command in
    ``showing(not args.quiet)``.

    Examples
    --------
    >>> with showing():
    ...     showing_now()
    True
    >>> showing_now()
    False
    """
    previous, _state["show"] = _state["show"], bool(show)
    try:
        yield
    finally:
        _state["show"] = previous


def _stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):       # closed or replaced by an object
        return False


def _amount(x: float) -> str:
    return f"{x:.4g}"


def duration_text(seconds: float) -> str:
    """A duration in the unit that reads best (for amounts of simulated time).

    Examples
    --------
    >>> duration_text(45.0), duration_text(5400.0), duration_text(30 * 86400.0)
    ('45 s', '90 min', '30 d')
    """
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if abs(seconds) >= 2 * size:
            return f"{seconds / size:.4g} {unit}"
    return f"{seconds:.4g} s"


class Progress:
    """A report of ``total`` units of work, advanced by :meth:`update`.

    Parameters
    ----------
    total : float
        The amount of work (steps, tasks, simulated seconds, ...); ``None`` when
        unknown (the count alone is shown).
    label : str
        What is done (``"propagation"``, ``"posterior"``), first on each line.
    unit : str
        The unit of ``total`` (``"steps"``), after the amounts.
    show : bool, optional
        Shown or not; ``None``: as :func:`showing` says.
    amount : callable, optional
        ``amount(x) -> str``: the text of an amount (default 4 significant digits).

    Examples
    --------
    >>> with Progress(3, "demo", unit="steps", show=False) as bar:
    ...     for _ in range(3):
    ...         bar.update()
    >>> bar.done
    3.0
    """

    def __init__(self, total, label: str, *, unit: str = "", show: bool | None = None,
                 amount=None):
        self.total = None if total is None else max(float(total), 0.0)
        self.label, self.unit = label, unit
        self.amount = amount or _amount
        self.done = 0.0
        self.t0 = time.monotonic()
        self._last = self.t0          # of the last line written
        self._mode = None             # None (silent), "rich", "line" or "plain"
        self._started = False
        self._rich = self._task = None
        self._written = False
        self._guard = threading.Lock()
        enabled = showing_now() if show is None else bool(show)
        with _lock:
            if enabled and not _active:
                _active.append(self)
                self._mode = "terminal" if _stderr_is_terminal() else "plain"

    @property
    def shown(self) -> bool:
        """Whether this report is drawn (off, nested in another, or closed: False)."""
        return self._mode is not None

    # -- the text of a line ------------------------------------------------------------
    def _text(self, now: float) -> str:
        count = self._count()
        if self.total:
            count = f"{100.0 * min(self.done / self.total, 1.0):.0f} % ({count})"
        return f"attitude: {self.label}: {count + ', ' if count else ''}{now - self.t0:.1f} s"

    def _start(self) -> None:
        """The display, made when the work has lasted :data:`DELAY`."""
        self._started = True
        if self._mode != "terminal":
            return
        try:
            import rich.progress as bars  # optional ('attitude-dynamics[cli]'): the bar
            from rich.console import Console  # as above
        except ImportError:
            self._mode = "line"
            return
        self._mode = "rich"
        columns = [bars.TextColumn(f"[bold]{self.label}")]
        if self.total:
            columns += [bars.BarColumn(), bars.TaskProgressColumn()]
        columns += [bars.TextColumn("{task.fields[count]}"), bars.TimeElapsedColumn()]
        if self.total:
            columns.append(bars.TimeRemainingColumn())
        self._rich = bars.Progress(*columns, console=Console(stderr=True), transient=True)
        self._task = self._rich.add_task(self.label, total=self.total or None,
                                         count=self._count())
        self._rich.start()

    def _count(self) -> str:
        """``12.5 of 30 d`` (or ``12`` without a total, nothing for an activity)."""
        unit = f" {self.unit}" if self.unit else ""
        if self.total:
            return f"{self.amount(self.done)} of {self.amount(self.total)}{unit}"
        done = self.amount(self.done)
        return f"{done}{unit}" if done else ""

    def update(self, advance: float = 1.0, *, total=None) -> None:
        """``advance`` more units done (and the total, when it has become known)."""
        with self._guard:            # the ticking thread updates too
            if total is not None:
                self.total = max(float(total), 0.0)
                if self._rich is not None:
                    self._rich.update(self._task, total=self.total or None)
            self._update(advance)

    def _update(self, advance: float) -> None:
        self.done += advance
        if self._mode is None:
            return
        now = time.monotonic()
        if not self._started:
            if now - self.t0 < DELAY:
                return
            self._start()
            self._last = -float("inf")
        if self._mode == "rich":
            self._rich.update(self._task, completed=self.done, count=self._count())
        elif self._mode == "line":
            if now - self._last >= REFRESH:
                self._last = now
                self._write("\r" + self._text(now), newline=False)
        elif now - self._last >= INTERVAL:
            self._last = now
            self._write(self._text(now))

    def _write(self, text: str, newline: bool = True) -> None:
        self._written = True
        try:
            sys.stderr.write(text + ("\n" if newline else ""))
            sys.stderr.flush()
        except (OSError, ValueError):     # stderr closed: the work goes on in silence
            self._mode = None

    def close(self) -> None:
        """The end of the work: the bar is removed, a plain log gets its last line."""
        with self._guard:
            self._close()

    def _close(self) -> None:
        if self._mode is None:
            return
        now = time.monotonic()
        if self._mode == "rich":
            self._rich.stop()
        elif self._mode == "line" and self._written:
            self._write("\r" + self._text(now))
        elif self._mode == "plain" and self._written:
            count = self._count()
            self._write(f"attitude: {self.label}: done{', ' + count if count else ''} in "
                        f"{now - self.t0:.1f} s")
        self._mode = None
        with _lock:
            if self in _active:
                _active.remove(self)

    @contextlib.contextmanager
    def ticking(self):
        """A context in which the elapsed time is shown even while no :meth:`update`
        comes (one long call into compiled code that releases the GIL)."""
        stop = threading.Event()

        def tick():
            while not stop.wait(REFRESH):
                self.update(0.0)

        thread = None
        if self._mode is not None:
            thread = threading.Thread(target=tick, name=f"progress: {self.label}",
                                      daemon=True)
            thread.start()
        try:
            yield self
        finally:
            stop.set()
            if thread is not None:
                thread.join()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def track(iterable, total=None, label: str = "work", *, unit: str = "",
          show: bool | None = None):
    """The items of ``iterable``, with a :class:`Progress` advanced by one per item.

    Examples
    --------
    >>> [x * x for x in track(range(4), 4, "squares", unit="numbers", show=False)]
    [0, 1, 4, 9]
    """
    with Progress(total, label, unit=unit, show=show) as bar:
        for item in iterable:
            yield item
            bar.update()


@contextlib.contextmanager
def activity(label: str, *, show: bool | None = None):
    """Work without a count (a compile): the time it takes, shown once it has lasted
    :data:`DELAY`.

    Examples
    --------
    >>> with activity("compiling the kernels", show=False):
    ...     pass
    """
    with Progress(None, label, show=show, amount=lambda x: "") as bar, bar.ticking():
        if DELAY <= 0.0:             # shown at once: now, not at the first tick
            bar.update(0.0)
        yield bar
