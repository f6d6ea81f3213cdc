"""Whole-run fluid throughput: the dam break from release through the wall impact.

``bench_fluid_step.py`` times blocks of early steps (slow flow, few neighbour rebuilds). A
run also pays for what comes later: the neighbour list rebuilt nearly every step once the
surge is fast, splashes, the late-time neighbour counts, the checks and the probes. This
benchmark times whole runs of the shipped ``dam_break`` problem (Martin & Moyce column,
``a/dx = 40`` by default) with ``Simulation.run`` (no output written) and reports

- particle-steps per second over the whole run (total particles × steps / wall time);
- wall time per simulated second;
- the cost of each term: the fluid solver's time per stage (``summary.json``'s
  ``time_per_stage_s``), in seconds and as a fraction of the run.

Configurations (each a set of problem parameters, so anyone can rerun one with
``mlsgalerkin run dam_break --set ...``):

``terms of issue 9``
    the physics the dam break listed before the stabilising terms existed: Monaghan
    ``α = 0.05``, tension allowed, no density diffusion, no shifting, no penalty surface.
    (It also listed a Shepard density filter every 20 steps, which the problem no longer
    offers; the filter cost about 2 % of a step.) It diverges at the wall impact, so every
    configuration is timed to ``t = 0.25`` s, before it, for the ratio;
``+ density diffusion``, ``+ shifting``, ``+ penalty walls``
    one term added to the above;
``shipped defaults``
    everything the problem lists now (``α = 0.02``, ``cavitate``, δ = 0.1, local shifting,
    penalty walls); also timed through the impact to ``t = 0.4`` s.

Goal printed next to the numbers (never asserted): whole-run throughput with the new terms
at least 0.8 × that of the terms of issue 9.

    .venv/bin/python benchmarks/bench_fluid_run.py                 # a/dx = 40, 1 and 2 threads, ~6 min
    .venv/bin/python benchmarks/bench_fluid_run.py --ratios 20 --threads 1   # quick
"""

from __future__ import annotations

import argparse
import io
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

#: (label, parameter overrides, end time (s)).
CONFIGS = (
    ("terms of issue 9", {"alpha": 0.05, "negative_pressure": "allow", "delta": 0.0, "shifting": "off",
                          "penalty_walls": False}, 0.25),
    ("+ density diffusion", {"alpha": 0.05, "negative_pressure": "allow", "shifting": "off",
                             "penalty_walls": False}, 0.25),
    ("+ shifting", {"alpha": 0.05, "negative_pressure": "allow", "delta": 0.0, "penalty_walls": False}, 0.25),
    ("+ penalty walls", {"alpha": 0.05, "negative_pressure": "allow", "delta": 0.0, "shifting": "off"}, 0.25),
    ("shipped defaults", {}, 0.25),
    ("shipped defaults, through the impact", {}, 0.4),
)
GOAL = 0.8


def run_one(ratio: int, overrides: dict, t_end: float) -> dict:
    from mlsgalerkin.problem import prepare_problem
    from mlsgalerkin.problems.dam_break import Parameters
    from mlsgalerkin.simulation import Simulation

    a = Parameters().column_width
    prepared = prepare_problem("dam_break", dict(overrides, dx=a / ratio, t_end=t_end))
    sim = Simulation(prepared.scene)
    t0 = time.perf_counter()
    res = sim.run(out=None, progress=False)
    wall = time.perf_counter() - t0
    s = res.summary
    n = sum(b.n for b in prepared.scene.bodies)
    return {"particles": n, "steps": s["steps"], "t_reached": float(res.state.t), "status": s.get("status"),
            "wall_s": wall, "particle_steps_per_s": n * s["steps"] / wall,
            "wall_s_per_simulated_s": wall / max(float(res.state.t), 1e-12),
            "stages": s["fluid"]["time_per_stage_s"],
            "rebuilds": s["fluid"]["diagnostics"]["neighbour_rebuilds"]}


def main(argv: list[str] | None = None) -> int:
    import numba

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ratios", type=int, nargs="+", default=[40], help="a/dx values (even)")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--out", default=str(HERE / "results" / "fluid_run.md"))
    args = ap.parse_args(argv)
    from mlsgalerkin.io import atomic_write, provenance

    # warm the numba cache (a short run of the full configuration)
    run_one(10, {}, 0.005)
    rows = []
    for threads in args.threads:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        for ratio in args.ratios:
            base = None
            for label, ov, t_end in CONFIGS:
                r = run_one(ratio, ov, t_end)
                r.update(label=label, ratio=ratio, threads=numba.get_num_threads())
                if base is None:
                    base = r["particle_steps_per_s"]
                r["relative_throughput"] = r["particle_steps_per_s"] / base
                rows.append(r)
                print(f"{threads} thr a/dx={ratio} {label}: {r['steps']} steps to {r['t_reached']:.3f} s, "
                      f"{r['wall_s']:.1f} s, {r['particle_steps_per_s']:.3g} p-steps/s "
                      f"({r['relative_throughput']:.2f}x), {r['wall_s_per_simulated_s']:.1f} s per simulated s",
                      flush=True)
    prov = provenance("bench_fluid_run")
    out = io.StringIO()
    out.write("# Whole-run fluid throughput: dam break through the wall impact\n\n")
    out.write(f"Produced by `{prov['command']}`, mlsgalerkin {prov['mlsgalerkin_version']}, commit "
              f"{prov['git_commit']}, {prov['date_utc']}, {prov['machine']}.\n\n")
    out.write("| threads | a/dx | configuration | particles | t_end (s) | steps | rebuilds | wall (s) | "
              "particle-steps/s | vs issue-9 terms | wall s per simulated s | status |\n")
    out.write("|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        out.write(f"| {r['threads']} | {r['ratio']} | {r['label']} | {r['particles']} | {r['t_reached']:.3f} | "
                  f"{r['steps']} | {r['rebuilds']} | {r['wall_s']:.1f} | {r['particle_steps_per_s']:.3g} | "
                  f"{r['relative_throughput']:.2f} | {r['wall_s_per_simulated_s']:.1f} | {r['status']} |\n")
    out.write(f"\nGoal (not asserted): whole-run throughput with the new terms at least {GOAL} x that of the "
              "terms of issue 9.\n\n## Cost of each term (seconds of the run, fraction)\n\n")
    for r in rows:
        total = r["wall_s"]
        top = sorted(r["stages"].items(), key=lambda kv: -kv[1])
        cells = ", ".join(f"{k} {v:.1f} s ({100 * v / total:.0f} %)" for k, v in top if v / total >= 0.01)
        out.write(f"- {r['threads']} thr, a/dx = {r['ratio']}, {r['label']}: {cells}\n")
    atomic_write(Path(args.out), out.getvalue())
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
