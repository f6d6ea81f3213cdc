"""Fluid core at impact and at rest: the dam break with wall impact against De Courcy et al.
(2024), the gravity-current matrix, the two-layer tank at rest, the drop impact without the
cavitation floor, and the ablation of each stabilising term. Every row records the error
*and* the wall time.

    python verification/fluid_core.py --section impact --out verification/results/fluid_core
    python verification/fluid_core.py --section all --out verification/results/fluid_core
    python verification/fluid_core.py --section impact --quick --out results/fluid_core_quick   # smoke
    python verification/fluid_core.py --section ablation --rerun gravity   # run the matching cases, re-analyse the rest

Sections: ``impact`` (dam_break_impact at H/dx = 40 and 80, ``--finest 160`` adds 160),
``scatter`` (the impact's cases again with ``c0_factor`` or ``g`` perturbed by 10⁻¹²: how far
round-off moves the measures; with the ``impact`` table's rows, the mean and standard deviation),
``dam_break`` (Martin & Moyce through the wall impact), ``gravity`` (head speed for three
density ratios × three depths at 20 rows per depth), ``gravity_lid`` (both fronts of the deep
weakly stratified exchange, one setting changed at a time), ``rest`` (two-layer tank, 5 s),
``drop`` (2, 5, 10 m/s), ``ablation`` (each term off in turn, dam break with impact and
gravity current). Each section writes ``<section>.csv`` and ``<section>.md`` into ``--out``
(atomically, with the command, version, commit and date that produced them) and its plots;
``summary.md`` indexes the sections present. Particle output goes to ``--runs`` (default
``results/fluid_core_runs``, not committed).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
import time
from pathlib import Path

import numpy as np

from mlsgalerkin.fluid.recommended import RECOMMENDED
from mlsgalerkin.io import atomic_write, csv_text, format_cell, provenance
from mlsgalerkin.problem import run_problem

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from verification.report_format import produced_by

SECTIONS = ("impact", "scatter", "dam_break", "gravity", "gravity_lid", "rest", "drop", "ablation")


# ----------------------------------------------------------------------------- cases
def impact_cases(quick: bool, finest: int) -> list[tuple[str, dict]]:
    if quick:
        return [("H/dx=10", {"dx": 0.06, "t_end": 0.6})]
    return [(f"H/dx={n}", {"dx": 0.6 / n}) for n in (40, 80, 160) if n <= finest]


def scatter_cases(quick: bool, finest: int) -> list[tuple[str, dict]]:
    """The impact's cases with one input perturbed by a relative 10⁻¹² (the sound speed's factor up
    and down, gravity up): twins that differ from the table's run at round-off only."""
    from mlsgalerkin.problem import load_problem
    p = load_problem("dam_break_impact").Parameters()
    perturbed = (("c0_factor x (1+1e-12)", {"c0_factor": p.c0_factor * (1 + 1e-12)}),
                 ("c0_factor x (1-1e-12)", {"c0_factor": p.c0_factor * (1 - 1e-12)}),
                 ("g x (1+1e-12)", {"g": p.g * (1 + 1e-12)}))
    return [(f"{label} {name}", {**ov, **change}) for label, ov in impact_cases(quick, finest) for name, change in perturbed]


def gravity_cases(quick: bool) -> list[tuple[str, dict]]:
    """The 3 × 3 matrix of depths and density ratios, each in the tank whose length scales with
    the depth (0.34 m at ``D = 0.06``; 20 rows per depth) and in the problem's own 0.34 m tank
    (at the problem's default spacing, 20 rows per depth, and at ``Δx = 3`` mm, the default
    before 2026-12-04: 13 rows at ``D = 0.04`` m, 40 at 0.12 m), plus the weakly stratified lock
    exchange (``Δρ/ρ0 = 0.03``) whose pressure noise under the lid is measured. Every case runs
    the problem's defaults (the one recommended set) apart from the geometry, the spacing and
    the end time."""
    if quick:
        return [("D=0.06 drho=0.5 (5 rows)", {"depth": 0.06, "dx": 0.012, "t_end": 0.3, "gif": False})]
    out = []
    # the matrix, the weakly stratified lock exchange in the scaled tank, and the deep
    # weakly stratified case in the 0.34 m tank (+16 % at the former default 3 mm, +2.4 % at 20 rows)
    for depth, ratio in [(d, r) for d in (0.04, 0.06, 0.12) for r in (0.1, 0.5, 1.0)] + [(0.06, 0.03), (0.09, 0.05)]:
        speed = 0.4 * math.sqrt(9.81 * depth * ratio)
        tanks = [("scaled tank", 0.34 * depth / 0.06, depth / 20, "20 rows")] if ratio != 0.05 else []
        if ratio != 0.03:
            tanks += [("0.34 m tank", 0.34, None, "default spacing (20 rows)")]   # the problem's dx = D / 20
            if not math.isclose(depth / 20, 0.003):   # at D = 0.06 m, 20 rows is 3 mm
                tanks += [("0.34 m tank", 0.34, 0.003, "dx=3 mm")]
        for tank, length, dx, resolution in tanks:
            # the run lasts until the head has crossed 80 % of the lock-to-wall distance at the
            # formula's speed, plus 30 %
            t_end = round(1.3 * 0.8 * 0.5 * length / speed, 2)
            case = {"depth": depth, "length": round(length, 6), "rho_heavy": 1000.0 * (1 + ratio),
                    "t_end": t_end, "gif": False}
            if dx is not None:
                case["dx"] = dx
            out.append((f"D={depth:g} drho/rho0={ratio:g}, {tank}, {resolution}", case))
            if ratio != 0.03 and resolution == "dx=3 mm" or tank == "scaled tank" and ratio != 0.03:
                # the problem's alpha departs from the recommended set's: what the set gives here
                out.append((f"D={depth:g} drho/rho0={ratio:g}, {tank}, {resolution}, alpha={RECOMMENDED.alpha:g}",
                            dict(case, alpha=RECOMMENDED.alpha)))
    return out


