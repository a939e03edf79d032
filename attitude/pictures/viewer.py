"""An interactive 3D view of an ephemeris in one self-contained HTML file (plotly).

Why plotly: its offline HTML embeds plotly.js in the file (``include_plotlyjs=True``), so
the page needs no server and no network and can be mailed or attached to a report; it
draws WebGL 3D scenes (rotate, zoom) with animation frames, a time slider and play/pause
built in; it is widely used and actively maintained, and the same figure shows inline in
Jupyter.  The price is plotly.js itself (about 4.8 MB in every file).

The page holds: the body (its shape model, else the uniform ellipsoid of its moments)
with its axes, ``L`` and ``omega`` (inertial frame); Poinsot's construction (the energy
ellipsoid carried by the body on the invariable plane, the polhode on it and the whole
herpolhode at full resolution); the rates and nutation angle against time with a
cursor; the Sun and observer directions (variables ``sun_direction``,
``observer_direction`` of the dataset, inertial unit vectors, or ``geometry=``) and the
lightcurve (a ``magnitude`` variable, or ``lightcurve=``) when present; and for a batch
ephemeris the cloud of angular-momentum directions of its bodies.  A binary system's
ephemeris gets its own page (:mod:`attitude.pictures.binary_view`): both bodies on their
mutual orbit.  The frames are
decimated to at most ``max_frames`` (each carries the moving meshes as float32); the
traces are drawn at full resolution, up to :data:`MAX_LINE_POINTS` points each.
"""

from __future__ import annotations

import numpy as np

from ..binary.propagate import is_binary_dataset
from ..foundations import quaternion as quat
from .binary_view import binary_view
from .motion import body_polygons, ephemeris_inertia, nutation_series, sample_motion
from .page import (
    MAX_LINE_POINTS,
    View,
    animation_controls,
    float32,
    mesh_faces,
    plotly_modules,
    thinned,
)
from .poinsot import ellipsoid_surface, plane_patch, surface_quads

__all__ = ["View", "view", "MAX_LINE_POINTS"]

_AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")


