"""Studies: a small, general study engine and the two shipped studies' measurements.

:mod:`mlsgalerkin.studies.engine` runs a parameter grid x a measurement on Dask (a local
cluster by default) into records of error *and* wall time, with power-law fits through
:mod:`mlsgalerkin.analysis.convergence` and a work-precision plot.

The shipped studies keep here what computes their numbers; their reports (claims, observations,
prose, the study-specific figures) live in the repository's ``verification/``:

:mod:`mlsgalerkin.studies.kernels`   kernel x smoothing-length accuracy (SPH sums, MLS/RKPM)
:mod:`mlsgalerkin.studies.galerkin`  Galerkin convergence (patch tests, orders, h-sweep)

Both run as ``mlsgalerkin study kernels|galerkin [--quick] [--out DIR] [--scheduler ADDRESS]``.
"""

from __future__ import annotations

from mlsgalerkin.studies.engine import (
    Grid,
    GridError,
    MeasurementError,
    StudyResult,
    run_study,
)

__all__ = ["Grid", "GridError", "MeasurementError", "StudyResult", "run_study"]
