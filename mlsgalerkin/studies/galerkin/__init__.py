"""Galerkin convergence study: patch tests, observed orders, smoothing-length sweep, cost.

Modules, one purpose each:

``problems``  exact solutions, loads, boundary data and node sets (patch tests, manufactured
              Poisson, Timoshenko cantilever)
``vci``       variationally consistent integration of DNI (a third rule, beyond the sources)
``runner``    one measured solve (wall time split into shape functions, assembly, solve) and
              the stiffness spectrum of one discretisation
``sweeps``    the configuration, the points of each sweep and the observed orders
``plots``     convergence, work-precision, wall split, h-sweep and spectrum figures
``report``    ``summary.md`` and the console report
``output``    atomic files, CSV and provenance
``study``     :func:`run_galerkin_study`, which runs it all

Run with ``mlsgalerkin study galerkin --quick --out results/demo`` or
``python verification/galerkin_convergence.py``.
"""

from mlsgalerkin.studies.galerkin.report import GalerkinStudyResult
from mlsgalerkin.studies.galerkin.study import COLUMNS, run_galerkin_study

__all__ = ["COLUMNS", "GalerkinStudyResult", "run_galerkin_study"]
