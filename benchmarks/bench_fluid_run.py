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

``shipped at COMMIT`` (``--baseline-commit``)
    the dam break as shipped by an earlier commit, its own code and defaults, run from a
    temporary git worktree in a subprocess (the reference of the 0.8 goal);
``terms of issue 9``
    the physics the dam break listed before the stabilising terms existed: Monaghan
    ``α = 0.05``, tension allowed, no density diffusion, no shifting, no penalty surface.
    (It also listed a Shepard density filter every 20 steps, which the problem no longer
    offers; the filter cost about 2 % of a step.) Without the filter it diverges as the surge
    reaches the end wall (0.235 s at ``a/dx = 40``), so every configuration is timed to
    ``t = 0.2`` s, before it, for the ratio;
``+ density diffusion``, ``+ shifting``, ``+ penalty walls``
    one term added to the above;
``shipped defaults``
    everything the problem lists now (``α = 0.02``, ``cavitate``, δ = 0.1, local shifting,
    penalty walls); also timed through the impact to ``t = 0.4`` s.

Goal printed next to the numbers (never asserted): whole-run throughput with the new terms
at least 0.8 × that of the terms of issue 9.

``--problem dam_break_impact`` times the dam break with wall impact (Zhou et al. 1999; ``H/dx``
from ``--ratios``) from release through the P1 peak (``T = t sqrt(g/H) = 3.5``): the shipped
defaults, and the same with the linear consistency of the pressure integration
(``linear_consistency=true``); with ``--baseline-commit`` the problem as shipped by that commit
comes first, and the goal is at least 0.8 × its throughput.

    .venv/bin/python benchmarks/bench_fluid_run.py                 # a/dx = 40, 1 and 2 threads, ~6 min
    .venv/bin/python benchmarks/bench_fluid_run.py --ratios 20 --threads 1   # quick
    .venv/bin/python benchmarks/bench_fluid_run.py --problem dam_break_impact --baseline-commit COMMIT \
        --ratios 20 40 --threads 1 --out benchmarks/results/fluid_run_impact.md
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
                          "penalty_walls": False}, 0.2),
    ("+ density diffusion", {"alpha": 0.05, "negative_pressure": "allow", "shifting": "off",
                             "penalty_walls": False}, 0.2),
    ("+ shifting", {"alpha": 0.05, "negative_pressure": "allow", "delta": 0.0, "penalty_walls": False}, 0.2),
    ("+ penalty walls", {"alpha": 0.05, "negative_pressure": "allow", "delta": 0.0, "shifting": "off"}, 0.2),
    ("shipped defaults", {}, 0.2),
    ("shipped defaults, through the impact", {}, 0.4),
)
GOAL = 0.8

#: The dam break with impact through the P1 peak: T = t sqrt(g/H) = 3.5 for H = 0.6 m (s).
T_IMPACT = 3.5 * (0.6 / 9.81) ** 0.5
IMPACT_CONFIGS = (
    ("shipped defaults", {}, T_IMPACT),
    ("+ linear consistency", {"linear_consistency": True}, T_IMPACT),
)


def spacing(problem: str, ratio: int) -> float:
    """The particle spacing (m) of ``ratio`` particles over the problem's length scale: the
    column width ``a`` of ``dam_break``, the column height ``H`` of ``dam_break_impact``."""
    if problem == "dam_break":
        from mlsgalerkin.problems.dam_break import Parameters
        return Parameters().column_width / ratio
    from mlsgalerkin.problem import load_problem
    return load_problem(problem).Parameters().height / ratio

#: Run in a subprocess against another checkout (``--baseline-commit``): the shipped dam break of
#: that commit with its own defaults, to ``t_end``; prints one JSON line.
BASELINE_CODE = """
import json, sys, time
from pathlib import Path
tree, dx, t_end = Path(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
import numba
numba.set_num_threads(int(sys.argv[4]))
import mlsgalerkin
assert Path(mlsgalerkin.__file__).resolve().is_relative_to(tree.resolve()), mlsgalerkin.__file__
from mlsgalerkin.problem import prepare_problem
from mlsgalerkin.simulation import Simulation
path = tree / "problems" / (sys.argv[5] + ".py")
warm = prepare_problem(path, dict(dx=2 * dx, t_end=0.005))  # compiles (or loads) the numba kernels
Simulation(warm.scene).run(out=None, progress=False)
prepared = prepare_problem(path, dict(dx=dx, t_end=t_end))
t0 = time.perf_counter()
res = Simulation(prepared.scene).run(out=None, progress=False)
wall = time.perf_counter() - t0
s = res.summary
n = sum(b.n for b in prepared.scene.bodies)
print(json.dumps({"particles": n, "steps": s["steps"], "t_reached": float(res.state.t), "status": s.get("status"),
                  "wall_s": wall, "particle_steps_per_s": n * s["steps"] / wall,
                  "wall_s_per_simulated_s": wall / max(float(res.state.t), 1e-12),
                  "stages": s["fluid"]["time_per_stage_s"], "rebuilds": s["fluid"]["diagnostics"]["neighbour_rebuilds"]}))
"""