def gravity_lid_cases(quick: bool) -> list[tuple[str, dict]]:
    """The deep weakly stratified lock exchange (``D = 0.12`` m, ``Δρ/ρ0 = 0.1``, the problem's
    0.34 m tank) that went lopsided under the lid before the hydrostatic reference (2026-12-05):
    the problem's defaults at 20, 40 and 60 rows,
    then one setting changed at a time at 40 rows (3 mm, the default spacing before 2026-12-04),
    the free surface instead of the lid, and the weaker stratification ``Δρ/ρ0 = 0.03``. Every
    run lasts until the heavy head has crossed its fit window (time scaled with
    ``1/sqrt(Δρ/ρ0)``)."""
    if quick:
        return [("lid, 5 rows", {"depth": 0.12, "rho_heavy": 1100.0, "dx": 0.024, "t_end": 0.3, "gif": False})]
    base = {"depth": 0.12, "rho_heavy": 1100.0, "gif": False}
    rows = {20: 0.006, 40: 0.003, 60: 0.002}
    weak = dict(base, rho_heavy=1030.0, t_end=2.2)
    return [
        ("lid, 20 rows", dict(base, dx=rows[20], t_end=1.35)),
        ("lid, 40 rows", dict(base, dx=rows[40], t_end=1.15)),
        ("lid, 60 rows", dict(base, dx=rows[60], t_end=1.15)),
        ("lid, 40 rows, free-slip walls", dict(base, dx=rows[40], t_end=1.15, slip="free_slip")),
        ("lid, 40 rows, no penalty surface", dict(base, dx=rows[40], t_end=1.15, penalty_walls=False)),
        ("lid, 40 rows, direct nodal integration", dict(base, dx=rows[40], t_end=1.15, linear_consistency=False)),
        ("lid, 40 rows, no shifting", dict(base, dx=rows[40], t_end=1.15, shifting="off")),
        ("lid, 40 rows, lid pressure 0.2 rho_heavy g D", dict(base, dx=rows[40], t_end=1.15, lid_pressure_factor=0.2)),
        ("lid, 40 rows, alpha=0.02", dict(base, dx=rows[40], t_end=1.15, alpha=0.02)),
        ("lid, 40 rows, delta=0.05", dict(base, dx=rows[40], t_end=1.15, delta=0.05)),
        ("lid, 40 rows, no density diffusion", dict(base, dx=rows[40], t_end=1.15, delta=0.0)),
        ("lid, 60 rows, no density diffusion", dict(base, dx=rows[60], t_end=1.15, delta=0.0)),
        ("free surface, 40 rows", dict(base, dx=rows[40], t_end=1.15, lid=False)),
        ("free surface, 60 rows", dict(base, dx=rows[60], t_end=1.15, lid=False)),
        ("lid, 40 rows, drho/rho0=0.03", dict(weak, dx=rows[40])),
        ("free surface, 40 rows, drho/rho0=0.03", dict(weak, dx=rows[40], lid=False)),
    ]


def rest_cases(quick: bool) -> list[tuple[str, dict]]:
    """The two-layer tank at rest with the problem's defaults (the one recommended set), under
    the lid and with a free surface, at 20 and 40 rows, and under the lid from a disordered start
    (every particle moved by up to ± 0.25 Δx)."""
    if quick:
        return [("20 rows, 0.2 s", {"t_end": 0.2})]
    return ([(f"{'lid' if lid else 'free surface'}, {rows} rows", {"lid": lid, "dx": 0.06 / rows})
             for lid in (True, False) for rows in (20, 40)]
            + [(f"lid, {rows} rows, disordered start (jitter 0.25)", {"lid": True, "dx": 0.06 / rows, "jitter": 0.25})
               for rows in (20, 40)])


