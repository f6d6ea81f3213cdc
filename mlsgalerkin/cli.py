"""Command line: ``mlsgalerkin kernels | study kernels | study galerkin``.

Library code logs; this module prints.
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


def _cmd_study_kernels(args: argparse.Namespace) -> int:
    from mlsgalerkin.studies.kernels import run_kernel_study

    result = run_kernel_study(out=args.out, quick=args.quick, progress=not args.no_progress)
    print(result.report())
    return 0


def _cmd_study_galerkin(args: argparse.Namespace) -> int:
    from mlsgalerkin.studies.galerkin_convergence import run_galerkin_study

    result = run_galerkin_study(out=args.out, quick=args.quick, progress=not args.no_progress)
    print(result.report())
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mlsgalerkin",
        description="Meshfree Galerkin mechanics: kernels, MLS/RKPM shape functions, studies.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("kernels", help="list the kernels with support, constants and smoothness")
    p.set_defaults(func=_cmd_kernels)

    study = sub.add_parser("study", help="run a verification study")
    studies = study.add_subparsers(dest="study", required=True)
    p = studies.add_parser(
        "kernels", help="kernel x smoothing-length accuracy study (errors, wall times, plots)"
    )
    p.add_argument("--quick", action="store_true", help="small sweep (< 30 s)")
    p.add_argument("--out", default="results/kernel_study", help="output directory")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=_cmd_study_kernels)
    p = studies.add_parser(
        "galerkin", help="Galerkin convergence study: patch tests, rates, h-sweep, work-precision"
    )
    p.add_argument("--quick", action="store_true", help="three-level subset (< 60 s)")
    p.add_argument("--out", default="results/galerkin_convergence", help="output directory")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=_cmd_study_galerkin)
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
