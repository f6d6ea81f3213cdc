"""Off-screen pictures of particle fields: PNG snapshots and animated GIFs.

Plain pictures of points and one scalar. The pictures of a run (axes in metres, the field's
unit, walls apart from the fluid, the time) are drawn by :mod:`mlsgalerkin.io.render_frames`
and :mod:`mlsgalerkin.io.render_run`.

Two backends draw a frame (an RGB image):

``"pyvista"``
    VTK through :class:`pyvista.Plotter` with ``off_screen=True``: particles as shaded
    spheres (``render_points_as_spheres``), a scalar bar, the title (with the time) on top;
    2D data seen flat, the camera looking down ``z`` (``view_xy``, parallel projection).
    Without a display the VTK wheels (>= 9.4) render through EGL, or OSMesa when EGL is
    unavailable; no X server or GPU is needed when Mesa's ``libEGL`` is installed.
``"matplotlib"``
    A scatter plot with a colour bar on an Agg canvas (3D data on a 3D axis). Always works.

``backend="auto"`` (the default) uses pyvista when off-screen rendering works and falls back
to matplotlib, logging a warning, otherwise. Whether VTK can render is checked once per
process in a child process (:func:`offscreen_backend`), because a VTK that cannot create an
OpenGL context may abort the interpreter instead of raising. On Linux without ``DISPLAY`` or
``WAYLAND_DISPLAY`` the check first tries EGL and, if that works, sets
``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` for this process (never overriding a value the
user set): VTK then skips its failing attempt to reach an X server (a logged
"bad X server connection" warning and about two seconds per process).

Images are encoded with Pillow (PNG, and GIF frames quantised to 256 colours each) and written
atomically. pyvista and matplotlib are imported inside the functions, so importing
:mod:`mlsgalerkin` stays fast.
"""

from __future__ import annotations

import functools
import io
import logging
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

from mlsgalerkin.io.files import atomic_write

__all__ = [
    "offscreen_backend",
    "render_animation",
    "render_snapshot",
    "render_vtu_series",
]

logger = logging.getLogger(__name__)

_BACKENDS = ("auto", "pyvista", "matplotlib")

_PROBE = """
import numpy as np, pyvista as pv
pl = pv.Plotter(off_screen=True, window_size=(64, 48))
pl.set_background("black")
pl.add_mesh(pv.Sphere(), color="white")
window = type(pl.ren_win).__name__
img = pl.screenshot(return_img=True)
pl.close()
ok = img is not None and img.shape[:2] == (48, 64) and float(np.std(img)) > 0.0
print("RENDER_OK" if ok else "RENDER_BLANK", window)
"""


# ------------------------------------------------------------------------------------------
# backend selection
# ------------------------------------------------------------------------------------------


def _probe(window: str | None) -> tuple[bool, str]:
    """Run the off-screen probe in a child process; ``(works, detail)``."""
    env = dict(os.environ)
    if window is not None:
        env["VTK_DEFAULT_OPENGL_WINDOW"] = window
    try:
        out = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                             timeout=120, env=env)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, f"{type(exc).__name__}: {exc}"
    lines = out.stdout.strip().splitlines()
    if out.returncode == 0 and lines and lines[-1].startswith("RENDER_OK"):
        return True, lines[-1].split(" ", 1)[-1]
    tail = (out.stderr.strip().splitlines() or lines or ["no output"])[-1]
    return False, f"exit code {out.returncode}: {tail}"


@functools.lru_cache(maxsize=1)
def offscreen_backend() -> str:
    """``"pyvista"`` if VTK can render off screen here, else ``"matplotlib"`` (cached).

    See the module docstring for how this is checked and for the ``VTK_DEFAULT_OPENGL_WINDOW``
    setting it may make.
    """
    candidates: list[str | None] = [None]
    headless_linux = sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    )
    if headless_linux and not os.environ.get("VTK_DEFAULT_OPENGL_WINDOW"):
        candidates = ["vtkEGLRenderWindow", None]
    details = []
    for window in candidates:
        ok, detail = _probe(window)
        if ok:
            if window is not None:
                os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = window
            logger.info("off-screen rendering with pyvista/VTK (%s)", detail)
            return "pyvista"
        details.append(f"{window or 'VTK default window'}: {detail}")
    logger.warning(
        "pyvista off-screen rendering does not work here (%s); rendering with matplotlib "
        "instead", "; ".join(details),
    )
    return "matplotlib"