def drop_cases(quick: bool) -> list[tuple[str, dict]]:
    if quick:
        return [("2 m/s", {"speed": 2.0, "dx": 0.004, "t_end": 0.02, "gif": False})]
    return [(f"{v:g} m/s", {"speed": v, "gif": False, "t_end": round(0.16 * 2.0 / v, 4)})
            for v in (2.0, 5.0, 10.0)]


# ----------------------------------------------------------------------------- running
def run_check_columns(summary: dict) -> dict:
    """The run checks' largest volume error and most clumped pairs, from a run's summary."""
    checks = summary.get("fluid", {}).get("run_checks") or {}
    return {"largest_volume_error": (checks.get("volume") or {}).get("max_abs_error"),
            "max_clumped_pairs": (checks.get("particle_distribution") or {}).get("max_clumped_pairs")}


def run(problem: str, label: str, overrides: dict, runs: Path) -> dict:
    """Run one case; returns a row with the problem's results, the status and the wall time."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in f"{problem}_{label}")
    t0 = time.perf_counter()
    row = {"problem": problem, "case": label, "overrides": json.dumps(overrides, sort_keys=True)}
    try:
        result, res = run_problem(problem, overrides, out=runs / safe, progress=False, overwrite=True)
        row["status"] = result.summary.get("status", "completed")
        row["steps"] = result.summary.get("steps")
        row["t_reached_s"] = float(result.state.t)
        pen = result.summary.get("fluid", {}).get("wall_penetration", {})
        row["max_penetration_dx"] = pen.get("max_depth_dx")
        row.update(run_check_columns(result.summary))
        row["particles"] = int(result.state.fluid.n)
        row["fluid_particles"] = int(result.state.fluid.n_fluid)
        row["run_dir"] = str(runs / safe)
        row["run_commit"] = written_commit(runs / safe)
        row.update({k: v for k, v in res.items() if isinstance(v, (int, float, str)) and k != "headline"})
        row["headline"] = res.get("headline", "")
    except Exception as err:  # a diverged or failed case is a result too
        row["status"] = f"failed: {type(err).__name__}: {str(err).splitlines()[0][:200]}"
    row["wall_time_s"] = time.perf_counter() - t0
    if row.get("t_reached_s"):
        row["wall_s_per_simulated_s"] = row["wall_time_s"] / row["t_reached_s"]
    print(f"  {problem} {label}: {row['status']}, {row['wall_time_s']:.0f} s. {row.get('headline', '')}", flush=True)
    return row


def written_commit(run_dir: Path) -> str | None:
    """The commit of the code a run ran (``summary.json``'s provenance; the summary a run returns
    in memory has none, it is added as the file is written)."""
    try:
        return json.loads((run_dir / "summary.json").read_text()).get("provenance", {}).get("git_commit")
    except (OSError, ValueError):
        return None


def reanalysed(problem: str, label: str, overrides: dict, runs: Path) -> dict:
    """The row of a case already run, rebuilt from its run directory (``summary.json``, the
    time series) with the problem's current ``analyse`` (``--reanalyse``): the simulation is not
    repeated, its status, steps and wall time are those recorded."""
    from types import SimpleNamespace

    from mlsgalerkin.io import read_timeseries
    from mlsgalerkin.problem import load_problem

    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in f"{problem}_{label}")
    run_dir = runs / safe
    if not (run_dir / "summary.json").is_file():      # not run yet (or still running): an empty row
        return {"problem": problem, "case": label, "overrides": json.dumps(overrides, sort_keys=True),
                "status": "not run", "headline": f"no run in {run_dir}"}
    summary = json.loads((run_dir / "summary.json").read_text())
    module = load_problem(problem)
    params = module.Parameters(**{k: v for k, v in summary["parameters"].items()
                                  if k in module.Parameters.__dataclass_fields__})
    ts = read_timeseries(run_dir / "timeseries.csv")
    res = module.analyse(SimpleNamespace(timeseries=ts, out=None, summary=summary), params)
    row = {"problem": problem, "case": label, "overrides": json.dumps(overrides, sort_keys=True),
           "status": summary.get("status"), "steps": summary.get("steps"), "t_reached_s": float(ts["time"][-1]),
           "max_penetration_dx": summary.get("fluid", {}).get("wall_penetration", {}).get("max_depth_dx"),
           "fluid_particles": summary.get("fluid", {}).get("particles", {}).get("fluid"),
           "particles": summary.get("fluid", {}).get("particles", {}).get("total"),
           "run_dir": str(run_dir), "wall_time_s": summary.get("wall_time_s"),
           "run_commit": summary.get("provenance", {}).get("git_commit")}
    row.update(run_check_columns(summary))
    row.update({k: v for k, v in res.items() if isinstance(v, (int, float, str)) and k != "headline"})
    row["headline"] = res.get("headline", "")
    if row.get("t_reached_s") and row.get("wall_time_s"):
        row["wall_s_per_simulated_s"] = row["wall_time_s"] / row["t_reached_s"]
    print(f"  {problem} {label} (re-analysed): {row['headline']}", flush=True)
    return row


def previous_rows(out: Path, name: str) -> dict[str, dict]:
    """The rows of the committed table ``out/<name>.csv`` by case label (``{}`` without one), each
    marked ``kept_from_table``: what ``--reanalyse`` and ``--rerun`` keep for a case whose run
    directory is not at hand (its ``run_commit`` column says when it ran)."""
    table = out / f"{name}.csv"
    if not table.is_file():
        return {}
    return {r["case"]: {**r, "kept_from_table": True} for r in csv.DictReader(table.read_text().splitlines())}


def kept_note(rows: list[dict]) -> str:
    """The sentence a table's notes gain when some of its rows were kept from the previous table."""
    kept = [r["case"] for r in rows if r.get("kept_from_table")]
    if not kept:
        return ""
    return (" Kept from the previous table, whose run directories were not at hand (run_commit says when "
            "each ran, with the code of that commit, where the previous table recorded it; otherwise its "
            f"provenance line does): {'; '.join(kept)}.")


