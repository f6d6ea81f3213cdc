"""Measured statements for ``summary.md``: every number is read from the rows, none is expected.

Each ``_*`` function returns zero or more sentences about one aspect; :func:`observations`
collects them. A statement whose data are missing (e.g. the quick run has one kernel and no
perturbed convergence series) is skipped.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from mlsgalerkin.studies.galerkin.runner import PENALTY_BETA
from mlsgalerkin.studies.galerkin.sweeps import energy_quantity as quantity

from .plots import KERNEL_LABELS, PROBLEM_LABELS, RULE_LABELS

__all__ = ["observations"]


def _p(problem: str) -> str:
    return PROBLEM_LABELS.get(problem, problem)


def _r(rule: str) -> str:
    return RULE_LABELS.get(rule, rule)


def _k(kernel: str) -> str:
    return KERNEL_LABELS.get(kernel, kernel)


def _find(orders, **sel) -> list[dict]:
    return [o for o in orders if all(o.get(k) == v for k, v in sel.items())]


def _patch(patch_agg: dict) -> list[str]:
    out = []
    for rule in dict.fromkeys(k[1] for k in patch_agg):
        nit = [a for k, a in patch_agg.items() if k[1] == rule and k[3] == "nitsche"]
        pen = [a for k, a in patch_agg.items() if k[1] == rule and k[3] == "penalty"]
        if not nit:
            continue
        lo, hi = min(a["min_l2"] for a in nit), max(a["max_l2"] for a in nit)
        en = max(a["max_en"] for a in nit)
        verdict = "passes at round-off" if hi < 1e-10 else "fails"
        s = (f"Patch tests, {_r(rule)} + Nitsche: {verdict}: relative L2 error {lo:.1e} – "
             f"{hi:.1e}, energy error up to {en:.1e} (both problems, regular and perturbed "
             "nodes, every kernel and basis)")
        if pen:
            lo_p, hi_p = min(a["min_l2"] for a in pen), max(a["max_l2"] for a in pen)
            s += (f"; with the penalty method (β = {PENALTY_BETA:g}) {lo_p:.1e} – {hi_p:.1e}, "
                  "since penalty is not consistent")
        out.append(s + ".")
    return out


def _orders(orders: list[dict]) -> list[str]:
    by = defaultdict(list)
    for o in orders:
        if o["nodes"] == "regular":
            by[(o["problem"], o["rule"], o["basis"])].append(o)
    out = []
    for problem in dict.fromkeys(k[0] for k in by):
        q, qname = quantity(problem)
        key = q.removeprefix("error_")
        parts = []
        for (p, rule, basis), os_ in by.items():
            if p != problem:
                continue
            l2 = [o["order_l2"] for o in os_]
            en = [o[f"order_{key}"] for o in os_]
            rng = (lambda v: f"{min(v):.2f}" if len(v) == 1 else f"{min(v):.2f} – {max(v):.2f}")
            parts.append(f"{_r(rule)} {basis} {rng(l2)} / {rng(en)}")
        out.append(f"{_p(problem)}, observed orders L2 / {qname} (least squares over all levels, "
                   "range over kernels, regular nodes): " + "; ".join(parts) + ".")
    return out


def _dni(orders: list[dict]) -> list[str]:
    out = []
    for problem in dict.fromkeys(o["problem"] for o in orders):
        q, qname = quantity(problem)
        key = q.removeprefix("error_")
        dni = _find(orders, problem=problem, rule="dni", nodes="regular")
        ratios = []
        for d in dni:
            s = _find(orders, problem=problem, rule="scni", nodes="regular", basis=d["basis"],
                      kernel=d["kernel"])
            if s:
                ratios.append(d[f"{q}_finest"] / s[0][f"{q}_finest"])
        if dni and ratios:
            last = [d[f"order_{key}_last"] for d in dni]
            out.append(f"{_p(problem)}, DNI on regular nodes: {qname} order between the two "
                       f"finest levels {min(last):.2f} – {max(last):.2f}; at the finest level "
                       f"the {qname} error is {min(ratios):.0f} – {max(ratios):.0f}× the SCNI "
                       f"error with the same basis and kernel.")
    return out


def _scni_quadratic(orders: list[dict]) -> list[str]:
    out = []
    for problem in dict.fromkeys(o["problem"] for o in orders):
        q, qname = quantity(problem)
        key = q.removeprefix("error_")
        parts, pairs = [], []
        for o in _find(orders, problem=problem, rule="scni", basis="quadratic", nodes="regular"):
            lin = _find(orders, problem=problem, rule="scni", basis="linear", nodes="regular",
                        kernel=o["kernel"])
            if lin:
                pairs.append((o, lin[0]))
                err = o[f"{q}_finest"] / lin[0][f"{q}_finest"]
                parts.append(f"{_k(o['kernel'])}: order {o[f'order_{key}']:.2f} vs "
                             f"{lin[0][f'order_{key}']:.2f}, error {err:.2f}× "
                             f"at {o['wall_s_finest'] / lin[0]['wall_s_finest']:.1f}× the time")
        if parts:
            gain = [o[f"order_{key}"] - lin_o[f"order_{key}"] for o, lin_o in pairs]
            tail = (" The quadratic basis does not raise SCNI's order (its smoothed gradients "
                    "meet only the linear integration constraint)." if max(gain) < 0.3 else "")
            out.append(f"{_p(problem)}, SCNI quadratic against SCNI linear ({qname}, finest "
                       "level): " + "; ".join(parts) + "." + tail)
    return out


def _scni_beam_l2(orders: list[dict]) -> list[str]:
    s = _find(orders, problem="timoshenko", rule="scni", nodes="regular")
    if len(s) < 2:
        return []
    v = [o["error_l2_finest"] for o in s]
    if max(v) > 1.05 * min(v):
        return []
    return [f"Timoshenko cantilever, SCNI: the finest-level L2 error is {min(v):.3e} – "
            f"{max(v):.3e} "
            f"for every basis and kernel ({len(s)} series): the displacement error is set by the "
            "rule (smoothed strains), not by the approximation."]


def _perturbed(orders: list[dict]) -> list[str]:
    out = []
    for o in _find(orders, nodes="perturbed"):
        if o["rule"] not in ("scni", "vci") or o["basis"] != "linear":
            continue
        q, qname = quantity(o["problem"])
        key = q.removeprefix("error_")
        reg = _find(orders, nodes="regular", problem=o["problem"], rule=o["rule"], basis="linear",
                    kernel=o["kernel"])
        if not reg:
            continue
        out.append(
            f"{_p(o['problem'])}, {_r(o['rule'])} linear on perturbed nodes (±0.3 Δx): orders L2 "
            f"{o['order_l2']:.2f}, {qname} {o[f'order_{key}']:.2f} (regular nodes "
            f"{reg[0]['order_l2']:.2f}, {reg[0][f'order_{key}']:.2f}); finest {qname} error "
            f"{o[f'{q}_finest']:.2e} against {reg[0][f'{q}_finest']:.2e} on regular nodes. The "
            f"error of the rule's own gradients at its points converges with order "
            f"{o['order_h1_rule']:.2f} (finest {o['error_h1_rule_finest']:.2e}): the solution "
            "carries oscillations that the rule's energy barely sees (soft modes, see the h-sweep),"
            " which the exact gradients on the background grid do see.")
    return out


def _unstable(orders: list[dict]) -> list[str]:
    """Series whose error exceeds 100 % at some level, and the erratic VCI quadratic series."""
    out = []
    for problem in dict.fromkeys(o["problem"] for o in orders):
        q, qname = quantity(problem)
        big = [o for o in orders if o["problem"] == problem and o[f"{q}_max"] > 1.0]
        if big:
            out.append(f"{_p(problem)}, series with a relative {qname} error above 100 % at some "
                       "level: " + "; ".join(
                           f"{_r(o['rule'])} {o['basis']} {_k(o['kernel'])} {o['nodes']} "
                           f"(largest {o[f'{q}_max']:.1e}, finest {o[f'{q}_finest']:.1e})"
                           for o in big) + ". Their fitted orders are not meaningful.")
    return out


def _vci(orders: list[dict]) -> list[str]:
    out = []
    for problem in dict.fromkeys(o["problem"] for o in orders):
        q, qname = quantity(problem)
        key = q.removeprefix("error_")
        quad = _find(orders, problem=problem, rule="vci", basis="quadratic", nodes="regular")
        lin = _find(orders, problem=problem, rule="vci", basis="linear", nodes="regular")
        bad = [o for o in quad if o["order_l2_last"] < 1.0 or o[f"order_{key}_last"] < 0.5
               or o[f"{q}_max"] > 1.0]
        if bad and lin:
            out.append(f"{_p(problem)}, VCI: with a linear basis {qname} orders "
                       + ", ".join(f"{o[f'order_{key}']:.2f}" for o in lin)
                       + f"; with the quadratic basis {len(bad)} of {len(quad)} series are "
                       "erratic (error above 100 % at a level, or last-pair order below 1 in L2 "
                       f"or 0.5 in {qname}). VCI restores consistency, not stability: DNI's soft "
                       "modes remain.")
        shape = _find(orders, problem=problem, rule="vci", basis="linear", nodes="regular")
        const = _find(orders, problem=problem, rule="vci_constant", basis="linear",
                      nodes="regular")
        if shape and const:
            s = [o for o in shape if o["kernel"] == const[0]["kernel"]]
            if s:
                s, c = s[0], const[0]
                out.append(
                    f"{_p(problem)}, VCI correction profile ({_k(c['kernel'])}, linear): "
                    f"c_I = N_I gives orders {s['order_l2']:.2f} / {s[f'order_{key}']:.2f} and a "
                    f"finest {qname} error {s[f'{q}_finest']:.2e}; the constant profile "
                    f"{c['order_l2']:.2f} / {c[f'order_{key}']:.2f} and {c[f'{q}_finest']:.2e} "
                    f"(largest over the levels {c[f'{q}_max']:.2e}). The study uses c_I = N_I.")
    return out


def _kernels(orders: list[dict]) -> list[str]:
    out = []
    for problem in dict.fromkeys(o["problem"] for o in orders):
        q, qname = quantity(problem)
        s = _find(orders, problem=problem, rule="scni", basis="linear", nodes="regular")
        if len(s) < 2:
            continue
        best = min(s, key=lambda o: o[f"{q}_finest"])
        worst = max(s, key=lambda o: o[f"{q}_finest"])
        out.append(f"{_p(problem)}, SCNI linear at equal support radius: smallest finest-level "
                   f"{qname} error with the {_k(best['kernel'])} ({best[f'{q}_finest']:.2e}), "
                   f"largest with the {_k(worst['kernel'])} ({worst[f'{q}_finest']:.2e}).")
    return out


def _modes(rows: list[dict]) -> list[str]:
    sw = [r for r in rows if r["study"] == "h_sweep"]
    if not sw:
        return []
    out = []
    n_spur = sum(1 for r in sw if r["n_spurious_modes"] > 0)
    below = max(r["eig_below"] for r in sw)
    above = min(r["eig_above"] for r in sw)
    out.append(f"Zero-energy modes: {n_spur} of {len(sw)} sweep points have a stiffness "
               f"eigenvalue below the threshold besides the rigid modes. Over all points the "
               f"values counted as zero are ≤ {below:.1e} × the largest and the others ≥ "
               f"{above:.1e}: a gap of {math.log10(above / below):.0f} decades around the "
               "threshold, so the count does not depend on its exact value.")
    for problem in dict.fromkeys(r["problem"] for r in sw):
        parts = []
        for rule in ("dni", "scni"):
            rs = [r for r in sw if r["problem"] == problem and r["rule"] == rule
                  and r["nodes"] == "regular" and r.get("energy_ratio_max") is not None
                  and math.isfinite(r["energy_ratio_max"])]
            if rs:
                mu = [r["energy_ratio_max"] for r in rs]
                soft = [r["n_soft_modes"] for r in rs]
                parts.append(f"{_r(rule)} median μ_max {float(np.median(mu)):.0f} (range "
                             f"{min(mu):.0f} – {max(mu):.0f}), soft modes per point "
                             f"{min(soft)} – {max(soft)}")
        if parts:
            out.append(f"{_p(problem)}, regular nodes, over the h-sweep, worst energy "
                       "underestimate μ_max and soft modes (μ > 10): " + "; ".join(parts) + ".")
    return out


def _sweep_best(rows: list[dict]) -> list[str]:
    sw = [r for r in rows if r["study"] == "h_sweep" and r["nodes"] == "regular"]
    out = []
    for problem in dict.fromkeys(r["problem"] for r in sw):
        q, qname = quantity(problem)
        parts = []
        for rule in dict.fromkeys(r["rule"] for r in sw):
            for basis in ("linear", "quadratic"):
                rs = [r for r in sw if r["problem"] == problem and r["rule"] == rule
                      and r["basis"] == basis]
                if rs:
                    b = min(rs, key=lambda r: r[q])
                    parts.append(f"{_r(rule)} {basis} {b[q]:.1e} at κh/Δx = "
                                 f"{b['support_ratio']:g} ({_k(b['kernel'])})")
        if parts:
            out.append(f"{_p(problem)}, h-sweep, smallest {qname} error per rule and basis: "
                       + "; ".join(parts) + ".")
    return out


def _timing(rows: list[dict]) -> list[str]:
    conv = [r for r in rows if r["study"] == "convergence"]
    fin: dict[tuple, dict] = {}
    for r in conv:
        k = (r["problem"], r["rule"], r["basis"], r["kernel"], r["nodes"])
        if k not in fin or r["n_nodes"] > fin[k]["n_nodes"]:
            fin[k] = r
    parts = []
    for rule in dict.fromkeys(r["rule"] for r in conv):
        rs = [r for k, r in fin.items() if k[1] == rule]
        tot = sum(r["wall_s"] for r in rs)
        if tot > 0:
            sh = sum(r["wall_shape_s"] for r in rs) / tot
            asm = sum(r["wall_assembly_s"] for r in rs) / tot
            so = sum(r["wall_solve_s"] for r in rs) / tot
            parts.append(f"{_r(rule)} {100 * sh:.0f} / {100 * asm:.0f} / {100 * so:.0f} %")
    if not parts:
        return []
    return ["Wall-time split shape functions / assembly / solve, summed over the finest level "
            "of every series: " + "; ".join(parts) + "."]


def observations(rows: list[dict], orders: list[dict], patch_agg: dict) -> list[str]:
    """All measured statements, in the order of the summary's sections."""
    out: list[str] = []
    for f in (_patch,):
        out += f(patch_agg)
    for f in (_orders, _unstable, _dni, _scni_quadratic, _scni_beam_l2, _kernels,
              _perturbed, _vci):
        out += f(orders)
    for f in (_modes, _sweep_best, _timing):
        out += f(rows)
    return out
