"""The canvas every figure of the package is drawn on (matplotlib, the optional extra
``plot``, imported on first use), so that the wings' figures (photometry, fitting,
spin-orbit) and the application's (:mod:`attitude.app.plot`) share it without a wing
importing the application layer."""

from __future__ import annotations

from .errors import PlotUnavailableError

__all__ = ["agg_figure"]


def agg_figure(**kw):
    """A matplotlib Figure on an Agg canvas, not registered with pyplot (no GUI, no
    global state): what every figure of the package is drawn on.

    Raises
    ------
    PlotUnavailableError
        Without matplotlib (the ``plot`` extra).

    Examples
    --------
    >>> fig = agg_figure(figsize=(4, 3))
    >>> type(fig.canvas).__name__
    'FigureCanvasAgg'
    """
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg  # optional: [plot] extra
        from matplotlib.figure import Figure
    except ImportError:
        raise PlotUnavailableError("plots need matplotlib: pip install "
                                   "'attitude-dynamics[plot]' (or pip install matplotlib)"
                                   ) from None
    fig = Figure(**kw)
    FigureCanvasAgg(fig)
    return fig
