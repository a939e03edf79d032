"""Public names imported on first use (PEP 562): the one mechanism of the package
namespaces that load nothing until a name is read (``attitude``, ``attitude.formats``),
and of the methods of the model layer that a wing carries out (:data:`WING_METHODS`:
``Ephemeris.animate`` and ``Ephemeris.view`` draw with :mod:`attitude.pictures`, which
the model layer may not import; ``att.propagate`` of a ``BinarySystem`` runs
:mod:`attitude.binary.propagate`, which the propagation layer may not import)."""

from __future__ import annotations

import importlib

__all__ = ["owned_attribute", "wing_method", "WING_METHODS"]

#: Methods of the lower layers carried out by a wing: ``"Class.method"`` -> (module,
#: function), the module imported by name on the first call (tests/test_architecture.py
#: declares it in IMPORTS_BY_NAME).
WING_METHODS = {
    "Ephemeris.animate": ("attitude.pictures.animation", "animate"),
    "Ephemeris.view": ("attitude.pictures.viewer", "view"),
    "propagate.BinarySystem": ("attitude.binary.propagate", "propagate_binary"),
}


def owned_attribute(package: str, owners: dict[str, str], name: str, namespace: dict):
    """The name ``name`` of ``package``, read from the module ``owners[name]`` (relative
    to the package) and kept in ``namespace`` (the package's globals: later reads skip
    the package's ``__getattr__``); :class:`AttributeError` for a name it does not own.

    Examples
    --------
    >>> space = {}
    >>> f = owned_attribute("attitude", {"propagate": "propagation.propagator"},
    ...                     "propagate", space)
    >>> f.__module__, space["propagate"] is f
    ('attitude.propagation.propagator', True)
    >>> owned_attribute("attitude", {}, "nothing", space)
    Traceback (most recent call last):
    ...
    AttributeError: module 'attitude' has no attribute 'nothing'
    """
    owner = owners.get(name)
    if owner is None:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{package}.{owner}"), name)
    namespace[name] = value
    return value


def wing_method(key: str):
    """The function of :data:`WING_METHODS` named ``key``, its module imported on first
    use.

    Examples
    --------
    >>> wing_method("Ephemeris.view").__module__
    'attitude.pictures.viewer'
    """
    module, name = WING_METHODS[key]
    return getattr(importlib.import_module(module), name)
