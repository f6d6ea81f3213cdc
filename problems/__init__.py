"""Runnable scenes shipped with mlsgalerkin, one module per problem (installed as
``mlsgalerkin.problems``): ``hydrostatic``, ``dam_break``, ``gravity_current``,
``drop_impact``, ``wave_maker``, the periodic ``taylor_green``, ``poiseuille`` and ``couette``, and the others
``mlsgalerkin problems`` lists.

Each defines ``Parameters`` (named, with defaults), ``make_scene``, ``analyse`` and ``SMOKE``,
and uses only the public API, so any of them is a starting point for your own case: copy it,
edit it, and run it with ``mlsgalerkin run my_case.py``. :func:`mlsgalerkin.problem.run_problem`
builds, runs and analyses one, as ``mlsgalerkin run`` does.
"""

import pkgutil

#: The shipped problems' names (every public module of this package).
PROBLEMS = tuple(sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")))

__all__ = ["PROBLEMS"]
