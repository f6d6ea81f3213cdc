"""Penalty contact throughput: the kernel in pairs per second (numba against the numpy
reference), and the cost of ``PenaltyWalls`` in a fluid step.

**Kernel.** :func:`mlsgalerkin.contact.penalty_forces` as one call does it: broad phase
(:func:`~mlsgalerkin.contact.candidate_pairs`), closest points and forces of every candidate
pair, reactions gathered on the master nodes, totals, moment and stable step. The geometry is
that of particles on a wall: a floor of facets of the particle spacing ``dx`` (2D: segments; 3D:
two triangles per ``dx × dx`` cell) and one row of slaves above it at height ``dx/2`` jittered
by ``±0.3 dx`` in every coordinate, thickness ``dx/2``, reach ``dx``: the half of the slaves
below ``dx/2`` are within the margin of the floor and in contact. *Pairs* are the candidate
slave–facet pairs the narrow phase tests (about 1 per slave in 2D — 2 per candidate slave — and
4 in 3D); *contacts* the active ones. The numba kernel is timed at about 1e4, 1e5 and 1e6
slaves, the reference (:func:`penalty_forces_reference`, a Python loop over slaves with an
``O(n k)`` broad phase) at 1e3 and 1e4 (2D) and 1e3 (3D).

**Fluid step.** The 2D dam break of ``bench_fluid_step.py`` (``a/dx`` = 62 and 134, 9.8e3 and
4.0e4 fluid + wall particles) as shipped (``Walls``) and with the tank's penalty surface and
``PenaltyWalls`` added (``wall_box(..., surface=True)``): the same snapshot after 5 warm-up
steps, blocks of steps timed alternately, best of 3 each. Early in the collapse few particles
touch (the column stands on the floor at ``g = 0``): the cost is the broad phase of every
fluid particle against the tank, which does not depend on how many touch.

Timing as in the other benchmarks (``bench_neighbors.measure``: best of several calls, a
re-measurement when other processes were busy, the *other load* column). Nothing is asserted.

Run alone::

    .venv/bin/python benchmarks/bench_contact.py                 # both parts, about 2 min
    .venv/bin/python benchmarks/bench_contact.py --quick         # 1e4 slaves, a/dx = 62 only
    .venv/bin/python benchmarks/bench_contact.py --out benchmarks/results/contact.md

Measured on 2026-11-30 with ``NUMBA_NUM_THREADS=1`` (the reference machine, 2 cores, was
shared: another process held one core during most rows, column *other load*); full tables in
``benchmarks/results/contact.md``:

- kernel, 2D: 3.1×10⁶ pairs/s at 1e4 slaves, 4.7×10⁶ at 1e5, 4.4×10⁶ at 1e6; the reference
  2.1×10⁴ pairs/s at 1e3 slaves and 4.0×10³ at 1e4 (its broad phase is ``O(n k)``): numba
  150× (against the reference at 1e3) to 770× (at 1e4) faster;
- kernel, 3D: 8.1×10⁶ pairs/s at 1e4 slaves, 8.3×10⁶ at 1e5, 7.2×10⁶ at 1e6 (2.0×10⁶
  slaves/s); the reference 1.75×10⁴ pairs/s at 1e3: 460×;
- fluid step, dam break, 1 thread: ``PenaltyWalls`` adds 6.4 % at 9.8e3 particles (0.37 ms of
  6.1 ms per step) and 3.8 % at 4.0e4 (1.1 ms of 25 ms).

Before the kernel was tuned (closest point inlined, narrow phase over the slaves with candidates
only, boxes in numba) the 2D kernel did 1.8×10⁶ pairs/s at 1e4 slaves and the fluid step paid
10 % at 9.8e3 particles.
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_fluid_step import FILTER_EVERY, WARMUP_STEPS, _time_block  # noqa: E402
from bench_neighbors import OtherLoad, measure, provenance_line  # noqa: E402

#: Slave counts of the kernel benchmark, numba and reference.
SIZES = (10_000, 100_000, 1_000_000)
REFERENCE_SIZES = {2: (1_000, 10_000), 3: (1_000,)}
#: a/dx of the dam break (9.8e3 and 4.0e4 fluid + wall particles, as in bench_fluid_step).
RATIOS = (62, 134)
DX = 0.01
JITTER = 0.3


def wall_and_slaves(n: int, dim: int, seed: int = 0):
    """A floor of facets of size ``DX`` under one jittered row of about ``n`` slaves (module
    docstring): ``(slave positions, master nodes, facets)``."""
    rng = np.random.default_rng(seed)
    side = int(round(n if dim == 2 else n ** 0.5))
    if dim == 2:
        nodes = np.column_stack([np.arange(side + 1)[::-1] * DX, np.zeros(side + 1)])  # right to left: normal up
        facets = np.column_stack([np.arange(side), np.arange(1, side + 1)])
        x = np.column_stack([(np.arange(side) + 0.5) * DX, np.full(side, 0.5 * DX)])
    else:
        g = np.arange(side + 1) * DX
        gx, gy = np.meshgrid(g, g, indexing="ij")
        nodes = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
        idx = np.arange((side + 1) ** 2).reshape(side + 1, side + 1)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
        facets = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
        cx, cy = np.meshgrid((np.arange(side) + 0.5) * DX, (np.arange(side) + 0.5) * DX, indexing="ij")
        x = np.column_stack([cx.ravel(), cy.ravel(), np.full(cx.size, 0.5 * DX)])
    x += rng.uniform(-JITTER, JITTER, x.shape) * DX
    return np.ascontiguousarray(x), nodes, facets


def kernel_rows(sizes: Sequence[int], dims: Sequence[int], reference: bool, repeats: int,
                log: Callable[[str], None] = print) -> list[dict]:
    """Time ``penalty_forces`` (and the reference); one row per (implementation, dim, size)."""
    import numba

    from mlsgalerkin.contact import candidate_pairs, penalty_forces, penalty_forces_reference, search_margin

    kw = dict(dt_ref=1e-4, thickness=0.5 * DX, reach=DX)
    rows = []
    for dim in dims:
        impls = [("numba", penalty_forces, sizes)]
        if reference:
            impls.append(("reference", penalty_forces_reference, REFERENCE_SIZES[dim]))
        for name, fn, ns in impls:
            x, nodes, facets = wall_and_slaves(2000, dim)
            fn(x, np.zeros_like(x), 0.1, nodes, None, None, facets, **kw)  # compile / load the cache
            for n in ns:
                x, nodes, facets = wall_and_slaves(n, dim)
                v = np.zeros_like(x)
                pairs = int(candidate_pairs(x, nodes, facets, search_margin(kw["thickness"], kw["reach"]))[1].size)
                t, res, done, other = measure(lambda: fn(x, v, 0.1, nodes, None, None, facets, **kw), repeats,
                                              log=log)
                row = {"benchmark": "contact_kernel", "implementation": name, "dim": dim, "n_slaves": len(x),
                       "n_facets": len(facets), "pairs": pairs, "contacts": res.contacts, "seconds": t,
                       "repeats": done, "other_load": other, "pairs_per_s": pairs / t,
                       "slaves_per_s": len(x) / t, "threads": numba.get_num_threads()}
                rows.append(row)
                log(f"penalty kernel {name:<9} {dim}D  slaves={len(x):>9,d} facets={len(facets):>9,d} "
                    f"pairs={pairs:>9,d} contacts={res.contacts:>8,d}  {t:9.5f} s  {row['pairs_per_s']:10.3e} pairs/s  "
                    f"{row['slaves_per_s']:10.3e} slaves/s  other load={other:.2f}")
                del x, nodes, facets, v, res
                gc.collect()
    return rows


def dam_break(ratio: int, penalty: bool):
    """The dam-break simulation of bench_fluid_step at ``a/dx = ratio``, with or without the
    tank's penalty surface and ``PenaltyWalls`` (the problem's ``penalty_walls`` parameter; on by
    default)."""
    from mlsgalerkin.problems.dam_break import Parameters, make_scene
    from mlsgalerkin.simulation import Simulation

    p = Parameters(dx=Parameters().column_width / ratio, penalty_walls=penalty)
    scene = make_scene(p)
    sim = Simulation(scene)
    sim.start()
    for _ in range(WARMUP_STEPS):
        sim.step(sim.time_step())
    return sim, sim.snapshot()


def fluid_rows(ratios: Sequence[int], repeats: int, steps: int | None,
               log: Callable[[str], None] = print) -> list[dict]:
    """Time dam-break steps without and with PenaltyWalls, alternately; one row per size."""
    import numba

    rows = []
    for ratio in ratios:
        cases = {pen: dam_break(ratio, pen) for pen in (False, True)}
        s = cases[False][0].state.fluid
        n_steps = steps or FILTER_EVERY * max(1, round(3e6 / s.n / FILTER_EVERY))
        best = {False: None, True: None}
        load = OtherLoad().start()
        for _ in range(repeats):
            for pen, (sim, snap) in cases.items():
                blk = _time_block(sim, snap, n_steps)
                if best[pen] is None or blk["seconds"] < best[pen]["seconds"]:
                    best[pen] = blk
        other = load.stop()
        sim = cases[True][0]
        contacts = sim.state.fluid.sensors["penalty_contacts"]
        t0, t1 = best[False]["seconds"], best[True]["seconds"]
        row = {"benchmark": "contact_fluid_step", "a_over_dx": ratio, "n_points": s.n, "n_fluid": s.n_fluid,
               "steps": n_steps, "repeats": repeats, "threads": numba.get_num_threads(),
               "ms_per_step_without": 1e3 * t0 / n_steps, "ms_per_step_with": 1e3 * t1 / n_steps,
               "penalty_stage_ms_per_step": 1e3 * best[True]["stages"].get("penalty_walls", 0.0) / n_steps,
               "overhead": t1 / t0 - 1.0, "contacts_at_end": int(contacts), "other_load": other}
        rows.append(row)
        log(f"dam break a/dx={ratio:>4d} n={s.n:>7,d}  {n_steps} steps x{repeats}: without {row['ms_per_step_without']:7.3f}"
            f" ms/step, with PenaltyWalls {row['ms_per_step_with']:7.3f} ms/step ({100 * row['overhead']:+.1f} %), "
            f"penalty_walls stage {row['penalty_stage_ms_per_step']:.3f} ms/step, contacts {contacts}, "
            f"other load={other:.2f}")
        del cases, sim
        gc.collect()
    return rows


def markdown(kernel: list[dict], fluid: list[dict]) -> list[str]:
    md = []
    if kernel:
        md += ["## Penalty kernel (`penalty_forces`, broad + narrow phase + gather)", "",
               "| implementation | dim | slaves | facets | candidate pairs | contacts | best (s) | pairs/s | slaves/s "
               "| runs | other load |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for r in kernel:
            md.append(f"| {r['implementation']} | {r['dim']} | {r['n_slaves']:,} | {r['n_facets']:,} | {r['pairs']:,} "
                      f"| {r['contacts']:,} | {r['seconds']:.4g} | {r['pairs_per_s']:.3g} | {r['slaves_per_s']:.3g} "
                      f"| {r['repeats']} | {r['other_load']:.2f} |")
        md.append("")
        for dim in sorted({r["dim"] for r in kernel}):
            ref = [r for r in kernel if r["dim"] == dim and r["implementation"] == "reference"]
            for r in ref:
                nb = next((q for q in kernel if q["dim"] == dim and q["implementation"] == "numba"
                           and q["n_slaves"] == r["n_slaves"]), None) or min(
                    (q for q in kernel if q["dim"] == dim and q["implementation"] == "numba"),
                    key=lambda q: q["n_slaves"], default=None)
                if nb is not None:
                    md.append(f"- {dim}D, {r['n_slaves']:,} slaves: numba {nb['pairs_per_s'] / r['pairs_per_s']:.0f}× "
                              f"the reference's pairs/s (numba at {nb['n_slaves']:,} slaves)")
        md.append("")
    if fluid:
        md += ["## PenaltyWalls in a fluid step (2D dam break, early steps)", "",
               "| a/dx | particles | steps × runs | ms/step without | ms/step with | overhead | `penalty_walls` stage "
               "(ms/step) | contacts | other load |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for r in fluid:
            md.append(f"| {r['a_over_dx']} | {r['n_points']:,} | {r['steps']} × {r['repeats']} "
                      f"| {r['ms_per_step_without']:.3f} | {r['ms_per_step_with']:.3f} | {100 * r['overhead']:+.1f} % "
                      f"| {r['penalty_stage_ms_per_step']:.3f} | {r['contacts_at_end']} | {r['other_load']:.2f} |")
        md.append("")
    return md


def provenance() -> str:
    return provenance_line("benchmarks/bench_contact.py", sys.argv[1:])


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="1e4 slaves and a/dx = 62 only")
    p.add_argument("--sizes", nargs="+", type=float, default=list(SIZES), help="slave counts of the kernel")
    p.add_argument("--dims", nargs="+", type=int, default=[2, 3])
    p.add_argument("--ratios", nargs="+", type=int, default=list(RATIOS), help="a/dx of the dam break")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--steps", type=int, help="steps per fluid block (default ~3e6 particle-steps)")
    p.add_argument("--no-reference", action="store_true", help="skip the numpy reference")
    p.add_argument("--no-fluid", action="store_true", help="skip the fluid step")
    p.add_argument("--out", type=Path, help="write the tables to this markdown file")
    a = p.parse_args(argv)
    sizes = [int(s) for s in a.sizes]
    ratios = a.ratios
    if a.quick:
        sizes, ratios = [min(sizes)], [min(ratios)]
    t0 = time.perf_counter()
    kernel = kernel_rows(sizes, a.dims, not a.no_reference, a.repeats)
    fluid = [] if a.no_fluid else fluid_rows(ratios, a.repeats, a.steps)
    md = ["# Penalty contact benchmark", "", provenance(), ""] + markdown(kernel, fluid)
    print()
    print("\n".join(md))
    print(f"({time.perf_counter() - t0:.0f} s)")
    if a.out:
        a.out.write_text("\n".join(md) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
