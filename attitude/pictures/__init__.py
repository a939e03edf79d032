"""Pictures of an ephemeris (docs/pictures.md): Poinsot's construction animated
(matplotlib; MP4 through imageio-ffmpeg's ffmpeg, GIF through Pillow) and an interactive
3D view in one self-contained HTML file (plotly).  matplotlib, plotly and imageio-ffmpeg
are the optional extra ``pictures``, imported when a picture is drawn."""

from .animation import PoinsotAnimation, animate
from .motion import Motion, characteristic_periods, frame_times, sample_motion
from .poinsot import (
    body_axes,
    energy_ellipsoid_surface,
    energy_residual,
    equivalent_ellipsoid_axes,
    herpolhode_point,
    invariable_plane,
    momentum_residual,
    on_polhode,
)
from .viewer import View, view

__all__ = ["animate", "PoinsotAnimation", "view", "View", "Motion", "characteristic_periods",
           "frame_times", "sample_motion", "body_axes", "energy_ellipsoid_surface",
           "energy_residual", "equivalent_ellipsoid_axes", "herpolhode_point",
           "invariable_plane", "momentum_residual", "on_polhode"]
