r"""Pictures of particle frames that a reader can interpret without the code (matplotlib, Agg).

Every picture has axes in metres (``x (m)``, ``y (m)``), the time in seconds
(``t = 0.1234 s``), a colour bar naming the field and its unit (or, for a categorical field
such as the phase, a legend of its categories), and the walls drawn apart from the fluid:
grey, smaller and never colour-mapped, so a wall's extrapolated pressure or velocity cannot
be mistaken for the fluid's. Field labels, units and colour maps come from
:mod:`mlsgalerkin.plots.fields`.

All frames of one picture share a :class:`FrameView` (the colour range, the categories, the
framed region, the particle spacing), so colours and positions compare across the frames of
a panel or an animation, and every frame of an animation has the same size. Particles are drawn
as discs of about one particle spacing on screen (the spacing is estimated from the first
frame).

The figure is laid out from the data's aspect ratio: the axes keep equal scales in ``x`` and
``y`` and the figure is sized around them (no empty margins); a flat domain (a long wave tank)
gets its colour bar below the axes instead of beside them.

Why matplotlib: pyvista/VTK renders off screen here (EGL), but its axes annotations in a flat
2D view overlap their tick labels and log VTK errors, and a frame took 0.33 s against 0.09 s
with matplotlib for 5000 particles (measured 2026-11-30); the particles are points in a plane,
which matplotlib draws exactly.

>>> import numpy as np
>>> pts = np.array([[0.0, 0.0], [0.01, 0.0], [0.0, 0.01], [0.05, 0.05]])
>>> data = {"pressure": np.array([0.0, 10.0, 20.0, 0.0]), "is_wall": np.array([0, 0, 0, 1])}
>>> view = frame_view([(0.25, pts, data)], "pressure", title="demo")
>>> fig = frame_figure(view, [(0.25, pts, data)])
>>> fig.axes[0].get_xlabel(), fig.axes[0].get_title(loc="right"), fig.axes[1].get_ylabel()
('x (m)', 't = 0.2500 s', 'pressure (Pa)')
"""

from __future__ import annotations

import io
import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mlsgalerkin.io.files import atomic_write
from mlsgalerkin.plots.fields import FieldStyle, resolve_field

__all__ = [
    "STRUCTURE_COLOR",
    "WALL_COLOR",
    "Frame",
    "with_structure",
    "FrameView",
    "figure_png",
    "figure_rgb",
    "frame_figure",
    "frame_view",
    "time_text",
    "write_gif",
]

logger = logging.getLogger(__name__)

#: One frame: time (s), positions ``(n, 2)`` or ``(n, 3)`` (m), point data by name.
Frame = tuple[float, np.ndarray, Mapping[str, np.ndarray]]

#: Colour of the wall particles (never colour-mapped).
WALL_COLOR = "0.62"
#: Colour of a structure's nodes (``is_structure`` points; never colour-mapped).
STRUCTURE_COLOR = "#3a2e8c"
#: Colour of fluid particles whose value is not finite.
_BAD_COLOR = "black"

# layout, in inches
_LEFT, _BOTTOM, _TOP, _SUPTITLE = 0.75, 0.5, 0.36, 0.34
_GAP_X, _GAP_Y = 0.8, 0.72
_KEY_RIGHT = {"colorbar": 1.45, "legend": 2.0}
_KEY_BOTTOM = 0.85        # extra height for a horizontal colour bar or legend under the axes
_KEY_BAR_Y = 0.52         # bottom of a horizontal colour bar (in); its label goes below it
_FLAT = 1.6               # below this plot height (in) the key goes under the axes
_MAX_HEIGHT = {1: 4.8, 2: 3.2}


