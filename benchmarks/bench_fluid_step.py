"""Fluid-solver throughput: particle-steps per second of one time step on the 2D dam break.

The scene is :func:`mlsgalerkin.problems.dam_break.make_scene` as shipped (Martin & Moyce
column, ``a`` wide and ``2a`` high, in a ``5.5 a`` tank with three layers of wall particles
and its penalty surface; linear MLS, cubic spline, ``h = 1.3 dx``, KDK integrator, Tait
pressure with the tension floor, free-slip walls, Monaghan viscosity, density diffusion,
particle shifting every 4 steps, penalty walls; before the fluid-core work it listed a
density filter every 20 steps instead of the last three). Whole runs, through the wall
impact, are timed by ``bench_fluid_run.py``. The resolution ``a/dx`` is chosen so that fluid
plus wall particles come closest to the target sizes (default about 1e4, 4e4 and 1.6e5:
``a/dx`` = 62, 134, 274; even values only, see :func:`ratio_for`); the exact counts are
reported.

Per size and thread count: a fresh :class:`~mlsgalerkin.simulation.Simulation`,
``start()`` and a few warm-up steps (numba loads its disk cache on the first call), then a
snapshot (``sim.snapshot()``). A *block* is ``restore(*snapshot)`` (not timed) followed by
``sim.step(sim.time_step())`` a fixed number of times (timed, on one BLAS thread as a run holds
it): every repetition performs
exactly the same steps, neighbour rebuilds included. The time is the best of several blocks
(default 3). Blocks are a multiple of 20 steps, so each holds the same number of shifting
passes. Throughput = ``n_total × steps / best block time``.

Stage split: the fluid solver's ``timer.seconds`` (cleared before each block) of the best block, grouped as
neighbours (``neighbors``), shape functions (``shape_functions``), integration
(``integrate``) and forces (every other entry: velocity gradient, walls, pressure, internal
force, viscosities, gravity, acceleration, density filter); *untimed* is the rest of the wall
time (time-step limit, the skin check when no rebuild happens, Python between stages).

The neighbour list carries a skin of 0.15 dx and is rebuilt only when some particle has moved
0.075 dx. The timed steps are early in the collapse (slow flow, few rebuilds); later a fast
particle moves about 0.05 dx per step and the list is rebuilt nearly every step. The column
*rebuild every step (est.)* adds the cost of one ``find_neighbors`` call (timed separately,
best of 3) per step in place of the rebuilds that happened, to show that regime; ``--skin 0``
measures it directly (radius without skin, rebuilt every step).

Threads: numba's default (all cores, 2 on the reference machine) and one
(``numba.set_num_threads(1)``). Goal printed next to the numbers (never asserted): PySPH WCSPH
on the same 2D dam break on the reference machine, about 1.6e6 particle-steps/s with 2 OpenMP
threads and 0.95e6 single-threaded, at 7.6e3 to 2.5e4 particles; per-particle-step cost of the
largest size within 1.5x of the smallest.

Run alone::

    .venv/bin/python benchmarks/bench_fluid_step.py            # 3 sizes x 2 thread counts, 1-3 min
    .venv/bin/python benchmarks/bench_fluid_step.py --quick    # smallest size, few steps
    .venv/bin/python benchmarks/bench_fluid_step.py --sizes 1e4 4e4 --threads 1 --steps 100
"""

from __future__ import annotations

import argparse
import gc
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_neighbors import RETRY_BUDGET, OtherLoad, add_flatness  # noqa: E402

#: Target total particle counts (fluid + wall).
SIZES = (10_000, 40_000, 160_000)
#: PySPH WCSPH, same 2D dam break, reference machine: particle-steps/s by thread count.
GOAL_BY_THREADS = {2: 1.6e6, 1: 0.95e6}
GOAL_NOTE = "PySPH WCSPH, same 2D dam break, this machine, 7.6e3–2.5e4 particles"
FLATNESS_GOAL = 1.5
#: A block holds about this many particle-steps (~2 s at 2 threads), rounded to FILTER_EVERY.
PARTICLE_STEPS_PER_BLOCK = 3e6
FILTER_EVERY = 20
WARMUP_STEPS = 5
QUICK_STEPS = 40
#: Stage groups of the fluid solver's ``timer.seconds``; every other entry counts as "forces".
GROUPS = {
    "neighbors": "neighbours", "shape_functions": "shape functions", "integrate": "integration",
}
GROUP_ORDER = ("neighbours", "shape functions", "forces", "integration", "untimed")


