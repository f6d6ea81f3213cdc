"""Galerkin convergence study: patch tests, orders, smoothing-length sweep, work-precision.

Thin wrapper around :func:`mlsgalerkin.studies.galerkin_convergence.run_galerkin_study`; the
same study runs as ``mlsgalerkin study galerkin``. See ``verification/README.md``.

    python verification/galerkin_convergence.py --out verification/results/galerkin_convergence
    python verification/galerkin_convergence.py --quick --out results/demo
"""

from __future__ import annotations

import argparse
import logging
import os
import sys

# Single-threaded BLAS, like the study's numba kernels: the dense eigenvalue problems of the
# h-sweep otherwise fight for the cores of a shared 2-core machine (several times slower).
# Must be set before numpy is imported.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from mlsgalerkin.studies.galerkin_convergence import run_galerkin_study  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="three-level subset, one kernel (< 60 s)")
    parser.add_argument("--out", default="verification/results/galerkin_convergence",
                        help="output directory (default: %(default)s)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    parser.add_argument("-v", "--verbose", action="store_true", help="log the stages")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    result = run_galerkin_study(out=args.out, quick=args.quick, progress=not args.no_progress)
    print(result.report())
    return 0


if __name__ == "__main__":
    sys.exit(main())
