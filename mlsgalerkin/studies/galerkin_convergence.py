"""Galerkin convergence study (entry point; implementation in :mod:`mlsgalerkin.studies.galerkin`).

Patch tests per integration rule (DNI, SCNI, VCI), observed L2/H1 orders for a manufactured
Poisson problem and the Timoshenko cantilever over rule x basis x kernel, a smoothing-length
sweep with spurious zero-energy modes, and work-precision data (every solve timed, split into
shape functions, assembly and solve).

    mlsgalerkin study galerkin --quick --out results/demo
    python verification/galerkin_convergence.py --out verification/results/galerkin_convergence
"""

from mlsgalerkin.studies.galerkin import COLUMNS, GalerkinStudyResult, run_galerkin_study

__all__ = ["COLUMNS", "GalerkinStudyResult", "run_galerkin_study"]