def runner(args, previous: dict[str, dict] | None = None):
    """``run`` or ``reanalysed`` per case: ``--reanalyse`` rebuilds every row from its saved run,
    ``--rerun PATTERN`` runs only the cases whose label matches the regular expression and
    rebuilds the others; a case not run and without a run directory keeps its row of ``previous``
    (:func:`previous_rows`) when it has one."""
    def one(problem: str, label: str, overrides: dict, runs: Path) -> dict:
        if args.reanalyse or (args.rerun and not re.search(args.rerun, label)):
            row = reanalysed(problem, label, overrides, runs)
            if row["status"] == "not run" and previous and label in previous:
                return previous[label]
            return row
        return run(problem, label, overrides, runs)
    return one


def write_table(out: Path, name: str, rows: list[dict], title: str, notes: str, columns: list[str],
                report: str = "fluid_core") -> None:
    """``out/<name>.csv`` and ``.md``: the given columns of each row (those some row has), with
    ``run_commit`` last when the rows name their runs' commits, and the notes saying which rows
    were kept from the previous table (:func:`kept_note`)."""
    kept = kept_note(rows).strip()
    notes = notes.strip() + (f"\n\n{kept}" if kept else "")
    columns = [*columns, *(["run_commit"] if "run_commit" not in columns else [])]
    keys = [c for c in columns if any(r.get(c) not in (None, "") for r in rows)]
    atomic_write(out / f"{name}.csv", csv_text(keys, [[format_cell(r.get(k, "")) for k in keys] for r in rows]))
    lines = [f"# {title}", "", notes.strip(), "", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for r in rows:
        lines.append("| " + " | ".join(format_cell(r.get(k, "")) for k in keys) + " |")
    prov = provenance(f"{report}/{name}")
    lines += ["", produced_by(prov)]
    atomic_write(out / f"{name}.md", "\n".join(lines) + "\n")


# ----------------------------------------------------------------------------- sections
IMPACT_COLUMNS = ["case", "status", "t_reached_s", "fluid_particles", "steps", "P1_peak", "P1_peak_T",
                  "P1_reference_peak", "P1_reference_peak_T", "P1_peak_error", "P1_peak_time_error_T", "P1_peak_raw",
                  "ringing_period_T",
                  "rms_deviation_P1", "rms_deviation_P2", "rms_deviation_P3", "rms_deviation_P4", "noise_rms_P1",
                  "noise_rms_P2", "noise_rms_P3", "noise_rms_P4", "energy_lost_fraction", "max_penetration_dx", "wall_time_s",
                  "wall_s_per_simulated_s"]


def section_impact(args, out: Path, runs: Path) -> None:
    one = runner(args, previous_rows(out, "impact"))
    rows = [one("dam_break_impact", label, ov, runs) for label, ov in impact_cases(args.quick, args.finest)]
    write_table(out, "impact", rows, "Dam break with wall impact (Zhou et al. 1999 tank) against De Courcy et al. (2024)",
                """Pressure p/(rho g H) at the four sensors of the downstream wall against the converged
delta-SPH solution of De Courcy et al. (2024), T = t sqrt(g/H). P1 peak: of the running mean over
one period of the acoustic ringing after the impact (ringing_period_T, measured from the
spectrum of P1; about 4 d/c0 of the thin layer at the wall, an artefact of weak
compressibility), in 2 <= T <= 3.5 (P1_peak_raw: the largest raw sample). RMS deviation: over
2 <= T <= 7 at the reference's samples. Noise: RMS of the series about its running mean over
dT = 0.05. Goal (the issue): P1 peak within 15 % and its time within 0.1 at the finest
resolution; the RMS deviation falling with resolution; no particle through a wall.""",
                IMPACT_COLUMNS)
    plot_impact(out, rows)


SCATTER_MEASURES = ("P1_peak", "P1_peak_error", "P1_peak_raw", "rms_deviation_P1", "rms_deviation_P2",
                    "rms_deviation_P3", "rms_deviation_P4")


def section_scatter(args, out: Path, runs: Path) -> None:
    one = runner(args, previous_rows(out, "impact_scatter"))
    rows = [one("dam_break_impact", label, ov, runs) for label, ov in scatter_cases(args.quick, args.finest)]
    table = out / "impact.csv"
    if table.is_file():      # the impact section's runs are the unperturbed members of each family
        for r in csv.DictReader(table.read_text().splitlines()):
            rows.append({**r, "case": f"{r['case']} (impact table)"})
    stats = []
    for label, _ in impact_cases(args.quick, args.finest):
        family = [r for r in rows if r["case"].split(" ")[0] == label and str(r.get("status", "")).startswith("completed")]
        for name, fn in (("mean", np.mean), ("standard deviation", lambda v: np.std(v, ddof=1))):
            row = {"case": f"{label}: {name} of {len(family)} runs", "status": ""}
            for k in SCATTER_MEASURES:
                values = [float(r[k]) for r in family if r.get(k) not in (None, "")]
                row[k] = float(fn(values)) if len(values) > 1 else None
            stats.append(row)
    write_table(out, "impact_scatter", rows + stats,
                "Dam break with wall impact: the measures' scatter under round-off",
                """The impact's cases rerun with one input perturbed by a relative 1e-12 (c0_factor up or
down, g up) beside the impact table's own run: four runs per resolution that differ at round-off
only. The measures are those of impact.md. The spread of the family is how far a single run's
P1 peak and RMS deviations can be trusted; the mean is the estimate to compare with the goal (P1
peak within 15 % at the finest resolution). The rows marked "(impact table)" are impact.md's own runs, with its provenance.""", ["case", "status", "steps", *SCATTER_MEASURES, "P1_peak_T",
                                                 "ringing_period_T", "wall_time_s", "run_commit"])


def plot_impact(out: Path, rows: list[dict]) -> None:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mlsgalerkin.problems.dam_break_impact import load_reference

    from mlsgalerkin.io import read_timeseries

    ref = load_reference()
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for k, ax in enumerate(axes, start=1):
        d = ref[f"P{k}"]
        ax.plot(d[:, 0], d[:, 1], "k.", ms=2, label="De Courcy et al. 2024 (delta-SPH, H/dx = 400)")
        for r in rows:
            if "run_dir" not in r:
                continue
            ts = read_timeseries(Path(r["run_dir"]) / "timeseries.csv")
            ov = json.loads(r["overrides"])
            H = ov.get("height", 0.6)
            T = np.asarray(ts["time"]) * math.sqrt(9.81 / H)
            ax.plot(T, np.asarray(ts[f"pressure_P{k}"]) / (1000 * 9.81 * H), lw=0.7, label=r["case"])
        ax.set_ylabel(f"P{k}: p/(rho g H)")
        ax.set_xlim(1.5, 7.0)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[-1].set_xlabel("T = t sqrt(g/H)")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(out / "impact_pressure.png", buf.getvalue())
    finest = [r for r in rows if "run_dir" in r]
    if finest:
        snapshots(Path(finest[-1]["run_dir"]), out / "impact_snapshots.png")


def snapshots(run_dir: Path, png: Path, times_T=(2.4, 4.0, 5.0, 5.6, 6.2, 7.0), H: float = 0.6) -> None:
    """The frames closest to the given ``T`` (impact, run-up, plunging jet, re-entry)."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mlsgalerkin.io import read_pvd, read_vtu

    frames = read_pvd(run_dir / "particles.pvd")
    times = np.array([t for t, _ in frames])
    fig, axes = plt.subplots(len(times_T), 1, figsize=(8, 2.2 * len(times_T)))
    for ax, T in zip(axes, times_T):
        i = int(np.argmin(np.abs(times * math.sqrt(9.81 / H) - T)))
        pts, data = read_vtu(frames[i][1])
        wall = np.asarray(data["is_wall"]).astype(bool)
        p = np.asarray(data["pressure"]) / (1000 * 9.81 * H)
        ax.scatter(pts[wall, 0], pts[wall, 1], s=0.2, c="0.6")
        sc = ax.scatter(pts[~wall, 0], pts[~wall, 1], s=0.3, c=p[~wall], cmap="viridis", vmin=0, vmax=1.5)
        ax.set_aspect("equal")
        ax.set_xlim(-0.1, 3.35)
        ax.set_ylim(-0.1, 1.9)
        ax.set_title(f"T = {times[i] * math.sqrt(9.81 / H):.2f} (t = {times[i]:.3f} s)", fontsize=9)
        ax.set_ylabel("y (m)")
        fig.colorbar(sc, ax=ax, label="p/(rho g H)")
    axes[-1].set_xlabel("x (m)")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    atomic_write(png, buf.getvalue())


def section_dam_break(args, out: Path, runs: Path) -> None:
    a = 2.25 * 0.0254
    cases = [("a/dx=10", {"dx": a / 10, "t_end": 0.1})] if args.quick else \
        [(f"a/dx={n}", {"dx": a / n}) for n in (20, 40, 80)]
    one = runner(args, previous_rows(out, "dam_break"))
    rows = [one("dam_break", label, ov, runs) for label, ov in cases]
    write_table(out, "dam_break", rows, "Dam break (Martin & Moyce 1952) through the wall impact",
                """Surge front against Martin & Moyce for T <= 3; the runs continue through the wall
impact (t = 0.27 s) and the run-up to the problem's default end, t = 0.4 s (T = 7.4).""",
                ["case", "status", "t_reached_s", "fluid_particles", "steps", "rms_deviation_Z",
                 "rms_deviation_Z_time_shifted", "max_penetration_dx", "wall_time_s", "wall_s_per_simulated_s"])


