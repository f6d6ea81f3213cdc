"""Make the gallery: one picture per shipped problem, ``docs/gallery/*.png`` and ``docs/gallery.md``.

Usage (from the repository's root)::

    python docs/make_gallery.py               # run every problem, draw, write the page
    python docs/make_gallery.py --only dam_break
    python docs/make_gallery.py --dry-run     # rewrite the page from docs/gallery/gallery.json
    python docs/make_gallery.py --runs results/gallery_runs   # keep the run directories ...
    python docs/make_gallery.py --runs results/gallery_runs --redraw   # ... and redraw from them

Each problem runs at a small size up to its interesting moment (the dam break's surge, the
gravity current's head, the drop's crown, the waves in the tank) in a temporary directory,
and its last frame is drawn with :func:`mlsgalerkin.plots.render_frame` — the picture
``mlsgalerkin render RUN_DIR --color-by FIELD`` writes as ``final.png`` (the page gives both
commands). What was run (parameters, particles, steps, wall time, the problem's headline
result, commit and date) is kept in ``docs/gallery/gallery.json``; the page is built from that
file alone. About a minute and a half on two cores.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

DOCS = Path(__file__).resolve().parent
PROBLEMS = DOCS.parent / "problems"  # this checkout's problems, whatever is installed
IMAGES = DOCS / "gallery"
PAGE = DOCS / "gallery.md"
META = IMAGES / "gallery.json"
COMMAND = "python docs/make_gallery.py"
MAX_BYTES = 200_000

__all__ = ["ENTRIES", "Entry", "build_page", "draw_entry", "main", "run_command", "run_entry"]


@dataclass(frozen=True)
class Entry:
    """One picture: the problem, its parameters (``--set`` names), the colour field, the title
    and what the picture shows (a sentence for the caption)."""

    problem: str
    parameters: dict = field(default_factory=dict)
    color_by: str = "pressure"
    title: str = ""
    shows: str = ""


ENTRIES: tuple[Entry, ...] = (
    Entry("hydrostatic", {"dx": 0.01, "t_end": 1.0, "frame_every": 1.0}, "pressure",
          "Hydrostatic tank",
          "Water at rest in a tank after one second: the pressure grows linearly with depth, "
          "from zero at the free surface to ρ g H ≈ 3.9 kPa at the floor (H = 0.4 m), the state "
          "the problem checks against p = ρ0 g (H − y)."),
    Entry("dam_break", {"t_end": 0.16, "frame_every": 0.16}, "speed",
          "Dam break",
          "The collapsing water column of Martin & Moyce (1952) (a = 57 mm wide, 2a = 114 mm "
          "high) at T = t √(2g/a) ≈ 3, the end of their measurements: the surge runs along the "
          "floor, fastest at its tip (about 1.5 m/s), about 0.23 m (Z = z/a ≈ 4) from the left "
          "wall, while the water at the wall has fallen to less than half the column's height."),
    Entry("dam_break_impact", {"dx": 0.03, "t_end": 1.385, "frame_every": 1.385}, "pressure",
          "Dam break with wall impact",
          "The 0.6 m column of Zhou et al. (1999) at T = t √(g/H) = 5.6, after the surge has hit the "
          "end wall and run up it (H/Δx = 20): the run-up falls back as a plunging jet that is about "
          "to re-enter the flow and close an air cavity; the pressure at the foot of the wall is "
          "what the sensors P1–P4 read."),
    Entry("gravity_current", {"dx": 0.003, "t_end": 0.5, "frame_every": 0.5}, "density",
          "Gravity current (lock exchange)",
          "Lock exchange of Cueto-Felgueroso et al. (2005) half a second after the lock (at "
          "x = 0.17 m) was lifted: the heavy fluid (1500 kg/m³) runs under the light one "
          "(1000 kg/m³) towards the left wall, with the raised head at its front, and the light "
          "fluid runs over it to the right under the lid."),
    Entry("stratified_rest", {"t_end": 1.0, "frame_every": 1.0, "alpha": 0.1}, "speed",
          "Two-layer tank at rest",
          "Fresh water (1000 kg/m³) over salt water (1030 kg/m³), 6 cm deep under a lid, one "
          "second after a hydrostatic start (α = 0.1, consistent nodal integration): the speeds "
          "that remain are the solver's noise, a tenth of a millimetre per second against the "
          "internal-wave speed √(g′D) = 13 cm/s."),
    Entry("drop_impact", {"t_end": 0.03}, "speed",
          "Drop impact",
          "A drop 20 mm across hitting still liquid at 2 m/s (Cueto-Felgueroso et al. 2005; "
          "viscosity 0.5 Pa s), 30 ms after the start: the drop has sunk into the pool and "
          "pushed up a crown around the crater."),
    Entry("wave_maker", {"dx": 0.0125, "t_end": 3.0, "frame_every": 3.0, "tank_length": 2.0}, "velocity_x",
          "Piston wave maker",
          "Waves made by a piston paddle at the left (stroke 2 cm, period 1 s, depth 0.2 m) in a "
          "2 m tank, three seconds after the start: the horizontal velocity alternates under "
          "crests (to the right) and troughs (to the left), one wavelength ≈ 1.2 m; the wave "
          "front has nearly reached the far wall."),
    Entry("hydrostatic_plate", {"dx": 0.05, "t_end": 0.1, "frame_every": 0.1}, "pressure",
          "Plate under a water column",
          "Two metres of water on an aluminium plate 1 m long and 5 cm thick, clamped at both ends "
          "(O'Connor & Rogers 2021), 0.1 s after a hydrostatic start: the pressure reaches ρ g H ≈ 20 kPa "
          "at the plate (dark blue points: its finite-element nodes), which sags by 0.07 mm, too little to "
          "see here; the problem checks the mean mid-span deflection against plate theory."),
    Entry("elastic_gate", {"dx": 0.002, "t_end": 0.16, "frame_every": 0.16}, "speed",
          "Dam break through an elastic gate",
          "The rubber gate of Antoci et al. (2007), clamped at its top, 0.16 s after the water (0.14 m "
          "deep) was let against it: the gate (dark blue: its finite-element nodes, neo-Hookean) is "
          "bent open by about 5 cm and the water jets out under its free end along the floor."),
    Entry("wedge_drop", {"dx": 0.01, "t_end": 0.015, "frame_every": 0.015}, "pressure",
          "Wedge water entry",
          "A rigid 30° wedge of 241 kg per metre (Zhao, Faltinsen & Aarsnes 1996) 15 ms after its keel "
          "touched the water at 6.15 m/s, at the moment of peak force: the pressure is highest where "
          "the water turns up along the wedge's faces, and jets leave at the knuckles."),
    Entry("beam_clamped", {"dx": 0.004, "t_end": 0.4, "frame_every": 0.4}, "pressure",
          "Dam break on a clamped elastic beam",
          "A 0.2 m water column (left) has collapsed and run up the steel-like beam clamped at the "
          "floor 0.35 m away (Sun 2016), 0.4 s after release: the water thrown up the beam falls back "
          "while the beam, bent by about 1 cm at its tip, swings with its first period, about 0.6 s."),
    Entry("beam_on_spring", {"dx": 0.02, "t_end": 1.2, "frame_every": 1.2}, "pressure",
          "Dam break on a spring-supported beam",
          "The tank of the dam break with wall impact, whose end wall is a 2 m rigid beam of 1 kg on a "
          "hinge with a rotational spring (Sun 2016), 1.2 s after the column was released: the surge "
          "has run up the beam and turned it several degrees outward."),
    Entry("taylor_green", {"dx": 0.03125, "t_end": 0.5, "frame_every": 0.5}, "speed",
          "Taylor–Green vortex",
          "The doubly periodic array of vortices at Re = 100 (box side 1 m, U = 1 m/s, 32 × 32 "
          "particles), half a second after the start: the four vortices keep their shape while their "
          "speed decays under the viscosity; particles crossing the box's edges re-enter on the other "
          "side."),
    Entry("poiseuille", {"dx": 0.05, "t_end": 5.0, "frame_every": 5.0}, "velocity_x",
          "Plane Poiseuille flow",
          "A body force drives the fluid between two no-slip walls (three layers of wall particles "
          "each), periodic along the channel, at Re = 10, five seconds after the start from rest: the "
          "velocity has grown to the parabolic profile, fastest at the centre line."),
    Entry("couette", {"dx": 0.05, "t_end": 5.0, "frame_every": 5.0}, "velocity_x",
          "Plane Couette flow",
          "The top wall slides to the right at 1 m/s over fluid between two no-slip walls, periodic "
          "along the channel, at Re = 10, five seconds after the start from rest: the velocity has "
          "grown to the linear profile, from rest at the floor to the wall's speed under the lid."),
)


def run_command(entry: Entry, run_dir: str | None = None) -> str:
    """The two shell commands that reproduce the picture of ``entry``."""
    out = run_dir or f"results/{entry.problem}"
    sets = []
    for k, v in entry.parameters.items():
        if k == "dx":
            sets.append(f"--dx {v:g}")
        elif k == "t_end":
            sets.append(f"--t-end {v:g}")
        else:
            sets.append(f"--set {k}={v:g}" if isinstance(v, float) else f"--set {k}={v}")
    return (f"mlsgalerkin run {entry.problem} {' '.join(sets)} --no-gif --out {out}\n"
            f"mlsgalerkin render {out} --color-by {entry.color_by} --no-gif --snapshots 0")


def run_entry(entry: Entry, run_dir: Path) -> float:
    """Run ``entry``'s problem (this checkout's ``problems/``) into ``run_dir``; returns the
    wall time (s)."""
    from mlsgalerkin.problem import run_problem

    overrides = dict(entry.parameters)
    overrides["gif"] = False
    if run_dir.exists():  # a fresh run, not a continuation of an older one
        shutil.rmtree(run_dir)
    t0 = time.perf_counter()
    run_problem(PROBLEMS / f"{entry.problem}.py", overrides, out=run_dir, progress=False)
    return time.perf_counter() - t0


def draw_entry(entry: Entry, run_dir: Path, images: Path = IMAGES) -> dict:
    """Draw the last frame of the run in ``run_dir`` to ``images/PROBLEM.png``; returns the record
    kept in ``gallery.json`` (with the particles, steps, wall time and headline of the run's
    ``summary.json``)."""
    from mlsgalerkin.plots import render_frame

    t0 = time.perf_counter()
    png = images / f"{entry.problem}.png"
    _, t_frame = render_frame(run_dir, png, color_by=entry.color_by, title=entry.title, width=8.0, dpi=110)
    s = json.loads((run_dir / "summary.json").read_text(encoding="utf-8"))
    particles = s.get("fluid", {}).get("particles", {})
    record = {
        "problem": entry.problem, "title": entry.title, "image": f"gallery/{png.name}",
        "parameters": entry.parameters, "color_by": entry.color_by, "shows": entry.shows,
        "frame_time_s": t_frame, "fluid_particles": particles.get("fluid"), "wall_particles": particles.get("wall"),
        "steps": s.get("steps"), "run_wall_time_s": round(float(s.get("wall_time_s", float("nan"))), 2),
        "picture_wall_time_s": round(time.perf_counter() - t0, 2),
        "headline": (s.get("results") or {}).get("headline", ""), "png_bytes": png.stat().st_size,
    }
    if record["png_bytes"] > MAX_BYTES:
        logging.getLogger(__name__).warning("%s is %d bytes (> %d)", png, record["png_bytes"], MAX_BYTES)
    return record


def _describe(problem: str) -> str:
    from mlsgalerkin.problem import load_problem

    doc = (load_problem(PROBLEMS / f"{problem}.py").__doc__ or "").strip().splitlines()
    return doc[0].rstrip(".").replace("``", "`") if doc else problem  # reST to Markdown code


def build_page(meta: dict) -> str:
    """The Markdown of ``docs/gallery.md`` from the records of ``gallery.json`` (one section per
    record, in the order of :data:`ENTRIES`)."""
    from mlsgalerkin.plots.fields import FIELDS

    order = {e.problem: k for k, e in enumerate(ENTRIES)}
    records = sorted(meta["entries"].values(), key=lambda r: order.get(r["problem"], len(order)))
    prov = meta.get("provenance", {})
    lines = [
        "# Gallery",
        "",
        "One picture per shipped problem (`mlsgalerkin problems` lists them), each run at a small size up",
        "to its interesting moment. Every picture shows the particles at one instant: positions in metres,",
        "the time in seconds at the top right, the fluid coloured by the field named on the colour bar",
        "(with its unit), and the **wall particles in grey** (smaller, never coloured: their values are",
        "extrapolated from the fluid); a structure's finite-element or surface nodes are small dark blue",
        "points. Each caption gives the parameters that differ from the problem's",
        "defaults and the two commands that redraw the picture (`final.png` in the run directory); the",
        "problem modules' docstrings (`problems/*.py`) describe the physics and the checks.",
        "",
        (f"Generated by `{prov.get('command', COMMAND)}` at commit `{prov.get('git_commit', 'unknown')}` on "
         f"{prov.get('date_utc', 'unknown date')} ({prov.get('total_wall_time_s', '?')} s on "
         f"{prov.get('cpu_count', '?')} cores); the records are in "
         "[gallery/gallery.json](gallery/gallery.json)."),
        "",
    ]
    for r in records:
        style = FIELDS.get(r["color_by"])
        colour = (f"{style.axis_label}: {style.description}" if style else r["color_by"])
        params = ", ".join(f"`{k} = {v:g}`" if isinstance(v, float) else f"`{k} = {v}`"
                           for k, v in r["parameters"].items())
        entry = next((e for e in ENTRIES if e.problem == r["problem"]), Entry(r["problem"], r["parameters"],
                                                                              r["color_by"]))
        lines += [
            f"## {r['title'] or r['problem']}",
            "",
            f"![{r['title']}: {colour.split(':')[0]} at t = {r['frame_time_s']:.4g} s]({r['image']})",
            "",
            f"*{_describe(r['problem'])}* (`{r['problem']}`). {r['shows']}",
            "",
            f"- **Colour:** {colour}. Grey: wall particles.",
            (f"- **Shown:** t = {r['frame_time_s']:.4g} s; {r['fluid_particles']} fluid and "
             f"{r['wall_particles']} wall particles, {r['steps']} time steps ({r['run_wall_time_s']:.1f} s of "
             "wall-clock time)."),
            f"- **Parameters** (others at their defaults): {params}.",
        ]
        if r.get("headline"):
            lines.append(f"- **The problem's analysis of this short run:** {r['headline']}.")
        lines += ["- **Commands:**", "", "  ```bash"]
        lines += [f"  {c}" for c in run_command(entry).splitlines()]
        lines += ["  ```", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    from mlsgalerkin.io import atomic_write, git_commit, write_json

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", metavar="PROBLEM", help="regenerate only these pictures")
    parser.add_argument("--dry-run", action="store_true", help="run nothing; rewrite the page from gallery.json")
    parser.add_argument("--runs", metavar="DIR", help="keep the run directories in DIR/PROBLEM (default: a "
                                                      "temporary directory, removed at the end)")
    parser.add_argument("--redraw", action="store_true", help="run nothing; redraw the pictures from the run "
                                                               "directories kept in --runs")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    known = {e.problem for e in ENTRIES}
    unknown = sorted(set(args.only or ()) - known)
    if unknown:
        print(f"error: no gallery entry for {unknown}; choose from {sorted(known)}", file=sys.stderr)
        return 2
    if args.redraw and not args.runs:
        print("error: --redraw needs --runs DIR (the run directories of an earlier --runs DIR)", file=sys.stderr)
        return 2
    meta = json.loads(META.read_text(encoding="utf-8")) if META.is_file() else {"entries": {}}
    if not args.dry_run:
        IMAGES.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="gallery_") as tmp:
            runs = Path(args.runs) if args.runs else Path(tmp)
            for entry in ENTRIES:
                if args.only and entry.problem not in args.only:
                    continue
                run_dir = runs / entry.problem
                print(f"{entry.problem} ...", flush=True)
                if not args.redraw:
                    run_entry(entry, run_dir)
                rec = draw_entry(entry, run_dir)
                meta["entries"][entry.problem] = rec
                print(f"  {rec['fluid_particles']} fluid particles, {rec['steps']} steps, run "
                      f"{rec['run_wall_time_s']} s, picture {rec['picture_wall_time_s']} s, "
                      f"{rec['png_bytes'] / 1000:.0f} kB", flush=True)
        if not args.redraw:
            meta["provenance"] = {
                "command": COMMAND + (f" --only {' '.join(args.only)}" if args.only else ""),
                "git_commit": git_commit(), "date_utc": datetime.now(UTC).isoformat(timespec="seconds"),
                "total_wall_time_s": round(time.perf_counter() - t0, 1), "cpu_count": os.cpu_count(),
            }
        write_json(META, meta)
    missing = sorted(set(known) - set(meta["entries"]))
    if missing:
        print(f"error: {META} has no record of {missing}; run without --dry-run", file=sys.stderr)
        return 2
    atomic_write(PAGE, build_page(meta))
    print(f"wrote {PAGE.relative_to(DOCS.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
