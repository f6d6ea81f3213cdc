"""Command line: ``mlsgalerkin kernels | run PROBLEM|FILE.py | problems | render RUN_DIR | study kernels | study galerkin``.

Also ``python -m mlsgalerkin ...`` and ``mlsgalerkin --version``. Library code logs; this module
prints.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

__all__ = ["main"]


def _cmd_kernels(args: argparse.Namespace) -> int:
    from mlsgalerkin.kernels import KERNELS

    header = f"{'name':<18} {'support':>7}  {'alpha_1':>9} {'alpha_2':>9} {'alpha_3':>9}  {'W>=0':<4}  smoothness"
    print(header)
    print("-" * len(header))
    for k in KERNELS.values():
        a1, a2, a3 = k.alpha
        print(
            f"{k.name:<18} {k.support:>7.2f}  {a1:>9.5f} {a2:>9.5f} {a3:>9.5f}  "
            f"{'yes' if k.nonnegative else 'no':<4}  {k.smoothness}"
        )
    print("\nW(r, h) = alpha_d / h^d * f(r/h), zero for r >= support * h.")
    return 0


def _run_study(run, args: argparse.Namespace) -> int:
    from mlsgalerkin.studies.engine import GridError, MeasurementError, SchedulerError

    if not args.verbose:  # Dask logs every cluster start and stop at INFO
        import distributed  # noqa: F401  (importing it sets its loggers' levels)

        logging.getLogger("distributed").setLevel(logging.WARNING)
    try:
        result = run(out=args.out, quick=args.quick, scheduler=args.scheduler,
                     progress=not args.no_progress)
    except (SchedulerError, GridError, MeasurementError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(result.report())
    print("full report (summary.md, all figures): python verification/"
          f"{args.report_script} --out DIR (in a clone of the repository)")
    return 0


def _cmd_study_kernels(args: argparse.Namespace) -> int:
    from mlsgalerkin.studies.kernels import run_kernel_study

    return _run_study(run_kernel_study, args)


def _cmd_study_galerkin(args: argparse.Namespace) -> int:
    from mlsgalerkin.studies.galerkin import run_galerkin_study

    return _run_study(run_galerkin_study, args)


def _parse_sets(items: list[str]) -> dict[str, str]:
    out = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"--set expects NAME=VALUE, got {item!r}")
        k, v = item.split("=", 1)
        out[k.strip().replace("-", "_")] = v.strip()
    return out


def _cmd_problems(args: argparse.Namespace) -> int:
    import dataclasses

    from mlsgalerkin.problem import load_problem, shipped_problems

    for name in shipped_problems():
        mod = load_problem(name)
        print(f"{name}: {(mod.__doc__ or '').strip().splitlines()[0]}")
        for f in dataclasses.fields(mod.Parameters):
            print(f"    {f.name:<20} = {f.default!r}")
    print("\nRun one with `mlsgalerkin run NAME`, or your own problem file with `mlsgalerkin run my_case.py`.")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from mlsgalerkin.problem import run_problem
    from mlsgalerkin.scene import SceneError
    from mlsgalerkin.simulation import SimulationDiverged

    overrides = _parse_sets(args.set or [])
    if args.dx is not None:
        overrides["dx"] = args.dx
    if args.t_end is not None:
        overrides["t_end"] = args.t_end
    if args.no_gif:
        overrides["gif"] = "false"
    name = Path(args.problem).stem if args.problem.endswith(".py") else args.problem
    out = Path(args.out or f"results/{name}")
    try:
        result, results = run_problem(args.problem, overrides, out=out, progress=not args.no_progress,
                                      restart="latest" if args.restart else None)
    except (ValueError, SceneError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except SimulationDiverged as err:
        print(f"error: {err}", file=sys.stderr)
        print(f"the run's summary (with the diagnosis) is in {out / 'summary.json'}", file=sys.stderr)
        return 3
    s = result.summary
    fluid = s.get("fluid", {})
    particles = fluid.get("particles", {})
    rate = s.get("particle_steps_per_s")
    print(f"{name}: {particles.get('total', '?')} particles ({particles.get('fluid', '?')} fluid), "
          f"{s['steps_this_run']} steps to t = {s['t_end_s']:.4g} s in {s['wall_time_s']:.1f} s"
          + (f" ({rate:.3g} particle-steps/s)" if rate else ""))
    if results:
        print(results.get("headline", json.dumps(results)))
    print(f"output: {out}/ (timeseries.csv, particles.pvd, summary.json"
          + (", animation.gif" if (out / "animation.gif").exists() else "") + ")")
    return 0


def _cmd_render(args: argparse.Namespace) -> int:
    from mlsgalerkin.io.render_run import RenderError, inspect_run, render_run

    if args.snapshots < 0:
        print(f"error: --snapshots must be 0 or more, got {args.snapshots}", file=sys.stderr)
        return 2
    if not (args.fps > 0):
        print(f"error: --fps must be positive, got {args.fps}", file=sys.stderr)
        return 2
    frames_wanted = args.gif or args.png
    try:
        contents = inspect_run(args.run_dir, color_by=args.color_by if frames_wanted else None,
                               need_frames=frames_wanted, need_timeseries=not frames_wanted)
        written = render_run(args.run_dir, color_by=args.color_by, out=args.out, gif=args.gif, png=args.png,
                             snapshots=args.snapshots if args.png else 0,
                             timeseries=contents.timeseries is not None, fps=args.fps)
    except (RenderError, ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    state = contents.status or "no summary.json: unfinished or interrupted"
    print(f"{contents.title} ({state}): {len(contents.frames)} frames"
          + (f", coloured by {args.color_by}" if frames_wanted else ""))
    if contents.timeseries is None:
        print(f"no {contents.directory / 'timeseries.csv'}: no time-series plot")
    for path in written:
        print(f"wrote {path}")
    return 0


def _version() -> str:
    from mlsgalerkin import __version__

    return __version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mlsgalerkin",
        description="Meshfree Galerkin mechanics: kernels, MLS/RKPM shape functions, studies.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("kernels", help="list the kernels with support, constants and smoothness")
    p.set_defaults(func=_cmd_kernels)

    p = sub.add_parser("problems", help="list the runnable problems and their parameters")
    p.set_defaults(func=_cmd_problems)

    p = sub.add_parser("run", help="run a problem: mlsgalerkin run gravity_current --set depth=0.1 --dx 0.002")
    p.add_argument("problem", help="a shipped problem (see `mlsgalerkin problems`) or the path of your own "
                                   "problem file, e.g. my_case.py")
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a problem parameter (repeatable)")
    p.add_argument("--dx", type=float, help="particle spacing (m)")
    p.add_argument("--t-end", type=float, help="end time (s)")
    p.add_argument("--out", help="run directory (default results/PROBLEM)")
    p.add_argument("--restart", action="store_true", help="continue from the latest checkpoint in --out")
    p.add_argument("--no-gif", action="store_true", help="skip the animation")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("render", help="draw the pictures of a finished or interrupted run: frames, animation, "
                                      "time-series plots",
                       description="Draw the pictures of a run directory from its files (particles.pvd, "
                                   "particles_*.vtu, timeseries.csv; summary.json is not needed): final.png, a "
                                   "panel of frames (frames.png), animation.gif and timeseries.png.")
    p.add_argument("run_dir", help="the run directory (the --out of `mlsgalerkin run`, default results/PROBLEM)")
    p.add_argument("--color-by", default="pressure", metavar="FIELD",
                   help="colour field: pressure, density, density_ratio, speed, velocity, velocity_x, "
                        "velocity_y, phase, mls_order, free_surface, ... (default: %(default)s)")
    p.add_argument("--gif", action=argparse.BooleanOptionalAction, default=True,
                   help="animation.gif of every frame (default: on)")
    p.add_argument("--png", action=argparse.BooleanOptionalAction, default=True,
                   help="final.png and the panel frames.png (default: on)")
    p.add_argument("--snapshots", type=int, default=4, metavar="N",
                   help="frames in the panel frames.png, spread over the run; 0: no panel (default: %(default)s)")
    p.add_argument("--fps", type=float, default=8.0, help="frames per second of the animation (default: %(default)s)")
    p.add_argument("--out", metavar="DIR", help="where to write the pictures (default: the run directory)")
    p.set_defaults(func=_cmd_render)

    study = sub.add_parser("study", help="run a shipped study on the study engine (Dask)")
    studies = study.add_subparsers(dest="study", required=True)
    for name, help_text, quick_help, func, script in (
        ("kernels", "kernel x smoothing-length accuracy study (errors, wall times, fits)",
         "small sweep (< 30 s)", _cmd_study_kernels, "kernel_study.py"),
        ("galerkin", "Galerkin convergence study: patch tests, orders, h-sweep, work-precision",
         "three-level subset (< 60 s)", _cmd_study_galerkin, "galerkin_convergence.py"),
    ):
        p = studies.add_parser(name, help=help_text)
        p.add_argument("--quick", action="store_true", help=quick_help)
        p.add_argument("--out", default=f"results/{script.removesuffix('.py')}",
                       help="output directory (default: %(default)s)")
        p.add_argument("--scheduler", metavar="ADDRESS",
                       help="Dask scheduler to fan out to (tcp://host:port), or 'serial' "
                            "(default: a local cluster, one worker per core)")
        p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
        p.set_defaults(func=func, report_script=script)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
