"""Periodic flows: the Taylor–Green vortex at Re = 100 (three resolutions), plane Poiseuille and Couette flow (two each).

Runs ``problems/taylor_green.py`` (doubly periodic box), ``problems/poiseuille.py`` and
``problems/couette.py`` (channels periodic along x between no-slip walls) at two or three particle
spacings each, with the problems' scheme
settings (``--set NAME=VALUE`` changes one for every run, e.g. ``--set alpha=0.02``), and records
the error *and* the wall time of every run:

    python verification/fluid_periodic.py --out verification/results/fluid_periodic
    python verification/fluid_periodic.py --quick --out results/periodic_quick     # coarse, < 1 min
    python verification/fluid_periodic.py --only taylor_green --set alpha=0.02 --out results/tg_alpha

Writes ``summary.md`` (the tables, the settings, provenance), ``results.json`` and
``periodic.png`` (the kinetic-energy decay of the vortex against ``exp(−4νk²t)`` and the channels'
velocity profiles against the start-up series). The particle output goes to ``--runs``
(default ``results/periodic_runs``, not committed).
"""

from __future__ import annotations

import argparse
import io
import json
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from mlsgalerkin.io import atomic_write, provenance
from mlsgalerkin.problem import load_problem, parse_overrides, run_problem

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from verification.report_format import generated_by

#: (problem, label, overrides) of the full study; the quick one halves nothing but the spacing
CASES = {
    "taylor_green": [("L/dx = 32", {"dx": 1.0 / 32}), ("L/dx = 64", {"dx": 1.0 / 64}),
                     ("L/dx = 128", {"dx": 1.0 / 128})],
    "poiseuille": [("H/dx = 20", {"dx": 0.05}), ("H/dx = 40", {"dx": 0.025})],
    "couette": [("H/dx = 20", {"dx": 0.05}), ("H/dx = 40", {"dx": 0.025})],
}
QUICK = {
    "taylor_green": [("L/dx = 16", {"dx": 1.0 / 16, "t_end": 0.2}), ("L/dx = 32", {"dx": 1.0 / 32, "t_end": 0.2})],
    "poiseuille": [("H/dx = 10", {"dx": 0.1, "t_end": 0.5}), ("H/dx = 20", {"dx": 0.05, "t_end": 0.5})],
    "couette": [("H/dx = 10", {"dx": 0.1, "t_end": 0.5}), ("H/dx = 20", {"dx": 0.05, "t_end": 0.5})],
}


def params(problem: str, overrides: dict):
    """The problem's ``Parameters`` with ``overrides`` (strings read as each field's type)."""
    return parse_overrides(load_problem(problem).Parameters, overrides)


def run_all(runs: Path, quick: bool, only: list[str] | None, common: dict) -> list[dict]:
    rows = []
    for problem, cases in (QUICK if quick else CASES).items():
        if only and problem not in only:
            continue
        fields = set(load_problem(problem).Parameters.__dataclass_fields__)
        for k, (label, ov) in enumerate(cases):
            run_dir = runs / f"{problem}_{k}"
            if run_dir.exists():
                shutil.rmtree(run_dir)
            overrides = {**ov, **{n: v for n, v in common.items() if n in fields}, "gif": False}
            params(problem, overrides)   # an unreadable value stops here, before any run
            t0 = time.perf_counter()
            result, res = run_problem(problem, overrides, out=run_dir, progress=False)
            wall = time.perf_counter() - t0
            s = result.summary
            extra = {}
            if problem in ("poiseuille", "couette"):   # the final row profile, for the figure
                mod, st = load_problem(problem), result.state.fluid
                y, u = mod.row_profile(st.x[:st.n_fluid], st.v[:st.n_fluid], params(problem, overrides))
                extra = {"profile_y_m": y.tolist(), "profile_u_m_s": u.tolist(), "time_s": float(st.t)}
            rows.append({**extra, "problem": problem, "case": label, "overrides": overrides, "dx_m": s["fluid"]["spacing_m"],
                         "particles": s["fluid"]["particles"]["total"], "steps": s["steps"], "wall_time_s": wall,
                         "effects": s["fluid"]["effects"], "results": res, "run_dir": str(run_dir)})
            print(f"{problem:<13} {label:<10} n={rows[-1]['particles']:>6} steps={s['steps']:>6} wall={wall:7.1f} s  "
                  f"{res['headline']}", flush=True)
    return rows


def percent(value: float) -> str:
    """A fraction in % with two decimals: ``0.0123`` -> ``1.23 %``."""
    return f"{100 * value:.2f} %"