def section_gravity(args, out: Path, runs: Path) -> None:
    one = runner(args, previous_rows(out, "gravity"))
    rows = [one("gravity_current", label, ov, runs) for label, ov in gravity_cases(args.quick)]
    write_table(out, "gravity", rows, "Gravity current head speed: the 3 x 3 matrix in two tanks, two resolutions",
                """Head speed against 0.4 sqrt(g D drho/rho0) (Rottman & Simpson 1983). Goal: within 10 %,
no divergence. Each depth D and density ratio in the tank whose length scales with the depth
(0.34 D/0.06 m) at 20 rows per depth, and in the problem's own 0.34 m tank at the problem's default
spacing (20 rows per depth since 2026-12-04: dx = D/20) and at dx = 3 mm (the default before; 13
rows at D = 0.04 m, 40 at 0.12 m); every other setting is the problem's default (delta =
0.1, local shifting, linear consistency as in the recommended set, with its hydrostatic
reference under the lid since 2026-12-05, alpha = 0.01, no-slip walls, the lid with
ClosedVolume); the rows marked alpha=0.02 run the recommended set's alpha. A row whose
run_commit is older than e989f6b ran without the hydrostatic reference (the exchange lopsided). The last
rows are the issue's deep weakly stratified case (D = 0.09 m, drho/rho0 = 0.05). The
simulated tank is the given one rounded to whole particle spacings. Both fronts: front_speed_ratio is
the light front's speed over the heavy head's (1 in a Boussinesq exchange under a lid; blank where
the row was kept from a table without it). Pressure noise under the lid: the spread (max - min) of the top row's pressure after
0.2 s, its median and largest value, and the mean top-row pressure at 0.2 s and at the end (the
lid's pressure level, 1 rho_heavy g D at the start). largest_volume_error: the run's largest
|geometric volume / sum M/rho - 1|.""",
                ["case", "status", "fluid_particles", "steps", "head_speed_m_s", "reference_head_speed_m_s",
                 "relative_error", "froude_number", "light_froude_number", "front_speed_ratio", "largest_volume_error",
                 "max_clumped_pairs", "top_pressure_spread_median_pa", "top_pressure_spread_max_pa",
                 "top_pressure_spread_median_over_drho_g_d", "top_pressure_mean_start_pa", "top_pressure_mean_end_pa",
                 "max_penetration_dx", "wall_time_s", "wall_s_per_simulated_s"])


