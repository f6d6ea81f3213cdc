"""``summary.md`` of the Galerkin study: tables and measured observations.

Everything here is computed from the rows; nothing is hard-coded from expectations.
"""

from __future__ import annotations

import math
from collections import defaultdict

from mlsgalerkin.studies.galerkin.runner import NITSCHE_BETA, PENALTY_BETA, VCI_CORRECTION
from mlsgalerkin.studies.galerkin.sweeps import energy_quantity as _quantity

from ..report_format import fmt_num as _g
from ..report_format import md_table as _table
from .observations import observations
from .plots import KERNEL_LABELS, PROBLEM_LABELS, RULE_LABELS

__all__ = ["TARGETS", "orders_table", "patch_table", "summary_markdown", "time_to_error"]

#: Relative errors whose cost (wall time to reach them) the summary tabulates.
TARGETS = {"poisson_mms": {"error_l2": 1e-3, "error_h1": 1e-2},
           "timoshenko": {"error_l2": 3e-3, "error_energy": 1e-2}}


def _rule(r: str) -> str:
    return RULE_LABELS.get(r, r)


def _kern(k: str) -> str:
    return KERNEL_LABELS.get(k, k)


# --------------------------------------------------------------------------------------
# tables
# --------------------------------------------------------------------------------------


def patch_table(rows: list[dict]) -> tuple[str, dict]:
    """Markdown patch-test table and the worst/best errors per (problem, rule, nodes, bc)."""
    patch = [r for r in rows if r["study"] == "patch"]
    agg: dict[tuple, dict] = {}
    for r in patch:
        key = (r["problem"], r["rule"], r["nodes"], r["bc"])
        a = agg.setdefault(key, {"max_l2": 0.0, "min_l2": math.inf, "max_en": 0.0, "n": 0})
        a["max_l2"] = max(a["max_l2"], r["error_l2"])
        a["min_l2"] = min(a["min_l2"], r["error_l2"])
        a["max_en"] = max(a["max_en"], r["error_energy"])
        a["n"] += 1
    problems = list(dict.fromkeys(r["problem"] for r in patch))
    rules = list(dict.fromkeys(r["rule"] for r in patch))
    body = []
    for p in problems:
        for rule in rules:
            cells = [PROBLEM_LABELS.get(p, p), _rule(rule)]
            for bc in ("nitsche", "penalty"):
                for nodes in ("regular", "perturbed"):
                    a = agg.get((p, rule, nodes, bc))
                    if a is None:
                        cells.append("—")
                    elif bc == "nitsche":
                        cells.append(f"{a['min_l2']:.1e} – {a['max_l2']:.1e} / {a['max_en']:.1e}")
                    else:
                        cells.append(f"{a['max_l2']:.1e}")
            body.append(cells)
    header = ["problem", "rule", "Nitsche, regular: L2 min – max / energy max",
              "Nitsche, perturbed", "penalty, regular: L2", "penalty, perturbed"]
    return _table(header, body), agg


def orders_table(orders: list[dict], problem: str, nodes: str = "regular") -> str:
    q, qname = _quantity(problem)
    key = q.removeprefix("error_")
    body = []
    for o in orders:
        if o["problem"] != problem or o["nodes"] != nodes:
            continue
        body.append([_rule(o["rule"]), o["basis"], _kern(o["kernel"]), _g(o["support_ratio"], "g"),
                     f"{_g(o['order_l2'])} ({_g(o['order_l2_last'])})",
                     f"{_g(o[f'order_{key}'])} ({_g(o[f'order_{key}_last'])})",
                     _g(o["order_h1_rule"]),
                     _g(o["error_l2_finest"], ".2e"), _g(o[f"{q}_finest"], ".2e"),
                     str(o["n_nodes_max"]), _g(o["wall_s_finest"], ".2f")])
    header = ["rule", "basis", "kernel", "κh/Δx", "order L2 fit (last pair)",
              f"order {qname} fit (last pair)", "order rule gradient", "L2 error, finest",
              f"{qname} error, finest", "nodes, finest", "wall [s], finest"]
    return _table(header, body)


def time_to_error(rs: list[dict], key: str, target: float) -> float:
    """Wall time at which a refinement series reaches ``target`` (log-log interpolation between
    measured levels; NaN if it never does)."""
    pts = sorted((r["wall_s"], r[key]) for r in rs if r[key] > 0 and math.isfinite(r[key]))
    if not pts:
        return math.nan
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 > target >= e1:
            s = math.log(target / e0) / math.log(e1 / e0)
            return math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0)))
    if pts[0][1] <= target:
        return pts[0][0]
    return math.nan


