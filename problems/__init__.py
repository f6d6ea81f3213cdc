"""Runnable scenes shipped with mlsgalerkin, one module per problem (installed as
``mlsgalerkin.problems``): ``hydrostatic``, ``dam_break``, ``gravity_current``,
``drop_impact``, ``wave_maker``.

Each defines ``Parameters`` (named, with defaults), ``make_scene``, ``analyse`` and ``SMOKE``,
and uses only the public API, so any of them is a starting point for your own case: copy it,
edit it, and run it with ``mlsgalerkin run my_case.py``. :func:`mlsgalerkin.problem.run_problem`
builds, runs and analyses one, as ``mlsgalerkin run`` does.
"""

from mlsgalerkin.problem import load_problem as get_problem
from mlsgalerkin.problem import run_problem, shipped_problems

PROBLEMS = shipped_problems()

__all__ = ["PROBLEMS", "get_problem", "run_problem"]
