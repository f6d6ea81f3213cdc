"""Kernel accuracy study (seed digest §6, §9.9) and its MLS/RKPM/Shepard extension.

Thin wrapper around :func:`mlsgalerkin.studies.kernels.run_kernel_study`; the same study
runs as ``mlsgalerkin study kernels``. See ``verification/README.md``.

    python verification/kernel_study.py --out verification/results/kernel_study
    python verification/kernel_study.py --quick --out results/demo
"""

from __future__ import annotations

import argparse
import logging
import sys

from mlsgalerkin.studies.kernels import run_kernel_study


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer sweep points (< 30 s)")
    parser.add_argument(
        "--out",
        default="verification/results/kernel_study",
        help="output directory (default: %(default)s)",
    )
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    parser.add_argument("-v", "--verbose", action="store_true", help="log the stages")
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    result = run_kernel_study(out=args.out, quick=args.quick, progress=not args.no_progress)
    print(result.report())
    return 0


if __name__ == "__main__":
    sys.exit(main())