def section_gravity_lid(args, out: Path, runs: Path) -> None:
    one = runner(args, previous_rows(out, "gravity_lid"))
    rows = [one("gravity_current", label, ov, runs) for label, ov in gravity_lid_cases(args.quick)]
    write_table(out, "gravity_lid", rows, "The deep weakly stratified lock exchange under the lid: both fronts",
                """D = 0.12 m, drho/rho0 = 0.1 (and 0.03), the problem's 0.34 m tank (0.339 m simulated). Head
speed of the heavy current (along the floor) against 0.4 sqrt(g D drho/rho0) (Rottman & Simpson
1983), and the light current's front (along the lid or the free surface) fitted over the same
time window: froude_number and light_froude_number are both fronts' speeds over sqrt(g D
drho/rho0); front_speed_ratio = light / heavy. A Boussinesq exchange under a lid runs both fronts
alike (ratio 1, Froude number about 0.5 at high Reynolds number, a few per cent less with
mixing: Shin, Dalziel & Linden 2004). Every setting is the problem's default (the recommended
set with alpha = 0.01, no-slip walls, the lid with ClosedVolume) except the one named. Since
2026-12-05 the set's linear consistency keeps a fixed hydrostatic reference under the lid
(docs/theory/stabilisation.md section 7); a lid row whose run_commit is older, or blank (kept from
the table of 2026-12-03), ran without it, when the exchange under the lid was lopsided (the light
front at 0.6-0.8 of the head). The free-surface rows are untouched by it.

![both fronts per case](gravity_lid.png)""",
                ["case", "status", "fluid_particles", "steps", "t_reached_s", "head_speed_m_s", "relative_error",
                 "froude_number", "light_front_speed_m_s", "light_froude_number", "front_speed_ratio",
                 "largest_volume_error", "max_clumped_pairs", "top_pressure_spread_median_over_drho_g_d",
                 "max_penetration_dx", "wall_time_s", "wall_s_per_simulated_s"])
    plot_gravity_lid(out, rows)


