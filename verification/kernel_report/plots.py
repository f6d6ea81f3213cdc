"""Figures of the kernel study (matplotlib, Agg backend; PNG written atomically)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mlsgalerkin.studies.figures import PLOT_FLOOR, pyplot, save_png, tidy_log_axes
from mlsgalerkin.studies.kernels import (
    FUNCTIONS,
    FUNCTIONS_BY_LABEL,
    SMOOTH_FUNCTIONS,
    U2D_TEXT,
    StudyConfig,
)

from .rows import select_rows, xy_points
from .style import (
    KERNEL_STYLES,
    MARKERS,
    METHOD_COLORS,
    VALUE_ORDER,
    legend,
    method_line,
    order_guide,
    ref_slope,
)

__all__ = ["plots_shape_functions", "plots_sph"]


def plots_sph(rows: list[dict], cfg: StudyConfig, out: Path) -> list[Path]:
    """Part-1 figures: error against h, and against neighbour/particle count."""
    plt = pyplot()
    from matplotlib.lines import Line2D

    paths: list[Path] = []
    kernels = list(cfg.sph_kernels)
    kcolor = {k: plt.cm.tab10(i % 10) for i, k in enumerate(kernels)}
    plt.rcParams.update({"font.size": 8, "axes.titlesize": 9})

    def sph_fig(specs, fname, title, ylabel_kind):
        fig, axes = plt.subplots(2, len(FUNCTIONS), figsize=(17, 7.2), squeeze=False)
        for row, (approx, sweep, xname, xlabel, yname, extra) in enumerate(specs):
            for col, fn in enumerate(FUNCTIONS):
                ax = axes[row, col]
                for i, k in enumerate(kernels):
                    rs = select_rows(
                        rows,
                        part="sph",
                        approximation=approx,
                        kernel=k,
                        function=fn.label,
                        sweep=sweep,
                        region="interior",
                    )
                    x, y = xy_points(rs, xname, yname)
                    ax.loglog(x, y, marker=MARKERS[i], ms=3.5, lw=1.1, color=kcolor[k], label=k)
                ax.set_title(f"{approx}: {fn.key} = {fn.label}")
                ax.set_xlabel(xlabel)
                if col == 0:
                    ax.set_ylabel(ylabel_kind)
                ax.grid(True, which="both", alpha=0.25)
                if extra:
                    extra(ax, fn)
                tidy_log_axes(ax)
        handles = [
            Line2D([], [], color=kcolor[k], marker=MARKERS[i], ms=4, label=k)
            for i, k in enumerate(kernels)
        ]
        fig.legend(handles=handles, loc="lower center", ncol=len(kernels), frameon=False)
        fig.suptitle(title)
        fig.subplots_adjust(left=0.05, right=0.99, bottom=0.12, top=0.88, wspace=0.3, hspace=0.42)
        p = save_png(fig, out / fname, compact=not cfg.quick)
        return p

    def slope2(ax, fn):
        if fn.label in SMOOTH_FUNCTIONS:
            x0, x1 = ax.get_xlim()
            ref_slope(ax, [x0 * 1.3, x1 / 1.3], 2.0)

    def five_percent(ax, fn):
        ax.axhline(0.05, color="k", lw=0.8, ls="--")
        ax.axvline(5, color="0.5", lw=0.8, ls=":")
        ax.annotate("5 %", (ax.get_xlim()[0], 0.05), fontsize=7, va="bottom")

    paths.append(
        sph_fig(
            [
                ("integral", "h", "h", "h", "error_abs", slope2),
                ("particle", "h", "h", "h", "error_abs", slope2),
            ],
            "sph_error_vs_h.png",
            f"SPH sums: RMS error vs h (interior points). Top: integral approximation, "
            f"N_nb = {cfg.int_nnb_fixed} quadrature points in the support.\nBottom: particle "
            f"(normalised) approximation, N = {cfg.part_n_fixed} particles. Dashed grey: slope 2.",
            "absolute RMS error",
        )
    )
    paths.append(
        sph_fig(
            [
                (
                    "integral",
                    "n_neighbors",
                    "n_neighbors",
                    "neighbours in the support N_nb",
                    "error_rel",
                    five_percent,
                ),
                (
                    "particle",
                    "n_particles",
                    "n_particles",
                    "particles N on [0, 2]",
                    "error_rel",
                    None,
                ),
            ],
            "sph_error_vs_neighbors.png",
            f"SPH sums at h = {cfg.int_h_fixed}: relative RMS error (interior) vs neighbour count "
            f"(top, integral approximation; dashed: 5 %, dotted: 5 neighbours)\nand vs particle "
            f"count (bottom, particle approximation).",
            "relative RMS error",
        )
    )

    return paths


def plots_shape_functions(rows: list[dict], cfg: StudyConfig, out: Path) -> list[Path]:
    """Part-2 figures: 1D errors, 2D errors against h/Δx and Δx, work-precision."""
    plt = pyplot()

    paths: list[Path] = []
    plt.rcParams.update({"font.size": 8, "axes.titlesize": 9})
    mls_rows = [r for r in rows if r["part"] == "mls1d"]
    if mls_rows:
        plot_kernels = [k for k in ("cubic_spline", "quintic_spline") if k in cfg.mls_kernels]
        funcs = list(cfg.mls_functions)
        specs = [
            ("h", "h", f"h  (N = {cfg.part_n_fixed})"),
            ("n_particles", "n_particles", f"particles N  (h = {cfg.part_h_fixed})"),
            ("refine", "spacing", f"mean spacing Δx  (h = {cfg.refine_ratio} Δx)"),
        ]
        fig, axes = plt.subplots(len(specs), len(funcs), figsize=(15, 9.5), squeeze=False)
        for i, (sweep, xname, xlabel) in enumerate(specs):
            for j, fl in enumerate(funcs):
                ax = axes[i, j]
                for m in cfg.mls_methods:
                    for n_k, k in enumerate(plot_kernels):
                        rs = select_rows(
                            mls_rows,
                            approximation=m,
                            kernel=k,
                            function=fl,
                            sweep=sweep,
                            region="all",
                        )
                        x, y = xy_points(rs, xname, "error_abs")
                        method_line(ax, x, y, m, KERNEL_STYLES[k])
                        if (
                            sweep == "refine"
                            and fl in SMOOTH_FUNCTIONS
                            and n_k == 0
                            and m != "rkpm_linear"
                        ):
                            order_guide(ax, x, y, VALUE_ORDER[m], METHOD_COLORS[m])
                ax.set_title(f"{FUNCTIONS_BY_LABEL[fl].key} = {fl}, sweep {sweep}")
                ax.set_xlabel(xlabel)
                if j == 0:
                    ax.set_ylabel("absolute RMS error (all points)")
                ax.grid(True, which="both", alpha=0.25)
                tidy_log_axes(ax)
        legend(fig, cfg.mls_methods, plot_kernels, KERNEL_STYLES)
        fig.suptitle(
            "1D shape functions on jittered particles (±%.0f%% Δx): RMS error over all "
            "particles, boundary included; dotted: reference slopes; rkpm_linear (×) lies "
            "on mls_linear (□); other kernels: see CSV" % (100 * cfg.jitter_1d)
        )
        fig.subplots_adjust(left=0.07, right=0.99, bottom=0.09, top=0.93, wspace=0.25, hspace=0.4)
        paths.append(save_png(fig, out / "mls1d_errors.png", compact=not cfg.quick))

    rows2 = [r for r in rows if r["part"] == "mls2d"]
    kstyle2 = {k: KERNEL_STYLES.get(k, "-") for k in cfg.kernels_2d}
    if rows2:
        for sweep, xname, xlabel, fname in (
            (
                "h_over_dx",
                "h_over_dx",
                f"h / Δx  (n = {cfg.n_fixed_2d}² nodes)",
                "mls2d_error_vs_h.png",
            ),
            (
                "resolution",
                "spacing",
                f"Δx  (h = {cfg.ratio_fixed_2d} Δx)",
                "mls2d_error_vs_dx.png",
            ),
        ):
            cols = [
                ("error_abs", "interior", "value, interior"),
                ("error_abs", "all", "value, all points"),
                ("error_grad", "interior", "gradient, interior"),
                ("error_grad", "all", "gradient, all points"),
            ]
            fig, axes = plt.subplots(
                len(cfg.layouts_2d), 4, figsize=(16, 3.6 * len(cfg.layouts_2d) + 0.8), squeeze=False
            )
            for i, layout in enumerate(cfg.layouts_2d):
                for j, (q, region, what) in enumerate(cols):
                    ax = axes[i, j]
                    for m in cfg.methods_2d:
                        for n_k, k in enumerate(cfg.kernels_2d):
                            rs = select_rows(
                                rows2,
                                approximation=m,
                                kernel=k,
                                layout=layout,
                                sweep=sweep,
                                region=region,
                            )
                            x, y = xy_points(rs, xname, q)
                            method_line(ax, x, y, m, kstyle2[k])
                            if sweep == "resolution" and n_k == 0:
                                p = VALUE_ORDER[m] - (1 if q == "error_grad" else 0)
                                order_guide(ax, x, y, p, METHOD_COLORS[m])
                    ax.set_title(f"{layout} nodes: {what}")
                    ax.set_xlabel(xlabel)
                    if j in (0, 2):
                        ax.set_ylabel("RMS error" if q == "error_abs" else "RMS |∇ error|")
                    ax.grid(True, which="both", alpha=0.25)
                    tidy_log_axes(ax)
                    if sweep == "h_over_dx":
                        ax.set_xticks(list(cfg.ratios_2d))
                        ax.set_xticklabels([f"{v:g}" for v in cfg.ratios_2d])
                        ax.minorticks_off()
            legend(fig, cfg.methods_2d, cfg.kernels_2d, kstyle2)
            extra = "; dotted: reference slopes" if sweep == "resolution" else ""
            fig.suptitle(
                f"2D shape functions, u = {U2D_TEXT} on the unit square, evaluated on a "
                f"grid of spacing Δx/2 (interior = farther than κh from the boundary){extra}"
            )
            fig.subplots_adjust(
                left=0.06, right=0.99, bottom=0.14, top=0.9, wspace=0.28, hspace=0.45
            )
            paths.append(save_png(fig, out / fname, compact=not cfg.quick))

    # work-precision: error against wall time along the refinement sweeps
    if mls_rows or rows2:
        panels = []
        if mls_rows:
            panels.append(
                (
                    f"1D sin(x), jittered, N = {min(cfg.refine_n)} … {max(cfg.refine_n)} "
                    f"(h = {cfg.refine_ratio:g} Δx)",
                    mls_rows,
                    dict(sweep="refine", function="sin(x)"),
                    "error_abs",
                    list(cfg.mls_methods),
                    list(cfg.mls_kernels),
                    KERNEL_STYLES,
                )
            )
        if rows2:
            for q, what in (("error_abs", "value"), ("error_grad", "gradient")):
                panels.append(
                    (
                        f"2D jittered, {what}, n = {min(cfg.levels_2d)}² … {max(cfg.levels_2d)}² "
                        f"(h = {cfg.ratio_fixed_2d:g} Δx)",
                        rows2,
                        dict(sweep="resolution", layout="jittered"),
                        q,
                        list(cfg.methods_2d),
                        list(cfg.kernels_2d),
                        kstyle2,
                    )
                )
        fig, axes = plt.subplots(2, len(panels), figsize=(5.4 * len(panels), 8.4), squeeze=False)
        for j, (title, rs_all, sel, q, methods, kerns, kst) in enumerate(panels):
            for i, region in enumerate(("interior", "all")):
                ax = axes[i, j]
                for m in methods:
                    for k in kerns:
                        rs = sorted(
                            select_rows(rs_all, approximation=m, kernel=k, region=region, **sel),
                            key=lambda r: -r["spacing"],
                        )
                        x = np.array([r["wall_s"] for r in rs])
                        y = np.maximum(np.array([r[q] for r in rs], float), PLOT_FLOOR)
                        method_line(ax, x, y, m, kst.get(k, "-"))
                ax.set_title(f"{title}\n{region} points", fontsize=8)
                ax.set_xlabel("wall time per approximation [s]")
                ax.set_ylabel("RMS error" if q == "error_abs" else "RMS |∇ error|")
                ax.grid(True, which="both", alpha=0.25)
                tidy_log_axes(ax)
        methods_all = [
            m for m in METHOD_COLORS if any(r["approximation"] == m for r in mls_rows + rows2)
        ]
        kern_all = [k for k in KERNEL_STYLES if any(r["kernel"] == k for r in mls_rows + rows2)]
        legend(fig, methods_all, kern_all, {**KERNEL_STYLES, **kstyle2})
        fig.suptitle(
            "Work-precision along the refinement sweeps: RMS error against wall time "
            f"(neighbour search + shape functions + apply, numba threads = {cfg.threads}; "
            "lower-left is better)"
        )
        fig.subplots_adjust(left=0.08, right=0.99, bottom=0.11, top=0.9, wspace=0.3, hspace=0.38)
        paths.append(save_png(fig, out / "work_precision.png", compact=not cfg.quick))
    return paths
