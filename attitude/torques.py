"""The torque models (``att.torques.GravityGradient``, ...): the public namespace of
:mod:`attitude.model.torques`, which owns them (every other name of that module is
forwarded too)."""

from .model import torques as _owner
from .model.torques import *  # noqa: F403
from .model.torques import __all__  # noqa: F401


def __getattr__(name):
    return getattr(_owner, name)
