"""Kernel accuracy study (Xing 2019, §12.2.3) and its MLS/RKPM/Shepard extension.

The measurements run on the study engine (:func:`mlsgalerkin.studies.kernels.run_kernel_study`,
a local Dask cluster by default); this script adds the report (``summary.md`` with Xing's (2019)
claims measured, the figures) from :mod:`verification.kernel_report`. ``mlsgalerkin study kernels`` runs
the same measurements without the report. See ``verification/README.md``.

    python verification/kernel_study.py --out verification/results/kernel_study
    python verification/kernel_study.py --quick --out results/demo
    python verification/kernel_study.py --scheduler tcp://10.0.0.5:8786   # an existing cluster
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make the repository root importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mlsgalerkin.studies.kernels import run_kernel_study  # noqa: E402
from verification.kernel_report import write_report  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer sweep points (< 30 s)")
    parser.add_argument(
        "--out",
        default="verification/results/kernel_study",
        help="output directory (default: %(default)s)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="Dask scheduler address to fan out to, or 'serial' (default: a local cluster)",
    )
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    parser.add_argument("-v", "--verbose", action="store_true", help="log the stages")
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if not args.verbose:  # Dask logs every cluster start and stop at INFO
        import distributed  # noqa: F401  (importing it sets its loggers' levels)

        logging.getLogger("distributed").setLevel(logging.WARNING)
    result = run_kernel_study(out=args.out, quick=args.quick, scheduler=args.scheduler,
                              progress=not args.no_progress)
    plots = write_report(result)
    print(result.report())
    print(f"report    : {result.out / 'summary.md'}; figures: "
          + ", ".join(p.name for p in plots))
    return 0


if __name__ == "__main__":
    sys.exit(main())
