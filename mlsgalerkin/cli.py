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
    except (SchedulerError, GridError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except MeasurementError as err:
        where, _, worker_traceback = str(err).partition("\n--- traceback on the worker ---\n")
        print(f"error: {where}" + (" (run with -v for the worker's traceback)" if worker_traceback and not args.verbose
                                   else ""), file=sys.stderr)
        if worker_traceback and args.verbose:
            print(worker_traceback, file=sys.stderr, end="")
        return 3
    except BrokenPipeError:
        raise  # the reader of our output went away: main() ends quietly
    except OSError as err:
        print(f"error: the study could not write its files in {args.out}: {_os_error_text(err)}. Choose a "
              "writable directory with --out", file=sys.stderr)
        return 4
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
    """``--set NAME=VALUE`` items as a dict; a malformed or repeated item is a ValueError."""
    out = {}
    for item in items:
        k, sep, v = item.partition("=")
        k = k.strip().replace("-", "_")
        if not sep or not k:
            raise ValueError(f"--set expects NAME=VALUE, got {item!r}")
        if k in out:
            raise ValueError(f"--set {k} is given twice ({out[k]!r} and {v.strip()!r}); give it once")
        out[k] = v.strip()
    return out


#: Width of a problem's description in ``mlsgalerkin problems`` (its table is 100 wide, indented by 4).
_DESCRIPTION_WIDTH = 96


def _cmd_problems(args: argparse.Namespace) -> int:
    import textwrap

    from mlsgalerkin.problem import (
        ProblemError,
        load_problem,
        parameter_table,
        problem_description,
        problem_notes,
        shipped_problems,
    )

    try:
        names = [args.problem] if args.problem else list(shipped_problems())
        chosen = [(name, load_problem(name)) for name in names]
    except ProblemError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    for k, (name, mod) in enumerate(chosen):
        # The description wraps at a fixed width of its own, so where the lines break does not depend
        # on the name (a problem file's path is as long as the directory it lives in).
        first, *rest = textwrap.wrap(problem_description(mod), _DESCRIPTION_WIDTH) or [""]
        print(("\n" if k else "") + f"{name}: {first}".rstrip())
        for line in rest:
            print(f"    {line}")
        print(textwrap.indent(parameter_table(mod.Parameters, width=96), "    "))
    if args.problem:
        notes = problem_notes(chosen[0][1])
        if notes:   # what it models, its reference and the configuration its numbers were measured in
            print("\n" + textwrap.indent(notes, "    "))
        copy = " (copy it to start your own case)" if args.problem in shipped_problems() else ""
        print(f"\nfile: {chosen[0][1].__file__}{copy}")
        print(f"Run it with `mlsgalerkin run {args.problem} --set PARAMETER=VALUE`.")
    else:
        print("\nRun one with `mlsgalerkin run NAME --set PARAMETER=VALUE`, your own problem file with\n"
              "`mlsgalerkin run my_case.py`; `mlsgalerkin problems NAME` shows one problem and its file.")
    return 0


def _positive_seconds(text: str) -> float:
    """An argparse type: a finite number of seconds > 0."""
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: give a positive, finite number of seconds")
    return value


def _positive_count(text: str) -> int:
    """An argparse type: a whole number > 0 (``2e6`` is accepted)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value >= 1 and value == int(value)):
        raise argparse.ArgumentTypeError(f"{text!r}: give a whole number >= 1")
    return int(value)


#: ``mlsgalerkin run`` flags that set a problem parameter, and the parameter they set.
_FLAG_PARAMETERS = {"--dx": ("dx", "dx"), "--t-end": ("t_end", "t_end"),
                    "--frame-every": ("frame_every", "frame_every"), "--no-gif": ("no_gif", "gif")}


def _refuse_conflicting_flags(args: argparse.Namespace, overrides: dict[str, str]) -> None:
    """A ValueError for flags that contradict each other, before any work: ``--restart`` with
    ``--overwrite``, ``--allow-changes`` without ``--restart``, and a parameter given both by its
    own flag and by ``--set`` (``--dx 0.01 --set dx=0.02``: which one was meant?)."""
    if args.restart and args.overwrite:
        raise ValueError("--restart continues the run in --out and --overwrite deletes it: give one of them")
    if args.allow_changes and not args.restart:
        raise ValueError("--allow-changes applies to --restart only: add --restart, or drop --allow-changes")
    for flag, (attr, name) in _FLAG_PARAMETERS.items():
        given = getattr(args, attr)
        if name in overrides and given not in (None, False):
            raise ValueError(f"{name} is given twice, by {flag} and by --set {name}={overrides[name]}; give it once")


#: What ``mlsgalerkin run`` says before the first step when numba has no compiled kernels on disk yet.
COMPILING_NOTE = "compiling numba kernels (first run only, about a minute)…"


def numba_cache_is_cold() -> bool:
    """Whether numba has no compiled mlsgalerkin kernel on disk, so the first step compiles them all.

    numba writes an index file ``*.nbi`` per cached function into ``__pycache__`` beside the
    source, or under ``NUMBA_CACHE_DIR``, or (when the package folder is not writable) into the
    user's numba cache folder; none of them holding an index file for mlsgalerkin means cold.
    """
    import os
    from pathlib import Path

    import mlsgalerkin

    package = Path(mlsgalerkin.__file__).resolve().parent
    roots = [package]
    if os.environ.get("NUMBA_CACHE_DIR"):
        roots = [Path(os.environ["NUMBA_CACHE_DIR"])]
    else:
        try:
            from numba.misc import appdirs

            roots.append(Path(appdirs.user_cache_dir("numba", appauthor=False)))
        except Exception:  # numba's layout changed: look beside the sources only
            pass
    for root in roots:
        if root.is_dir() and any("mlsgalerkin" in str(p) or root == package for p in root.rglob("*.nbi")):
            return False
    return True


#: Exit codes of ``mlsgalerkin run``.
EXIT_BAD_INPUT, EXIT_DIVERGED, EXIT_WRITE_FAILED = 2, 3, 4


def _cmd_run(args: argparse.Namespace) -> int:
    import dataclasses
    import json
    from pathlib import Path

    from mlsgalerkin.io import CheckpointError
    from mlsgalerkin.problem import load_problem, origin_of, prepare_problem
    from mlsgalerkin.run_directory import RestartMismatch, RunDirectoryError
    from mlsgalerkin.scene import SceneError
    from mlsgalerkin.simulation import RunInterrupted, Simulation, SimulationDiverged

    name = Path(args.problem).stem if args.problem.endswith(".py") else args.problem
    out = Path(args.out or f"results/{name}")
    output: dict = {}
    if args.frame_every is not None:
        output["every"] = args.frame_every
    if args.checkpoint_every is not None:
        output["checkpoint_every"] = args.checkpoint_every
    if args.checkpoint_wall is not None:
        output["checkpoint_wall_every"] = args.checkpoint_wall
    if args.no_gif:
        output.update(gif=False, png=False)
    try:
        overrides = _parse_sets(args.set or [])
        _refuse_conflicting_flags(args, overrides)
        if args.dx is not None:
            overrides["dx"] = args.dx
        if args.t_end is not None:
            overrides["t_end"] = args.t_end
        module = load_problem(args.problem)
        fields = {f.name for f in dataclasses.fields(module.Parameters)}
        if args.no_gif and "gif" in fields:
            overrides["gif"] = "false"
        if args.frame_every is not None and "frame_every" in fields:
            overrides["frame_every"] = args.frame_every
        prepared = prepare_problem(module, overrides, output=output, max_particles=args.max_particles,
                                   max_elements=args.max_elements)
        prepared.origin = origin_of(args.problem)
        print(f"{name}: {prepared.describe()}", flush=True)
        if args.check:
            print("the problem and its scene are valid (--check: nothing was run)")
            return 0
        analyse = getattr(module, "analyse", None)
        params = prepared.params
        if numba_cache_is_cold():
            print(COMPILING_NOTE, flush=True)
        result = Simulation(prepared.scene).run(
            out=out, progress=not args.no_progress, restart="latest" if args.restart else None,
            overwrite=args.overwrite, allow_changes=args.allow_changes, origin=prepared.origin,
            analyse=(lambda r: analyse(r, params)) if analyse else None)
        results = result.results or {}
    except (RestartMismatch, RunDirectoryError, CheckpointError, SceneError, ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SimulationDiverged as err:
        print(f"error: {err}", file=sys.stderr)
        print(f"the run's summary (with the diagnosis) is in {out / 'summary.json'}", file=sys.stderr)
        return EXIT_DIVERGED
    except RunInterrupted as err:
        where = f" (checkpoint {err.checkpoint})" if err.checkpoint else ""
        print(f"\n{name}: {err}; its files are written{where}. Continue it with the same command and --restart.",
              file=sys.stderr)
        return 128 + int(err.signum)
    except BrokenPipeError:
        raise  # the reader of our output went away: main() ends quietly
    except OSError as err:
        print(f"error: writing the run's files failed: {err}. The files written before are intact; free space "
              "(or fix the directory) and continue with --restart.", file=sys.stderr)
        return EXIT_WRITE_FAILED
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
    from mlsgalerkin.plots.run import RenderError, inspect_run, render_run

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
    except BrokenPipeError:
        raise  # the reader of our output went away: main() ends quietly
    except OSError as err:
        print(f"error: the pictures could not be written to {args.out or args.run_dir}: {_os_error_text(err)}. "
              "Choose a writable directory with --out", file=sys.stderr)
        return 4
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

    p = sub.add_parser("problems", help="list the runnable problems and their parameters (default, unit, "
                                        "meaning)")
    p.add_argument("problem", nargs="?", help="show only this problem (a shipped name or your problem "
                                              "file) with its description")
    p.set_defaults(func=_cmd_problems)

    p = sub.add_parser("run", help="run a problem: mlsgalerkin run gravity_current --set depth=0.1 --dx 0.002")
    p.add_argument("problem", help="a shipped problem (see `mlsgalerkin problems`) or the path of your own "
                                   "problem file, e.g. my_case.py")
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a problem parameter (repeatable)")
    p.add_argument("--dx", type=float, help="particle spacing (m)")
    p.add_argument("--t-end", type=float, help="end time (s)")
    p.add_argument("--out", help="run directory (default results/PROBLEM)")
    p.add_argument("--restart", action="store_true",
                   help="continue the run in --out from its newest valid checkpoint (same parameters; a longer "
                        "--t-end extends it)")
    p.add_argument("--allow-changes", action="store_true",
                   help="with --restart: continue although parameters differ from the checkpoint's (recorded in "
                        "summary.json)")
    p.add_argument("--overwrite", action="store_true", help="replace a run already in --out")
    p.add_argument("--check", action="store_true",
                   help="check the parameters and the scene, print the size of the run, and stop")
    p.add_argument("--frame-every", type=_positive_seconds, metavar="S", help="simulated seconds between VTU frames")
    p.add_argument("--checkpoint-every", type=_positive_seconds, metavar="S",
                   help="simulated seconds between checkpoints (default t_end/10)")
    p.add_argument("--checkpoint-wall", type=_positive_seconds, metavar="S",
                   help="wall-clock seconds between checkpoints (default 120)")
    p.add_argument("--max-particles", type=_positive_count, default=2_000_000, metavar="N",
                   help="refuse scenes with more particles than this, before building them (default 2e6)")
    p.add_argument("--max-elements", type=_positive_count, default=200_000, metavar="N",
                   help="refuse structure meshes with more elements than this, before building them (default 2e5)")
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


def _os_error_text(err: OSError) -> str:
    """``[Errno 28] No space left on device: 'PATH'`` as ``No space left on device (PATH)``."""
    if err.strerror and err.filename:
        return f"{err.strerror} ({err.filename})"
    return err.strerror or str(err)


#: Exit code of a command whose output pipe was closed (``mlsgalerkin problems | head``): 128 + SIGPIPE.
EXIT_BROKEN_PIPE = 141
#: Exit code of an unexpected error (a bug, or a case no message was written for).
EXIT_UNEXPECTED = 1


def _quiet_stdout() -> None:
    """Point stdout at /dev/null, so that flushing it at exit raises no second BrokenPipeError."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real file descriptor (e.g. captured by a test)
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; every failure ends in one line on stderr and a nonzero exit code (``-v``
    shows the traceback of an unexpected error). A closed output pipe ends quietly."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    try:
        code = int(args.func(args) or 0)
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        _quiet_stdout()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return 130
    except Exception as err:
        if args.verbose:
            raise
        first = (str(err).strip().splitlines() or [""])[0]
        print(f"error: {type(err).__name__}: {first} (unexpected; run with -v to see where, and please report it)",
              file=sys.stderr)
        return EXIT_UNEXPECTED


if __name__ == "__main__":
    sys.exit(main())