def _backend(backend: str) -> str:
    if backend not in _BACKENDS:
        raise ValueError(f"backend must be one of {_BACKENDS}, got {backend!r}")
    if backend == "matplotlib":
        return backend
    found = offscreen_backend()
    if backend == "pyvista" and found != "pyvista":
        raise RuntimeError(
            "backend='pyvista' was requested but VTK cannot render off screen here (see the "
            "logged warning); use backend='auto' or 'matplotlib'"
        )
    return found


# ------------------------------------------------------------------------------------------
# input checking
# ------------------------------------------------------------------------------------------


def _prepare(points: np.ndarray, scalars: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``(points (n, 3) float64, scalars (n,) float64)``; ValueError on bad shapes."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or pts.shape[0] == 0:
        raise ValueError(f"{what}: points must have shape (n, 2) or (n, 3) with n >= 1, got "
                         f"{pts.shape}")
    s = np.asarray(scalars)
    if s.dtype == np.bool_:
        s = s.astype(np.float64)
    if s.shape != (pts.shape[0],):
        raise ValueError(f"{what}: scalars must have shape ({pts.shape[0]},) (one value per "
                         f"point), got {s.shape}; for a vector field pass its magnitude")
    s = np.asarray(s, dtype=np.float64)
    if pts.shape[1] == 2:
        pts = np.concatenate([pts, np.zeros((pts.shape[0], 1))], axis=1)
    return pts, s


def _is_flat(points3: Sequence[np.ndarray]) -> bool:
    return all(float(np.ptp(p[:, 2])) == 0.0 for p in points3)


def _clim(scalars: Sequence[np.ndarray], clim: tuple[float, float] | None) -> tuple[float, float]:
    if clim is not None:
        lo, hi = (float(c) for c in clim)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"clim must be (low, high) finite with low < high, got {clim!r}")
        return lo, hi
    finite = [s[np.isfinite(s)] for s in scalars]
    finite = [f for f in finite if f.size]
    if not finite:
        return 0.0, 1.0
    lo = min(float(f.min()) for f in finite)
    hi = max(float(f.max()) for f in finite)
    if lo == hi:
        pad = 0.5 * abs(lo) if lo != 0.0 else 0.5
        lo, hi = lo - pad, hi + pad
    return lo, hi


def _bounds(
    points3: Sequence[np.ndarray], bounds: Sequence[float] | None, flat: bool
) -> tuple[float, float, float, float, float, float]:
    """``(xmin, xmax, ymin, ymax, zmin, zmax)``: given (4 or 6 numbers) or data + 5 % margin."""
    if bounds is not None:
        b = [float(v) for v in bounds]
        if len(b) == 4:
            b += [0.0, 0.0]
        if len(b) != 6 or not all(math.isfinite(v) for v in b) or any(
            b[2 * i] > b[2 * i + 1] for i in range(3)
        ):
            raise ValueError(
                f"bounds must be (xmin, xmax, ymin, ymax) or (xmin, xmax, ymin, ymax, zmin, "
                f"zmax) with finite min <= max, got {bounds!r}"
            )
        return tuple(b)  # type: ignore[return-value]
    allp = np.concatenate([p[np.all(np.isfinite(p), axis=1)] for p in points3])
    if allp.size == 0:
        return (0.0, 1.0, 0.0, 1.0, 0.0, 0.0 if flat else 1.0)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = float(np.max(hi - lo)) or 1.0
    out = []
    for k in range(3):
        pad = 0.0 if (k == 2 and flat) else 0.05 * span
        out += [float(lo[k]) - pad, float(hi[k]) + pad]
    return tuple(out)  # type: ignore[return-value]