def signed_percent(value: float) -> str:
    """A fraction in % with two decimals and its sign: ``0.0123`` -> ``+1.23 %``."""
    return f"{100 * value:+.2f} %"


def runs_table(runs: list[dict], columns: list[tuple[str, str, Callable[[float], str]]], pass_key: str) -> list[str]:
    """The lines of a Markdown table with a row per run: its case, particles, steps and wall time,
    then one column per ``(header, result key, format)`` of its ``results`` (right-aligned), and
    ``pass``: yes or NO as the result ``pass_key`` says."""
    lines = ["| case | particles | steps | wall time (s) | " + " | ".join(head for head, _, _ in columns) + " | pass |",
             "|---|---:|---:|---:|" + "---:|" * len(columns) + "---|"]
    for r in runs:
        q = r["results"]
        lines.append(f"| {r['case']} | {r['particles']} | {r['steps']} | {r['wall_time_s']:.1f} | "
                     + " | ".join(fmt(q[key]) for _, key, fmt in columns)
                     + f" | {'yes' if q[pass_key] else 'NO'} |")
    return lines


def effects_line(runs: list[dict]) -> str:
    """The fluid effects of the first run, as the summary lists them."""
    return "Effects: " + ", ".join(f"`{e}`" for e in runs[0]["effects"])


def summary_md(rows: list[dict], quick: bool) -> str:
    prov = provenance("fluid_periodic", "quick" if quick else "full")
    lines = ["# Periodic flows: Taylor–Green vortex, plane Poiseuille and Couette flow", "",
             *generated_by(prov)]
    lines += taylor_green_section([r for r in rows if r["problem"] == "taylor_green"])
    for problem in CHANNELS:
        lines += channel_section(problem, [r for r in rows if r["problem"] == problem])
    return "\n".join(lines) + "\n"


def taylor_green_section(runs: list[dict]) -> list[str]:
    """The summary section of the Taylor–Green vortex: the kinetic energy's decay against the exact one."""
    if not runs:
        return []
    p = params("taylor_green", runs[0]["overrides"])
    return (["## Taylor–Green vortex", "",
             f"Re = UL/ν = {p.reynolds:g}, box side {p.side:g} m, U = {p.speed:g} m/s, c0 = {p.c0_factor:g} U, "
             f"to t = {p.t_end:g} s (KE falls to {np.exp(-load_problem('taylor_green').energy_decay_rate(p) * p.t_end):.3f} "
             "of its start). Acceptance: KE(t)/KE(0) within 2 % of exp(−4νk²t) over the whole run. Velocity L1 error "
             "Σ|v − v_exact| / Σ|v_exact| at the particles at the end.", ""]
            + runs_table(runs, [("KE error, largest", "kinetic_energy_error_max", percent),
                                ("KE error, end", "kinetic_energy_error_final", percent),
                                ("decay rate error", "decay_rate_error", signed_percent),
                                ("velocity L1 error", "velocity_l1_error_final", percent),
                                ("ν_art/ν", "numerical_viscosity_ratio", "{:.3g}".format)],
                         pass_key="kinetic_energy_within_tolerance")
            + ["", effects_line(runs), ""])


@dataclass(frozen=True)
class Channel:
    """A channel flow of the study, as its summary section and figure panel name it."""

    title: str          #: section title
    panel: str          #: figure panel title
    scale_name: str     #: the name of the speed scale of its errors
    scale_field: str    #: the field of the problem's ``Parameters`` holding that scale (m/s)
    flow: str           #: what drives it, formatted with the parameters as ``p``

    def scale(self, p) -> float:
        """The speed scale (m/s) of parameters ``p``."""
        return getattr(p, self.scale_field)


CHANNELS = {
    "poiseuille": Channel("Plane Poiseuille flow", "Poiseuille", "u_max", "u_max",
                          "driven by a body force, Re = u_max H/ν = {p.reynolds:g}, u_max = {p.u_max:g} m/s"),
    "couette": Channel("Plane Couette flow", "Couette", "U", "wall_speed",
                       "driven by the top wall sliding at U = {p.wall_speed:g} m/s, Re = U H/ν = {p.reynolds:g}"),
}


