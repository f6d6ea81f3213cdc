"""Figures of the Galerkin study (matplotlib, Agg backend, written atomically as PNG).

``convergence_<problem>.png``  log-log error against spacing, one row per kernel (and node
                               layout), L2 and H1/energy columns, fitted slopes annotated.
``work_precision.png``         error against wall time (shape + assembly + solve), one curve per
                               rule/basis: what an accuracy costs.
``wall_split.png``             wall time split into shape functions, assembly and solve.
``h_sweep_<problem>.png``      error, spurious zero-energy modes and the smallest non-rigid
                               stiffness eigenvalue against support radius / spacing.
``spectra.png``                the lowest stiffness eigenvalues (no boundary conditions): the gap
                               that justifies the zero-mode threshold.

Log axes and PNG output: :mod:`mlsgalerkin.studies.figures`.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from mlsgalerkin.analysis.convergence import observed_order
from mlsgalerkin.studies.figures import pyplot, save_png, tidy_log_axes
from mlsgalerkin.studies.galerkin.runner import RULE_LABELS
from mlsgalerkin.studies.galerkin.sweeps import energy_quantity

__all__ = ["BASIS_STYLES", "KERNEL_LABELS", "PROBLEM_LABELS", "RULE_COLORS", "RULE_LABELS",
           "make_plots"]

logger = logging.getLogger(__name__)

RULE_COLORS = {"dni": "tab:red", "scni": "tab:blue", "vci": "tab:green"}
BASIS_STYLES = {"linear": ("-", "o"), "quadratic": ("--", "s")}
KERNEL_LABELS = {"cubic_spline": "cubic spline", "quintic_spline": "quintic spline",
                 "wendland_c2": "Wendland C2"}
PROBLEM_LABELS = {"poisson_mms": "Poisson MMS", "timoshenko": "Timoshenko cantilever",
                  "poisson_patch": "Poisson patch", "elastic_patch": "elasticity patch"}
_FLOOR = 1e-16


def _label(rule: str, basis: str) -> str:
    return f"{RULE_LABELS.get(rule, rule)} {basis}"


def _series(rows, **sel):
    return [r for r in rows if all(r.get(k) == v for k, v in sel.items())]


def _slope_triangle(ax, x0: float, y0: float, slope: float, width: float = 2.0) -> None:
    """A small reference triangle of the given slope at (x0, y0) (log axes)."""
    x1 = x0 * width
    y1 = y0 * width**slope
    ax.plot([x0, x1, x1, x0], [y0, y0, y1, y0], color="0.45", lw=0.8, zorder=1)
    ax.annotate(f"{slope:g}", (x1, math.sqrt(y0 * y1)), xytext=(3, 0), textcoords="offset points",
                fontsize=7, color="0.35", va="center")


def _legend_handles(rules, bases):
    from matplotlib.lines import Line2D

    return [Line2D([], [], color=RULE_COLORS[r], ls=BASIS_STYLES[b][0], marker=BASIS_STYLES[b][1],
                   ms=4, label=_label(r, b)) for r in rules for b in bases]


def _header(fig, title: str, rules, bases,
            top_in: float = 0.62) -> tuple[float, float, float, float]:
    """Title and the rule/basis legend at the top; returns the ``tight_layout`` rect below them."""
    h = fig.get_figheight()
    fig.suptitle(title, fontsize=10, y=1.0 - 0.08 / h, va="top")
    fig.legend(handles=_legend_handles(rules, bases), loc="upper center",
               bbox_to_anchor=(0.5, 1.0 - 0.36 / h), ncol=len(rules) * len(bases), fontsize=8,
               frameon=False)
    return (0.0, 0.0, 1.0, 1.0 - top_in / h)


def _tidy_all(fig) -> None:
    for ax in fig.axes:
        tidy_log_axes(ax, "y")


def _spacing_ticks(ax, xs) -> None:
    """Ticks at the measured spacings, labelled 1/n for unit fractions."""
    from matplotlib.ticker import NullFormatter, NullLocator

    labels = []
    for x in xs:
        inv = 1.0 / x
        labels.append(f"1/{round(inv)}" if x < 1 and abs(inv - round(inv)) < 1e-9 else f"{x:g}")
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(xs, labels)


def _convergence_figure(rows, problem: str, rules, bases, out: Path) -> Path | None:
    plt = pyplot()
    conv = _series(rows, study="convergence", problem=problem)
    if not conv:
        return None
    panels = []  # (kernel, nodes)
    for nodes in ("regular", "perturbed"):
        for k in dict.fromkeys(r["kernel"] for r in conv if r["nodes"] == nodes):
            panels.append((k, nodes))
    qkey, qname = energy_quantity(problem)
    fig, axes = plt.subplots(len(panels), 2, figsize=(10.5, 3.1 * len(panels) + 0.8),
                             squeeze=False, sharex=True)
    for i, (kernel, nodes) in enumerate(panels):
        for j, (key, name) in enumerate((("error_l2", "L2"), (qkey, qname))):
            ax = axes[i, j]
            notes = []
            for rule in rules:
                for basis in bases:
                    rs = sorted(_series(conv, kernel=kernel, nodes=nodes, rule=rule, basis=basis),
                                key=lambda r: r["spacing"])
                    if not rs:
                        continue
                    x = np.array([r["spacing"] for r in rs])
                    y = np.maximum([r[key] for r in rs], _FLOOR)
                    ls, mk = BASIS_STYLES[basis]
                    ax.loglog(x, y, ls=ls, marker=mk, ms=4, color=RULE_COLORS[rule], lw=1.3)
                    p, _ = observed_order(x, y)
                    if math.isfinite(p):
                        notes.append((y[0], f"{p:.2f}", RULE_COLORS[rule], ls))
            # slope labels stacked at the right edge, in the order of the finest errors
            for k, (_, txt, col, ls) in enumerate(sorted(notes, key=lambda t: -t[0])):
                ax.annotate(("— " if ls == "-" else "-- ") + txt, xy=(1.01, 0.95 - 0.085 * k),
                            xycoords="axes fraction", fontsize=7.5, color=col, va="top")
            xs = sorted({r["spacing"] for r in conv})
            lo, hi = ax.get_ylim()
            _slope_triangle(ax, xs[0] * 1.05, lo * 2.0, 1.0)
            _slope_triangle(ax, xs[0] * 1.05, lo * 2.0 * 8.0, 2.0)
            ax.set_title(f"{KERNEL_LABELS.get(kernel, kernel)}, {nodes} nodes — {name} error",
                         fontsize=9)
            ax.set_ylabel(f"relative {name} error", fontsize=8)
            ax.grid(True, which="major", alpha=0.3)
            ax.tick_params(labelsize=7.5)
    xs = sorted({r["spacing"] for r in conv})
    for ax in axes.ravel():
        _spacing_ticks(ax, xs)
    for ax in axes[-1]:
        ax.set_xlabel("nodal spacing Δx", fontsize=8)
    rect = _header(fig, f"{PROBLEM_LABELS.get(problem, problem)}: convergence (fitted order at the "
                   f"right of each panel: least squares over all levels)", rules, bases)
    _tidy_all(fig)
    fig.tight_layout(rect=(rect[0], rect[1], 0.95, rect[3]))
    return save_png(fig, out / f"convergence_{problem}.png")


def _work_precision(rows, problems, rules, bases, kernel: str, out: Path) -> Path | None:
    plt = pyplot()
    conv = _series(rows, study="convergence", kernel=kernel, nodes="regular")
    problems = [p for p in problems if _series(conv, problem=p)]
    if not problems:
        return None
    fig, axes = plt.subplots(2, len(problems), figsize=(5.4 * len(problems), 8.2), squeeze=False)
    for j, problem in enumerate(problems):
        qkey, qname = energy_quantity(problem)
        for i, (key, name) in enumerate((("error_l2", "L2"), (qkey, qname))):
            ax = axes[i, j]
            for rule in rules:
                for basis in bases:
                    rs = sorted(_series(conv, problem=problem, rule=rule, basis=basis),
                                key=lambda r: r["wall_s"])
                    if not rs:
                        continue
                    ls, mk = BASIS_STYLES[basis]
                    x = [r["wall_s"] for r in rs]
                    y = np.maximum([r[key] for r in rs], _FLOOR)
                    ax.loglog(x, y, ls=ls, marker=mk, ms=4, color=RULE_COLORS[rule], lw=1.3)
                    r_fin = max(rs, key=lambda r: r["n_nodes"])
                    ax.annotate(f"{r_fin['n_nodes']}", (r_fin["wall_s"], max(r_fin[key], _FLOOR)),
                                xytext=(3, -2), textcoords="offset points", fontsize=6,
                                color=RULE_COLORS[rule])
            ax.set_title(f"{PROBLEM_LABELS.get(problem, problem)} — {name} error", fontsize=9)
            ax.set_xlabel("wall time: shape functions + assembly + solve [s]", fontsize=8)
            ax.set_ylabel(f"relative {name} error", fontsize=8)
            ax.grid(True, which="major", alpha=0.3)
            ax.tick_params(labelsize=7.5)
    rect = _header(fig, "Work–precision: error against wall time "
                   f"({KERNEL_LABELS.get(kernel, kernel)}, "
                   f"regular nodes; numbers: node count of the finest level)", rules, bases)
    _tidy_all(fig)
    fig.tight_layout(rect=rect)
    return save_png(fig, out / "work_precision.png")


def _wall_split(rows, problems, rules, bases, kernel: str, out: Path) -> Path | None:
    plt = pyplot()
    conv = _series(rows, study="convergence", kernel=kernel, nodes="regular")
    problems = [p for p in problems if _series(conv, problem=p)]
    if not problems:
        return None
    fig, axes = plt.subplots(1, len(problems), figsize=(5.6 * len(problems), 4.2), squeeze=False)
    parts = (("wall_shape_s", "shape functions", "tab:olive"),
             ("wall_assembly_s", "assembly", "tab:cyan"), ("wall_solve_s", "solve", "tab:gray"))
    for j, problem in enumerate(problems):
        ax = axes[0, j]
        labels, bottoms = [], None
        rs_all = _series(conv, problem=problem)
        n_max = max(r["n_nodes"] for r in rs_all)
        sel = []
        for rule in rules:
            for basis in bases:
                rs = _series(rs_all, rule=rule, basis=basis, n_nodes=n_max)
                if rs:
                    sel.append(rs[0])
                    labels.append(_label(rule, basis))
        x = np.arange(len(sel))
        bottoms = np.zeros(len(sel))
        for key, name, col in parts:
            v = np.array([r[key] for r in sel])
            ax.bar(x, v, bottom=bottoms, color=col, label=name, width=0.7)
            bottoms += v
        ax.set_xticks(x, labels, rotation=30, ha="right", fontsize=7.5)
        ax.set_ylabel("wall time [s]", fontsize=8)
        ax.set_title(f"{PROBLEM_LABELS.get(problem, problem)}, {n_max} nodes "
                     f"({KERNEL_LABELS.get(kernel, kernel)})", fontsize=9)
        ax.tick_params(labelsize=7.5)
        ax.grid(True, axis="y", alpha=0.3)
    axes[0, 0].legend(fontsize=7.5)
    _tidy_all(fig)
    fig.tight_layout()
    return save_png(fig, out / "wall_split.png")


def _h_sweep_figure(rows, problem: str, rules, bases, tol: float, out: Path) -> Path | None:
    plt = pyplot()
    sw = _series(rows, study="h_sweep", problem=problem)
    if not sw:
        return None
    panels = []
    for nodes in ("regular", "perturbed"):
        for k in dict.fromkeys(r["kernel"] for r in sw if r["nodes"] == nodes):
            panels.append((k, nodes))
    qkey, qname = energy_quantity(problem)
    fig, axes = plt.subplots(len(panels), 4, figsize=(16, 2.9 * len(panels) + 1.0), squeeze=False,
                             sharex=True)
    n_max = 0
    for i, (kernel, nodes) in enumerate(panels):
        n_zero = 0
        for rule in rules:
            for basis in bases:
                rs = sorted(_series(sw, kernel=kernel, nodes=nodes, rule=rule, basis=basis),
                            key=lambda r: r["support_ratio"])
                if not rs:
                    continue
                ls, mk = BASIS_STYLES[basis]
                kw = dict(ls=ls, marker=mk, ms=4, color=RULE_COLORS[rule], lw=1.2)
                x = np.array([r["support_ratio"] for r in rs])
                axes[i, 0].semilogy(x, np.maximum([r[qkey] for r in rs], _FLOOR), **kw)
                off = {"dni": -0.06, "scni": 0.0, "vci": 0.06}.get(rule, 0.0)
                off += 0.02 if basis == "quadratic" else -0.02
                nsp = np.array([r["n_spurious_modes"] for r in rs])
                n_zero += int(nsp.sum())
                soft = np.array([np.nan if r.get("n_soft_modes") is None else r["n_soft_modes"]
                                 for r in rs], float)
                if np.isfinite(soft).any():
                    axes[i, 1].plot(x + off, soft, **kw)
                    n_max = max(n_max, int(np.nanmax(soft)))
                if nsp.any():
                    axes[i, 1].plot(x + off, nsp, ls="none", marker="x", ms=7, mew=2,
                                    color=RULE_COLORS[rule])
                    n_max = max(n_max, int(nsp.max()))
                axes[i, 2].semilogy(x, np.maximum([r["eig_first"] for r in rs], _FLOOR), **kw)
                mu = np.array([r.get("energy_ratio_max", math.nan) for r in rs], float)
                if np.isfinite(mu).any():
                    axes[i, 3].semilogy(x, mu, **kw)
        axes[i, 2].axhline(tol, color="0.3", lw=0.8, ls=":")
        axes[i, 2].annotate(f"zero-mode threshold {tol:g}", (0.02, tol),
                            xycoords=("axes fraction", "data"), fontsize=7, color="0.3",
                            va="bottom")
        where = f"{KERNEL_LABELS.get(kernel, kernel)}, {nodes}"
        axes[i, 0].set_title(f"{where}: {qname} error (with BCs)", fontsize=8.5)
        axes[i, 1].set_title(f"{where}: soft modes (μ > 10); spurious zero modes: {n_zero}"
                             + ("" if n_zero == 0 else " (×)"), fontsize=8.5)
        axes[i, 2].set_title(f"{where}: min non-rigid eigenvalue / max", fontsize=8.5)
        axes[i, 3].set_title(f"{where}: worst energy underestimate μ", fontsize=8.5)
        for ax in axes[i]:
            ax.grid(True, alpha=0.3)
            ax.tick_params(labelsize=7.5)
    for ax in axes[:, 1]:
        ax.set_ylim(-0.05 * (n_max + 1), 1.05 * (n_max + 1))
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.set_ylabel("number of modes", fontsize=7.5)
    for ax in axes[:, 3]:
        ax.set_ylabel("max true energy / rule energy", fontsize=7.5)
    for ax in axes[-1]:
        ax.set_xlabel("support radius / spacing  (κh/Δx)", fontsize=8)
    r0 = sw[0]
    rect = _header(fig, f"{PROBLEM_LABELS.get(problem, problem)}: smoothing-length sweep at "
                   f"{r0['n_nodes']} nodes (modes: stiffness without boundary conditions; last "
                   f"column symmetric rules only)", rules, bases)
    _tidy_all(fig)
    fig.tight_layout(rect=rect)
    return save_png(fig, out / f"h_sweep_{problem}.png")


def _spectra_figure(sweep_rows: list[dict], problems, rules, bases, ratio_of, kernel: str,
                    tol: float, out: Path, n_show: int = 30) -> Path | None:
    plt = pyplot()
    problems = [p for p in problems if any(r["problem"] == p for r in sweep_rows)]
    if not problems:
        return None
    fig, axes = plt.subplots(1, len(problems), figsize=(5.8 * len(problems), 4.4), squeeze=False)
    for j, problem in enumerate(problems):
        ax = axes[0, j]
        for rule in rules:
            for basis in bases:
                want = ratio_of[basis]
                match = [r["eigenvalues"] for r in sweep_rows
                         if r["problem"] == problem and r["rule"] == rule
                         and r["basis"] == basis and r["kernel"] == kernel
                         and r["nodes"] == "regular" and abs(r["support_ratio"] - want) < 1e-9]
                if not match:
                    continue
                vals = match[0]
                ls, mk = BASIS_STYLES[basis]
                k = np.arange(1, min(n_show, vals.size) + 1)
                ax.semilogy(k, np.maximum(vals[: k.size], _FLOOR), ls=ls, marker=mk, ms=3,
                            color=RULE_COLORS[rule], lw=1.0)
        ax.axhline(tol, color="0.3", lw=0.8, ls=":")
        ax.annotate(f"threshold {tol:g}", (0.6, tol), xycoords=("axes fraction", "data"),
                    fontsize=7, color="0.3", va="bottom")
        ax.set_title(f"{PROBLEM_LABELS.get(problem, problem)} "
                     f"({KERNEL_LABELS.get(kernel, kernel)}, κh/Δx = {ratio_of['linear']:g} "
                     f"linear / {ratio_of['quadratic']:g} quadratic)",
                     fontsize=8.5)
        ax.set_xlabel("eigenvalue index (ascending)", fontsize=8)
        ax.set_ylabel("eigenvalue / largest (singular values for VCI)", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=7.5)
    rect = _header(fig, "Lowest stiffness eigenvalues without boundary conditions, regular nodes",
                   rules, bases)
    _tidy_all(fig)
    fig.tight_layout(rect=rect)
    return save_png(fig, out / "spectra.png")


def make_plots(rows: list[dict], cfg, out: Path) -> list[Path]:
    """Every figure of the study; returns the paths written. The spectra come from the
    ``eigenvalues`` of the h-sweep rows."""
    rules = [r for r in cfg.rules if any(x["rule"] == r for x in rows)]
    bases = list(cfg.bases)
    problems = list(cfg.levels)
    kernel = cfg.kernels[0]
    paths = []
    for problem in problems:
        paths.append(_convergence_figure(rows, problem, rules, bases, out))
    paths.append(_work_precision(rows, problems, rules, bases, kernel, out))
    paths.append(_wall_split(rows, problems, rules, bases, kernel, out))
    for problem in cfg.sweep_spacing:
        paths.append(_h_sweep_figure(rows, problem, rules, bases, cfg.eig_tol, out))
    sweep_rows = [r for r in rows if r["study"] == "h_sweep" and "eigenvalues" in r]
    ratio_of = dict(cfg.support_ratio)
    avail = {r["support_ratio"] for r in sweep_rows}
    for b, r in list(ratio_of.items()):  # fall back to the closest swept ratio
        if avail and r not in avail:
            ratio_of[b] = min(avail, key=lambda a: abs(a - r))
    paths.append(_spectra_figure(sweep_rows, list(cfg.sweep_spacing), rules, bases, ratio_of,
                                 kernel, cfg.eig_tol, out))
    out_paths = [p for p in paths if p is not None]
    logger.info("%d figures written", len(out_paths))
    return out_paths
