"""Shape-function throughput: points per second of MLS values + exact gradients.

For each case the nodes are a jittered lattice of spacing ``dx`` (see ``bench_neighbors``), the
evaluation points are the nodes themselves (the Galerkin nodal-integration case), the kernel is
the cubic spline with ``h = 1.2 dx`` and ``kappa = 2`` (about 21 neighbours in 2D, 57 in 3D).
The neighbour table is built *first*, outside the timing; the timed call is the compiled
evaluation :func:`mlsgalerkin.approximation.evaluate_shape_functions` (values and gradients
of every pair, per-point condition numbers and fallback orders) — what a solver calls every
step after its own neighbour update.

Cases: 2D linear MLS (the fused fast path; once with fresh output arrays per call and once
reusing the previous call's pair buffers via ``out=``, as a time-stepping solver does), 2D
linear through the general path (to show what
the fused path buys), 2D quadratic, 3D linear, 3D quadratic; sizes about 1e4, 1e5 and 1e6
points. Warm-up (JIT) on a small problem first; each size is the best of several runs
(``bench_neighbors.best_of``).
Timings are reported, never asserted.

Run alone::

    .venv/bin/python benchmarks/bench_shape_functions.py [--sizes 1e4 1e5] [--cases 2d-linear]
"""

from __future__ import annotations

import argparse
import gc
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_neighbors import (  # noqa: E402
    DX, H_OVER_DX, SIZES, add_flatness, jittered_lattice, measure,
)

#: Goal printed next to the 2D linear MLS numbers (not asserted anywhere).
GOAL_POINTS_PER_S = 4e6

#: name -> (dim, polynomial order, method, use the fused fast path where it exists)
CASES: dict[str, tuple[int, int, str, bool]] = {
    "2d-linear": (2, 1, "mls", True),
    "2d-linear-reuse": (2, 1, "mls", True),
    "2d-linear-general": (2, 1, "mls", False),
    "2d-quadratic": (2, 2, "mls", True),
    "3d-linear": (3, 1, "mls", True),
    "3d-quadratic": (3, 2, "mls", True),
}
_ORDER_NAMES = {0: "constant", 1: "linear", 2: "quadratic"}


def _case_label(name: str) -> str:
    dim, order, method, fast = CASES[name]
    label = f"{dim}D {_ORDER_NAMES[order]} {method.upper()}"
    if name.endswith("-reuse"):
        return label + " (reused buffers)"
    return label + ("" if fast else " (general path)")


def run(
    sizes: Sequence[int] = SIZES,
    cases: Sequence[str] = tuple(CASES),
    repeats: int = 3,
    log: Callable[[str], None] = print,
) -> list[dict]:
    """Time the shape-function evaluation; one row per (case, size)."""
    from mlsgalerkin.approximation import evaluate_shape_functions
    from mlsgalerkin.kernels import get_kernel
    from mlsgalerkin.neighbors import find_neighbors

    kernel = get_kernel("cubic_spline")
    rows = []
    for name in cases:
        dim, order, method, fast = CASES[name]

        def setup(n: int):
            nodes = jittered_lattice(n, dim)
            h = np.full(nodes.shape[0], H_OVER_DX * DX)
            nb = find_neighbors(nodes, nodes, node_radius=kernel.support * h)
            return nodes, h, nb

        reuse = name.endswith("-reuse")
        previous: list = [None]

        def evaluate(nodes, h, nb):
            # "-reuse": a solver's step, which overwrites the pair buffers of its last table
            table = evaluate_shape_functions(
                nodes, nodes, h, nb, kernel, order, method, fast=fast,
                out=previous[0] if reuse else None,
            )
            if reuse:
                previous[0] = table
            return table

        evaluate(*setup(2_000))  # JIT compile (or load from the cache)
        for n in sizes:
            nodes, h, nb = setup(n)
            t, table, done, other = measure(lambda: evaluate(nodes, h, nb), repeats, log=log)
            n_pts = nodes.shape[0]
            row = {
                "benchmark": "shape_functions",
                "case": _case_label(name),
                "dim": dim,
                "basis": _ORDER_NAMES[order],
                "method": method,
                "n_points": n_pts,
                "n_pairs": nb.n_pairs,
                "mean_neighbors": nb.n_pairs / n_pts,
                "seconds": t,
                "repeats": done,
                "other_load": other,
                "points_per_s": n_pts / t,
                "ns_per_point": 1e9 * t / n_pts,
                "n_fallback": table.n_fallback,
                "max_condition": float(table.condition.max()),
                "goal_points_per_s": GOAL_POINTS_PER_S if name.startswith("2d-linear") and fast else float("nan"),
            }
            rows.append(row)
            log(
                f"{row['case']:<34} n={n_pts:>9,d}  nbrs={row['mean_neighbors']:5.1f}  "
                f"t={t:8.4f} s  {row['points_per_s']:11.3e} points/s  "
                f"fallbacks={row['n_fallback']}  other load={other:.2f}"
            )
            del table, nodes, h, nb
            gc.collect()
    add_flatness(rows)
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", nargs="+", type=float, default=list(SIZES))
    p.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args(argv)
    rows = run([int(s) for s in a.sizes], a.cases, a.repeats)
    print(f"\ngoal (2D linear MLS): >= {GOAL_POINTS_PER_S:.0e} points/s")
    print("cost ratio = per-point cost against the smallest size (flatness goal <= 1.5)")
    for r in rows:
        print(f"{r['case']:<34} n={r['n_points']:>9,d}  cost ratio = {r['cost_ratio']:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
