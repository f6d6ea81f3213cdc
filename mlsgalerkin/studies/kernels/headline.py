"""The key numbers of a kernel-study run, from its rows and fits (console report and summary).

``beta_integral``  fitted slope β (error ∝ h^β) of the integral approximation, N_nb fixed,
                   interior absolute error, per kernel and function;
``rel_5nb``        interior relative error with 5 neighbours at h = ``int_h_fixed``, per kernel
                   and function, and ``worst_rel_5nb`` its worst over F1-F4;
``orders_2d_all``  observed 2D orders in Δx (value, gradient) per (layout, method, kernel,
                   region); ``orders_2d`` the jittered-lattice interior ones, keyed
                   ``"method / kernel"``.
"""

from __future__ import annotations

import math
from typing import Any

from mlsgalerkin.studies.kernels.config import CLAIM_FUNCTIONS, FUNCTIONS, U2D_LABEL, StudyConfig
from mlsgalerkin.studies.kernels.fits import fit_lookup

__all__ = ["five_neighbour_errors", "headline", "orders_2d", "sph_slopes"]


def sph_slopes(fits: list[dict], kernels: list[str] | tuple[str, ...],
                    approximation: str = "integral", sweep: str = "h",
                    quantity: str = "error_abs") -> dict[str, dict[str, float]]:
    """Fitted exponent per kernel and function label of an SPH sweep (interior points)."""
    lookup = fit_lookup(fits)
    layout = "quadrature" if approximation == "integral" else "uniform"

    def exponent(k: str, f: str) -> float:
        e = lookup.get(("sph", approximation, layout, k, f, sweep, "interior", quantity))
        return e["exponent"] if e else math.nan

    return {k: {f.label: exponent(k, f.label) for f in FUNCTIONS} for k in kernels}


def five_neighbour_errors(rows: list[dict], kernels: list[str] | tuple[str, ...]
                          ) -> dict[str, dict[str, float]]:
    """Interior relative error of the integral approximation with 5 neighbours, per kernel and
    function label."""
    return {
        k: {
            r["function"]: r["error_rel"]
            for r in rows
            if r["part"] == "sph"
            and r["approximation"] == "integral"
            and r["kernel"] == k
            and r["sweep"] == "n_neighbors"
            and r["n_neighbors"] == 5
            and r["region"] == "interior"
        }
        for k in kernels
    }


def orders_2d(fits: list[dict], cfg: StudyConfig) -> dict[tuple, tuple[float, float]]:
    """(value, gradient) order in Δx per (layout, method, kernel, region) of the 2D
    resolution sweep."""
    lookup = fit_lookup(fits)
    out = {}
    for layout in cfg.layouts_2d:
        for m in cfg.methods_2d:
            for k in cfg.kernels_2d:
                for region in ("interior", "all"):
                    pv, pg = (lookup.get(("mls2d", m, layout, k, U2D_LABEL, "resolution",
                                          region, q)) for q in ("error_abs", "error_grad"))
                    out[(layout, m, k, region)] = (pv["exponent"] if pv else math.nan,
                                                   pg["exponent"] if pg else math.nan)
    return out


def headline(rows: list[dict], fits: list[dict], cfg: StudyConfig) -> dict[str, Any]:
    """The key numbers (see the module docstring)."""
    kernels = list(cfg.sph_kernels)
    rel5 = five_neighbour_errors(rows, kernels)
    out: dict[str, Any] = {
        "beta_integral": sph_slopes(fits, kernels),
        "rel_5nb": rel5,
        "worst_rel_5nb": {
            k: max((v.get(f, math.nan) for f in CLAIM_FUNCTIONS), default=math.nan)
            for k, v in rel5.items()
        },
    }
    if any(r["part"] == "mls2d" for r in rows):
        o2 = orders_2d(fits, cfg)
        out["orders_2d_all"] = o2
        out["orders_2d"] = {
            f"{m} / {k}": o2[("jittered", m, k, "interior")]
            for m in cfg.methods_2d
            for k in cfg.kernels_2d
        }
    return out
