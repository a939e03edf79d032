"""numba for the kernels, optional and lazy: :func:`jit`, :func:`jit_formula`, the compile
notice, the cache of compiled code, and :func:`each_on_cores`.

- :data:`NUMBA` is True when numba is installed and ``ATTITUDE_NO_NUMBA=1`` is not set;
- :func:`jit` is ``numba.njit(cache=True, nogil=True, error_model="numpy")`` then, else the
  identity (numba is imported on the first call of a kernel, not with this module).  No
  ``fastmath``: the compiled path must round as IEEE arithmetic does, so that it agrees
  with the numpy fallback to round-off (``tests/propagation/test_compiled.py``);
- :func:`jit_formula`: a formula of the model layer (written on floats or arrays)
  compiled as it is, with the package's functions it calls (one source per formula,
  docs/architecture.md);
- when numba compiles a kernel (not when it loads it from its cache), the first time in
  the process, :data:`COMPILE_NOTICE` goes to stderr (:func:`set_compile_notice`,
  :func:`quiet_compiles`).

The kernels themselves are in :mod:`.compiled` (the free flow and its special
functions), :mod:`.compiled_torques`, :mod:`.compiled_loop` and :mod:`.compiled_dop853`.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import os
import sys
import threading
import types
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ..foundations import progress

__all__ = ["NUMBA", "jit", "jit_formula", "set_compile_notice", "quiet_compiles",
           "COMPILE_NOTICE", "each_on_cores", "KERNEL_MODULES", "KERNEL_SOURCES"]


def _numba():
    """The numba module, or None when it is absent or ``ATTITUDE_NO_NUMBA=1``."""
    if os.environ.get("ATTITUDE_NO_NUMBA", "") == "1":
        return None
    try:
        import numba  # optional (wheels for some platforms only): the kernels compile with it
    except ImportError:
        return None
    return numba


#: The modules whose jitted functions call one another, relative to this folder: the
#: kernels', the Kepler solver of :mod:`attitude.model.orbit`, the shadow test of
#: :mod:`attitude.model.shadow` and the torque formulas of :mod:`attitude.model.torques`
#: (compiled by :mod:`.compiled_torques` with :func:`jit_formula`), the free-body,
#: quaternion and Landen helpers (compiled by this module).  numba's cache checks only
#: the source file of the function it loads, so a function compiled against an older
#: callee would be loaded stale (and may crash): :func:`_drop_stale_cache` clears the
#: cached code of all of them when any of them changes.
KERNEL_MODULES = ("compiled.py", "compiled_torques.py", "compiled_loop.py",
                  "compiled_dop853.py", "events.py", "../model/orbit.py",
                  "../model/shadow.py",
                  "../model/freebody_algebra.py", "../model/freebody_constants.py",
                  "../model/torques/common.py", "../model/torques/gravity_gradient.py",
                  "../model/torques/heavy_top.py", "../model/torques/eddy_current.py",
                  "../model/torques/magnetic_dipole.py",
                  "../model/torques/dissipation.py", "../model/torques/fields.py",
                  "../model/torques/surface_forces.py", "../foundations/quaternion.py",
                  "../foundations/elliptic.py", "../foundations/cubic.py")
#: The sources compiled into the kernels (all of :data:`KERNEL_MODULES`).
KERNEL_SOURCES = KERNEL_MODULES


def _drop_stale_cache() -> None:
    """Delete numba's cached code of :data:`KERNEL_MODULES` when :data:`KERNEL_SOURCES`
    changed (a stamp of their SHA-1 beside the cache); silent where the folder is
    read-only."""
    here = Path(__file__).parent
    folder = here / "__pycache__"
    try:
        # a source that moved away counts by its name (the stamp still changes)
        digest = hashlib.sha1(b"".join((here / name).read_bytes() if (here / name).is_file()
                                       else name.encode() for name in KERNEL_SOURCES)
                              ).hexdigest()
        stamp = folder / "attitude-kernels.sha1"
        if stamp.is_file() and stamp.read_text() == digest:
            return
        folder.mkdir(exist_ok=True)
        for name in KERNEL_MODULES:
            source = here / name
            stem = source.name[:-3]
            for pattern in (f"{stem}.*.nbi", f"{stem}.*.nbc"):
                for old in (source.parent / "__pycache__").glob(pattern):
                    old.unlink()
        stamp.write_text(digest)
    except OSError:           # read-only install: numba uses its own cache folder then
        return


#: The message :func:`jit`'s kernels print on stderr, once per process, when numba compiles
#: them (not when it loads them from its cache).
COMPILE_NOTICE = "attitude: compiling the propagation kernels (first run only, ~10 s)..."
#: Whether to print :data:`COMPILE_NOTICE` (:func:`set_compile_notice`; off with the
#: environment variable ``ATTITUDE_QUIET=1``); ``_notice[1]``: printed already.
_notice = [os.environ.get("ATTITUDE_QUIET", "") in ("", "0"), False]
#: The dispatchers :func:`jit` made (a compile of any other numba function says nothing).
_KERNELS: set = set()


def set_compile_notice(enabled: bool) -> bool:
    """Say (``True``, the default) or not on stderr when numba compiles the kernels, which
    takes ~10 s the first time they run (afterwards numba loads them from its cache and
    nothing is said).  The ``--quiet`` of ``attitude`` and ``ATTITUDE_QUIET=1`` turn it off.

    Returns the previous setting.

    Examples
    --------
    >>> from attitude.propagation.jit import set_compile_notice
    >>> previous = set_compile_notice(False)
    >>> set_compile_notice(previous)
    False
    """
    previous, _notice[0] = _notice[0], bool(enabled)
    return previous


@contextlib.contextmanager
def quiet_compiles(quiet: bool = True):
    """A context in which, if ``quiet``, compiling the kernels says nothing (the
    ``--quiet`` of ``attitude``); the setting of :func:`set_compile_notice` comes back
    after it.

    Examples
    --------
    >>> from attitude.propagation.jit import quiet_compiles
    >>> with quiet_compiles():
    ...     pass
    """
    previous = set_compile_notice(_notice[0] and not quiet)
    try:
        yield
    finally:
        set_compile_notice(previous)


#: The terminal's report of the first compile (``[dispatcher, context]``), while it lasts.
_compiling: list = []


def _say_compiling(dispatcher) -> None:
    """Say once, when one of :func:`jit`'s kernels compiles: :data:`COMPILE_NOTICE` as a
    line, or on a terminal the same words with the time going
    (:func:`attitude.foundations.progress.activity`, until that kernel is compiled)."""
    if _notice[0] and not _notice[1] and dispatcher in _KERNELS:
        _notice[1] = True
        terminal = False
        try:
            terminal = sys.stderr.isatty()
        except (AttributeError, ValueError):
            pass
        if terminal:
            report = progress.activity(
                COMPILE_NOTICE.removeprefix("attitude: ").rstrip("."), show=True)
            if report.__enter__().shown:
                _compiling[:] = [dispatcher, report]
                return
            report.__exit__(None, None, None)   # within another report: the line
        print(COMPILE_NOTICE, file=sys.stderr, flush=True)


def _compiled(dispatcher) -> None:
    """The end of the compile that :func:`_say_compiling` reported on a terminal."""
    if _compiling and _compiling[0] is dispatcher:
        report = _compiling[1]
        _compiling.clear()
        report.__exit__(None, None, None)


def _listen_to_compiles(numba) -> None:
    """Call :func:`_say_compiling` when numba compiles a function: its ``numba:compile``
    event comes on a compile only, not on a load from the cache (numba's event API; a
    numba without it compiles in silence)."""
    try:
        event = numba.core.event

        class CompileNotice(event.Listener):
            def on_start(self, ev):
                _say_compiling(ev.data["dispatcher"])

            def on_end(self, ev):
                _compiled(ev.data["dispatcher"])

        event.register("numba:compile", CompileNotice())
    except (AttributeError, TypeError):   # pragma: no cover - numba's API changed
        return


#: True when the kernels below are compiled by numba (installed and not disabled by the
#: environment variable ``ATTITUDE_NO_NUMBA=1``); False: they run as plain Python.  numba
#: itself is imported on the first call of a kernel, not with this module: ``import
#: numba`` takes ~1 s, which a torque-free propagation does not need.
NUMBA = (os.environ.get("ATTITUDE_NO_NUMBA", "") != "1"
         and importlib.util.find_spec("numba") is not None)
#: The numba module once :func:`_load_numba` ran (None: not yet, or numba failed to import
#: and the kernels run as plain Python).
_NB = None
_LOADED = threading.Event()
_LOCK = threading.Lock()


class _Kernel:
    """A function :func:`jit` compiles: its numba dispatcher is made, with those of every
    other kernel, on the first call of any kernel (:func:`_load_numba`)."""

    def __init__(self, function):
        functools.update_wrapper(self, function)
        self.py_func = function
        self.dispatcher = None
        _PENDING.append(self)

    def __call__(self, *args, **kwargs):
        if not _LOADED.is_set():      # (not self.dispatcher: it is set before the rebinding)
            _load_numba()
        return self.dispatcher(*args, **kwargs)

    def __getattr__(self, name):        # the dispatcher's (signatures, stats, ...)
        if name.startswith("__") or name in ("py_func", "dispatcher"):
            raise AttributeError(name)
        if not _LOADED.is_set():
            _load_numba()
        return getattr(self.dispatcher, name)

    def __repr__(self) -> str:
        return f"<attitude kernel {self.__qualname__} (numba not loaded yet)>"


#: The kernels made before numba was imported (:class:`_Kernel`).
_PENDING: list[_Kernel] = []


def _njit(numba, function):
    """``function`` compiled by numba, lazily (on its first call), as :func:`jit` says."""
    try:
        kernel = numba.njit(cache=True, nogil=True, error_model="numpy")(function)
    except RuntimeError:          # no file to cache it beside (typed at a prompt, doctest)
        kernel = numba.njit(nogil=True, error_model="numpy")(function)
    _KERNELS.add(kernel)
    return kernel


def _rebind(namespace: dict) -> None:
    """Put the dispatcher in place of each :class:`_Kernel` in ``namespace`` (numba reads
    the functions a kernel calls from its module's globals when it compiles it)."""
    for key, value in list(namespace.items()):
        if isinstance(value, _Kernel) and value.dispatcher is not None:
            namespace[key] = value.dispatcher


def _load_numba() -> None:
    """Import numba and make the dispatchers of the kernels made so far, in the modules of
    the package and of the kernels; once, on the first call of a kernel."""
    global _NB
    with _LOCK:
        if _LOADED.is_set():
            return
        _NB = _numba()
        if _NB is not None:
            _drop_stale_cache()
            _listen_to_compiles(_NB)
        for kernel in _PENDING:
            kernel.dispatcher = (kernel.py_func if _NB is None
                                 else _njit(_NB, kernel.py_func))
        spaces = {id(k.py_func.__globals__): k.py_func.__globals__ for k in _PENDING}
        for name, module in list(sys.modules.items()):
            if name.split(".")[0] == "attitude" and isinstance(
                    getattr(module, "__dict__", None), dict):
                spaces[id(module.__dict__)] = module.__dict__
        for namespace in spaces.values():
            _rebind(namespace)
        _PENDING.clear()
        _LOADED.set()


def jit(function):
    """Compile ``function`` with numba (``njit``, cached, numpy error model, no fastmath)
    when :data:`NUMBA`, else return it unchanged.

    The compiled function keeps the Python one as ``.py_func``.  Compiled code is cached
    beside the source (numba's ``__pycache__``), or not cached when there is no source
    file.  numba is imported on the first call of any kernel (until then a kernel is a
    stand-in that makes the numba dispatchers of all of them and puts them in its
    place).  When numba compiles a kernel (not when it loads it from the cache), the
    first time in the process, :data:`COMPILE_NOTICE` goes to stderr
    (:func:`set_compile_notice`).  The package's modules then hold the dispatchers
    themselves; a kernel imported by name elsewhere before that stays the stand-in,
    which forwards each call (about 0.5 us more from Python, nothing inside compiled
    code): read it from its module after the first call for the dispatcher.

    Examples
    --------
    >>> from attitude.propagation.jit import jit
    >>> @jit
    ... def twice(x):
    ...     return 2.0 * x
    >>> twice(1.5)
    3.0
    """
    if not NUMBA:
        return function
    if not _LOADED.is_set():
        return _Kernel(function)
    if _NB is None:               # numba failed to import: plain Python
        return function
    _rebind(function.__globals__)
    return _njit(_NB, function)


#: The kernels :func:`jit_formula` made, by the function they compile (each compiled once).
_FORMULAS: dict = {}


def jit_formula(function):
    """:func:`jit` of a formula of the model layer together with the functions of the
    package it calls by name (numba compiles a call only to a compiled function): the
    one source of a formula, written on floats or arrays, compiled as it is.

    Each function of the package among ``function``'s global names (a plain function
    of an ``attitude`` module) is compiled the same way, once; ``function`` is then
    compiled as a twin that reads those names as the compiled ones (its code object is
    ``function.__code__``; without a callee it is ``function`` itself, ``.py_func``).
    Without numba, ``function`` is returned unchanged.

    Examples
    --------
    >>> from attitude.foundations.quaternion import cross_parts
    >>> from attitude.propagation.jit import jit_formula
    >>> jit_formula(cross_parts)((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    (0.0, 0.0, 1.0)
    """
    known = _FORMULAS.get(function)
    if known is not None:       # (once numba is loaded, the dispatcher, not the stand-in)
        return known.dispatcher if isinstance(known, _Kernel) and _LOADED.is_set() \
            else known
    if not NUMBA:
        _FORMULAS[function] = function
        return function
    namespace = function.__globals__
    callees = {name: jit_formula(value) for name in function.__code__.co_names
               if isinstance(value := namespace.get(name), types.FunctionType)
               and value is not function
               and str(getattr(value, "__module__", "")).startswith("attitude.")}
    twin = function
    if callees:
        twin = types.FunctionType(function.__code__, {**namespace, **callees},
                                  function.__name__, function.__defaults__,
                                  function.__closure__)
        twin.__qualname__, twin.__doc__ = function.__qualname__, function.__doc__
        twin.__module__ = function.__module__
    kernel = jit(twin)
    _FORMULAS[function] = kernel
    return kernel


def each_on_cores(run, n: int):
    """``run(i)`` for ``i`` in ``range(n)``, yielding the results in order: on a thread
    per core when :data:`NUMBA` (the compiled loops release the GIL), else one by one.

    Examples
    --------
    >>> from attitude.propagation.jit import each_on_cores
    >>> list(each_on_cores(lambda i: i * i, 4))
    [0, 1, 4, 9]
    """
    workers = min(n, os.cpu_count() or 1) if NUMBA else 1
    if workers <= 1:
        for i in range(n):
            yield run(i)
        return
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for done in [pool.submit(run, i) for i in range(n)]:
            yield done.result()