def _window(window_size: Sequence[int]) -> tuple[int, int]:
    w = tuple(int(v) for v in window_size)
    if len(w) != 2 or min(w) < 16:
        raise ValueError(f"window_size must be (width, height) in pixels >= 16, got "
                         f"{window_size!r}")
    return w  # type: ignore[return-value]


# ------------------------------------------------------------------------------------------
# one frame -> RGB image (h, w, 3) uint8
# ------------------------------------------------------------------------------------------


def _frame_pyvista(pts, s, *, flat, title, clim, cmap, point_size, window_size, bounds,
                   scalar_name) -> np.ndarray:
    import pyvista as pv

    pl = pv.Plotter(off_screen=True, window_size=list(window_size))
    try:
        pl.set_background("white")
        cloud = pv.PolyData(pts)
        cloud.point_data[scalar_name] = s
        pl.add_mesh(
            cloud, scalars=scalar_name, cmap=cmap, clim=list(clim), nan_color="lightgrey",
            point_size=float(point_size), render_points_as_spheres=True,
            scalar_bar_args={"title": scalar_name, "color": "black", "fmt": "%.3g",
                             "vertical": True, "position_x": 0.86, "position_y": 0.1,
                             "width": 0.06, "height": 0.7},
        )
        if title:
            pl.add_text(title, position="upper_edge", font_size=10, color="black")
        if flat:
            _flat_camera(pl, bounds, window_size)
        else:
            pl.view_isometric()
            pl.reset_camera(bounds=bounds)
            pl.camera.zoom(1.2)
        img = pl.screenshot(return_img=True)
    finally:
        pl.close()
    return np.ascontiguousarray(np.asarray(img)[..., :3], dtype=np.uint8)


def _flat_camera(pl, bounds, window_size) -> None:
    """Parallel view down ``z`` fitting ``bounds`` into the part of the window left free by
    the title (top) and the scalar bar (right)."""
    x0, x1, y0, y1, z0, _ = bounds
    aspect = window_size[0] / window_size[1]
    free_x, free_y = 0.80, 0.84  # window fractions available to the particles
    scale = max((y1 - y0) / (2 * free_y), (x1 - x0) / (2 * aspect * free_x)) or 1.0
    fx = 0.5 * (x0 + x1) + (0.5 - 0.42) * 2 * scale * aspect  # data centred at 42 % width
    fy = 0.5 * (y0 + y1) + (0.5 - 0.46) * 2 * scale  # and a little below the middle
    pl.enable_parallel_projection()
    cam = pl.camera
    cam.focal_point = (fx, fy, z0)
    cam.position = (fx, fy, z0 + 10.0 * scale)
    cam.up = (0.0, 1.0, 0.0)
    cam.parallel_scale = scale
    pl.renderer.ResetCameraClippingRange()


def _frame_matplotlib(pts, s, *, flat, title, clim, cmap, point_size, window_size, bounds,
                      scalar_name) -> np.ndarray:
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    cmap = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    cmap = cmap.with_extremes(bad="lightgrey")

    dpi = 100
    fig = Figure(figsize=(window_size[0] / dpi, window_size[1] / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    size = (0.72 * float(point_size)) ** 2  # pixel diameter -> points^2
    kw = dict(c=s, cmap=cmap, vmin=clim[0], vmax=clim[1], s=size, linewidths=0,
              plotnonfinite=True)
    if flat:
        ax = fig.add_subplot()
        sc = ax.scatter(pts[:, 0], pts[:, 1], **kw)
        ax.set_xlim(bounds[0], bounds[1])
        ax.set_ylim(bounds[2], bounds[3])
        ax.set_aspect("equal", adjustable="box")
    else:
        ax = fig.add_subplot(projection="3d")
        sc = ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], **kw)
        ax.set_xlim(bounds[0], bounds[1])
        ax.set_ylim(bounds[2], bounds[3])
        ax.set_zlim(bounds[4], bounds[5])
    fig.colorbar(sc, ax=ax, label=scalar_name)
    if title:
        ax.set_title(title)
    canvas.draw()
    return np.array(canvas.buffer_rgba())[..., :3]


