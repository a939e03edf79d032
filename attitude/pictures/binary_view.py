"""The interactive view of a binary system's ephemeris: both bodies turning on their
mutual orbit, in one self-contained HTML file (plotly, as :mod:`attitude.pictures.viewer`).

The scene is the inertial frame centred on the primary, in km: the primary at the
origin and the secondary at the relative position, each drawn as the uniform ellipsoid
of its principal moments and mass (true size) with its long axis; the whole mutual orbit
as a line; a line from the secondary toward the primary.  Below, against time with a
cursor: the separation and the secondary's libration angle (its long axis against the
direction to the primary, in the orbit plane: the binary wing's
:func:`attitude.binary.diagnostics.libration_angle`).  A binary ephemeris is recognised
by :func:`attitude.binary.propagate.is_binary_dataset`.
"""

from __future__ import annotations

import numpy as np

from ..binary.diagnostics import libration_angle
from ..binary.propagate import is_binary_dataset
from ..foundations import quaternion as quat
from ..foundations.errors import EphemerisFormatError
from .page import MAX_LINE_POINTS, animation_controls, float32, mesh_faces, plotly_modules, thinned
from .poinsot import ellipsoid_surface, solid_semi_axes, surface_quads

__all__ = ["binary_view"]


def binary_view(eph, *, max_frames: int = 150):
    """The plotly figure of a binary ephemeris (what ``view`` draws for a binary).

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> ball = att.RigidBody.from_mass_properties(att.MassProperties.solid_sphere(1e12, 500.0))
    >>> egg = att.RigidBody.from_mass_properties(
    ...     att.MassProperties.solid_ellipsoid(1e9, [100.0, 80.0, 60.0]))
    >>> system = att.BinarySystem(ball, egg)
    >>> n = np.sqrt(system.mu / 1200.0**3)
    >>> state = att.BinaryState("2026-12-01", [1200.0, 0, 0], [0, n * 1200.0, 0],
    ...                         Rotation.identity(), [0, 0, 1e-4], Rotation.identity(),
    ...                         [0, 0, n])
    >>> eph = att.propagate(system, state, np.linspace(0.0, 3600.0, 13), method="integrator")
    >>> fig = binary_view(eph, max_frames=4)
    >>> len(fig.frames), {"primary", "secondary", "mutual orbit"} <= {d.name for d in fig.data}
    (4, True)
    """
    if not is_binary_dataset(eph.dataset):
        raise EphemerisFormatError("not a binary ephemeris: expected relative_position and "
                                   "the masses attribute (att.propagate of a BinarySystem)")
    go, make_subplots = plotly_modules()
    ds = eph.dataset
    t = np.asarray(eph.time, dtype=float)
    frames = np.unique(np.linspace(0, t.size - 1, max(min(int(max_frames), t.size), 1)
                                   ).round().astype(int))
    km = 1e-3
    R = np.asarray(ds["relative_position"].values, float) * km
    q = np.asarray(ds["quaternion"].values, float)
    masses = np.asarray(ds.attrs["masses"], float)
    moments = np.asarray(ds["principal_moments"].values, float)
    inertia = np.asarray(ds["inertia"].values, float).reshape(2, 3, 3)
    libration = np.degrees(libration_angle(eph))
    fig = make_subplots(rows=2, cols=1, row_heights=[0.68, 0.32],
                        specs=[[{"type": "scene"}], [{"type": "xy", "secondary_y": True}]],
                        subplot_titles=("primary and secondary (inertial frame, km)",
                                        "separation and libration"), vertical_spacing=0.08)
    moving = []

    def add(trace, row, update=None, **where):
        fig.add_trace(trace, row=row, col=1, **where)
        if update is not None:
            moving.append((len(fig.data) - 1, update))

    for b, (name, colour) in enumerate((("primary", "tan"), ("secondary", "#8d8d8d"))):
        axes = np.linalg.eigh(inertia[b])[1]
        semi = solid_semi_axes(moments[b], masses[b]) * km
        verts, tri = mesh_faces(surface_quads(*ellipsoid_surface(semi, axes, n_lat=10,
                                                                   n_lon=20)))
        centre = (lambda k: np.zeros(3)) if b == 0 else (lambda k: R[k])

        def mesh(k, verts=verts, b=b, centre=centre):
            p = float32(quat.rotate(q[b, k], verts) + centre(k))
            return {"x": p[:, 0], "y": p[:, 1], "z": p[:, 2]}
        add(go.Mesh3d(i=tri[:, 0], j=tri[:, 1], k=tri[:, 2], color=colour, flatshading=True,
                      name=name, hoverinfo="skip", **mesh(frames[0])), 1, mesh)
        long_axis = axes[:, 0] * semi[0] * 1.6

        def axis_line(k, b=b, long_axis=long_axis, centre=centre):
            tip = quat.rotate(q[b, k], long_axis)
            c = centre(k)
            return {"x": [c[0] - tip[0], c[0] + tip[0]], "y": [c[1] - tip[1], c[1] + tip[1]],
                    "z": [c[2] - tip[2], c[2] + tip[2]]}
        add(go.Scatter3d(mode="lines", line={"color": "#d62728", "width": 5},
                         name=f"{name} long axis", **axis_line(frames[0])), 1, axis_line)
    idx = thinned(t.size, MAX_LINE_POINTS)
    path = float32(R[idx])
    add(go.Scatter3d(mode="lines", line={"color": "royalblue", "width": 2},
                     name="mutual orbit", x=path[:, 0], y=path[:, 1], z=path[:, 2]), 1)

    def toward_primary(k):
        return {"x": [R[k, 0], 0.0], "y": [R[k, 1], 0.0], "z": [R[k, 2], 0.0]}
    add(go.Scatter3d(mode="lines", line={"color": "gray", "width": 2, "dash": "dash"},
                     name="toward the primary", **toward_primary(frames[0])), 1,
        toward_primary)
    hours = t[-1] - t[0] >= 3 * 3600.0
    size, unit = (3600.0, "h") if hours else (1.0, "s")
    separation = np.linalg.norm(R, axis=-1)
    add(go.Scatter(x=float32(t[idx] / size), y=float32(separation[idx]), mode="lines",
                   line={"color": "royalblue", "width": 1}, name="separation (km)"), 2)
    add(go.Scatter(x=float32(t[idx] / size), y=float32(libration[idx]), mode="lines",
                   line={"color": "#d62728", "width": 1}, name="libration (deg)"), 2,
        secondary_y=True)
    low, high = float(separation.min()), float(separation.max())
    if high - low < 1e-9 * high:
        low, high = low * 0.999, high * 1.001

    def cursor(k):
        x = float(t[k] / size)
        return {"x": [x, x], "y": [low, high]}
    add(go.Scatter(mode="lines", line={"color": "gray", "width": 2}, name="now",
                   showlegend=False, **cursor(frames[0])), 2, cursor)
    fig.update_xaxes(title_text=f"time ({unit})", row=2, col=1)
    fig.update_yaxes(title_text="separation (km)", row=2, col=1, secondary_y=False)
    fig.update_yaxes(title_text="libration (deg)", row=2, col=1, secondary_y=True)
    names = [f"{t[k] / size:.4g} {unit}" for k in frames]
    fig.frames = [go.Frame(name=name, traces=[i for i, _ in moving],
                           data=[dict(type=fig.data[i].type, **f(k)) for i, f in moving])
                  for name, k in zip(names, frames)]
    reach = 1.15 * float(np.abs(R).max() + solid_semi_axes(moments[0], masses[0]).max() * km)
    box = {"range": [-reach, reach], "autorange": False}
    fig.update_layout(
        title=f"{ds.attrs.get('title', 'binary system')} — epoch {ds.attrs['epoch']} "
              f"{eph.time_scale}, frame {eph.frame}",
        height=860, margin={"l": 40, "r": 20, "t": 70, "b": 40},
        scene={"aspectmode": "cube", "xaxis": box, "yaxis": box, "zaxis": box},
        **animation_controls(names))
    return fig
