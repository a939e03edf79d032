r"""The rotation as a movie: the body turning and Poinsot's construction in step with it
(matplotlib's animation; MP4 through the ffmpeg that the imageio-ffmpeg wheel ships, GIF
through Pillow).

Three panels, drawn in the **scene frame**: the inertial frame turned so that its ``z``
axis points against the angular momentum at the first frame (:attr:`PoinsotAnimation.
scene_rotation`), so that the invariable plane lies flat under the rolling ellipsoid:

1. the body turning: its shape model (``shape=`` or the ephemeris attribute
   ``shape_model``, an OBJ path), else the uniform ellipsoid with its principal moments
   (:func:`~attitude.pictures.poinsot.equivalent_ellipsoid_axes`); the body axes ``x y z``
   (red, green, blue), the angular momentum ``L`` (black, fixed without torques) and the
   angular velocity ``omega`` (magenta);
2. Poinsot's construction: the energy ellipsoid ``omega . I omega = 2E`` carried by the
   body, rolling on the invariable plane, with the polhode (on the ellipsoid) and the
   herpolhode (on the plane) drawn as far as they have been traced, in rad/s;
3. the body rates and the nutation angle against time, with a cursor.

Without an inertia tensor (a CCSDS AEM read without a body) the movie has the body axes,
``omega`` and the rates only.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..foundations import quaternion as quat
from ..foundations.errors import EphemerisFormatError, MissingDependencyError, WriterError
from ..foundations.figures import agg_figure
from ..model.ephemeris import write_atomically
from .motion import body_polygons, frame_times, nutation_series, sample_motion
from .poinsot import body_axes, ellipsoid_surface, plane_patch, surface_quads

__all__ = ["PoinsotAnimation", "animate", "MOVIE_SUFFIXES"]

#: The movie formats, by file suffix.
MOVIE_SUFFIXES = (".mp4", ".gif")
_AXIS_COLOURS = ("tab:red", "tab:green", "tab:blue")
_SUBSTEPS = 4            # trace points per frame: the polhode and herpolhode look smooth
_MAX_LINE_POINTS = 4000  # points of the time series drawn in the rates panel
_LIGHT = np.array([0.4, -0.5, 0.77])


def scene_rotation(L) -> np.ndarray:
    """The rotation (3, 3) from the inertial frame to the scene frame, whose ``z`` axis is
    ``-L / |L|`` (the identity for ``L = 0`` or unknown).

    Examples
    --------
    >>> M = scene_rotation([0.0, 0.0, 2.0])
    >>> (M @ [0.0, 0.0, 2.0]).round(15).tolist()
    [0.0, 0.0, -2.0]
    """
    L = None if L is None else np.asarray(L, dtype=float)
    if L is None or not np.all(np.isfinite(L)) or not np.linalg.norm(L) > 0:
        return np.eye(3)
    z = -L / np.linalg.norm(L)
    helper = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def _shaded(polys: np.ndarray, base) -> np.ndarray:
    """Face colours of the polygons (k, m, 3) lit from the fixed light direction."""
    from matplotlib.colors import to_rgb  # optional: the [pictures] extra

    n = np.cross(polys[:, 1] - polys[:, 0], polys[:, 2] - polys[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    centre = polys.mean(axis=1)
    outward = np.sign(np.sum(n * (centre - centre.mean(axis=0)), -1, keepdims=True))
    light = _LIGHT / np.linalg.norm(_LIGHT)
    k = 0.35 + 0.65 * np.clip(np.sum(outward * n * light, -1), 0.0, 1.0)
    return np.column_stack([np.outer(k, to_rgb(base)), np.ones(len(k))])


def _time_unit(span: float) -> tuple[float, str]:
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if span >= 3 * size:
            return size, unit
    return 1.0, "s"


class PoinsotAnimation:
    """The figure and its frames: :meth:`update` draws frame ``k``; :meth:`save` writes
    the movie.  :attr:`artists` names what is drawn (``"body_axes"``: three lines from
    the origin along the body axes; ``"polhode_point"``, ``"herpolhode_point"``: the
    contact point in the scene frame, ...), so that a test can read the figure's data.

    Parameters
    ----------
    eph : Ephemeris
    times : (n,) array_like
        Frame times, s since the epoch (:func:`~attitude.pictures.motion.frame_times`).
    poinsot : bool
        Draw Poinsot's construction (needs the inertia).
    shape : Polyhedron, optional
        The body's shape (body frame); default the ephemeris's ``shape_model`` or the
        equivalent ellipsoid.
    body_index : int, optional
        The body of a batch (default 0).
    figsize : (float, float)
        Inches.

    Examples
    --------
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
    >>> anim = PoinsotAnimation(eph, np.linspace(0.0, 300.0, 5))
    >>> anim.update(2)
    >>> x, y, z = anim.artists["body_axes"][0].get_data_3d()
    >>> drawn = anim.scene_rotation.T @ [x[1], y[1], z[1]] / anim.axis_length
    >>> truth = eph.rotation[15].apply([1.0, 0.0, 0.0])         # t = 150 s is sample 15
    >>> bool(np.allclose(drawn, truth, rtol=0, atol=1e-14))
    True
    """

    def __init__(self, eph, times, *, poinsot: bool = True, shape=None,
                 body_index: int | None = None, figsize=(12.0, 4.5)):
        self.times = np.asarray(times, dtype=float)
        if self.times.ndim != 1 or self.times.size < 2:
            raise EphemerisFormatError("an animation needs at least two frame times")
        self.eph, self.body_index = eph, body_index
        trace_t = np.linspace(self.times[0], self.times[-1],
                              (self.times.size - 1) * _SUBSTEPS + 1)
        trace_t[::_SUBSTEPS] = self.times
        self.trace = sample_motion(eph, trace_t, body_index=body_index)
        self.inertia = self.trace.inertia
        self.poinsot = bool(poinsot) and self.inertia is not None
        L0 = self.trace.angular_momentum[0] if self.inertia is not None else None
        #: inertial -> scene frame (rows: the scene axes in inertial components)
        self.scene_rotation = scene_rotation(L0)
        #: length of the drawn body axes (the body is scaled to a largest extent of 1)
        self.axis_length = 1.5
        self._body = body_polygons(eph, shape, body_index)
        self.figure = agg_figure(figsize=figsize)
        self.artists: dict = {}
        self._build()

    # --- frame geometry (scene frame) ------------------------------------------------
    def _to_scene(self, quaternion, v):
        """Body-frame vectors ``v`` (..., 3) in the scene frame at ``quaternion``."""
        return quat.rotate(quaternion, v) @ self.scene_rotation.T

    def _build(self):
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # optional: [pictures] extra

        fig = self.figure
        n_panels = 3 if self.poinsot else 2
        widths = [1.0, 1.0, 1.3] if self.poinsot else [1.0, 1.3]
        grid = fig.add_gridspec(1, n_panels, width_ratios=widths, left=0.02, right=0.93,
                                wspace=0.12, bottom=0.14, top=0.9)
        ax = fig.add_subplot(grid[0], projection="3d")
        self._setup_3d(ax, 1.6, "body (L down)")
        self._body_poly = Poly3DCollection(self._body, edgecolor="none", alpha=0.9)
        ax.add_collection3d(self._body_poly)
        self.artists["body"] = self._body_poly
        self.artists["body_axes"] = [ax.plot([], [], [], color=c, lw=2.5, label=lbl)[0]
                                     for c, lbl in zip(_AXIS_COLOURS, "xyz")]
        self.artists["omega_direction"] = ax.plot([], [], [], color="m", lw=2,
                                                  label="omega")[0]
        if self.inertia is not None:
            Lhat = np.array([0.0, 0.0, -1.0]) * self.axis_length * 1.15
            self.artists["momentum_direction"] = ax.plot(
                [0, Lhat[0]], [0, Lhat[1]], [0, Lhat[2]], color="k", lw=2, label="L")[0]
        ax.legend(loc="upper left", fontsize=7, ncol=3, frameon=False)
        self._ax_body = ax
        if self.poinsot:
            self._build_poinsot(fig.add_subplot(grid[1], projection="3d"), Poly3DCollection)
        self._build_rates(fig.add_subplot(grid[-1]))
        self.title = fig.suptitle("")

    def _setup_3d(self, ax, r, title):
        ax.set_xlim(-r, r)
        ax.set_ylim(-r, r)
        ax.set_zlim(-r, r)
        ax.set_box_aspect((1, 1, 1))
        ax.set_title(title, fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_zticks([])
        ax.view_init(elev=18, azim=-60)       # z = -L up: the plane below the body
        ax.computed_zorder = False            # drawn in the order of self._animated

    def _build_poinsot(self, ax, Poly3DCollection):
        m = self.trace
        moments, axes = np.linalg.eigh(self.inertia)
        E = float(m.energy[0])
        semi = np.sqrt(2.0 * E / moments)
        self._ellipsoid = surface_quads(*ellipsoid_surface(semi, axes, n_lat=10, n_lon=20))
        r = float(semi.max()) * 1.25
        self._setup_3d(ax, r, "Poinsot construction")
        self._poinsot_poly = Poly3DCollection(self._ellipsoid, edgecolor="none", alpha=0.55)
        ax.add_collection3d(self._poinsot_poly)
        self.artists["ellipsoid"] = self._poinsot_poly
        distance = 2 * E / float(m.momentum[0])
        corners = np.array([[-r, -r], [r, -r], [r, r], [-r, r]]) * 0.9
        plane = np.column_stack([corners, np.full(4, -distance)])   # z = -L: L up is -z
        # under torques E and L change: the ellipsoid scales with sqrt(E), the plane
        # follows L at 2E/|L| (then both are redrawn each frame)
        self._energy_scale = np.sqrt(np.asarray(m.energy, float) / E)
        L = np.asarray(m.angular_momentum, float)
        self._plane_half_width = 0.9 * r
        self.varying = bool(np.abs(self._energy_scale - 1.0).max() > 1e-9
                            or np.abs(L - L[0]).max() > 1e-9 * np.linalg.norm(L[0]))
        self.artists["plane"] = Poly3DCollection([plane], facecolor=(0.6, 0.6, 0.6, 0.25),
                                                 edgecolor="0.5")
        ax.add_collection3d(self.artists["plane"])
        self.artists["polhode"] = ax.plot([], [], [], color="tab:orange", lw=1.5,
                                          label="polhode")[0]
        self.artists["herpolhode"] = ax.plot([], [], [], color="tab:purple", lw=1.5,
                                             label="herpolhode")[0]
        self.artists["polhode_point"] = ax.plot([], [], [], "o", color="m", ms=2.5)[0]
        self.artists["herpolhode_point"] = self.artists["polhode_point"]
        self.artists["omega"] = ax.plot([], [], [], color="m", lw=1.5, label="omega")[0]
        self.artists["momentum"] = ax.plot([0, 0], [0, 0], [0, -distance], color="k",
                                           lw=1.5, label="L")[0]
        ax.legend(loc="upper left", fontsize=7, ncol=2, frameon=False)
        self._ax_poinsot = ax

    def _build_rates(self, ax):
        eph, t0, t1 = self.eph, self.times[0], self.times[-1]
        t = np.asarray(eph.time, dtype=float)
        inside = np.flatnonzero((t >= t0) & (t <= t1))
        step = max(1, int(np.ceil(inside.size / _MAX_LINE_POINTS)))
        idx = inside[::step]
        w = np.asarray(eph.dataset["angular_velocity"].values, dtype=float)
        if eph.is_batch:
            w = w[self.body_index or 0]
        size, unit = _time_unit(float(t1 - t0))
        rate_unit = 180 / np.pi * (3600.0 if size >= 3600.0 else 1.0)
        rate_label = "deg/h" if size >= 3600.0 else "deg/s"
        for k, (c, name) in enumerate(zip(_AXIS_COLOURS, "xyz")):
            ax.plot(t[idx] / size, w[idx, k] * rate_unit, color=c, lw=1,
                    label=f"omega_{name}")
        ax.set_xlabel(f"time ({unit})")
        ax.set_ylabel(f"body rates ({rate_label})")
        ax.set_xlim(t0 / size, t1 / size)
        nutation = nutation_series(eph, self.body_index)
        handles, labels = ax.get_legend_handles_labels()
        if nutation is not None:
            twin = ax.twinx()
            line = twin.plot(t[idx] / size, np.degrees(nutation[idx]), color="k", lw=1,
                             ls="--", label="nutation")[0]
            twin.set_ylabel("nutation angle (deg)")
            handles.append(line)
            labels.append("nutation")
        ax.legend(handles, labels, loc="upper right", fontsize=7, ncol=2, framealpha=0.7)
        self.artists["cursor"] = ax.axvline(t0 / size, color="0.3", lw=1)
        #: the time axis: (seconds per unit, unit)
        self.time_unit = (size, unit)

    # --- one frame -------------------------------------------------------------------
    def update(self, k: int):
        """Draw frame ``k`` (the motion at ``times[k]``)."""
        j = int(k) * _SUBSTEPS
        m = self.trace
        q, w = m.quaternion[j], m.omega[j]
        R = self.scene_rotation @ quat.rotate(q, np.eye(3)).T          # body -> scene
        polys = self._body @ R.T
        self._body_poly.set_verts(polys)
        self._body_poly.set_facecolor(_shaded(polys, "tan"))
        axes = body_axes(q) @ self.scene_rotation.T * self.axis_length
        for line, a in zip(self.artists["body_axes"], axes):
            line.set_data_3d([0.0, a[0]], [0.0, a[1]], [0.0, a[2]])
        wi = R @ w
        norm = np.linalg.norm(wi)
        tip = wi / norm * self.axis_length * 1.15 if norm > 0 else wi
        self.artists["omega_direction"].set_data_3d([0, tip[0]], [0, tip[1]], [0, tip[2]])
        if self.poinsot:
            shell = self._ellipsoid * self._energy_scale[j] @ R.T
            self._poinsot_poly.set_verts(shell)
            self._poinsot_poly.set_facecolor(_shaded(shell, "tab:cyan"))
            pol = m.omega[: j + 1] @ R.T                              # on the ellipsoid now
            self.artists["polhode"].set_data_3d(pol[:, 0], pol[:, 1], pol[:, 2])
            her = quat.rotate(m.quaternion[: j + 1], m.omega[: j + 1]) @ self.scene_rotation.T
            self.artists["herpolhode"].set_data_3d(her[:, 0], her[:, 1], her[:, 2])
            self.artists["polhode_point"].set_data_3d([wi[0]], [wi[1]], [wi[2]])
            self.artists["omega"].set_data_3d([0, wi[0]], [0, wi[1]], [0, wi[2]])
            if self.varying:
                Ls = self.scene_rotation @ m.angular_momentum[j]
                d = 2.0 * float(m.energy[j]) / np.linalg.norm(Ls)
                self.artists["plane"].set_verts([plane_patch(Ls, d, np.zeros(3),
                                                             self._plane_half_width)])
                tip = Ls / np.linalg.norm(Ls) * d
                self.artists["momentum"].set_data_3d([0, tip[0]], [0, tip[1]], [0, tip[2]])
                tip = Ls / np.linalg.norm(Ls) * self.axis_length * 1.15
                self.artists["momentum_direction"].set_data_3d([0, tip[0]], [0, tip[1]],
                                                               [0, tip[2]])
        x = self.times[k] / self.time_unit[0]
        self.artists["cursor"].set_xdata([x, x])
        self.title.set_text(f"{self.eph.epoch.isot[:19]} {self.eph.time_scale} + "
                            f"{self.times[k] / self.time_unit[0]:.2f} {self.time_unit[1]}")

    def _animated(self) -> list:
        """The artists that change from frame to frame, in drawing order."""
        names = ["body", "body_axes", "omega_direction", "momentum_direction",
                 *(["plane"] if getattr(self, "varying", False) else []),
                 "ellipsoid", "polhode", "herpolhode", "omega", "momentum",
                 "polhode_point", "cursor"]
        out = []
        for name in names:
            a = self.artists.get(name)
            out += a if isinstance(a, list) else [] if a is None else [a]
        return out + [self.title]

    def frames(self, dpi: float = 80.0):
        """The frames as ``(height, width, 3)`` uint8 arrays, one per frame time: the
        figure is drawn once without the moving artists (axes, ticks, legends, the time
        series), then each frame draws only these over that background."""
        fig = self.figure
        w, h = fig.get_size_inches() * dpi
        fig.set_size_inches(2 * round(w / 2) / dpi, 2 * round(h / 2) / dpi)
        fig.set_dpi(dpi)
        canvas = fig.canvas
        moving = self._animated()
        self.update(0)
        for a in moving:
            a.set_visible(False)
        canvas.draw()
        background = canvas.copy_from_bbox(fig.bbox)
        for a in moving:
            a.set_visible(True)
        for k in range(self.times.size):
            self.update(k)
            canvas.restore_region(background)
            for a in moving:
                if hasattr(a, "do_3d_projection"):
                    a.do_3d_projection()
                (a.axes or fig).draw_artist(a)
            yield np.asarray(canvas.buffer_rgba())[..., :3].copy()

    def funcanimation(self, fps: float = 20.0):
        """A :class:`matplotlib.animation.FuncAnimation` of the same frames (for a
        notebook: ``HTML(movie.funcanimation().to_jshtml())``); :meth:`save` is faster."""
        from matplotlib.animation import FuncAnimation  # optional: the [pictures] extra

        return FuncAnimation(self.figure, self.update, frames=self.times.size,
                             interval=1000.0 / fps, repeat=False)

    def save(self, path, *, fps: float = 20.0, dpi: float = 80.0, progress=None) -> Path:
        """Write the movie atomically: ``.mp4`` (H.264 through the ffmpeg of the
        imageio-ffmpeg wheel) or ``.gif`` (Pillow); ``progress(i, n)`` after each frame.

        Raises
        ------
        WriterError
            Another suffix.
        MissingDependencyError
            MP4 without imageio-ffmpeg.
        """
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in MOVIE_SUFFIXES:
            raise WriterError(f"unknown movie suffix {path.suffix!r} (use "
                              f"{' or '.join(MOVIE_SUFFIXES)})", path=str(path))
        n = self.times.size

        def frames():
            for i, frame in enumerate(self.frames(dpi)):
                yield frame
                if progress is not None:
                    progress(i, n)

        write = _write_mp4 if suffix == ".mp4" else _write_gif
        return write_atomically(path, lambda tmp: write(tmp, frames(), fps))


def _write_mp4(path: Path, frames, fps: float) -> None:
    try:
        import imageio_ffmpeg  # optional: the [pictures] extra (ffmpeg in a wheel)
    except ImportError:
        raise MissingDependencyError(
            "MP4 needs imageio-ffmpeg: pip install 'attitude-dynamics[pictures]' (or "
            "write a .gif)") from None
    first = next(frames)
    h, w = first.shape[:2]
    writer = imageio_ffmpeg.write_frames(str(path), (w, h), fps=fps, codec="libx264",
                                         macro_block_size=2, quality=6,
                                         output_params=["-preset", "veryfast"])
    writer.send(None)
    try:
        writer.send(first.tobytes())
        for frame in frames:
            writer.send(frame.tobytes())
    finally:
        writer.close()


def _write_gif(path: Path, frames, fps: float) -> None:
    """One palette for every frame (the first frame and the colours of the moving
    artists), so that Pillow stores each frame as its change from the one before."""
    from matplotlib.colors import to_rgb  # optional: the [pictures] extra
    from PIL import Image  # optional: Pillow, with matplotlib in the [pictures] extra

    first = next(frames)
    colours = ("tab:orange", "tab:purple", "m", "k", "tan", "tab:cyan", *_AXIS_COLOURS)
    swatch = (np.array([to_rgb(c) for c in colours]) * 255).astype(np.uint8)
    row = np.resize(swatch.repeat(8, axis=0), (first.shape[1], 3))
    strip = np.broadcast_to(row, (8,) + row.shape)
    palette = Image.fromarray(np.concatenate([first, strip], axis=0)).quantize(
        colors=96, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)

    def indexed(frame):
        return Image.fromarray(frame).quantize(palette=palette, dither=Image.Dither.NONE)

    images = [indexed(first)] + [indexed(f) for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], loop=0,
                   duration=max(20, int(round(1000.0 / fps))), optimize=False)


def terminal_progress(stream=None, *, label: str = "frames"):
    """A ``progress(i, n)`` callback: a bar redrawn in place on a terminal, one line per
    tenth of the frames otherwise.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> report = terminal_progress(out)
    >>> for i in range(20):
    ...     report(i, 20)
    >>> out.getvalue().splitlines()[-1]
    'frames 20/20 (100 %)'
    """
    stream = stream or sys.stderr
    tty = hasattr(stream, "isatty") and stream.isatty()

    def report(i: int, n: int) -> None:
        done = i + 1
        if tty:
            bar = "#" * (30 * done // n)
            stream.write(f"\r{label} [{bar:<30}] {done}/{n}")
            if done == n:
                stream.write("\n")
        elif done == n or (10 * done // n) != (10 * i // n):
            stream.write(f"{label} {done}/{n} ({100 * done // n} %)\n")
        stream.flush()

    return report


def animate(eph, path, *, poinsot: bool = True, fps: float = 20.0,
            duration: float | None = None, span=None, shape=None,
            body_index: int | None = None, dpi: float = 80.0, figsize=(12.0, 4.5),
            progress=None) -> Path:
    """Write a movie of the ephemeris (what :meth:`Ephemeris.animate
    <attitude.model.ephemeris.Ephemeris.animate>` and ``attitude animate`` do).

    Parameters
    ----------
    eph : Ephemeris
    path : str or path-like
        ``.mp4`` or ``.gif``; written atomically.
    poinsot : bool
        Add the panel of Poinsot's construction (needs the inertia).
    fps, duration, span
        Frames per second, length of the movie (s) and times shown (s since the epoch):
        :func:`~attitude.pictures.motion.frame_times` (default: three turns of the longest
        period, 24 frames per shortest).
    shape : Polyhedron, optional
        The body's shape in the body frame.
    body_index : int, optional
        The body of a batch ephemeris.
    dpi, figsize
        Pixels per inch and the figure size (inches).
    progress : callable or bool, optional
        ``progress(i, n)`` after each frame; ``True`` for :func:`terminal_progress` on
        stderr; ``None``/``False`` for nothing.

    Returns
    -------
    Path

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np, attitude as att
    >>> from scipy.spatial.transform import Rotation
    >>> from PIL import Image
    >>> body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    >>> state = att.AttitudeState("2029-04-13", Rotation.identity(), [0.02, 0.0, 0.1])
    >>> eph = att.propagate(body, state, np.linspace(0.0, 300.0, 31))
    >>> out = animate(eph, pathlib.Path(tempfile.mkdtemp()) / "spin.gif", fps=4,
    ...               duration=1.0, dpi=30)
    >>> Image.open(out).n_frames
    4
    """
    if progress is True:
        progress = terminal_progress()
    times = frame_times(eph, fps=fps, duration=duration, span=span, body_index=body_index)
    movie = PoinsotAnimation(eph, times, poinsot=poinsot, shape=shape,
                             body_index=body_index, figsize=figsize)
    return movie.save(path, fps=fps, dpi=dpi, progress=progress or None)