def plot_gravity_lid(out: Path, rows: list[dict]) -> None:
    """``gravity_lid.png``: each case's two Froude numbers (heavy head, light front) side by side,
    with Benjamin's energy-conserving 0.5 and the formula's 0.4 marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mlsgalerkin.plots.frames import figure_png

    def number(value) -> float | None:       # a fresh row holds floats, a kept row its table's text
        try:
            return float(value)
        except (TypeError, ValueError):
            return None

    done = [{**r, "froude_number": number(r.get("froude_number")),
             "light_froude_number": number(r.get("light_froude_number"))} for r in rows]
    done = [r for r in done if r["froude_number"] is not None and r["light_froude_number"] is not None]
    if not done:
        return
    y = np.arange(len(done))[::-1]
    fig, ax = plt.subplots(figsize=(8, 0.42 * len(done) + 1.8), dpi=100)
    ax.barh(y + 0.2, [r["froude_number"] for r in done], 0.4, label="heavy head (floor)", color="tab:red")
    ax.barh(y - 0.2, [r["light_froude_number"] for r in done], 0.4, label="light front (top)", color="tab:blue")
    ax.axvline(0.5, color="k", lw=0.8, ls="--", label="energy-conserving 0.5")
    ax.axvline(0.4, color="0.5", lw=0.8, ls=":", label="0.4 (Rottman & Simpson 1983)")
    ax.set_yticks(y, [r["case"] for r in done], fontsize=8)
    ax.set_xlabel("front speed / sqrt(g D drho/rho0)")
    ax.set_title("D = 0.12 m lock exchange: both fronts (a Boussinesq exchange runs them alike)", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2)
    fig.tight_layout()
    figure_png(fig, out / "gravity_lid.png")
    plt.close(fig)


def section_rest(args, out: Path, runs: Path) -> None:
    one = runner(args, previous_rows(out, "rest"))
    rows = [one("stratified_rest", label, ov, runs) for label, ov in rest_cases(args.quick)]
    write_table(out, "rest", rows, "Two-layer tank at rest (1000/1030 kg/m3)",
                """Largest spurious speed over sqrt(g' D) and the RMS pressure deviation from the
hydrostatic profile (each layer's exact Tait equilibrium) over drho g D; under the lid the
mean deviation is removed (the lid's pressure level is free). Goal: below 1 % and 2 % over 5 s.
The disordered start moves every particle by up to +-0.25 dx per axis (seeded) and gives it the
density of its new height: the melted lattice of a mixing zone, at rest.""",
                ["case", "status", "t_end", "fluid_particles", "steps", "max_speed_ratio", "late_max_speed_ratio",
                 "pressure_rms_ratio_max", "late_pressure_rms_ratio", "largest_volume_error", "wall_time_s"])


def section_drop(args, out: Path, runs: Path) -> None:
    rows = []
    one = runner(args, previous_rows(out, "drop"))
    for label, ov in drop_cases(args.quick):
        for mode in ("cavitate", "free_surface", "allow"):
            rows.append(one("drop_impact", f"{label}, negative_pressure={mode}",
                            dict(ov, negative_pressure=mode, delta=0.1, shifting="local", density_filter=0), runs))
    write_table(out, "drop", rows, "Drop impact without the cavitation floor",
                """Drop impact at 2, 5 and 10 m/s with density diffusion and shifting: the cavitation floor
on every particle (cavitate), on the free-surface particles only (free_surface), and none
(allow).""",
                ["case", "status", "t_reached_s", "fluid_particles", "steps", "energy_initial_J", "energy_final_J",
                 "energy_max_growth_relative_to_initial_kinetic", "max_penetration_dx",
                 "wall_time_s"])


ABLATION = [
    ("all terms (defaults)", {}),
    ("direct nodal integration (no linear consistency)", {"linear_consistency": False}),
    ("constant VCI instead of the linear consistency", {"linear_consistency": False, "consistent_integration": True}),
    ("no density diffusion", {"delta": 0.0}),
    ("no shifting", {"shifting": "off"}),
    ("alpha = 0", {"alpha": 0.0}),
    ("tension allowed", {"negative_pressure": "allow"}),
    ("no volume consistency (nor its loose side and droplets)", {"volume_consistency": 0.0}),
]
GRAVITY_ABLATION = [
    ("all terms (defaults)", {}),
    ("no ClosedVolume", {"closed_volume": False}),
    ("alpha = 0.02 (the recommended set's)", {"alpha": 0.02}),
    ("direct nodal integration (no linear consistency)", {"linear_consistency": False}),
    ("no density diffusion", {"delta": 0.0}),
    ("no shifting", {"shifting": "off"}),
]


def section_ablation(args, out: Path, runs: Path) -> None:
    rows = []
    one = runner(args, previous_rows(out, "ablation"))
    base_impact = {"dx": 0.06, "t_end": 0.6} if args.quick else {"dx": 0.6 / 40}
    for label, ov in ABLATION[:2] if args.quick else ABLATION:
        rows.append(one("dam_break_impact", f"impact H/dx={0.6 / base_impact['dx']:.0f}: {label}",
                        dict(base_impact, **ov), runs))
    base_gc = {"dx": 0.012, "t_end": 0.3, "gif": False} if args.quick else \
        {"depth": 0.04, "length": 0.34 * 0.04 / 0.06, "rho_heavy": 1100.0, "dx": 0.002, "t_end": 1.6, "gif": False}
    for label, ov in GRAVITY_ABLATION[:2] if args.quick else GRAVITY_ABLATION:
        rows.append(one("gravity_current", f"gravity D=0.04 drho=0.1: {label}", dict(base_gc, **ov), runs))
    write_table(out, "ablation", rows, "Ablation: each stabilising term of the one recommended set off in turn",
                """Dam break with impact (H/dx = 40, to T = 7) and the weakly stratified gravity current
(D = 0.04 m, drho/rho0 = 0.1, 20 rows, the scaled tank): completes or not, the measures of each
problem, the largest geometric-volume error and the cost. The defaults are the one recommended set
(alpha = 0.02, delta = 0.1, local shifting, linear consistency, the volume consistency with its
loose side and droplets), with the gravity current's own alpha = 0.01 and its lid's ClosedVolume
(under which the volume consistency is idle).""",
                ["case", "status", "t_reached_s", "steps", "P1_peak", "P1_peak_T", "P1_peak_raw", "rms_deviation_P1",
                 "rms_deviation_P3", "noise_rms_P1", "noise_rms_P3", "energy_lost_fraction", "relative_error",
                 "largest_volume_error", "max_clumped_pairs", "max_penetration_dx", "wall_time_s",
                 "wall_s_per_simulated_s"])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--section", default="all", choices=SECTIONS + ("all",))
    ap.add_argument("--out", default="verification/results/fluid_core")
    ap.add_argument("--runs", default="results/fluid_core_runs")
    ap.add_argument("--quick", action="store_true", help="tiny runs (a smoke test of this script)")
    ap.add_argument("--reanalyse", action="store_true",
                    help="rebuild the tables from the run directories in --runs (no simulation)")
    ap.add_argument("--rerun", default=None, metavar="PATTERN",
                    help="run only the cases whose label matches this regular expression; rebuild the others "
                         "from their run directories")
    ap.add_argument("--finest", type=int, default=80, help="finest H/dx of the impact section (40, 80 or 160)")
    args = ap.parse_args(argv)
    out, runs = Path(args.out), Path(args.runs)
    out.mkdir(parents=True, exist_ok=True)
    runs.mkdir(parents=True, exist_ok=True)
    for name in SECTIONS if args.section == "all" else (args.section,):
        print(f"section {name}", flush=True)
        globals()[f"section_{name}"](args, out, runs)
    index = ["# Fluid core verification", "", "Sections (each table states its goal and how it was produced):", ""]
    index += [f"- [{p.stem}]({p.name})" for p in sorted(out.glob("*.md")) if p.name != "summary.md"]
    atomic_write(out / "summary.md", "\n".join(index) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