def channel_section(problem: str, runs: list[dict]) -> list[str]:
    """The summary section of a channel flow (``poiseuille`` or ``couette``): the row profile at
    the end against the start-up series, in units of the flow's speed scale."""
    if not runs:
        return []
    p = params(problem, runs[0]["overrides"])
    channel = CHANNELS[problem]
    scale = channel.scale_name
    return ([f"## {channel.title}", "",
             f"Between no-slip wall particles at y = 0 and H = {p.height:g} m, periodic length {p.length:g} m, "
             f"{channel.flow.format(p=p)}, c0 = {p.c0_factor:g} {scale}, from rest to t = {p.t_end:g} s; the "
             f"row-averaged x velocity at the end against the start-up series. Acceptance: largest deviation below "
             f"1 % of {scale}.", ""]
            + runs_table(runs, [(f"largest deviation / {scale}", "profile_error_max", percent),
                                (f"RMS deviation / {scale}", "profile_error_rms", percent),
                                ("smooth part, largest", "profile_error_max_smooth", percent),
                                ("row alternation", "row_alternation_amplitude", percent)],
                         pass_key="profile_within_tolerance")
            + ["", "The smooth part: both profiles filtered over three rows (¼, ½, ¼); the row alternation: the "
               "amplitude of what that filter removes from the deviation (alternate rows too fast and too slow).",
               "", effects_line(runs), ""])


def plots(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mlsgalerkin.io import read_timeseries

    fig, axes = plt.subplots(1, 1 + len(CHANNELS), figsize=(14, 4))
    panel = {problem: k + 1 for k, problem in enumerate(CHANNELS)}
    for r in rows:
        run = Path(r["run_dir"])
        mod = load_problem(r["problem"])
        p = params(r["problem"], r["overrides"])
        if r["problem"] == "taylor_green":
            ts = read_timeseries(run / "timeseries.csv")
            t, ke = np.asarray(ts["time"]), np.asarray(ts["kinetic_energy"])
            axes[0].plot(t, ke / ke[0], label=f"{r['case']}")
            axes[0].plot(t, np.exp(-mod.energy_decay_rate(p) * t), "k--", lw=0.8)
        else:
            ax = axes[panel[r["problem"]]]
            scale = CHANNELS[r["problem"]].scale(p)
            y, u, t = np.asarray(r["profile_y_m"]), np.asarray(r["profile_u_m_s"]), r["time_s"]
            ax.plot(u / scale, y / p.height, "o", ms=3, label=f"{r['case']}")
            yy = np.linspace(0.0, p.height, 101)
            ax.plot(mod.series_velocity(yy, t, p) / scale, yy / p.height, "k-", lw=0.8)
    axes[0].set(xlabel="t (s)", ylabel="KE(t)/KE(0)", title="Taylor–Green, Re = 100 (dashed: exact)")
    for problem, channel in CHANNELS.items():
        axes[panel[problem]].set(xlabel=f"u / {channel.scale_name}", ylabel="y / H",
                                 title=f"{channel.panel} (line: start-up series)")
    for a in axes:
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=8)
        else:
            a.set_axis_off()
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(out / "periodic.png", buf.getvalue())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarse runs (< 1 min)")
    parser.add_argument("--out", default="verification/results/fluid_periodic", help="tables and figure")
    parser.add_argument("--runs", default="results/periodic_runs", help="particle output of the runs (large)")
    parser.add_argument("--only", nargs="+", choices=sorted(CASES), help="run only these problems")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="a problem parameter for every run (the scheme settings: alpha, delta, shifting, ...)")
    args = parser.parse_args(argv)
    out, runs = Path(args.out), Path(args.runs)
    out.mkdir(parents=True, exist_ok=True)
    runs.mkdir(parents=True, exist_ok=True)
    common: dict = {}
    for item in args.set:
        name, sep, value = item.partition("=")
        if not sep:
            parser.error(f"--set takes NAME=VALUE, got {item!r}")
        common[name.strip()] = value.strip()
    known = set().union(*(load_problem(p).Parameters.__dataclass_fields__ for p in (args.only or sorted(CASES))))
    if set(common) - known:
        parser.error(f"unknown parameter(s) {sorted(set(common) - known)}; the problems' parameters: {sorted(known)}")
    rows = run_all(runs, args.quick, args.only, common)
    if args.only and (out / "results.json").exists():   # keep the other problems' rows of the last run
        rows = [r for r in json.loads((out / "results.json").read_text()) if r["problem"] not in args.only] + rows
    atomic_write(out / "results.json", json.dumps(rows, indent=1, default=str) + "\n")
    plots(rows, out)
    atomic_write(out / "summary.md", summary_md(rows, args.quick))
    print(f"tables and figure in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
