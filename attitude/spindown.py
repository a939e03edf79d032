"""The spin period of a run and its trend (``attitude.spindown.spin_trend``): the public
namespace of :mod:`attitude.analysis.spindown`, which owns it."""

from .analysis import spindown as _owner
from .analysis.spindown import *  # noqa: F403
from .analysis.spindown import __all__  # noqa: F401


def __getattr__(name):
    return getattr(_owner, name)
