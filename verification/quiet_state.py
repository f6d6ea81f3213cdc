"""Quiet states: water and a two-layer fluid at rest, with a free surface and under a lid, for a
long time, at two resolutions, with a named set of numerical settings. Every row records the
largest spurious speed, the pressure RMS deviation, the largest geometric-volume error and the
wall time.

    python verification/quiet_state.py --settings candidate --out verification/results/quiet_state
    python verification/quiet_state.py --settings problem --quick --out results/quiet_state_quick   # smoke

Cases: ``still`` — a 1 m tank of water 0.3 m deep (the ``hydrostatic`` problem with
``width = 1``, ``depth = 0.3``) for 10 s with a free surface and under a lid, at ``Δx = 0.02``
and 0.01 m; ``two_layer`` — the ``stratified_rest`` tank (1000/1030 kg/m³, 0.06 m deep) for
5 s with a free surface and under a lid, at 20 and 40 rows. Goals (the issue's quiet-state
suite): largest speed below 1 % of ``sqrt(g H)`` (``sqrt(g' D)``), pressure RMS deviation below
2 % of ``ρ g H`` (``Δρ g D``), geometric volume within 1 % of Σ M/ρ.

Settings (``--settings``): ``problem`` — each problem's own defaults; ``candidate`` — one set for
every case: Monaghan ``α = 0.02``, δ-SPH ``δ = 0.1``, shifting at each particle's speed, tension
released by cavitation, no density filter, and the pressure's linear fit integrated exactly with
the free-surface term (``linear_consistency``); ``candidate_dni`` — the same with direct nodal
integration (the ablation of that last piece).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from verification.fluid_core import run, write_table  # noqa: E402

ONE_SET = {"alpha": 0.02, "delta": 0.1, "shifting": "local", "negative_pressure": "cavitate", "density_filter": 0,
           "consistent_integration": False, "linear_consistency": True}
SETTINGS = {"problem": {}, "candidate": ONE_SET, "candidate_dni": dict(ONE_SET, linear_consistency=False)}
COLUMNS = ["problem", "case", "status", "t_reached_s", "fluid_particles", "max_speed_ratio", "pressure_rms_error_max",
           "pressure_rms_error_settled", "pressure_rms_ratio_max", "late_pressure_rms_ratio", "largest_volume_error",
           "wall_time_s", "overrides"]


def cases(settings: dict, quick: bool) -> list[tuple[str, str, dict]]:
    """``(problem, label, overrides)`` of every quiet case."""
    out = []
    still = [0.05] if quick else [0.02, 0.01]
    for lid in (False, True):
        for dx in still:
            base = {"width": 1.0, "depth": 0.3, "dx": dx, "lid": lid, "t_end": 1.0 if quick else 10.0}
            out.append(("hydrostatic", f"still {'lid' if lid else 'free surface'} dx={dx:g}", {**base, **settings}))
    for lid in (False, True):
        for dx in ([0.006] if quick else [0.003, 0.0015]):
            base = {"dx": dx, "lid": lid, "t_end": 0.5 if quick else 5.0}
            if quick:
                base["settle"] = 0.2
            out.append(("stratified_rest", f"two-layer {'lid' if lid else 'free surface'} {0.06 / dx:.0f} rows",
                        {**base, **settings}))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--settings", default="candidate", choices=sorted(SETTINGS))
    ap.add_argument("--quick", action="store_true", help="coarse and short (a smoke run)")
    ap.add_argument("--only", default="", help="run only the cases whose label contains this text")
    ap.add_argument("--out", default="verification/results/quiet_state")
    ap.add_argument("--runs", default="results/quiet_state_runs")
    args = ap.parse_args(argv)
    out, runs = Path(args.out), Path(args.runs)
    out.mkdir(parents=True, exist_ok=True)
    rows = [run(problem, label, overrides, runs) for problem, label, overrides in cases(SETTINGS[args.settings], args.quick)
            if args.only in label]
    for r in rows:
        r["case"] = f"{r['case']} ({args.settings})"
    write_table(out, f"quiet_{args.settings}" + ("_quick" if args.quick else ""), rows,
                f"Quiet states with the settings {args.settings!r}",
                __doc__.split("\n\n")[2] + "\n\n" + __doc__.split("\n\n")[3], COLUMNS, report="quiet_state")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
