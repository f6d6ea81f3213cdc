"""Galerkin scatter throughput: internal force plus continuity rate, points per second.

One fluid-step's worth of assembly on a shape table that is already built: the internal-force
sum ``f_i = -Σ_k σ_k ∇N_i(x_k) V_k`` (numba, a gather over the table's node columns, which
are built again in every repeat, as a fluid step after a neighbour rebuild builds them) and the collocated
continuity rate ``dρ_k/dt = -ρ_k tr Σ_j v_j ⊗ ∇N_j(x_k)``. 2D jittered lattice, cubic spline,
linear basis, ``h = 1.2 dx`` (about 21 neighbours). Goal (this project's): ≥ 1e6 points/s with 2
threads, per-point cost flat from 1e4 to 1e6. Timings are reported, never asserted.

Run alone::

    .venv/bin/python benchmarks/bench_assembly.py [--sizes 1e4 1e5]
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_neighbors import DX, H_OVER_DX, SIZES, add_flatness, jittered_lattice, measure  # noqa: E402

GOAL_POINTS_PER_S = 1e6


def run(sizes: Sequence[int] = SIZES, repeats: int = 3, log: Callable[[str], None] = print) -> list[dict]:
    """Time internal force + continuity rate; one row per size."""
    from mlsgalerkin import assembly
    from mlsgalerkin.approximation import evaluate_shape_functions
    from mlsgalerkin.neighbors import find_neighbors

    rng = np.random.default_rng(0)

    def setup(n: int):
        x = jittered_lattice(n, 2)
        h = np.full(x.shape[0], H_OVER_DX * DX)
        nb = find_neighbors(x, x, node_radius=2.0 * h)
        table = evaluate_shape_functions(x, x, h, nb, "cubic_spline", "linear")
        stress = rng.normal(size=(x.shape[0], 2, 2))
        velocity = rng.normal(size=(x.shape[0], 2))
        rho = np.full(x.shape[0], 1000.0)
        volume = np.full(x.shape[0], DX**2)
        return table, stress, velocity, rho, volume

    def step(table, stress, velocity, rho, volume):
        # a fresh table on fresh neighbour arrays, as after a neighbour rebuild: its node columns are built again
        table = dataclasses.replace(table, indices=table.indices.copy(), meta={})
        f = assembly.internal_force(table, stress, volume)
        drho = assembly.continuity_rate(table, velocity, rho)
        return f, drho

    step(*setup(2_000))  # JIT compile (or load from the cache)
    rows = []
    for n in sizes:
        args = setup(n)
        t, _, done, other = measure(lambda: step(*args), repeats, log=log)
        table = args[0]
        row = {
            "benchmark": "assembly",
            "case": "2D internal force + continuity",
            "dim": 2, "basis": "linear", "method": "mls",
            "n_points": table.n_points, "n_pairs": table.n_pairs,
            "mean_neighbors": table.n_pairs / table.n_points,
            "seconds": t, "repeats": done, "other_load": other,
            "points_per_s": table.n_points / t, "ns_per_point": 1e9 * t / table.n_points,
            "goal_points_per_s": GOAL_POINTS_PER_S,
        }
        rows.append(row)
        log(f"{row['case']:<34} n={row['n_points']:>9,d}  t={t:8.4f} s  "
            f"{row['points_per_s']:11.3e} points/s  other load={other:.2f}")
        del args, table
        gc.collect()
    add_flatness(rows)
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", nargs="+", type=float, default=list(SIZES))
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args(argv)
    rows = run([int(s) for s in a.sizes], a.repeats)
    print(f"\ngoal: >= {GOAL_POINTS_PER_S:.0e} points/s")
    for r in rows:
        print(f"n={r['n_points']:>9,d}  cost ratio = {r['cost_ratio']:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
