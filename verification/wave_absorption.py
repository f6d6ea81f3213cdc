"""How much of a wave the end of a tank sends back: the wave maker's reflection coefficient with a
sponge of several lengths and strengths, and with a bare wall, with error and wall time.

    python verification/wave_absorption.py --out verification/results/wave_absorption
    python verification/wave_absorption.py --quick --out results/wave_absorption_quick   # smoke

The ``wave_maker`` problem (depth 0.2 m, period 1 s: a wave 1.21 m long; stroke 2 cm; the
recommended set) with a sponge of length ``L_s`` whose rate rises as ``ξ²`` to ``σ_max = rate / T``
at the far wall. Three gauges between the probe and the sponge (Mansard & Funke 1980's spacing,
centred at 1.1 m in every sponge case: the sponge starts at 1.8 m) split the first harmonic into
incident and reflected waves; ``reflection_coefficient`` is ``|a_R| / |a_I|`` over the window from
one period after the reflected wave reaches the gauges at full height to the end of the run, and
``reflection_misfit`` the RMS misfit of the two-wave model at the gauges over the incident amplitude.
A bare wall in a 6 m tank, over the window before the paddle re-reflects the reflected wave, is
the check that the split reads a full reflection: a perfect reflector reads ``1 −
viscous_decay_round_trip`` (the artificial viscosity's decay of the wave over its round trip from
the gauges to the wall and back, ``ν ≈ α h c0 / 8``, Lamb 1932).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from mlsgalerkin.problem import load_problem
from verification.fluid_core import runner, write_table

#: Distance from the paddle to the sponge's start (m) in every case.
SPONGE_START = 3.0

COLUMNS = ["case", "status", "fluid_particles", "steps", "t_reached_s", "rows_per_depth", "reflection_coefficient",
           "reflection_coefficient_min", "reflection_coefficient_max", "sponge_round_trip_attenuation", "reflection_misfit",
           "incident_height_m", "reflected_height_m", "viscous_decay_round_trip",
           "paddle_rereflection_arrives_s", "largest_volume_error", "max_penetration_dx", "wall_time_s",
           "wall_s_per_simulated_s", "overrides"]


def cases(quick: bool) -> list[tuple[str, dict]]:
    """``(label, overrides)`` of every run: the sponge starts 3 m from the paddle (the gauges stand
    at 2.3–2.6 m), the paddle starts over one period, and each run ends when the paddle's own
    reflection of the reflected wave reaches the first gauge (the end of the steady window)."""
    wm = load_problem("wave_maker")

    def case(dx: float, length: float, rate: float) -> dict:
        o = {"dx": dx, "tank_length": SPONGE_START + length, "sponge_length": length, "sponge_rate": rate,
             "ramp_periods": 1.0}
        p = wm.Parameters(**o)
        x1 = float(wm.reflection_gauges(p)[0])
        o["t_end"] = math.ceil(10 * (2 * p.tank_length + x1) / wm.group_velocity(p.period, p.depth, p.g)) / 10
        return o

    if quick:
        return [("10 rows, sponge 1.2 m, rate 10", dict(case(0.02, 1.2, 10.0), t_end=0.5))]
    sponge = [(0.6, 10.0), (1.2, 3.0), (1.2, 5.0), (1.2, 10.0), (2.4, 5.0)]
    out = [(f"10 rows, sponge {length:g} m, rate {rate:g}", case(0.02, length, rate)) for length, rate in sponge]
    wall = case(0.02, 0.0, 10.0)
    out.append((f"10 rows, bare wall, {SPONGE_START:g} m tank", {k: v for k, v in wall.items() if k != "sponge_rate"}))
    out += [(f"20 rows, sponge {length:g} m, rate {rate:g}", case(0.01, length, rate)) for length, rate in [(2.4, 5.0)]]
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="one short coarse run (a smoke test of this script)")
    ap.add_argument("--only", default="", help="only the cases whose label contains this text")
    ap.add_argument("--reanalyse", action="store_true", help="rebuild the rows from the saved runs")
    ap.add_argument("--rerun", default=None, metavar="PATTERN", help="run only the cases matching PATTERN")
    ap.add_argument("--out", default="verification/results/wave_absorption")
    ap.add_argument("--runs", default="results/wave_absorption_runs")
    args = ap.parse_args(argv)
    out, runs = Path(args.out), Path(args.runs)
    out.mkdir(parents=True, exist_ok=True)
    one = runner(args)
    rows = [one("wave_maker", label, overrides, runs) for label, overrides in cases(args.quick) if args.only in label]
    write_table(out, "summary_quick" if args.quick else "summary", rows,
                "Wave absorption: the reflection coefficient of a sponge and of a bare wall",
                "\n\n".join(__doc__.split("\n\n")[2:]), COLUMNS, report="wave_absorption")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
