"""A small, general study engine: a parameter grid x a measurement -> error and wall-time records.

A researcher's convergence study in a few lines (see ``docs/howto/write_a_convergence_study.md``):

.. code-block:: python

    from mlsgalerkin.studies import Grid, run_study

    def measure(kernel, spacing):             # one point of the grid -> its error measures
        ...
        return {"error_l2": err}

    if __name__ == "__main__":                # worker processes re-import the script
        result = run_study(Grid.product(kernel=["cubic_spline", "wendland_c2"],
                                        spacing=[1 / 8, 1 / 16, 1 / 32]), measure)
        result.to_csv("study.csv")            # parameters, measures, wall_time_s, worker
        print(result.fit(x="spacing", y="error_l2", by=["kernel"]))
        result.work_precision_plot("work_precision.png", error="error_l2", by=["kernel"])

Modules, one purpose each:

``grid``        the parameter grid (product of named values, explicit points)
``timing``      the best-of-repeats timing policy
``schedulers``  serial, local Dask cluster, existing Dask cluster
``runner``      :func:`run_study`: checks, one task per point, progress, errors
``result``      :class:`StudyResult`: records, CSV, power-law fits, work-precision plot
``rowlog``      :class:`RowLog`: each point's records on disk the moment it is measured
"""

from __future__ import annotations

from mlsgalerkin.studies.engine.grid import RESERVED_COLUMNS, Grid, GridError, as_grid
from mlsgalerkin.studies.engine.result import FIT_COLUMNS, StudyResult, select, write_records
from mlsgalerkin.studies.engine.rowlog import RowLog, read_rows
from mlsgalerkin.studies.engine.runner import MeasurementError, run_study, worker_name
from mlsgalerkin.studies.engine.schedulers import (
    LOCAL,
    SERIAL,
    SchedulerError,
    available_cores,
    numeric_environment,
)
from mlsgalerkin.studies.engine.timing import TimingPolicy, best_time

__all__ = [
    "FIT_COLUMNS",
    "LOCAL",
    "RESERVED_COLUMNS",
    "SERIAL",
    "Grid",
    "GridError",
    "MeasurementError",
    "RowLog",
    "SchedulerError",
    "StudyResult",
    "TimingPolicy",
    "as_grid",
    "available_cores",
    "best_time",
    "numeric_environment",
    "read_rows",
    "run_study",
    "select",
    "worker_name",
    "write_records",
]
