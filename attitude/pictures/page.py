"""The page of an interactive view: the plotly figure as one self-contained HTML file
(:class:`View`), and the pieces every view shares (the animation's play/pause buttons and
time slider, meshes sent once, float32 traces, lines thinned to at most
:data:`MAX_LINE_POINTS` points)."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from ..foundations.errors import MissingDependencyError, WriterError
from ..model.ephemeris import write_atomically

__all__ = []   # the wing's shared pieces; View is public through attitude.pictures

#: The most points of one full-resolution line (time series, herpolhode).
MAX_LINE_POINTS = 20000


def plotly_modules():
    try:
        import plotly.graph_objects as go  # optional: the [pictures] extra
        from plotly.subplots import make_subplots  # optional: the [pictures] extra
    except ImportError:
        raise MissingDependencyError("the HTML view needs plotly: pip install "
                                     "'attitude-dynamics[pictures]'") from None
    return go, make_subplots


class View:
    """The interactive view: :attr:`html` (the whole page), :meth:`save`, and inline
    display in Jupyter (``_repr_html_``).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> from attitude.pictures.viewer import view
    >>> v = view(att.propagate(body, state, np.linspace(0.0, 300.0, 31)), max_frames=5)
    >>> len(v.figure.frames), "<html>" in v.html, "<iframe" in v._repr_html_()
    (5, True, True)
    """

    def __init__(self, figure, path: Path | None = None):
        self.figure = figure
        self.path = path

    @property
    def html(self) -> str:
        """The page: one HTML document with plotly.js embedded (no network)."""
        return self.figure.to_html(include_plotlyjs=True, full_html=True,
                                   auto_play=False, config={"displaylogo": False})

    def _repr_html_(self) -> str:
        page = html.escape(self.html, quote=True)
        return (f'<iframe srcdoc="{page}" style="width:100%;height:760px;border:none">'
                "</iframe>")

    def save(self, path) -> Path:
        """Write the page atomically; returns the path."""
        path = Path(path)
        if path.suffix.lower() not in (".html", ".htm"):
            raise WriterError(f"unknown suffix {path.suffix!r} for the view (use .html)",
                              path=str(path))
        text = self.html
        self.path = write_atomically(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
        return self.path


def thinned(n: int, most: int) -> np.ndarray:
    return np.arange(0, n, max(1, int(np.ceil(n / most))))


def mesh_faces(polys: np.ndarray):
    """Shared vertices and triangle indices of polygons (k, m, 3) (fans): the vertices
    that polygons share are sent once (a grid's seam and poles are merged)."""
    k, m, _ = polys.shape
    points = polys.reshape(-1, 3)
    scale = max(float(np.abs(points).max()), 1e-300)
    _, first, inverse = np.unique(np.round(points / scale, 12), axis=0, return_index=True,
                                  return_inverse=True)
    base = np.arange(k)[:, None] * m
    tri = np.concatenate([np.stack([base[:, 0], base[:, 0] + j, base[:, 0] + j + 1], -1)
                          for j in range(1, m - 1)])
    tri = inverse.reshape(-1)[tri]
    keep = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    return points[first], tri[keep]


def float32(x):
    return np.asarray(x, dtype=np.float32)


def animation_controls(names) -> dict:
    """The layout entries of an animation whose frames are named ``names``: play/pause
    buttons and a time slider.

    Examples
    --------
    >>> controls = animation_controls(["0 s", "10 s"])
    >>> [b["label"] for b in controls["updatemenus"][0]["buttons"]]
    ['play', 'pause']
    >>> len(controls["sliders"][0]["steps"])
    2
    """
    anim = {"frame": {"duration": 80, "redraw": True}, "transition": {"duration": 0},
            "mode": "immediate", "fromcurrent": True}
    return {
        "updatemenus": [{"type": "buttons", "direction": "left", "x": 0.0, "y": -0.02,
                         "xanchor": "left", "yanchor": "top", "showactive": False,
                         "buttons": [{"label": "play", "method": "animate",
                                      "args": [None, anim]},
                                     {"label": "pause", "method": "animate",
                                      "args": [[None], {"frame": {"duration": 0,
                                                                  "redraw": False},
                                                        "mode": "immediate"}]}]}],
        "sliders": [{"active": 0, "x": 0.12, "len": 0.88, "y": -0.02, "yanchor": "top",
                     "currentvalue": {"prefix": "t = "},
                     "steps": [{"label": name, "method": "animate",
                                "args": [[name], {"frame": {"duration": 0, "redraw": True},
                                                  "mode": "immediate",
                                                  "transition": {"duration": 0}}]}
                               for name in names]}],
    }