def _frame(backend: str, pts: np.ndarray, s: np.ndarray, **kw) -> np.ndarray:
    if backend == "pyvista":
        return _frame_pyvista(pts, s, **kw)
    return _frame_matplotlib(pts, s, **kw)


def _title(title: str, time: float | None) -> str:
    if time is None:
        return title
    stamp = f"t = {float(time):.6g} s"
    return f"{title}   {stamp}" if title else stamp


# ------------------------------------------------------------------------------------------
# public functions
# ------------------------------------------------------------------------------------------


def render_snapshot(
    path: str | Path,
    points: np.ndarray,
    scalars: np.ndarray,
    *,
    title: str = "",
    time: float | None = None,
    scalar_name: str = "value",
    clim: tuple[float, float] | None = None,
    cmap: str = "viridis",
    point_size: float = 8.0,
    window_size: tuple[int, int] = (800, 400),
    bounds: Sequence[float] | None = None,
    backend: str = "auto",
) -> Path:
    """Render particles coloured by a scalar to a PNG file (atomically); returns the path.

    Parameters
    ----------
    path : str or Path
        Target ``.png``; its directory must exist.
    points : ndarray, shape (n, d), d in {2, 3}
        Positions [m]. 2D data (or 3D data with one constant ``z``) are shown flat.
    scalars : ndarray, shape (n,)
        Colour values (any unit; ``nan`` drawn grey).
    title : str
        Title text; ``time`` [s], if given, is appended as ``t = ... s``.
    scalar_name : str
        Colour-bar label.
    clim : (float, float), optional
        Colour range; default the data's finite min/max.
    cmap : str
        Matplotlib colour-map name.
    point_size : float
        Particle diameter [pixels].
    window_size : (int, int)
        Image ``(width, height)`` [pixels].
    bounds : sequence of 4 or 6 floats, optional
        ``(xmin, xmax, ymin, ymax[, zmin, zmax])`` to frame; default the data + 5 %.
    backend : {"auto", "pyvista", "matplotlib"}
        See the module docstring.
    """
    from PIL import Image

    pts, s = _prepare(points, scalars, "render_snapshot")
    flat = _is_flat([pts])
    which = _backend(backend)
    img = _frame(which, pts, s, flat=flat, title=_title(title, time), clim=_clim([s], clim),
                 cmap=cmap, point_size=point_size, window_size=_window(window_size),
                 bounds=_bounds([pts], bounds, flat), scalar_name=scalar_name or "value")
    buf = io.BytesIO()
    Image.fromarray(img, mode="RGB").save(buf, format="PNG")
    atomic_write(path, buf.getvalue())
    logger.debug("rendered %s with %s", path, which)
    return Path(path)


