"""Galerkin convergence study: patch tests, orders, smoothing-length sweep, work-precision.

The solves run on the study engine (:func:`mlsgalerkin.studies.galerkin.run_galerkin_study`, a
local Dask cluster by default); this script adds the report (``summary.md`` with the measured
observations, the figures) from :mod:`verification.galerkin_report`. ``mlsgalerkin study
galerkin`` runs the same solves without the report. See ``verification/README.md``.

    python verification/galerkin_convergence.py --out verification/results/galerkin_convergence
    python verification/galerkin_convergence.py --quick --out results/demo
    python verification/galerkin_convergence.py --scheduler tcp://10.0.0.5:8786
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

# Single-threaded BLAS, like the study's numba kernels: the dense eigenvalue problems of the
# h-sweep otherwise fight for the cores of a shared machine (several times slower). Must be set
# before numpy is imported; local-cluster workers get it from the study engine.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

if __package__ in (None, ""):  # run as a script: make the repository root importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mlsgalerkin.studies.galerkin import run_galerkin_study  # noqa: E402
from verification.galerkin_report import write_report  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="three-level subset, one kernel (< 60 s)")
    parser.add_argument("--out", default="verification/results/galerkin_convergence",
                        help="output directory (default: %(default)s)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="Dask scheduler address to fan out to, or 'serial' "
                             "(default: a local cluster)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    parser.add_argument("-v", "--verbose", action="store_true", help="log the stages")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if not args.verbose:  # Dask logs every cluster start and stop at INFO
        import distributed  # noqa: F401  (importing it sets its loggers' levels)

        logging.getLogger("distributed").setLevel(logging.WARNING)
    result = run_galerkin_study(out=args.out, quick=args.quick, scheduler=args.scheduler,
                                progress=not args.no_progress)
    plots = write_report(result)
    print(result.report())
    print(f"report    : {result.out / 'summary.md'}; figures: "
          + ", ".join(p.name for p in plots))
    return 0


if __name__ == "__main__":
    sys.exit(main())
