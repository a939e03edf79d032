"""The version of the ``attitude`` package (``att.__version__``)."""

__all__ = ["__version__"]

__version__ = "0.1.0"
