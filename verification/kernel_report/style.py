"""Look of the kernel-study figures: colours and markers per method, kernel line styles,
reference slopes and legends (log axes and PNG output: :mod:`mlsgalerkin.studies.figures`)."""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "KERNEL_STYLES",
    "MARKERS",
    "METHOD_COLORS",
    "METHOD_MARKERS",
    "VALUE_ORDER",
    "legend",
    "method_line",
    "order_guide",
    "ref_slope",
]

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