def wall_particles_estimate(ratio: int) -> float:
    """Wall particles of the dam-break tank at ``a/dx = ratio`` (3 layers; fitted, ±1%)."""
    return 33.5 * ratio


def ratio_for(n_target: float) -> int:
    """Even ``a/dx`` whose fluid (``2 (a/dx)²``) plus wall particles come closest to ``n_target``.

    Only even values: with an odd ``a/dx`` the tank length ``5.5 a`` is a half-integer number of
    spacings, the wall lattice puts a column of wall particles *on* the right wall surface
    (4 columns instead of 3), and at some resolutions (``a/dx = 275``) their normals are 0/0 =
    NaN and the first step fails (``wall_box`` in ``mlsgalerkin/fluid/bodies.py``).
    """
    from mlsgalerkin.problems.dam_break import Parameters, make_scene

    r0 = (-33.5 + math.sqrt(33.5**2 + 8.0 * n_target)) / 4.0
    best = None
    for r in {max(4, 2 * int(math.floor(r0 / 2))), max(4, 2 * int(math.ceil(r0 / 2)))}:
        p = Parameters()
        scene = make_scene(Parameters(dx=p.column_width / r))
        n = sum(b.n for b in scene.bodies)
        if best is None or abs(n - n_target) < abs(best[1] - n_target):
            best = (r, n)
    return best[0]


def steps_for(n_total: int) -> int:
    """Steps per block: about PARTICLE_STEPS_PER_BLOCK particle-steps, a multiple of 20."""
    k = max(1, round(PARTICLE_STEPS_PER_BLOCK / n_total / FILTER_EVERY))
    return FILTER_EVERY * k


def make_simulation(ratio: int, skin: float | None = None):
    import dataclasses

    from mlsgalerkin.problems.dam_break import Parameters, make_scene
    from mlsgalerkin.simulation import Simulation

    if ratio % 2:
        raise ValueError(f"a/dx = {ratio} is odd: the right tank wall would not line up with the "
                         "particle lattice (see ratio_for); use an even a/dx")
    p = Parameters()
    scene = make_scene(Parameters(dx=p.column_width / ratio))
    if skin is not None:
        scene.schemes[0].approximation = dataclasses.replace(scene.schemes[0].approximation, skin=skin)
    return Simulation(scene)


def group_split(seconds: dict[str, float], wall: float) -> dict[str, float]:
    out = dict.fromkeys(GROUP_ORDER, 0.0)
    for k, v in seconds.items():
        out[GROUPS.get(k, "forces")] += v
    out["untimed"] = max(0.0, wall - sum(seconds.values()))
    return out


def _time_block(sim, snapshot, steps: int) -> dict:
    """Restore the snapshot (not timed), then time ``steps`` steps."""
    sim.restore(*snapshot)
    fluid = sim.solver("fluid")
    builds0 = fluid.neighbor_builds
    fluid.timer.seconds.clear()
    gc.collect()
    # one BLAS thread, as Simulation.run holds it (numba's threads own the cores; OpenBLAS threads
    # spinning after a call on a large array fought them: at 4e4 particles 2 threads ran slower than 1)
    with threadpool_limits(limits=1, user_api="blas"):
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step(sim.time_step())
        wall = time.perf_counter() - t0
    return {"seconds": wall, "stages": dict(fluid.timer.seconds),
            "builds": fluid.neighbor_builds - builds0, "t_phys": sim.state.t}


def _best_block(sim, snapshot, steps: int, repeats: int, attempts: int = 3, max_other: float = 0.2,
                log: Callable[[str], None] | None = None) -> tuple[dict, int, float]:
    """Best of ``repeats`` blocks under :class:`OtherLoad`, retried like ``measure``.

    When other processes used more than ``max_other`` cores, wait 3 s and measure again (up to
    ``attempts``, while the shared retry budget lasts and the disturbance does not look
    sustained). Returns the best block of the least disturbed attempt, the number of blocks
    and that attempt's other load.
    """
    best = None
    for k in range(attempts):
        load = OtherLoad().start()
        t0 = time.perf_counter()
        blocks = [_time_block(sim, snapshot, steps) for _ in range(repeats)]
        other = load.stop()
        took = time.perf_counter() - t0
        if k > 0:
            RETRY_BUDGET[0] -= took
        fastest = min(blocks, key=lambda b: b["seconds"])
        if best is None or (other, fastest["seconds"]) < (best[2], best[0]["seconds"]):
            best = (fastest, len(blocks), other)
        sustained = k >= 1 and other > 0.8
        if (other <= max_other or sustained or k == attempts - 1
                or RETRY_BUDGET[0] < took + 3.0):
            break
        if log:
            log(f"  (other processes used {other:.2f} cores; measuring again)")
        RETRY_BUDGET[0] -= 3.0
        time.sleep(3.0)
    return best