def _cost_table(rows: list[dict], problem: str, kernel: str) -> str:
    conv = [r for r in rows if r["study"] == "convergence" and r["problem"] == problem
            and r["kernel"] == kernel and r["nodes"] == "regular"]
    targets = TARGETS.get(problem, {})
    series = defaultdict(list)
    for r in conv:
        series[(r["rule"], r["basis"])].append(r)
    body = []
    for (rule, basis), rs in series.items():
        cells = [_rule(rule), basis]
        for key, tgt in targets.items():
            t = time_to_error(rs, key, tgt)
            cells.append(_g(t, ".2f") if math.isfinite(t) else "not reached")
        body.append(cells)
    header = ["rule", "basis"] + [f"time [s] to {k.removeprefix('error_')} error ≤ {v:g}"
                                  for k, v in targets.items()]
    return _table(header, body)


def _sweep_table(rows: list[dict], problem: str, nodes: str, what: str) -> str:
    """h-sweep table, one row per (rule, basis, kernel), one column per support ratio.

    ``what="modes"``: spurious zero modes / soft modes (μ > 10), worst energy underestimate μ;
    ``what="error"``: relative error with boundary conditions and the smallest non-rigid
    eigenvalue over the largest.
    """
    sw = [r for r in rows if r["study"] == "h_sweep" and r["problem"] == problem
          and r["nodes"] == nodes]
    if not sw:
        return ""
    ratios = sorted({r["support_ratio"] for r in sw})
    q, qname = _quantity(problem)
    body = []
    keys = list(dict.fromkeys((r["rule"], r["basis"], r["kernel"]) for r in sw))
    for rule, basis, kernel in keys:
        cells = [_rule(rule), basis, _kern(kernel)]
        for ratio in ratios:
            m = [r for r in sw if (r["rule"], r["basis"], r["kernel"]) == (rule, basis, kernel)
                 and r["support_ratio"] == ratio]
            if not m:
                cells.append("—")
                continue
            r = m[0]
            if what == "modes":
                soft = r.get("n_soft_modes")
                mu = r.get("energy_ratio_max", math.nan)
                cells.append(f"**{r['n_spurious_modes']}** / "
                             + ("—" if soft is None else f"{soft}")
                             + (f" ({mu:.0e})" if mu is not None and math.isfinite(mu) else ""))
            else:
                fb = f" ({r['n_fallback']} fb)" if r["n_fallback"] else ""
                cells.append(f"{r[q]:.1e} · {r['eig_first']:.0e}{fb}")
        body.append(cells)
    header = ["rule", "basis", "kernel"] + [f"κh/Δx = {x:g}" for x in ratios]
    return _table(header, body)


def _gap_lines(rows: list[dict]) -> list[str]:
    """The eigenvalue gap around the zero-mode threshold, per problem and rule."""
    sw = [r for r in rows if r["study"] == "h_sweep"]
    out = []
    for problem in dict.fromkeys(r["problem"] for r in sw):
        for rule in dict.fromkeys(r["rule"] for r in sw):
            rs = [r for r in sw if r["problem"] == problem and r["rule"] == rule]
            if not rs:
                continue
            below = max((r["eig_below"] for r in rs if math.isfinite(r["eig_below"])),
                        default=math.nan)
            above = min((r["eig_above"] for r in rs if math.isfinite(r["eig_above"])),
                        default=math.nan)
            out.append(f"{PROBLEM_LABELS.get(problem, problem)}, {_rule(rule)}: largest value "
                       f"counted as zero {below:.1e}, smallest value above the threshold "
                       f"{above:.1e} (over all {len(rs)} sweep points)")
    return out


def _ci_line(rows: list[dict]) -> str:
    sw = [r for r in rows
          if r["study"] == "h_sweep" and math.isfinite(r.get("nitsche_ci", math.nan))]
    if not sw:
        return ""
    parts = []
    for problem in dict.fromkeys(r["problem"] for r in sw):
        for rule in dict.fromkeys(r["rule"] for r in sw):
            rs = [r for r in sw if r["problem"] == problem and r["rule"] == rule]
            if rs:
                worst = max(rs, key=lambda r: r["nitsche_ci"])
                parts.append(f"{PROBLEM_LABELS.get(problem, problem)} {_rule(rule)} "
                             f"{worst['nitsche_ci']:.2f} (at {worst['basis']}, "
                             f"{_kern(worst['kernel'])}, "
                             f"κh/Δx = {worst['support_ratio']:g})")
    return ("Measured Nitsche inverse constant C_I (largest over the sweep; β = "
            f"{NITSCHE_BETA:g} is coercive for C_I < {NITSCHE_BETA / 2:g}): "
            + "; ".join(parts) + ".")