def run_baseline(commit: str, problem: str, dx: float, t_end: float, threads: int) -> dict:
    """The problem as shipped by ``commit`` (a temporary git worktree), in a subprocess."""
    import json
    import os
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "baseline"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), commit], check=True,
                       capture_output=True)
        try:
            env = dict(os.environ, PYTHONPATH=str(tree))
            out = subprocess.run([sys.executable, "-c", BASELINE_CODE, str(tree), repr(dx), str(t_end), str(threads),
                                  problem],
                                 check=False, capture_output=True, text=True, env=env, cwd=tmp)
            if out.returncode:
                raise RuntimeError(f"the baseline run at {commit} failed:\n{out.stderr[-2000:]}")
            return json.loads(out.stdout.strip().splitlines()[-1])
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False,
                           capture_output=True)


def run_one(problem: str, ratio: int, overrides: dict, t_end: float) -> dict:
    from mlsgalerkin.problem import prepare_problem
    from mlsgalerkin.simulation import Simulation

    prepared = prepare_problem(problem, dict(overrides, dx=spacing(problem, ratio), t_end=t_end))
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
    ap.add_argument("--problem", choices=("dam_break", "dam_break_impact"), default="dam_break")
    ap.add_argument("--ratios", type=int, nargs="+", default=[40],
                    help="a/dx (dam_break, even) or H/dx (dam_break_impact) values")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--out", default=str(HERE / "results" / "fluid_run.md"))
    ap.add_argument("--baseline-commit", default=None,
                    help="also time the shipped dam break of this commit (its own defaults), e.g. the one before "
                         "the stabilising terms")
    args = ap.parse_args(argv)
    from mlsgalerkin.io import atomic_write, provenance

    # warm the numba cache (a short run of the full configuration)
    configs = CONFIGS if args.problem == "dam_break" else IMPACT_CONFIGS
    for _, ov, _ in configs:      # compile (or load) every configuration's kernels before timing
        run_one(args.problem, 10, ov, 0.005)
    base_t_end = 0.2 if args.problem == "dam_break" else T_IMPACT
    rows = []
    for threads in args.threads:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        for ratio in args.ratios:
            base = None
            if args.baseline_commit:
                r = run_baseline(args.baseline_commit, args.problem, spacing(args.problem, ratio), base_t_end,
                                 numba.get_num_threads())
                r.update(label=f"shipped at {args.baseline_commit}", ratio=ratio, threads=numba.get_num_threads())
                base = r["particle_steps_per_s"]
                r["relative_throughput"] = 1.0
                rows.append(r)
                print(f"{threads} thr ratio {ratio} {r['label']}: {r['steps']} steps, {r['wall_s']:.1f} s, "
                      f"{r['particle_steps_per_s']:.3g} p-steps/s", flush=True)
            for label, ov, t_end in configs:
                r = run_one(args.problem, ratio, ov, t_end)
                r.update(label=label, ratio=ratio, threads=numba.get_num_threads())
                if base is None:
                    base = r["particle_steps_per_s"]
                r["relative_throughput"] = r["particle_steps_per_s"] / base
                rows.append(r)
                print(f"{threads} thr ratio {ratio} {label}: {r['steps']} steps to {r['t_reached']:.3f} s, "
                      f"{r['wall_s']:.1f} s, {r['particle_steps_per_s']:.3g} p-steps/s "
                      f"({r['relative_throughput']:.2f}x), {r['wall_s_per_simulated_s']:.1f} s per simulated s",
                      flush=True)
    prov = provenance("bench_fluid_run")
    out = io.StringIO()
    title = "dam break through the wall impact" if args.problem == "dam_break" else \
        "dam break with impact (Zhou et al. 1999) through the P1 peak"
    out.write(f"# Whole-run fluid throughput: {title}\n\n")
    out.write(f"Produced by `{prov['command']}`, mlsgalerkin {prov['mlsgalerkin_version']}, commit "
              f"{prov['git_commit']}, {prov['date_utc']}, {prov['machine']}.\n\n")
    out.write(f"| threads | {'a/dx' if args.problem == 'dam_break' else 'H/dx'} | configuration | particles | t_end (s) | steps | rebuilds | wall (s) | "
              "particle-steps/s | vs first row | wall s per simulated s | status |\n")
    out.write("|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        out.write(f"| {r['threads']} | {r['ratio']} | {r['label']} | {r['particles']} | {r['t_reached']:.3f} | "
                  f"{r['steps']} | {r['rebuilds']} | {r['wall_s']:.1f} | {r['particle_steps_per_s']:.3g} | "
                  f"{r['relative_throughput']:.2f} | {r['wall_s_per_simulated_s']:.1f} | {r['status']} |\n")
    out.write(f"\nGoal (not asserted): whole-run throughput with the new terms at least {GOAL} x that of the "
              "dam break as shipped before them (the first row of each block).\n\n"
              "## Cost of each term (seconds of the run, fraction)\n\n")
    for r in rows:
        total = r["wall_s"]
        top = sorted(r["stages"].items(), key=lambda kv: -kv[1])
        cells = ", ".join(f"{k} {v:.1f} s ({100 * v / total:.0f} %)" for k, v in top if v / total >= 0.01)
        out.write(f"- {r['threads']} thr, ratio {r['ratio']}, {r['label']}: {cells}\n")
    atomic_write(Path(args.out), out.getvalue())
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