def _neighbor_build_time(sim, repeats: int = 3) -> float:
    from mlsgalerkin.neighbors import find_neighbors

    s = sim.state.fluid
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        find_neighbors(s.x, s.x, radius=sim.solver("fluid").search_radius)
        best = min(best, time.perf_counter() - t0)
    return best


def run(
    sizes: Sequence[float] = SIZES,
    threads: Sequence[int] | None = None,
    repeats: int = 3,
    steps: int | None = None,
    skin: float | None = None,
    ratios: Sequence[int] | None = None,
    log: Callable[[str], None] = print,
) -> list[dict]:
    """Time the fluid step; one row per (thread count, size)."""
    import numba

    default_threads = numba.get_num_threads()
    threads = list(threads) if threads else sorted({default_threads, 1}, reverse=True)
    ratios = list(ratios) if ratios else [ratio_for(n) for n in sizes]
    rows = []
    try:
        for nt in threads:
            numba.set_num_threads(min(nt, numba.config.NUMBA_NUM_THREADS))
            nt = numba.get_num_threads()
            case = f"2D dam break step, {nt} thread{'s' if nt > 1 else ''}"
            for ratio in ratios:
                sim = make_simulation(ratio, skin)
                sim.start()
                for _ in range(WARMUP_STEPS):
                    sim.step(sim.time_step())
                snapshot = sim.snapshot()
                s = sim.state.fluid
                n_steps = steps or steps_for(s.n)
                blk, done, other = _best_block(sim, snapshot, n_steps, repeats, log=log)
                t = blk["seconds"]
                t_build = _neighbor_build_time(sim)
                nb_time = blk["stages"].get("neighbors", 0.0)
                t_every = t - nb_time + n_steps * t_build
                n_pairs = int(s.neighbors.n_pairs)
                row = {
                    "benchmark": "fluid_step",
                    "case": case,
                    "dim": 2, "basis": "linear", "method": "mls",
                    "threads": nt,
                    "a_over_dx": ratio,
                    "n_points": s.n, "n_fluid": s.n_fluid, "n_wall": s.n_walls,
                    "n_pairs": n_pairs, "mean_neighbors": n_pairs / s.n,
                    "steps": n_steps, "seconds": t, "repeats": done, "other_load": other,
                    "points_per_s": s.n * n_steps / t,
                    "ns_per_point": 1e9 * t / (s.n * n_steps),
                    "ms_per_step": 1e3 * t / n_steps,
                    "builds_per_step": blk["builds"] / n_steps,
                    "neighbor_build_s": t_build,
                    "points_per_s_rebuild_every_step": s.n * n_steps / t_every,
                    "t_start": snapshot[1]["t"], "t_end": blk["t_phys"],
                    "stages": blk["stages"],
                    "groups": group_split(blk["stages"], t),
                    "goal_points_per_s": GOAL_BY_THREADS.get(nt, float("nan")),
                }
                rows.append(row)
                log(
                    f"{case:<32} a/dx={ratio:>4d}  n={s.n:>8,d} "
                    f"({s.n_fluid:,} fluid + {s.n_walls:,} wall)  {n_steps} steps x{done}: "
                    f"{t:7.3f} s  {row['points_per_s']:10.3e} particle-steps/s  "
                    f"{row['ms_per_step']:7.2f} ms/step  builds/step={row['builds_per_step']:.2f}  "
                    f"other load={other:.2f}"
                )
                del sim, snapshot, s
                gc.collect()
    finally:
        numba.set_num_threads(default_threads)
    add_flatness(rows)
    return rows


# --------------------------------------------------------------------------------------
# report
# --------------------------------------------------------------------------------------


def _e6(x: float) -> str:
    return f"{x / 1e6:.2f}×10⁶"


def _goal_cell(r: dict) -> str:
    goal = r.get("goal_points_per_s", float("nan"))
    if goal != goal:
        return ""
    mark = "met" if r["points_per_s"] >= goal else "not met"
    return f"≈ {_e6(goal)} ({r['points_per_s'] / goal:.2f}×, {mark})"