# --------------------------------------------------------------------------------------
# summary.md
# --------------------------------------------------------------------------------------


def summary_markdown(rows: list[dict], orders: list[dict], cfg, prov: dict,
                     files: dict[str, str], extra_lines: list[str] | None = None) -> str:
    """The whole ``summary.md``."""
    L: list[str] = []
    L.append("# Galerkin convergence study: patch tests, orders, smoothing length, cost\n")
    L.append(f"Mode **{prov['mode']}**, `{prov['command']}`; "
             f"mlsgalerkin {prov['mlsgalerkin_version']}, "
             f"commit `{prov['git_commit']}`, {prov['date_utc']}; {prov['machine']['platform']}, "
             f"{prov['machine']['cpu_count']} CPUs; {prov.get('scheduler', 'serial')}, numba "
             f"threads {prov.get('numba_threads')} per worker; environment "
             + (", ".join(f"{k}={v}" for k, v in prov.get("environment", {}).items()) or "—")
             + f"; total wall time {prov.get('wall_s', math.nan):.0f} s. "
             f"See `{files.get('provenance')}`.\n")
    L.append("## Set-up\n")
    L.append("* **Problems** (`mlsgalerkin/studies/galerkin/problems.py`): linear patch tests "
             "(Poisson u = 1 + 2x − 3y; plane-strain elasticity u = c + Ax, E = 1000, ν = 0.3) on "
             "9 × 9 nodes of the unit square; manufactured Poisson u = sin(πx)cos(πy) + xy² on "
             "the unit square with Nitsche on all edges; the Timoshenko cantilever (Timoshenko & "
             "Goodier), **plane stress**, L = 48, D = 12, E = 3e7, ν = 0.3, P = 1000: exact "
             "displacement imposed by Nitsche on x = 0, parabolic shear traction on x = L, free "
             "top and bottom.")
    L.append("* **Nodes**: regular grids; *perturbed* = interior nodes moved by up to ±0.3 Δx "
             f"(uniform, seed {cfg.seed}), boundary nodes on the boundary.")
    L.append("* **Rules**: DNI (Voronoi volumes, direct gradients); SCNI (gradients smoothed over "
             "the clipped Voronoi cells, 2 Gauss points per cell edge); VCI (Chen, Hillman & Rüter 2013: "
             "DNI trial functions, test gradients corrected so that the linear integration "
             f"constraint holds, correction profile `{VCI_CORRECTION}`, Petrov–Galerkin, "
             "`mlsgalerkin/integration/vci.py`; the constant profile is measured as an "
             "ablation, `vci_constant`, linear basis and first kernel only).")
    L.append(f"* **Boundary conditions**: symmetric Nitsche, β = {NITSCHE_BETA:g}, modulus 1 "
             "(Poisson) or E (elasticity), flux from the rule's gradient at the nearest "
             "integration point; penalty β = "
             f"{PENALTY_BETA:g} in the patch tests for comparison. Boundary Gauss points on the "
             "Voronoi cell edges (the SCNI rule's own).")
    L.append("* **Support**: kernels compared at equal support radius κh; `support_ratio` = κh/Δx "
             "= 3 (linear basis) and 4 (quadratic basis), i.e. h/Δx = 1.5 / 2 for the cubic "
             "spline and Wendland C2 (κ = 2) and 1 / 1.33 for the quintic spline (κ = 3). The "
             "quadratic basis needs ≥ 6 well-spread neighbours at the domain corners; the "
             "h-sweep shows the fallbacks below that.")
    L.append("* **Errors**: relative L2 and H1-seminorm errors (and the energy norm for "
             "elasticity) against the exact solution, on a 4 × 4 Gauss grid per Δx × Δx cell, with "
             "the direct MLS shape functions of the solution (independent of the rule). "
             "*Rule gradient* error (`error_h1_rule`): the gradient the rule itself uses "
             "(smoothed for SCNI, direct for DNI/VCI trial functions) at its integration points, "
             "weighted by its weights, against the exact gradient there.")
    L.append("* **Wall time** per point = shape functions (Voronoi cells, rule, VCI correction, "
             "boundary quadratures) + assembly (stiffness, loads, Nitsche/traction terms) + solve "
             "(SuperLU, MMD_ATA ordering); the error evaluation is not counted. Single-threaded "
             f"numba and BLAS in every worker; runs under {cfg.min_time:g} s are repeated (up to "
             f"{cfg.max_repeats}×) and the fastest time per phase is kept; the `worker` column "
             "names the process that measured the row.\n")

    L.append("## Patch tests (relative errors)\n")
    ptab, agg = patch_table(rows)
    L.append("Nitsche columns: smallest – largest relative L2 error over kernels "
             f"({', '.join(_kern(k) for k in cfg.patch_kernels)}) and bases "
             f"({', '.join(cfg.patch_bases)}), and the largest energy-norm error; penalty: linear "
             f"basis, {', '.join(_kern(k) for k in cfg.penalty_kernels)}.\n")
    L.append(ptab + "\n")

    for problem in cfg.levels:
        q, qname = _quantity(problem)
        L.append(f"## {PROBLEM_LABELS.get(problem, problem)}: observed orders\n")
        lv = cfg.levels[problem]
        L.append(f"Spacings Δx = {', '.join(f'{s:g}' for s in sorted(lv, reverse=True))}. Order = "
                 "least-squares slope of log error against log Δx over all levels (in parentheses: "
                 "between the two finest levels).\n")
        L.append("Regular nodes:\n")
        L.append(orders_table(orders, problem, "regular") + "\n")
        if any(o["problem"] == problem and o["nodes"] == "perturbed" for o in orders):
            L.append("Perturbed nodes:\n")
            L.append(orders_table(orders, problem, "perturbed") + "\n")
        L.append(f"![convergence]({files.get('convergence_' + problem, '')})\n")

    L.append("## What accuracy costs in time\n")
    k0 = cfg.kernels[0]
    L.append(f"Wall time (shape + assembly + solve) to reach a relative error, interpolated in "
             f"log-log between the measured levels ({_kern(k0)}, regular nodes):\n")
    for problem in cfg.levels:
        L.append(f"{PROBLEM_LABELS.get(problem, problem)}:\n")
        L.append(_cost_table(rows, problem, k0) + "\n")
    L.append(f"![work-precision]({files.get('work_precision', '')})\n")
    L.append(f"![wall-time split]({files.get('wall_split', '')})\n")

    L.append("## Smoothing-length sweep and spurious zero-energy modes\n")
    L.append(f"Fixed resolution, support radius / spacing κh/Δx = "
             f"{', '.join(f'{x:g}' for x in cfg.sweep_ratios)}.\n")
    L.append(f"* **Spurious zero-energy modes** (bold): eigenvalues of the stiffness **without** "
             f"boundary conditions below {cfg.eig_tol:g} × the largest, minus the rigid modes "
             "(1 Poisson, 3 elasticity); dense `eigvalsh` (VCI is unsymmetric: singular values).")
    L.append("* **Soft modes** (symmetric rules): the rule's energy of every "
             "non-rigid nodal vector against the energy of the same shape functions integrated "
             "accurately (direct gradients, 4 × 4 Gauss points per cell), through the generalised "
             "eigenvalues μ of K_ref v = μ K_rule v. Count of modes with μ > 10 (energy "
             "underestimated more than tenfold) and, in parentheses, the largest μ.")
    L.append("* **Error table**: relative error with boundary conditions · smallest non-rigid "
             "eigenvalue / largest (fb = points that fell back to a lower polynomial order).\n")
    for problem in cfg.sweep_spacing:
        for nodes in cfg.sweep_layouts:
            sw = [r for r in rows if r["study"] == "h_sweep" and r["problem"] == problem
                  and r["nodes"] == nodes]
            if not sw:
                continue
            n = sw[0]["n_nodes"]
            q, qname = _quantity(problem)
            L.append(f"{PROBLEM_LABELS.get(problem, problem)}, {nodes} nodes ({n} nodes), "
                     "spurious zero modes / soft modes (largest μ):\n")
            L.append(_sweep_table(rows, problem, nodes, "modes") + "\n")
            L.append(f"{PROBLEM_LABELS.get(problem, problem)}, {nodes} nodes, relative {qname} "
                     "error · smallest non-rigid eigenvalue / largest:\n")
            L.append(_sweep_table(rows, problem, nodes, "error") + "\n")
        L.append(f"![h-sweep]({files.get('h_sweep_' + problem, '')})\n")
    L.append("**Threshold.** The eigenvalue gap around the threshold:\n")
    L.extend(f"* {s}" for s in _gap_lines(rows))
    L.append("")
    ci = _ci_line(rows)
    if ci:
        L.append(ci + "\n")
    L.append(f"![spectra]({files.get('spectra', '')})\n")

    L.append("## Observations (measured)\n")
    L.extend(f"* {s}" for s in observations(rows, orders, agg))
    if extra_lines:
        L.extend(f"* {s}" for s in extra_lines)
    L.append("")
    L.append("## Files\n")
    L.extend(f"* `{v}`" for v in files.values())
    return "\n".join(L) + "\n"
