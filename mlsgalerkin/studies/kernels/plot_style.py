"""Shared look of the kernel-study figures: colours, markers, log axes, legends, PNG output."""

from __future__ import annotations

import io
import logging
import math
from pathlib import Path

import numpy as np

from mlsgalerkin.io.files import atomic_write

logger = logging.getLogger(__name__)

MARKERS = ["o", "s", "^", "v", "D", "P", "X", "<", ">", "*", "h"]
METHOD_COLORS = {
    "shepard": "tab:red",
    "mls_linear": "tab:blue",
    "mls_quadratic": "tab:green",
    "rkpm_linear": "tab:purple",
}
KERNEL_STYLES = {
    "cubic_spline": "-",
    "quartic_spline": ":",
    "quintic_spline": "--",
    "wendland_c2": "-.",
}
METHOD_MARKERS = {"shepard": "o", "mls_linear": "s", "mls_quadratic": "^", "rkpm_linear": "x"}
#: Expected order in Δx of the value error at fixed h/Δx (gradient: one less).
VALUE_ORDER = {"shepard": 1, "mls_linear": 2, "rkpm_linear": 2, "mls_quadratic": 3}


def save_png(fig, path: Path, compact: bool = False, dpi: int = 110) -> Path:
    """PNG at ``dpi``; ``compact`` quantises it to a 128-colour palette (about 3x smaller)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    data = buf.getvalue()
    if compact:
        try:
            from PIL import Image

            im = Image.open(io.BytesIO(data)).convert("RGB")
            im = im.quantize(colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            out = io.BytesIO()
            im.save(out, format="PNG", optimize=True)
            data = out.getvalue()
        except Exception as exc:  # Pillow missing or too old: keep the plain PNG
            logger.info("PNG quantisation skipped: %s", exc)
    atomic_write(path, data)
    return path


def tidy_log_axes(ax) -> None:
    """Readable log axes: on short ranges (< 1.5 decades) label 1-2-3-5 ticks in plain numbers
    instead of matplotlib's overlapping minor labels."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        if not (lo > 0 and hi > lo):
            continue
        if math.log10(hi / lo) >= 1.5:
            axis.set_minor_formatter(NullFormatter())
            continue
        ticks = [
            m * 10.0**e
            for e in range(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1)
            for m in (1, 2, 3, 5)
        ]
        ticks = [t for t in ticks if lo <= t <= hi]
        if len(ticks) > 6:
            ticks = [
                t for t in ticks if round(t / 10.0 ** math.floor(math.log10(t)), 6) in (1, 2, 5)
            ]
        axis.set_ticks(ticks)
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())
        if axis is ax.xaxis:
            ax.set_xlim(lo, hi)
        else:
            ax.set_ylim(lo, hi)


def ref_slope(ax, x, slope, label=None, y0=None) -> None:
    """Grey dashed reference line of ``slope`` over the range of ``x``."""
    x = np.asarray([min(x), max(x)], float)
    if y0 is None:
        lo, hi = ax.get_ylim()
        y0 = 10 ** (0.5 * (math.log10(lo) + math.log10(hi)))
    y = y0 * (x / x[0]) ** slope
    ax.plot(x, y, color="0.55", lw=1.0, ls=(0, (4, 3)), zorder=0)
    ax.annotate(
        label or f"slope {slope:g}",
        (x[-1], y[-1]),
        fontsize=7,
        color="0.4",
        ha="right",
        va="bottom" if slope > 0 else "top",
    )


def method_line(ax, x, y, method, ls="-") -> None:
    """Log-log curve in the colour and marker of ``method``."""
    mk = METHOD_MARKERS.get(method, "o")
    ax.loglog(
        x,
        y,
        color=METHOD_COLORS.get(method, "k"),
        ls=ls,
        marker=mk,
        ms=5 if mk == "s" else 4,
        mfc="none" if mk == "s" else None,
        lw=1.1,
    )


def order_guide(ax, x, y, p: int, color) -> None:
    """Dotted line of slope ``p`` through the finest point of a curve (scaled by 0.4)."""
    if p <= 0 or x.size < 2:
        return
    i = int(np.argmin(x))
    xs = np.array([x.min(), x.max()])
    ys = 0.4 * y[i] * (xs / x[i]) ** p
    ax.plot(xs, ys, color=color, lw=0.9, ls=(0, (1, 2)), alpha=0.9)
    sup = str(p).translate(str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹"))
    ax.annotate(f"Δx{sup}", (xs[-1], ys[-1]), color=color, fontsize=7, ha="right", va="top")


def legend(fig, methods, kernels, kstyle) -> None:
    """Figure legend: one entry per method (colour, marker), one per kernel (line style)."""
    from matplotlib.lines import Line2D

    h1 = [
        Line2D(
            [],
            [],
            color=METHOD_COLORS[m],
            marker=METHOD_MARKERS[m],
            ms=4,
            mfc="none" if METHOD_MARKERS[m] == "s" else None,
            label=m,
        )
        for m in methods
    ]
    h2 = [Line2D([], [], color="k", ls=kstyle[k], label=k) for k in kernels]
    fig.legend(handles=h1 + h2, loc="lower center", ncol=len(h1) + len(h2), frameon=False)
