"""Galerkin convergence study: patch tests, observed orders, smoothing-length sweep, cost.

Modules, one purpose each:

``problems``  exact solutions, loads, boundary data and node sets (patch tests, manufactured
              Poisson, Timoshenko cantilever)
``runner``    one measured solve (wall time split into shape functions, assembly, solve) and
              the stiffness spectrum of one discretisation
``sweeps``    the configuration, the grid points of each sweep, the measurement of one point
              and the observed orders
``result``    :class:`GalerkinStudyResult` and its console report
``study``     :func:`run_galerkin_study`: the grid on the study engine, tables, provenance

The report (``summary.md`` with the observations, the study's figures) is written by
``verification/galerkin_convergence.py``. Run the numbers alone with
``mlsgalerkin study galerkin --quick --out results/demo``.
"""

from __future__ import annotations

from mlsgalerkin.studies.galerkin.result import GalerkinStudyResult
from mlsgalerkin.studies.galerkin.study import COLUMNS, ORDER_COLUMNS, run_galerkin_study

__all__ = ["COLUMNS", "GalerkinStudyResult", "ORDER_COLUMNS", "run_galerkin_study"]