@dataclass(frozen=True)
class FrameView:
    """What every frame of one picture shares.

    Attributes
    ----------
    field : str
        The colour field (as given to :func:`~mlsgalerkin.plots.fields.resolve_field`).
    style : FieldStyle
        Its label, unit and colour map.
    clim : (float, float)
        Colour range (continuous fields) in the field's unit.
    extend : str
        Colour-bar arrows for values beyond ``clim``: ``neither``, ``min``, ``max``, ``both``.
    categories : tuple of int
        Category values present in the fluid of any frame (categorical fields).
    bounds : (float, float, float, float)
        ``(xmin, xmax, ymin, ymax)`` framed (m).
    spacing : float
        Particle spacing (m), for the size of the discs.
    flat : bool
        2D data (or 3D data with one constant ``z``): drawn in the ``x``–``y`` plane.
    title : str
        Left-hand title (e.g. the problem's name).
    dim : int
        2 or 3 (for the names of vector components).
    """

    field: str
    style: FieldStyle
    clim: tuple[float, float]
    extend: str
    categories: tuple[int, ...]
    bounds: tuple[float, float, float, float]
    spacing: float
    flat: bool
    title: str = ""
    dim: int = 2


def time_text(t: float) -> str:
    """The time label of a frame: ``"t = 0.1234 s"`` (``"t = 5e-05 s"`` below 10 ms)."""
    t = float(t)
    if t != 0.0 and abs(t) < 0.01:
        return f"t = {t:.3g} s"
    return f"t = {t:.4f} s"


def with_structure(frame: Frame, points: np.ndarray) -> Frame:
    """``frame`` with a structure's node ``points`` appended: flagged ``is_structure`` and
    ``is_wall`` (drawn in :data:`STRUCTURE_COLOR`, never colour-mapped), every other field padded
    with NaN (zero for integer fields)."""
    t, pts, data = frame
    spts = np.asarray(points, dtype=float)[:, : pts.shape[1]]
    n, m = len(pts), len(spts)
    merged: dict[str, np.ndarray] = {}
    for key, value in data.items():
        v = np.asarray(value)
        pad = np.zeros((m, *v.shape[1:]), dtype=v.dtype) if v.dtype.kind in "iub" else np.full((m, *v.shape[1:]), np.nan)
        merged[key] = np.concatenate([v, pad.astype(v.dtype) if v.dtype.kind in "iub" else pad])
    merged["is_wall"] = np.concatenate([np.asarray(data.get("is_wall", np.zeros(n)), dtype=np.int32).reshape(-1),
                                        np.ones(m, dtype=np.int32)])
    merged["is_structure"] = np.concatenate([np.zeros(n, dtype=np.int32), np.ones(m, dtype=np.int32)])
    return t, np.concatenate([pts, spts]), merged


def _wall_mask(data: Mapping[str, np.ndarray], n: int) -> np.ndarray:
    flag = data.get("is_wall")
    return np.zeros(n, dtype=bool) if flag is None else np.asarray(flag).reshape(-1).astype(bool)


def _points(points: np.ndarray, what: str) -> np.ndarray:
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or pts.shape[0] == 0:
        raise ValueError(f"{what}: points must have shape (n, 2) or (n, 3) with n >= 1, got {pts.shape}")
    return pts


