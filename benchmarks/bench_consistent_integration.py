"""Cost of the consistent nodal integration (``ConsistentIntegration``) against the internal force
it corrects.

On the two-layer tank at rest (``stratified_rest`` under its lid, the state after the first
evaluation) at 20 and 40 rows per depth, each part of one evaluation of the effect is timed:

- the Shepard sums, one pass over the pairs with a kernel evaluation each
  (:func:`~mlsgalerkin.fluid.consistent_integration.shepard_sum`);
- the node sums ``e``, ``w``, ``S`` and the lowest Shepard sum, one scatter over the shape table
  (:func:`~mlsgalerkin.assembly.integration_terms`);
- the whole effect, ``ConsistentIntegration.force``;
- the internal force and lumped mass it corrects, one scatter
  (:func:`~mlsgalerkin.assembly.internal_force_and_mass`);
- the numpy reference of the correction, for the speed-up.

Timing as in the other benchmarks (``bench_neighbors.measure``: best of several calls, a
re-measurement when other processes were busy, the *other load* column). Nothing is asserted.

Run::

    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_consistent_integration.py \\
        --out benchmarks/results/consistent_integration.md
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_neighbors import measure, provenance_line  # noqa: E402


def tank(rows: int):
    """The started simulation of the two-layer tank at ``rows`` rows per depth, and its effect."""
    from mlsgalerkin.fluid import ConsistentIntegration
    from mlsgalerkin.problems import stratified_rest as sr
    from mlsgalerkin.simulation import Simulation

    p = sr.Parameters(dx=sr.Parameters().depth / rows)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = sr.make_scene(p)
        sim = Simulation(scene)
        sim.start()
    effect = next(e for e in scene.schemes[0].effects if isinstance(e, ConsistentIntegration))
    return sim.state.fluid, effect


def rows_for(rows: int, repeats: int) -> list[dict]:
    from mlsgalerkin.assembly import integration_terms, internal_force_and_mass
    from mlsgalerkin.fluid.consistent_integration import consistency_force_reference, shepard_sum
    from mlsgalerkin.kernels import get_kernel

    s, effect = tank(rows)
    kernel = get_kernel("cubic_spline")
    V = np.ascontiguousarray(s.volume)
    sv = np.ascontiguousarray(s.stress * V[:, None, None])
    c = shepard_sum(s.x, s.h, V, s.table, kernel)
    force = s.force.copy()

    def whole():
        s.force[:] = force
        effect.force(s)

    parts = [
        ("Shepard sums", lambda: shepard_sum(s.x, s.h, V, s.table, kernel)),
        ("node sums e, w, S", lambda: integration_terms(s.table, V, sv, c)),
        ("whole effect", whole),
        ("internal force and mass (for scale)", lambda: internal_force_and_mass(s.table, sv, s.M)),
        ("numpy reference of the correction", lambda: consistency_force_reference(s.table, V, sv, c)),
    ]
    out = []
    for name, fn in parts:
        t, _, runs, other = measure(fn, repeats=repeats)
        out.append({"rows": rows, "particles": s.n, "pairs": int(s.table.indptr[-1]), "part": name, "seconds": t,
                    "other": other})
    s.force[:] = force
    return out


def markdown(table: list[dict]) -> list[str]:
    lines = ["| rows per depth | particles | pairs | part | time per call | pairs per second | "
             "against the internal force | other load |", "|---|---|---|---|---|---|---|---|"]
    for rows in sorted({r["rows"] for r in table}):
        group = [r for r in table if r["rows"] == rows]
        scale = next(r["seconds"] for r in group if r["part"].startswith("internal force"))
        for r in group:
            lines.append(f"| {rows} | {r['particles']:,} | {r['pairs']:,} | {r['part']} | {1e6 * r['seconds']:.0f} µs | "
                         f"{r['pairs'] / r['seconds']:.2e} | {r['seconds'] / scale:.2f}× | {r['other']:.2f} |")
    return lines


def provenance() -> str:
    return provenance_line("benchmarks/bench_consistent_integration.py", sys.argv[1:])


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rows", nargs="+", type=int, default=[20, 40], help="particle rows per depth")
    p.add_argument("--repeats", type=int, default=20)
    p.add_argument("--out", type=Path, help="write the table to this markdown file")
    a = p.parse_args(argv)
    table = [r for rows in a.rows for r in rows_for(rows, a.repeats)]
    md = ["# Consistent nodal integration: cost per evaluation", "", provenance(), ""] + markdown(table)
    print("\n".join(md))
    if a.out:
        a.out.write_text("\n".join(md) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