def render_animation(
    path_gif: str | Path,
    frames: Sequence[tuple[float, np.ndarray, np.ndarray]],
    *,
    fps: float = 10.0,
    title: str = "",
    scalar_name: str = "value",
    clim: tuple[float, float] | None = None,
    cmap: str = "viridis",
    point_size: float = 8.0,
    window_size: tuple[int, int] = (800, 400),
    bounds: Sequence[float] | None = None,
    backend: str = "auto",
) -> Path:
    """Render ``(time, points, scalars)`` frames to an animated GIF (atomically).

    The colour range and the framed region are the same for all frames (by default the
    union over all frames), so colours and positions can be compared across the animation.
    Each frame's title ends with its time. Parameters are those of :func:`render_snapshot`,
    plus:

    Parameters
    ----------
    path_gif : str or Path
        Target ``.gif``; its directory must exist.
    frames : sequence of (float, ndarray (n_k, d), ndarray (n_k,))
        Time [s], positions [m] and colour values of each frame; ``n_k`` may vary.
    fps : float
        Frames per second (GIF delays are whole milliseconds). Identical consecutive
        pictures are merged into one longer GIF frame by the encoder.

    Returns
    -------
    Path
        ``path_gif``.
    """
    from PIL import Image

    frames = list(frames)
    if not frames:
        raise ValueError("render_animation: frames is empty; pass at least one "
                         "(time, points, scalars) tuple")
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"render_animation: fps must be a positive number, got {fps!r}")
    prepared = []
    for k, item in enumerate(frames):
        if len(item) != 3:
            raise ValueError(f"render_animation: frame {k} must be (time, points, scalars)")
        t, p, s = item
        prepared.append((float(t), *_prepare(p, s, f"render_animation frame {k}")))
    pts_all = [p for _, p, _ in prepared]
    flat = _is_flat(pts_all)
    common = dict(flat=flat, clim=_clim([s for _, _, s in prepared], clim), cmap=cmap,
                  point_size=point_size, window_size=_window(window_size),
                  bounds=_bounds(pts_all, bounds, flat), scalar_name=scalar_name or "value")
    which = _backend(backend)
    images = []
    for t, p, s in prepared:
        rgb = _frame(which, p, s, title=_title(title, t), **common)
        images.append(Image.fromarray(rgb, mode="RGB").quantize(colors=256))
    buf = io.BytesIO()
    images[0].save(buf, format="GIF", save_all=True, append_images=images[1:],
                   duration=max(int(round(1000.0 / fps)), 10), loop=0)
    atomic_write(path_gif, buf.getvalue())
    logger.debug("rendered %s (%d frames) with %s", path_gif, len(images), which)
    return Path(path_gif)


def render_vtu_series(
    pvd_path: str | Path,
    scalar_name: str,
    out_gif: str | Path,
    *,
    component: int | None = None,
    fps: float = 10.0,
    title: str = "",
    clim: tuple[float, float] | None = None,
    cmap: str = "viridis",
    point_size: float = 8.0,
    window_size: tuple[int, int] = (800, 400),
    bounds: Sequence[float] | None = None,
    backend: str = "auto",
) -> Path:
    """Animate one field of a ``.pvd`` series (e.g. from :class:`~mlsgalerkin.io.PVDSeries`).

    Parameters
    ----------
    pvd_path : str or Path
        The ``.pvd`` collection.
    scalar_name : str
        Name of a ``point_data`` array present in every frame.
    out_gif : str or Path
        Target ``.gif``.
    component : int, optional
        For a multi-component array: the component to show; default its Euclidean norm
        (e.g. the speed for a velocity).

    Other parameters are those of :func:`render_animation`. Series written in 2D (``z = 0``)
    are shown flat.
    """
    from mlsgalerkin.io.vtk import read_pvd, read_vtu

    listed = read_pvd(pvd_path)
    if not listed:
        raise ValueError(f"{pvd_path} lists no frames; nothing to animate")
    frames = []
    multi = False
    for t, f in listed:
        pts, data = read_vtu(f)
        if scalar_name not in data:
            raise ValueError(f"{f} has no point_data {scalar_name!r}; available: "
                             f"{sorted(data)}")
        v = np.asarray(data[scalar_name], dtype=np.float64)
        if v.ndim == 2:
            multi = True
            if component is None:
                v = np.linalg.norm(v, axis=1)
            elif -v.shape[1] <= component < v.shape[1]:
                v = v[:, component]
            else:
                raise ValueError(f"component {component} out of range for {scalar_name!r} "
                                 f"with {v.shape[1]} components")
        frames.append((t, pts, v))
    if not multi:
        label = scalar_name
    elif component is None:
        label = f"|{scalar_name}|"
    else:
        label = f"{scalar_name}[{component}]"
    return render_animation(out_gif, frames, fps=fps, title=title, scalar_name=label,
                            clim=clim, cmap=cmap, point_size=point_size,
                            window_size=window_size, bounds=bounds, backend=backend)