def view(eph, path=None, *, body_index: int | None = None, max_frames: int = 150,
         shape=None, geometry=None, lightcurve=None) -> View:
    """The interactive view of ``eph`` (what :meth:`Ephemeris.view
    <attitude.model.ephemeris.Ephemeris.view>` and ``attitude view`` do).

    Parameters
    ----------
    eph : Ephemeris
    path : str or path-like, optional
        Write the page there (``.html``, atomically).
    body_index : int, optional
        The body shown of a batch (default 0); the batch's ``L`` directions are a cloud.
    max_frames : int
        Frames of the animation (the time slider's steps).
    shape : Polyhedron, optional
        The body's shape, body frame.
    geometry : object with ``sun`` and ``observer``, optional
        Unit vectors (inertial) toward the Sun and the observer, (3,) or (T, 3)
        (an :class:`attitude.Geometry`).
    lightcurve : Lightcurve or Dataset, optional
        Drawn against time (``magnitude``).

    Returns
    -------
    View

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "view.html"
    >>> v = view(eph, out, max_frames=4)
    >>> v.path == out and "plotly" in out.read_text()[:100000]
    True
    """
    if is_binary_dataset(eph.dataset):          # two bodies on their mutual orbit
        out = View(binary_view(eph, max_frames=max_frames))
        if path is not None:
            out.save(path)
        return out
    go, make_subplots = plotly_modules()
    t = np.asarray(eph.time, dtype=float)
    n = min(int(max_frames), t.size)
    times = np.linspace(t[0], t[-1], max(n, 2))
    motion = sample_motion(eph, times, body_index=body_index)
    inertia = ephemeris_inertia(eph, body_index)
    ds = eph.dataset
    magnitude = None
    if lightcurve is not None:
        lc = getattr(lightcurve, "dataset", lightcurve)
        magnitude = (np.asarray(lc["time"].values, float), np.asarray(lc["magnitude"].values))
    elif "magnitude" in ds and ds["magnitude"].dims == ("time",):
        magnitude = (t, np.asarray(ds["magnitude"].values, float))
    rows = 3 if magnitude is not None else 2
    fig = make_subplots(
        rows=rows, cols=2, row_heights=[0.62, 0.38] if rows == 2 else [0.56, 0.22, 0.22],
        specs=[[{"type": "scene"}, {"type": "scene"}], [{"type": "xy", "colspan": 2}, None]]
        + ([[{"type": "xy", "colspan": 2}, None]] if rows == 3 else []),
        subplot_titles=("body (inertial frame)", "Poinsot: energy ellipsoid on the "
                        "invariable plane", "body rates and nutation")
        + (("lightcurve",) if rows == 3 else ()),
        vertical_spacing=0.07)
    moving = []         # (trace index, function k -> dict of the frame's values)

    def add(trace, row, col, update=None):
        fig.add_trace(trace, row=row, col=col)
        if update is not None:
            moving.append((len(fig.data) - 1, update))

    # --- the body --------------------------------------------------------------------
    polys = body_polygons(eph, shape, body_index)
    verts, tri = mesh_faces(polys)

    def rotated(k, v):
        return quat.rotate(motion.quaternion[k], v)

    def mesh_xyz(k, v):
        p = float32(rotated(k, v))
        return {"x": p[:, 0], "y": p[:, 1], "z": p[:, 2]}

    add(go.Mesh3d(i=tri[:, 0], j=tri[:, 1], k=tri[:, 2], color="tan", opacity=1.0,
                  flatshading=True, name="body", hoverinfo="skip", **mesh_xyz(0, verts)),
        1, 1, lambda k: mesh_xyz(k, verts))
    for a, (colour, label) in enumerate(zip(_AXIS_COLOURS, "xyz")):
        def axis(k, a=a):
            tip = 1.5 * rotated(k, np.eye(3)[a])
            return {"x": [0.0, tip[0]], "y": [0.0, tip[1]], "z": [0.0, tip[2]]}
        add(go.Scatter3d(mode="lines", line={"color": colour, "width": 6}, name=label,
                         **axis(0)), 1, 1, axis)

    def omega_line(k):
        w = motion.omega_inertial[k]
        tip = 1.7 * w / max(np.linalg.norm(w), 1e-300)
        return {"x": [0.0, tip[0]], "y": [0.0, tip[1]], "z": [0.0, tip[2]]}
    add(go.Scatter3d(mode="lines", line={"color": "magenta", "width": 5}, name="omega",
                     **omega_line(0)), 1, 1, omega_line)
    if inertia is not None:
        L = motion.angular_momentum
        def momentum_line(k):
            tip = 1.8 * L[k] / np.linalg.norm(L[k])
            return {"x": [0.0, tip[0]], "y": [0.0, tip[1]], "z": [0.0, tip[2]]}
        add(go.Scatter3d(mode="lines", line={"color": "black", "width": 5}, name="L",
                         **momentum_line(0)), 1, 1, momentum_line)
    for name, colour in (("sun", "orange"), ("observer", "royalblue")):
        d = getattr(geometry, name, None) if geometry is not None else None
        if d is None and f"{name}_direction" in ds:
            d = np.asarray(ds[f"{name}_direction"].values, float)
        if d is None:
            continue
        d = np.asarray(d, float)
        if d.ndim == 2:
            idx = np.clip(np.searchsorted(t, times), 0, d.shape[0] - 1)
            d = d[idx]
        def direction(k, d=d):
            u = d[k] if d.ndim == 2 else d
            tip = 2.0 * u / np.linalg.norm(u)
            return {"x": [0.0, tip[0]], "y": [0.0, tip[1]], "z": [0.0, tip[2]]}
        add(go.Scatter3d(mode="lines", line={"color": colour, "width": 4, "dash": "dash"},
                         name=f"to the {name}", **direction(0)), 1, 1,
            direction if d.ndim == 2 else None)
    if eph.is_batch and "angular_momentum" in ds:
        Lb = np.asarray(ds["angular_momentum"].values[:, 0], float)
        ok = np.all(np.isfinite(Lb), -1) & (np.linalg.norm(Lb, axis=-1) > 0)
        u = 1.9 * Lb[ok] / np.linalg.norm(Lb[ok], axis=-1, keepdims=True)
        add(go.Scatter3d(mode="markers", marker={"size": 2, "color": "black"},
                         name=f"L directions ({int(ok.sum())} bodies)",
                         x=float32(u[:, 0]), y=float32(u[:, 1]), z=float32(u[:, 2])), 1, 1)
    # --- Poinsot's construction ----------------------------------------------------------
    if inertia is not None:
        moments, axes = np.linalg.eigh(inertia)
        E = float(motion.energy[0])
        semi = np.sqrt(2 * E / moments)
        shell = ellipsoid_surface(semi, axes, n_lat=10, n_lon=20)
        ev, etri = mesh_faces(surface_quads(*shell))
        # under torques E and L change: the energy ellipsoid grows or shrinks with
        # sqrt(E), the invariable plane follows L and its distance 2E/|L|, frame by frame
        scale = np.sqrt(np.asarray(motion.energy, float) / E)
        Lk = np.asarray(motion.angular_momentum, float)
        varying = bool(np.abs(scale - 1.0).max() > 1e-9 or
                       np.abs(Lk - Lk[0]).max() > 1e-9 * np.linalg.norm(Lk[0]))
        add(go.Mesh3d(i=etri[:, 0], j=etri[:, 1], k=etri[:, 2], color="#4fc3d9",
                      opacity=0.6, flatshading=True, name="energy ellipsoid",
                      hoverinfo="skip", **mesh_xyz(0, ev)), 1, 2,
            lambda k: mesh_xyz(k, ev * scale[k]))

        def plane(k):
            c = plane_patch(Lk[k], 2 * float(motion.energy[k]) / np.linalg.norm(Lk[k]),
                            np.zeros(3), 1.2 * semi.max())
            return {"x": c[:, 0], "y": c[:, 1], "z": c[:, 2]}
        add(go.Mesh3d(i=[0, 0], j=[1, 2], k=[2, 3], color="gray", opacity=0.25,
                      name="invariable plane", hoverinfo="skip", **plane(0)), 1, 2,
            plane if varying else None)
        idx = thinned(t.size, MAX_LINE_POINTS)
        full = sample_motion(eph, t[idx], body_index=body_index)
        her = float32(full.omega_inertial)
        add(go.Scatter3d(mode="lines", line={"color": "purple", "width": 3},
                         name="herpolhode", x=her[:, 0], y=her[:, 1], z=her[:, 2]), 1, 2)
        pol_idx = thinned(idx.size, 200)
        pol = full.omega[pol_idx]

        def polhode(k):
            p = float32(rotated(k, pol))
            return {"x": p[:, 0], "y": p[:, 1], "z": p[:, 2]}
        add(go.Scatter3d(mode="lines", line={"color": "darkorange", "width": 4},
                         name="polhode", **polhode(0)), 1, 2, polhode)

        def contact(k):
            p = motion.omega_inertial[k]
            return {"x": [p[0]], "y": [p[1]], "z": [p[2]]}
        add(go.Scatter3d(mode="markers", marker={"size": 4, "color": "magenta"},
                         name="omega (contact point)", **contact(0)), 1, 2, contact)
    # --- time series -----------------------------------------------------------------
    idx = thinned(t.size, MAX_LINE_POINTS)
    w = np.asarray(ds["angular_velocity"].values, float)
    if eph.is_batch:
        w = w[body_index or 0]
    hours = t[-1] - t[0] >= 3 * 3600.0
    size, unit = (3600.0, "h") if hours else (1.0, "s")
    for a, (colour, label) in enumerate(zip(_AXIS_COLOURS, "xyz")):
        add(go.Scatter(x=float32(t[idx] / size), y=float32(np.degrees(w[idx, a]) * size),
                       mode="lines", line={"color": colour, "width": 1},
                       name=f"omega_{label} (deg/{unit})"), 2, 1)
    nutation = nutation_series(eph, body_index)
    if nutation is not None:
        add(go.Scatter(x=float32(t[idx] / size), y=float32(np.degrees(nutation[idx])),
                       mode="lines", line={"color": "black", "width": 1, "dash": "dot"},
                       name="nutation (deg)"), 2, 1)
    low = float(np.degrees(np.nanmin(w)) * size)
    high = float(np.degrees(np.nanmax(w)) * size)
    if nutation is not None:
        low, high = min(low, 0.0), max(high, float(np.degrees(nutation.max())))

    def cursor(k):
        x = float(times[k] / size)
        return {"x": [x, x], "y": [low, high]}
    add(go.Scatter(mode="lines", line={"color": "gray", "width": 2}, name="now",
                   showlegend=False, **cursor(0)), 2, 1, cursor)
    if magnitude is not None:
        lt, mag = magnitude
        li = thinned(lt.size, MAX_LINE_POINTS)
        add(go.Scatter(x=float32(lt[li] / size), y=float32(mag[li]), mode="lines",
                       line={"color": "black", "width": 1}, name="magnitude"), 3, 1)
        fig.update_yaxes(autorange="reversed", title_text="mag", row=3, col=1)
        mlo, mhi = float(np.nanmin(mag)), float(np.nanmax(mag))

        def mag_cursor(k):
            x = float(times[k] / size)
            return {"x": [x, x], "y": [mlo, mhi]}
        add(go.Scatter(mode="lines", line={"color": "gray", "width": 2},
                       showlegend=False, **mag_cursor(0)), 3, 1, mag_cursor)
    fig.update_xaxes(title_text=f"time ({unit})", row=rows, col=1)
    # --- frames, slider, play/pause ----------------------------------------------------
    names = [f"{times[k] / size:.4g} {unit}" for k in range(times.size)]
    fig.frames = [go.Frame(name=names[k], traces=[i for i, _ in moving],
                           data=[dict(type=fig.data[i].type, **f(k)) for i, f in moving])
                  for k in range(times.size)]
    fig.update_layout(
        title=f"{ds.attrs.get('title', 'attitude ephemeris')} — epoch "
              f"{ds.attrs['epoch']} {eph.time_scale}, frame {eph.frame}",
        height=820 if rows == 2 else 980, margin={"l": 40, "r": 20, "t": 70, "b": 40},
        scene={"aspectmode": "cube", **_box(2.0)},
        scene2={"aspectmode": "cube", **(_box(1.3 * float(semi.max()))
                                          if inertia is not None else {})},
        **animation_controls(names))
    out = View(fig)
    if path is not None:
        out.save(path)
    return out


def _box(r: float) -> dict:
    axis = {"range": [-r, r], "autorange": False}
    return {"xaxis": axis, "yaxis": axis, "zaxis": axis}