def markdown(rows: list[dict]) -> list[str]:
    """Markdown tables: throughput, stage split (grouped and raw), flatness."""
    md = [
        "| threads | a/dx | particles (fluid + wall) | mean neighbours | steps × runs "
        "| best block (s) | particle-steps/s | ns/particle-step | ms/step | cost ratio vs smallest "
        "| neighbour builds/step | particle-steps/s, rebuild every step (est.) | other load "
        "| goal: PySPH WCSPH |",
        "|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        md.append(
            f"| {r['threads']} | {r['a_over_dx']} "
            f"| {r['n_points']:,} ({r['n_fluid']:,} + {r['n_wall']:,}) "
            f"| {r['mean_neighbors']:.1f} | {r['steps']} × {r['repeats']} | {r['seconds']:.3f} "
            f"| {_e6(r['points_per_s'])} | {r['ns_per_point']:.0f} | {r['ms_per_step']:.2f} "
            f"| {r['cost_ratio']:.2f} | {r['builds_per_step']:.3f} "
            f"| {_e6(r['points_per_s_rebuild_every_step'])} | {r['other_load']:.2f} "
            f"| {_goal_cell(r)} |"
        )
    md += ["", f"Goal: {GOAL_NOTE}: ≈ 1.6×10⁶ particle-steps/s with 2 threads, "
           "0.95×10⁶ with 1.", ""]
    md += ["Stage split of the best block, ms per step (share of the block):", "",
           "| threads | particles | " + " | ".join(GROUP_ORDER) + " |",
           "|---:|---:|" + "---:|" * len(GROUP_ORDER)]
    for r in rows:
        g = r["groups"]
        cells = [f"{1e3 * g[k] / r['steps']:.2f} ({100 * g[k] / r['seconds']:.0f}%)"
                 for k in GROUP_ORDER]
        md.append(f"| {r['threads']} | {r['n_points']:,} | " + " | ".join(cells) + " |")
    names: list[str] = []
    for r in rows:
        for k in sorted(r["stages"], key=lambda k: -r["stages"][k]):
            if k not in names:
                names.append(k)
    md += ["", "Raw split (the fluid solver's `timer.seconds`), ms per step:", "",
           "| threads | particles | " + " | ".join(names) + " | untimed |",
           "|---:|---:|" + "---:|" * (len(names) + 1)]
    for r in rows:
        cells = [f"{1e3 * r['stages'].get(k, 0.0) / r['steps']:.2f}" for k in names]
        cells.append(f"{1e3 * r['groups']['untimed'] / r['steps']:.2f}")
        md.append(f"| {r['threads']} | {r['n_points']:,} | " + " | ".join(cells) + " |")
    md += ["", "Per-particle-step cost, largest against smallest size (goal ≤ "
           f"{FLATNESS_GOAL}):", "",
           "| threads | particles (small → large) | cost ratio | goal |", "|---:|---|---:|---|"]
    by_threads: dict[int, list[dict]] = {}
    for r in rows:
        by_threads.setdefault(r["threads"], []).append(r)
    for nt, group in by_threads.items():
        if len(group) < 2:
            continue
        small = min(group, key=lambda r: r["n_points"])
        large = max(group, key=lambda r: r["n_points"])
        ratio = large["ns_per_point"] / small["ns_per_point"]
        mark = "met" if ratio <= FLATNESS_GOAL else "not met"
        md.append(f"| {nt} | {small['n_points']:,} → {large['n_points']:,} | {ratio:.2f} "
                  f"| {mark} |")
    return md


def main(argv: Sequence[str] | None = None) -> list[dict]:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true",
                   help=f"smallest size only, {QUICK_STEPS} steps per block")
    p.add_argument("--sizes", nargs="+", type=float, default=list(SIZES),
                   help="target particle counts (fluid + wall); a/dx is chosen to come closest")
    p.add_argument("--ratios", nargs="+", type=int, help="a/dx values instead of --sizes")
    p.add_argument("--threads", nargs="+", type=int,
                   help="numba thread counts (default: numba's default, then 1)")
    p.add_argument("--steps", type=int, help="steps per block (default: ~3e6 particle-steps, "
                                             "a multiple of 20)")
    p.add_argument("--repeats", type=int, default=3, help="blocks per measurement (best is kept)")
    p.add_argument("--skin", type=float, help="override the neighbour skin (units of dx); "
                                              "0 rebuilds the list every step")
    a = p.parse_args(argv)
    sizes = a.sizes
    steps = a.steps
    if a.quick:
        sizes = [min(sizes)]
        steps = steps or QUICK_STEPS
        if a.ratios:
            a.ratios = [min(a.ratios)]
    rows = run(sizes, a.threads, a.repeats, steps, a.skin, a.ratios)
    print()
    print("\n".join(markdown(rows)))
    return rows


if __name__ == "__main__":
    main()
    raise SystemExit(0)