def _estimate_spacing(pts: np.ndarray) -> float:
    """Median nearest-neighbour distance of (up to 4000 of) the points (m)."""
    from scipy.spatial import cKDTree

    if len(pts) < 2:
        return 0.0
    sample = pts[:: max(1, len(pts) // 4000)]
    dist, _ = cKDTree(pts).query(sample, k=2)
    d = dist[:, 1]
    d = d[d > 0]
    return float(np.median(d)) if d.size else 0.0


def _color_range(values: np.ndarray, style: FieldStyle,
                 clim: tuple[float, float] | None) -> tuple[tuple[float, float], str]:
    finite = values[np.isfinite(values)]
    if clim is not None:
        lo, hi = float(clim[0]), float(clim[1])
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"clim must be two finite numbers with clim[0] < clim[1], got {clim!r}")
    elif finite.size == 0:
        lo, hi = 0.0, 1.0
    else:
        # the 0.5th to 99.5th percentile: a few extreme particles do not wash out the picture
        lo, hi = (float(v) for v in np.percentile(finite, [0.5, 99.5]))
        if style.center is not None:
            half = max(abs(hi - style.center), abs(lo - style.center))
            lo, hi = style.center - half, style.center + half
        if hi - lo <= 1e-12 * max(1.0, abs(lo), abs(hi)):
            pad = 0.01 * abs(lo) if lo != 0.0 else 1.0
            lo, hi = (lo, lo + 2 * pad) if finite.min() >= 0 and lo >= 0 and style.center is None \
                else (lo - pad, hi + pad)
    below = finite.size > 0 and finite.min() < lo
    above = finite.size > 0 and finite.max() > hi
    extend = {(False, False): "neither", (True, False): "min", (False, True): "max", (True, True): "both"}
    return (lo, hi), extend[(bool(below), bool(above))]


def frame_view(
    frames: Sequence[Frame],
    color_by: str,
    *,
    title: str = "",
    clim: tuple[float, float] | None = None,
    bounds: Sequence[float] | None = None,
    spacing: float | None = None,
) -> FrameView:
    """The :class:`FrameView` shared by ``frames``, coloured by the field ``color_by``.

    Parameters
    ----------
    frames : sequence of (float, ndarray (n_k, 2|3), mapping)
        Time (s), positions (m) and point data of each frame (``is_wall`` marks the walls).
    color_by : str
        A field of the point data (see :mod:`mlsgalerkin.plots.fields`); a missing one
        raises :class:`ValueError` listing the available fields.
    title : str
        Left-hand title of each frame.
    clim : (float, float), optional
        Colour range in the field's unit; default the fluid's 0.5th to 99.5th percentile over all
        frames (symmetric about the field's centre, e.g. zero for a velocity component).
    bounds : (xmin, xmax, ymin, ymax), optional
        Region to frame (m); default the fluid of all frames and four spacings around it (the
        walls next to it), within all particles plus one spacing.
    spacing : float, optional
        Particle spacing (m); default the median nearest-neighbour distance in the first frame.
    """
    frames = list(frames)
    if not frames:
        raise ValueError("no frames to draw; pass at least one (time, points, point_data)")
    values, fluid_pts, all_pts = [], [], []
    style = None
    dim = 2
    for k, (t, points, data) in enumerate(frames):
        pts = _points(points, f"frame {k}")
        if pts.shape[1] == 3 and float(np.ptp(pts[:, 2])) > 0.0:
            dim = 3
        all_pts.append(pts)
        v, style = resolve_field(data, color_by, dim)
        if v.shape != (len(pts),):
            raise ValueError(f"frame {k}: field {color_by!r} has {v.shape[0]} values for {len(pts)} points")
        fluid = ~_wall_mask(data, len(pts))
        values.append(v[fluid])
        fluid_pts.append(pts[fluid])
    vals = np.concatenate(values)
    categories: tuple[int, ...] = ()
    if style.categorical:
        finite = vals[np.isfinite(vals)]
        categories = tuple(int(c) for c in np.unique(np.round(finite)))
        crange, extend = (0.0, 1.0), "neither"
    else:
        crange, extend = _color_range(vals, style, clim)
    if spacing is None:
        first = fluid_pts[0] if len(fluid_pts[0]) >= 2 else all_pts[0]
        spacing = _estimate_spacing(first)
    if bounds is None:
        stacked = np.concatenate(all_pts)
        lo, hi = stacked.min(axis=0), stacked.max(axis=0)
        pad = spacing if spacing > 0 else 0.02 * float(np.max(hi - lo) or 1.0)
        lo, hi = lo - pad, hi + pad
        fluid = np.concatenate(fluid_pts)
        if len(fluid):  # frame the fluid and the walls next to it (four spacings), not empty tank
            lo = np.maximum(lo, fluid.min(axis=0) - 4 * pad)
            hi = np.minimum(hi, fluid.max(axis=0) + 4 * pad)
        bounds = (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
    bounds = tuple(float(b) for b in bounds)
    if len(bounds) != 4 or not (bounds[0] < bounds[1] and bounds[2] < bounds[3]):
        raise ValueError(f"bounds must be (xmin, xmax, ymin, ymax) with xmin < xmax, ymin < ymax, got {bounds!r}")
    return FrameView(field=color_by, style=style, clim=crange, extend=extend, categories=categories,
                     bounds=bounds, spacing=float(spacing), flat=dim == 2, title=title, dim=dim)


# ------------------------------------------------------------------------------------------
# layout
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Layout:
    size: tuple[float, float]                       # figure (in)
    axes: list[tuple[float, float, float, float]]   # each panel, figure fractions
    key: tuple[float, float, float, float]          # colour bar or legend anchor, fractions
    key_side: str                                   # "right" or "bottom"
    points_per_metre: float


def _layout(view: FrameView, rows: int, cols: int, width: float, suptitle: bool) -> _Layout:
    xmin, xmax, ymin, ymax = view.bounds
    xr, yr = xmax - xmin, ymax - ymin
    kind = "legend" if view.style.categorical else "colorbar"
    top = _TOP + (_SUPTITLE if suptitle else 0.0)
    max_h = _MAX_HEIGHT[min(rows, 2)]

    def panel(right: float) -> tuple[float, float]:
        pw = (width - _LEFT - right - (cols - 1) * _GAP_X) / cols
        ph = pw * yr / xr
        if ph > max_h:
            ph, pw = max_h, max_h * xr / yr
        return pw, ph

    pw, ph = panel(_KEY_RIGHT[kind])
    side = "right"
    if rows * ph + (rows - 1) * _GAP_Y < _FLAT:
        side = "bottom"
        pw, ph = panel(0.35)
    right = _KEY_RIGHT[kind] if side == "right" else 0.35
    bottom = _BOTTOM + (_KEY_BOTTOM if side == "bottom" else 0.0)
    W = _LEFT + cols * pw + (cols - 1) * _GAP_X + right
    H = bottom + rows * ph + (rows - 1) * _GAP_Y + top
    rects = []
    for r in range(rows):
        for c in range(cols):
            x0 = _LEFT + c * (pw + _GAP_X)
            y0 = bottom + (rows - 1 - r) * (ph + _GAP_Y)
            rects.append((x0 / W, y0 / H, pw / W, ph / H))
    plot_h = rows * ph + (rows - 1) * _GAP_Y
    if side == "right":
        x0 = _LEFT + cols * pw + (cols - 1) * _GAP_X + 0.15
        key = (x0 / W, bottom / H, 0.15 / W, plot_h / H)
    else:
        span = cols * pw + (cols - 1) * _GAP_X
        key = ((_LEFT + 0.15 * span) / W, _KEY_BAR_Y / H, 0.7 * span / W, 0.12 / H)
    return _Layout((W, H), rects, key, side, pw * 72.0 / xr)


# ------------------------------------------------------------------------------------------
# drawing
# ------------------------------------------------------------------------------------------


def _palette(view: FrameView) -> dict[int, tuple[float, ...]]:
    import matplotlib

    cmap = matplotlib.colormaps[view.style.cmap]
    n = getattr(cmap, "N", 256)
    if n <= 20:  # a qualitative map: one colour each, in order
        return {c: cmap(i % n) for i, c in enumerate(view.categories)}
    m = max(len(view.categories) - 1, 1)
    return {c: cmap(i / m) for i, c in enumerate(view.categories)}


def _draw(ax, view: FrameView, frame: Frame, disc: float, palette, title: str) -> object:
    """Draw one frame on ``ax``; returns the fluid's colour-mapped collection (or None)."""
    import matplotlib

    t, points, data = frame
    pts = _points(points, "frame")
    values, _ = resolve_field(data, view.field, view.dim)
    wall = _wall_mask(data, len(pts))
    fluid = ~wall
    flag = data.get("is_structure")
    structure = np.zeros(len(pts), dtype=bool) if flag is None else np.asarray(flag).reshape(-1).astype(bool)
    wall &= ~structure
    coords = (lambda sel: (pts[sel, 0], pts[sel, 1])) if view.flat else \
        (lambda sel: (pts[sel, 0], pts[sel, 1], pts[sel, 2]))
    if wall.any():
        ax.scatter(*coords(wall), s=(0.7 * disc) ** 2, color=WALL_COLOR, linewidths=0, zorder=1,
                   label="wall particles")
    if structure.any():
        ax.scatter(*coords(structure), s=(0.45 * disc) ** 2, color=STRUCTURE_COLOR, linewidths=0, zorder=3,
                   label="structure")
    mappable = None
    if fluid.any():
        v = values[fluid]
        if view.style.categorical:
            colors = [palette.get(int(round(x)), (0.0, 0.0, 0.0, 1.0)) if np.isfinite(x) else _BAD_COLOR
                      for x in v]
            ax.scatter(*coords(fluid), s=disc**2, color=colors, linewidths=0, zorder=2, label="fluid particles")
        else:
            cmap = matplotlib.colormaps[view.style.cmap].with_extremes(bad=_BAD_COLOR)
            mappable = ax.scatter(*coords(fluid), s=disc**2, c=v, cmap=cmap,
                                  norm=matplotlib.colors.Normalize(*view.clim), linewidths=0, zorder=2,
                                  plotnonfinite=True, label="fluid particles")
    xmin, xmax, ymin, ymax = view.bounds
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if view.flat:
        ax.set_aspect("equal", adjustable="box")
    else:
        ax.set_zlabel("z (m)")
    if title:
        ax.set_title(title, loc="left", fontsize=10)
    ax.set_title(time_text(t), loc="right", fontsize=10)
    return mappable


def _key(fig, view: FrameView, layout: _Layout, mappable, palette, has_walls: bool) -> None:
    """The colour bar (or the categories' legend) and the walls' legend entry."""
    from matplotlib.lines import Line2D

    wall_handle = Line2D([], [], marker="o", linestyle="", color=WALL_COLOR, markersize=6,
                         label="wall particles")
    if view.style.categorical:
        handles = [Line2D([], [], marker="o", linestyle="", color=palette[c], markersize=7,
                          label=view.style.category_label(c)) for c in view.categories]
        if has_walls:
            handles.append(wall_handle)
        if layout.key_side == "right":
            x0, y0, w, h = layout.key
            fig.legend(handles=handles, title=view.style.axis_label, loc="upper left",
                       bbox_to_anchor=(x0 - 0.01, y0 + h), frameon=False, fontsize=9, title_fontsize=9)
        else:
            x0, y0, w, h = layout.key
            fig.legend(handles=handles, title=view.style.axis_label, loc="lower center",
                       bbox_to_anchor=(x0 + 0.5 * w, 0.0), ncols=len(handles), frameon=False,
                       fontsize=9, title_fontsize=9)
        return
    import matplotlib
    from matplotlib.cm import ScalarMappable

    if mappable is None:  # no fluid in the frame: still show the range
        mappable = ScalarMappable(norm=matplotlib.colors.Normalize(*view.clim), cmap=view.style.cmap)
    cax = fig.add_axes(layout.key)
    orientation = "vertical" if layout.key_side == "right" else "horizontal"
    fig.colorbar(mappable, cax=cax, orientation=orientation, extend=view.extend, label=view.style.axis_label)
    if has_walls:
        x0, y0, w, h = layout.key
        if layout.key_side == "right":
            fig.legend(handles=[wall_handle], loc="upper left", bbox_to_anchor=(x0 - 0.02, y0 - 0.005),
                       frameon=False, fontsize=8, handletextpad=0.2, borderpad=0.0)
        else:
            fig.legend(handles=[wall_handle], loc="lower left", bbox_to_anchor=(x0 + w + 0.01, y0 - 0.01),
                       frameon=False, fontsize=8, handletextpad=0.2, borderpad=0.0)


def frame_figure(view: FrameView, frames: Sequence[Frame], *, columns: int | None = None,
                 width: float = 8.0, dpi: float = 100.0, suptitle: str = ""):
    """A matplotlib :class:`~matplotlib.figure.Figure` (Agg canvas) of one frame or a panel.

    Parameters
    ----------
    view : FrameView
        From :func:`frame_view` (shared colour range, region, spacing).
    frames : sequence of Frame
        One frame: a single picture; several: a grid of panels with one colour bar.
    columns : int, optional
        Panels per row; default 1 for a domain more than twice as wide as high, else 2.
    width : float
        Figure width (in) before it is fitted to the data's aspect ratio.
    dpi : float
        Pixels per inch of the rendered image.
    suptitle : str
        A heading over all panels.

    The axes are ``fig.axes[:len(frames)]``; each has ``x (m)``/``y (m)`` labels, the time as its
    right-hand title and ``view.title`` as its left-hand title (unless ``suptitle`` is given). The colour bar (continuous
    fields) is the next axes, labelled ``view.style.axis_label``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    frames = list(frames)
    if not frames:
        raise ValueError("frame_figure: no frames; pass at least one")
    xr, yr = view.bounds[1] - view.bounds[0], view.bounds[3] - view.bounds[2]
    if columns is None:
        columns = 1 if (len(frames) == 1 or xr > 2.0 * yr) else 2
    cols = max(1, min(int(columns), len(frames)))
    rows = -(-len(frames) // cols)
    if not view.flat:
        return _figure_3d(view, frames, width, dpi, suptitle)
    layout = _layout(view, rows, cols, width, bool(suptitle))
    fig = Figure(figsize=layout.size, dpi=dpi)
    FigureCanvasAgg(fig)
    disc = float(np.clip(0.95 * view.spacing * layout.points_per_metre, 0.6, 14.0))
    palette = _palette(view) if view.style.categorical else {}
    mappable, has_walls = None, False
    for rect, frame in zip(layout.axes, frames):
        ax = fig.add_axes(rect)
        m = _draw(ax, view, frame, disc, palette, "" if suptitle else view.title)
        if mappable is None:
            mappable = m
        has_walls = has_walls or bool(_wall_mask(frame[2], len(frame[1])).any())
    _key(fig, view, layout, mappable, palette, has_walls)
    if suptitle:
        fig.suptitle(suptitle, y=1.0 - 0.08 / layout.size[1], va="top", fontsize=11)
    return fig


def _figure_3d(view: FrameView, frames: Sequence[Frame], width: float, dpi: float, suptitle: str):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    cols = min(len(frames), 2)
    rows = -(-len(frames) // cols)
    fig = Figure(figsize=(width, 0.8 * width * rows / cols), dpi=dpi)
    FigureCanvasAgg(fig)
    palette = _palette(view) if view.style.categorical else {}
    mappable = None
    for k, frame in enumerate(frames):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        mappable = _draw(ax, view, frame, 3.0, palette, "" if suptitle else view.title) or mappable
    if mappable is not None:
        fig.colorbar(mappable, ax=fig.axes, label=view.style.axis_label, extend=view.extend, shrink=0.7)
    if suptitle:
        fig.suptitle(suptitle)
    return fig


def figure_rgb(fig) -> np.ndarray:
    """The figure rendered to an RGB array ``(height, width, 3)`` of ``uint8``."""
    fig.canvas.draw()
    return np.array(fig.canvas.buffer_rgba())[..., :3]


def _palette_for(rgb: np.ndarray, cmap: str) -> np.ndarray:
    """A palette ``(256, 3)`` of ``uint8``: 160 steps of the colour map ``cmap`` (all of it for a
    qualitative map), white, black, the walls' grey, and the image's other colours (text edges,
    antialiasing) by median cut."""
    import matplotlib
    from PIL import Image

    cm = matplotlib.colormaps[cmap]
    n_map = min(getattr(cm, "N", 256), 160)
    ramp = (np.asarray(cm(np.linspace(0.0, 1.0, n_map)))[:, :3] * 255.0).round()
    exact = np.array([(1.0, 1.0, 1.0), (0.0, 0.0, 0.0), matplotlib.colors.to_rgb(WALL_COLOR)]) * 255.0
    n_rest = 256 - n_map - len(exact)
    rest = Image.fromarray(rgb, mode="RGB").quantize(colors=n_rest, method=Image.Quantize.MEDIANCUT,
                                                     dither=Image.Dither.NONE).getpalette()[: 3 * n_rest]
    pal = np.vstack([ramp, exact.round(), np.asarray(rest, dtype=np.float64).reshape(-1, 3)])
    return np.clip(pal, 0, 255).astype(np.uint8)


def _indexed(rgb: np.ndarray, palette: np.ndarray):
    """``rgb`` as a palette image, each colour mapped to its nearest palette entry (exactly:
    Pillow's own mapping is approximate and turns white into light grey)."""
    from PIL import Image

    flat = rgb.reshape(-1, 3)
    code = (flat[:, 0].astype(np.uint32) << 16) | (flat[:, 1].astype(np.uint32) << 8) | flat[:, 2]
    colors, inverse = np.unique(code, return_inverse=True)
    unique_rgb = np.stack([(colors >> 16) & 255, (colors >> 8) & 255, colors & 255], axis=1).astype(np.int32)
    pal = palette.astype(np.int32)
    nearest = np.empty(len(unique_rgb), dtype=np.uint8)
    for lo in range(0, len(unique_rgb), 4096):  # (chunk, 256) distances
        d = ((unique_rgb[lo:lo + 4096, None, :] - pal[None, :, :]) ** 2).sum(axis=2)
        nearest[lo:lo + 4096] = np.argmin(d, axis=1)
    img = Image.fromarray(nearest[inverse.reshape(-1)].reshape(rgb.shape[:2]), mode="P")
    img.putpalette(palette.reshape(-1).tolist())
    return img


def figure_png(fig, path: str | Path, *, cmap: str | None = None) -> Path:
    """Write the figure as a PNG (atomically).

    With ``cmap`` (the colour map of the particles) the image is stored with a 256-colour
    palette — 160 steps of the colour map plus the figure's other colours — which is several
    times smaller than full RGB for particle pictures and keeps the colour bar smooth;
    without it, in full RGB.
    """
    from PIL import Image

    rgb = figure_rgb(fig)
    img = _indexed(rgb, _palette_for(rgb, cmap)) if cmap else Image.fromarray(rgb, mode="RGB")
    buf = io.BytesIO()
    img.save(buf, format="PNG", optimize=True)
    atomic_write(path, buf.getvalue())
    return Path(path)


def write_gif(view: FrameView, frames: Sequence[Frame], path: str | Path, *, fps: float = 8.0,
              width: float = 8.0, dpi: float = 100.0) -> Path:
    """An animated GIF of ``frames`` (one picture each, all the same size), written atomically.

    ``fps``: frames per second (GIF delays are whole milliseconds, at least 20 ms).
    """

    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps!r}")
    frames = list(frames)
    if not frames:
        raise ValueError("write_gif: no frames; pass at least one")
    rgbs = [figure_rgb(frame_figure(view, [frame], width=width, dpi=dpi)) for frame in frames]
    palette = _palette_for(rgbs[-1], view.style.cmap)  # one palette: no flicker between frames
    images = [_indexed(rgb, palette) for rgb in rgbs]
    buf = io.BytesIO()
    images[0].save(buf, format="GIF", save_all=True, append_images=images[1:],
                   duration=max(int(round(1000.0 / fps)), 20), loop=0)
    atomic_write(path, buf.getvalue())
    logger.debug("wrote %s (%d frames)", path, len(images))
    return Path(path)
