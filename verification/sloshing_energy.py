"""Does the volume consistency's loose side damp a sloshing tank? The wave's energy against the
rest state's, with and without it, at 10 and 20 rows in the depth.

The tank of ``tests/test_sponge.py``: water 0.6 m long and ``H = 0.15`` m deep in a box 0.3 m high,
started at rest in its hydrostatic density with the horizontal flow ``u = 0.2 cos(πx/L)`` m/s. That
flow converges everywhere, so it starts the symmetric second sloshing mode (both ends rise and fall
together; linear theory: ``ω² = g k tanh(kH)``, ``k = 2π/L``, period ``T = 0.647`` s) and its higher
harmonics, with the acoustic waves of its compression on top.

What a sceptic reads:

- **The wave's energy**: the mean kinetic energy over whole periods (for a linear standing wave half
  its energy; the acoustic swing of the kinetic energy averages out over a period), over periods
  1–2 and 3–4.
- **The end walls' elevation**: the mean of the two walls' water level (the highest fluid particle
  within three spacings of each wall) above its start, sampled every 0.05 s; its largest magnitude
  in each half period, averaged over the last four.
- **The rest state**: the mean potential energy above the start's over periods 3–4, less the wave's
  share (taken equal to the mean kinetic energy), over ``ρ g V``: how far the centre of mass has
  moved (mm). A packing that settles lowers it; one held loose raises it.
- The run's largest volume error, and the share of evaluations in which the loose side acted.

``python verification/sloshing_energy.py`` (about 5 min on one core) writes
``verification/results/volume_consistency/sloshing.{md,csv,png}``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from mlsgalerkin.fluid import FluidBody, Phase, hydrostatic_density, wall_box, water
from mlsgalerkin.io import atomic_write, csv_text, format_cell, provenance, read_pvd, read_vtu
from mlsgalerkin.scene import Output, Scene
from mlsgalerkin.simulation import Simulation

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from verification.report_format import produced_by

LENGTH, DEPTH, G, RHO = 0.6, 0.15, 9.81, 1000.0
K2 = 2 * math.pi / LENGTH
PERIOD = 2 * math.pi / math.sqrt(G * K2 * math.tanh(K2 * DEPTH))    # the second mode's, 0.647 s


def sloshing_scene(dx: float, loose_band: float, t_end: float, extra: list | tuple = (),
                   output: Output | None = None) -> Scene:
    """The tank at spacing ``dx`` (m), started with ``u = 0.2 cos(πx/L)`` m/s, with the
    recommended set (the loose side's band ``loose_band``, 0: off) and the effects ``extra``
    appended (``tests/test_sponge.py`` adds a sponge zone), run to ``t_end`` (s)."""
    fluid = FluidBody.block("water", (0.0, 0.0), (LENGTH, DEPTH), dx, [Phase("water", RHO)])
    c0 = 10 * math.sqrt(2 * G * DEPTH)
    fluid.density[:] = hydrostatic_density(np.full(fluid.n, RHO), DEPTH - fluid.positions[:, 1], G, c0)
    fluid.velocity[:, 0] = 0.2 * np.cos(math.pi * fluid.positions[:, 0] / LENGTH)
    walls = wall_box((0.0, 0.0), (LENGTH, 2 * DEPTH), dx, layers=3)
    scheme = water(c0, spacing=dx, loose_band=loose_band, extra=list(extra))
    return Scene([fluid, walls], [scheme], t_end=t_end, **({"output": output} if output else {}))


def run_case(rows: int, loose_band: float, t_end: float, runs: Path) -> dict:
    """One run of the tank (``rows`` particle rows in the depth, the loose side's band
    ``loose_band``, 0: off) to ``t_end`` (s), its frames in ``runs``; returns the row's measures."""
    dx = DEPTH / rows
    scene = sloshing_scene(dx, loose_band, t_end, output=Output(every=0.05, gif=False, png=False))
    out = runs / f"rows{rows}_loose{loose_band:g}"
    t0 = time.perf_counter()
    res = Simulation(scene).run(out, progress=False, overwrite=True)
    wall_time = time.perf_counter() - t0
    ts = res.timeseries
    t = np.asarray(ts["time"])
    kinetic = np.asarray(ts["kinetic_energy"])
    potential = np.asarray(ts["potential_energy"]) - float(ts["potential_energy"][0])
    window = [(t >= k * PERIOD) & (t < (k + 2) * PERIOD) for k in (0, 2)]
    ke = [float(kinetic[w].mean()) for w in window]
    pe = [float(potential[w].mean()) for w in window]
    times, level = end_wall_level(out, dx)
    half = [float(np.abs(level[(times >= a) & (times < a + PERIOD / 2)]).max())
            for a in np.arange(0.0, times[-1] - PERIOD / 2 + 1e-9, PERIOD / 2)]
    report = res.summary["fluid"]["effect_reports"]["volume_consistency"]
    error = np.asarray(ts["volume_error"], dtype=float)
    return {"case": f"{rows} rows (dx = {1000 * dx:g} mm), loose side {'off' if not loose_band else loose_band}",
            "rows": rows, "loose_band": loose_band, "mean_kinetic_periods_1_2_J_m": ke[0],
            "mean_kinetic_periods_3_4_J_m": ke[1], "mean_potential_above_start_periods_3_4_J_m": pe[1],
            "centre_of_mass_shift_mm": 1000 * (pe[1] - ke[1]) / (RHO * G * LENGTH * DEPTH),
            "end_wall_amplitude_last_four_half_periods_mm": 1000 * float(np.mean(half[-4:])),
            "largest_volume_error": float(np.nanmax(np.abs(error))),
            "loose_active_share": report.get("loose_active_share", 0.0), "wall_time_s": wall_time,
            "_series": (t, kinetic, times, level)}


def end_wall_level(run_dir: Path, dx: float) -> tuple[np.ndarray, np.ndarray]:
    """The frames' times (s) and the mean water level at the two end walls above its start (m)."""
    times, level = [], []
    for t, frame in read_pvd(run_dir / "particles.pvd"):
        pts, data = read_vtu(frame)
        fluid = np.asarray(data["is_wall"]) == 0
        x, y = pts[fluid, 0], pts[fluid, 1]
        times.append(t)
        level.append(0.5 * (y[x < 3 * dx].max() + y[x > LENGTH - 3 * dx].max()))
    level_arr = np.asarray(level)
    return np.asarray(times), level_arr - level_arr[0]


def plot(rows: list[dict], png: Path) -> None:
    """Kinetic energy (averaged over a tenth of a period) and end-wall level against time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mlsgalerkin.plots.frames import figure_png

    fig, axes = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    for r in rows:
        t, kinetic, times, level = r["_series"]
        col = 0 if r["rows"] == 10 else 1
        width = max(1, int(0.1 * PERIOD / np.median(np.diff(t))))
        smooth = np.convolve(kinetic, np.ones(width) / width, mode="same")
        style = "-" if not r["loose_band"] else "--"
        label = "loose side off" if not r["loose_band"] else f"loose side {r['loose_band']:g} (the set)"
        axes[0, col].plot(t, smooth, style, lw=0.9, label=label)
        axes[1, col].plot(times, 1000 * level, style, lw=0.9, label=label)
        axes[0, col].set_title(f"{r['rows']} rows in the depth", fontsize=9)
    for ax in axes[0]:
        ax.set_ylabel("kinetic energy (J/m)")
    for ax in axes[1]:
        ax.set_ylabel("end-wall level (mm)")
        ax.set_xlabel("t (s)")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    figure_png(fig, png)
    plt.close(fig)


COLUMNS = ["case", "mean_kinetic_periods_1_2_J_m", "mean_kinetic_periods_3_4_J_m",
           "mean_potential_above_start_periods_3_4_J_m", "centre_of_mass_shift_mm",
           "end_wall_amplitude_last_four_half_periods_mm", "largest_volume_error", "loose_active_share",
           "wall_time_s"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="verification/results/volume_consistency")
    ap.add_argument("--runs", default="results/sloshing_runs")
    ap.add_argument("--rows", type=int, nargs="+", default=[10, 20])
    ap.add_argument("--periods", type=float, default=4.0, help="simulated time in sloshing periods")
    args = ap.parse_args(argv)
    out, runs = Path(args.out), Path(args.runs)
    out.mkdir(parents=True, exist_ok=True)
    runs.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in args.rows:
        for band in (0.0, 0.005):
            rows.append(run_case(n, band, args.periods * PERIOD, runs))
            print(f"  {rows[-1]['case']}: " + ", ".join(f"{k} {format_cell(rows[-1][k])}" for k in COLUMNS[1:]),
                  flush=True)
    atomic_write(out / "sloshing.csv", csv_text(COLUMNS, [[format_cell(r[k]) for k in COLUMNS] for r in rows]))
    lines = ["# The loose side in a sloshing tank: the wave's energy and the rest state's", "",
             (__doc__ or "").split("\n\n", 1)[1].split("``python")[0].strip(), "",
             "![kinetic energy and end-wall level](sloshing.png)", "",
             "| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(format_cell(r[k]) for k in COLUMNS) + " |" for r in rows]
    lines += ["", produced_by(provenance("volume_consistency/sloshing"))]
    atomic_write(out / "sloshing.md", "\n".join(lines) + "\n")
    plot(rows, out / "sloshing.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
