"""Module paths of earlier releases, kept as thin aliases that warn.

The package was reorganised twice: into wings (:mod:`attitude.propagation`,
:mod:`attitude.formats`), then the flat modules into the layers' folders
(:mod:`attitude.foundations`, :mod:`attitude.model`, :mod:`attitude.analysis`,
:mod:`attitude.app`).  The old paths (``attitude.splitting``, ``attitude.aem``,
``attitude.body``, ``attitude.scenario``, ...) keep working: each is a module object
registered under the old name whose attributes are those of the new module, and reading
one issues a :class:`DeprecationWarning` that names the new path.  Nothing is imported
until an attribute is read.  ``import attitude.classify as m`` still gives the function
:func:`attitude.classify` (Python reads the package's attribute first), as it always did;
``from attitude.classify import Classification`` reads the old module path.

Examples
--------
>>> import warnings, attitude.splitting as old
>>> with warnings.catch_warnings(record=True) as caught:
...     warnings.simplefilter("always")
...     f = old.free_flow
>>> f.__module__, caught[0].category.__name__
('attitude.propagation.freeflow', 'DeprecationWarning')
>>> print(caught[0].message)
attitude.splitting is deprecated; use attitude.propagation.splitting.free_flow
"""

from __future__ import annotations

import importlib
import sys
import types
import warnings

__all__ = ["MOVED_MODULES", "MOVED_NAMES", "DeprecatedModule", "install", "moved_attribute"]

#: Old module path -> new module path.
MOVED_MODULES = {
    "attitude.propagate": "attitude.propagation.propagator",
    "attitude.torquefree": "attitude.propagation.torquefree",
    "attitude.splitting": "attitude.propagation.splitting",
    "attitude.integrate": "attitude.propagation.reference",
    "attitude.events": "attitude.propagation.events",
    "attitude.propagation.elliptic": "attitude.foundations.elliptic",
    "attitude.aem": "attitude.formats.aem",
    "attitude.spice": "attitude.formats.spice",
    "attitude.streaming": "attitude.formats.streaming",
    # round three: the flat modules into the layers' folders (docs/architecture.md)
    **{f"attitude.{old}": f"attitude.{layer}.{new}" for layer, names in {
        "foundations": ("errors", "quantities", "quaternion", "elliptic", "spec"),
        "model": ("body", "shape", "raycast", "surface", "state", "orbit", "population",
                  "sampling", "tables", "freebody", "regimes", "ephemeris"),
        "analysis": ("diagnostics", ("classify", "classification"), "lyapunov",
                     "statistics"),
        "app": ("scenario", "scenario_spec", "cli", "plot"),
    }.items() for old, new in (n if isinstance(n, tuple) else (n, n) for n in names)},
    "attitude.photometry.lightcurve": "attitude.photometry.dataset",
}

#: ``(old module, name)`` -> new module, for single names that moved: the old module's
#: ``__getattr__`` calls :func:`moved_attribute`.
MOVED_NAMES = {
    ("attitude.propagation.splitting", "BodyBatch"): "attitude.model.body",
    **{("attitude.propagation.torquefree", name): "attitude.model.freebody"
       for name in ("Diagnosis", "diagnose", "diagnose_principal", "diagnose_many",
                    "branch_of")},
}


def moved_attribute(module: str, name: str):
    """The value of a name that moved out of ``module``, with a :class:`DeprecationWarning`
    naming its new home; :class:`AttributeError` for any other name (for a module's
    ``__getattr__``).

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     cls = moved_attribute("attitude.propagation.splitting", "BodyBatch")
    >>> cls.__module__, str(caught[0].message).endswith("use attitude.model.body.BodyBatch")
    ('attitude.model.body', True)
    """
    new = MOVED_NAMES.get((module, name))
    if new is None:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    warnings.warn(f"{module}.{name} is deprecated; use {new}.{name}", DeprecationWarning,
                  stacklevel=3)
    return getattr(importlib.import_module(new), name)


class DeprecatedModule(types.ModuleType):
    """A module registered under an old path that forwards every attribute to the new
    module, with a :class:`DeprecationWarning` naming the new path.

    Examples
    --------
    >>> alias = DeprecatedModule("attitude.aem", "attitude.formats.aem")
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     read_aem = alias.read_aem
    >>> import attitude.formats.aem as new
    >>> read_aem is new.read_aem
    True
    >>> print(caught[0].category.__name__, caught[0].message)
    DeprecationWarning attitude.aem is deprecated; use attitude.formats.aem.read_aem
    """

    def __init__(self, old: str, new: str):
        super().__init__(old, f"Deprecated alias of :mod:`{new}`.")
        self.__new_path = new

    def __getattr__(self, name: str):
        if name.startswith("__"):              # import machinery probing dunders
            raise AttributeError(name)
        new = self.__new_path
        # imported on first use: the new module may be an optional wing (SPICE)
        value = getattr(importlib.import_module(new), name)
        warnings.warn(f"{self.__name__} is deprecated; use {new}.{name}",
                      DeprecationWarning, stacklevel=2)
        return value

    def __dir__(self):
        return dir(importlib.import_module(self.__new_path))


def install() -> None:
    """Register the aliases of :data:`MOVED_MODULES` in ``sys.modules`` (idempotent).

    Examples
    --------
    >>> install(); "attitude.aem" in sys.modules
    True
    """
    for old, new in MOVED_MODULES.items():
        sys.modules.setdefault(old, DeprecatedModule(old, new))
