"""Where a splashing flow's volume error sits: each particle's share of the geometric volume
against its own volume ``M/ρ``, by how many neighbours it has, at two or more resolutions.

The geometric volume (``mlsgalerkin.fluid.distribution``) is the closed union of the particles'
cells; :func:`~mlsgalerkin.fluid.distribution.cell_volumes` splits it among the particles (each
pixel to the nearest one). This script reads the frames of finished runs (the particle positions
and densities; the masses from the run's last checkpoint) and sorts the fluid particles by the
number of others within 1.5 spacings (a particle inside a square lattice has 8, one in a flat free
surface 5):

- **drops**: none;
- **sheets and ragged surface**: 1 to 4 (a chain, a tip, a corner, a surface torn open);
- **surface rows and bulk**: 5 or more.

For each class, averaged over the frames after the first impact: its share of the particles, and
its *contribution* ``Σ_class (v_i − M_i/ρ_i) / Σ M/ρ`` to the volume error (the contributions add
up to the error). If a class's excess per particle stays the same as the spacing falls while its
share of the particles falls like the spacing (a surface's share of a body), the error is a first-
order resolution error of that class, not a drift.

``python verification/volume_attribution.py`` reads the ``beam_clamped`` and ``beam_on_spring``
runs that ``verification/structure_validation.py`` leaves in ``results/structure_runs`` (a run
missing is skipped and said so) and writes
``verification/results/volume_consistency/attribution.{md,csv,png}`` (about a minute).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from mlsgalerkin.fluid.distribution import (
    AT_FLOOR,
    NEIGHBOUR_CLASSES,
    NEIGHBOURHOOD_REACH,
    cell_volumes,
    neighbourhood_excess,
    volume_error_by_class,
)
from mlsgalerkin.io import atomic_write, csv_text, format_cell, provenance, read_pvd, read_vtu
from mlsgalerkin.io.checkpoint import latest_checkpoint, load_checkpoint

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from verification.report_format import produced_by

#: The runs read by default: (label, run directory under --runs, the time of the first impact (s)).
RUNS = (
    ("beam_clamped 4 mm (default)", "beam_clamped_dx_4mm", 0.28),
    ("beam_clamped 2.5 mm", "beam_clamped_dx_2.5mm", 0.28),
    ("beam_clamped 2 mm", "beam_clamped_dx_2mm", 0.28),
    ("beam_on_spring 15 mm (default)", "beam_on_spring_dx_15mm", 0.59),
    ("beam_on_spring 7.5 mm", "beam_on_spring_dx_7.5mm", 0.59),
)
#: Neighbour counts within :data:`REACH` spacings of each class (inclusive bounds): the package's.
CLASSES = NEIGHBOUR_CLASSES
REACH = NEIGHBOURHOOD_REACH
#: The particles at the cavitation floor (``p ≤ 0``): their density is ``ρ0`` and cannot fall.
FLOOR = AT_FLOOR
#: The settled state: the frames of the run's last this many seconds.
SETTLED = 1.0


def frame_attribution(x: np.ndarray, volume: np.ndarray, spacing: float,
                      shares: np.ndarray | None = None, floor: np.ndarray | None = None) -> dict[str, float]:
    """The volume error of one frame and each class's share of the particles and contribution to
    it (fractions). ``x (n, d)`` fluid positions (m), ``volume (n,)`` their ``M/ρ`` (m^d),
    ``shares (n,)`` their :func:`cell_volumes` (m^d; computed when not given). With ``floor``
    (bool ``(n,)``: the particles at the cavitation floor, ``p ≤ 0``), also the share and the
    contribution of those: no density relaxation can give them volume
    (:func:`~mlsgalerkin.fluid.distribution.volume_error_by_class`, flattened into the table's columns)."""
    split = volume_error_by_class(x, volume, spacing, at_floor=floor, shares=shares)
    row = {"volume_error": split["volume_error"]}
    for name, _, _ in CLASSES:
        for what in ("particles", "contribution", "excess_per_particle"):
            row[f"{name}: {what.replace('_', ' ')}"] = split[name][what]
    if floor is not None:
        row[f"{FLOOR}: particles"] = split[FLOOR]["particles"]
        row[f"{FLOOR}: contribution"] = split[FLOOR]["contribution"]
    return row


def run_attribution(run: Path, after: float) -> tuple[dict, tuple[np.ndarray, np.ndarray, float] | None]:
    """Mean and largest over the frames after ``after`` (s) of :func:`frame_attribution`, the mean
    error and the loose class's contribution over the last :data:`SETTLED` seconds (the water at
    rest again), and the positions and :func:`~mlsgalerkin.fluid.distribution.neighbourhood_excess` of the frame of the largest error."""
    summary = json.loads((run / "summary.json").read_text())
    spacing = float(summary["parameters"]["dx"])
    arrays, _ = load_checkpoint(latest_checkpoint(run / "checkpoints"))
    mass = arrays["fluid__M"]
    rows, times, worst, worst_error, worst_row = [], [], None, -np.inf, {}
    for t, path in read_pvd(run / "particles.pvd"):
        if t < after:
            continue
        times.append(t)
        points, data = read_vtu(path)
        fluid = np.asarray(data["is_wall"]) == 0
        if "outside" in data:                       # particles taken out of the run, as the run's own measure
            fluid &= np.asarray(data["outside"]) == 0
        x = np.ascontiguousarray(points[fluid, :2])
        volume = mass[fluid] / np.asarray(data["density"])[fluid]
        shares = cell_volumes(x, spacing)
        row = frame_attribution(x, volume, spacing, shares, np.asarray(data["pressure"])[fluid] <= 0.0)
        rows.append(row)
        if row["volume_error"] > worst_error:
            worst_error = row["volume_error"]
            worst = (x, neighbourhood_excess(x, shares, volume, spacing, REACH), t)
            worst_row = row
    keys = rows[0].keys()
    series = np.genfromtxt(run / "timeseries.csv", delimiter=",", names=True)
    out = {"spacing_mm": 1e3 * spacing, "frames": len(rows), "after_s": after,
           "run_commit": summary.get("provenance", {}).get("git_commit", ""),
           "largest_sample_error": float(np.nanmax(series["volume_error"])),
           "largest_frame_error": max(r["volume_error"] for r in rows),
           "largest frame: time_s": worst[2],
           f"largest frame: {FLOOR} contribution": worst_row[f"{FLOOR}: contribution"]}
    out.update({k: float(np.nanmean([r[k] for r in rows])) for k in keys})   # a frame without drops has no per-particle excess for them
    last = [r for t, r in zip(times, rows) if t >= times[-1] - SETTLED]
    out["last second: volume_error"] = float(np.mean([r["volume_error"] for r in last]))
    out["last second: sheets and ragged surface contribution"] = float(
        np.mean([r["sheets and ragged surface: contribution"] for r in last]))
    return out, worst


INTRO = ("Each fluid particle's share of the geometric volume (`mlsgalerkin.fluid.distribution.cell_volumes`: "
         "each pixel of the closed union of the cells to the nearest particle) against its own volume M/ρ. "
         "Classes by the number of other particles within 1.5 spacings (8 inside a square lattice, 5 in a flat "
         "free surface): drops (none), sheets and ragged surface (1 to 4), surface rows and bulk (5 or more). "
         "For each: its share of the particles, its contribution Σ (v − M/ρ) / Σ M/ρ to the volume error, and "
         "the mean of (v − M/ρ)/(M/ρ) over its particles. Across the classes, the particles at the cavitation "
         "floor (p ≤ 0: their density is ρ0 and cannot fall, so no density relaxation gives them volume): their "
         "share and contribution, on average and at the frame of the largest error.")
COLUMNS = ["case", "spacing_mm", "run_commit", "frames", "after_s", "largest_sample_error", "largest_frame_error",
           "largest frame: time_s", f"largest frame: {FLOOR} contribution", "volume_error"] + [
    f"{name}: {what}" for name, _, _ in CLASSES for what in ("particles", "contribution", "excess per particle")] + [
    f"{FLOOR}: particles", f"{FLOOR}: contribution",
    "last second: volume_error", "last second: sheets and ragged surface contribution"]


def plot(out: Path, worst: dict[str, tuple]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = [c for c in worst if worst[c] is not None]
    rows = (len(cases) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(12.0, 3.0 * rows), squeeze=False, layout="constrained")
    for ax in axes.ravel()[len(cases):]:
        ax.set_visible(False)
    for ax, case in zip(axes.ravel(), cases):
        x, excess, t = worst[case]
        lo, hi = np.percentile(x, 0.5, axis=0), np.percentile(x, 99.5, axis=0)
        pad = 0.05 * (hi - lo)
        sc = ax.scatter(x[:, 0], x[:, 1], c=excess, s=max(1.0, 4000.0 / len(x)), cmap="RdBu_r", vmin=-0.2, vmax=0.2)
        ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])
        ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])
        ax.set_aspect("equal")
        ax.set_title(f"{case}: t = {t:.2f} s, the frame of the largest error", fontsize=9)
    fig.colorbar(sc, ax=axes.ravel().tolist(), shrink=0.6,
                 label="geometric volume over M/ρ − 1\n(a particle and its neighbours)")
    fig.savefig(out / "attribution.png", dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default="results/structure_runs", help="where the run directories are")
    ap.add_argument("--out", default="verification/results/volume_consistency")
    args = ap.parse_args(argv)
    out, runs = Path(args.out), Path(args.runs)
    out.mkdir(parents=True, exist_ok=True)
    rows, worst, skipped = [], {}, []
    for case, name, after in RUNS:
        run = runs / name
        if not (run / "summary.json").is_file():
            skipped.append(case)
            print(f"  {case}: no finished run in {run}; skipped", flush=True)
            continue
        start = time.perf_counter()
        row, worst[case] = run_attribution(run, after)
        row["case"] = case
        rows.append(row)
        print(f"  {case}: volume error {row['volume_error']:+.4f} on average over {row['frames']} frames "
              f"({time.perf_counter() - start:.0f} s)", flush=True)
    if not rows:
        print("no runs to read: run verification/structure_validation.py --section clamped (or spring) first")
        return 1
    atomic_write(out / "attribution.csv", csv_text(COLUMNS, [[format_cell(r.get(k, "")) for k in COLUMNS]
                                                            for r in rows]))
    lines = ["# Where the splashing flows' volume error sits", "", INTRO, "",
             "Averages over the frames (every 0.05 s) after the first impact (`after_s`); the error, the "
             "contributions (they add up to it) and the excess per particle as fractions. `largest_sample_error`: "
             "the run's time series (every probe interval), the summary's number; `largest_frame_error`: the "
             "frames'." +
             (f" Not read (no run at hand): {', '.join(skipped)}." if skipped else ""), "",
             "| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(format_cell(r.get(k, "")) for k in COLUMNS) + " |" for r in rows]
    lines += ["", "![each particle's excess at the frame of the largest error](attribution.png)", "",
              produced_by(provenance("volume_consistency/attribution"))]
    atomic_write(out / "attribution.md", "\n".join(lines) + "\n")
    plot(out, {k: worst[k] for k in worst})
    return 0


if __name__ == "__main__":
    sys.exit(main())
