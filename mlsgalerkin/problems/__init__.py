"""Runnable scenes, one module per problem: ``hydrostatic``, ``dam_break``, ``gravity_current``,
``drop_impact``. Each has ``Parameters`` (named, with defaults), ``make_scene``, ``analyse`` and
``SMOKE``; :func:`run_problem` builds, runs and analyses one, as ``mlsgalerkin run`` does.
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path
from types import ModuleType
from typing import Any

from mlsgalerkin.problems._common import parse_overrides
from mlsgalerkin.io.files import write_json

__all__ = ["PROBLEMS", "get_problem", "run_problem"]

PROBLEMS = ("hydrostatic", "dam_break", "gravity_current", "drop_impact")


def get_problem(name: str) -> ModuleType:
    """The problem module ``name`` (clear error listing the problems if unknown)."""
    if name not in PROBLEMS:
        raise ValueError(f"unknown problem {name!r}; choose one of {', '.join(PROBLEMS)}")
    return importlib.import_module(f"mlsgalerkin.problems.{name}")


def run_problem(name: str, overrides: dict[str, Any] | None = None, out: str | Path | None = None, *,
                progress: bool = True, restart: str | Path | None = None):
    """Build problem ``name`` with ``overrides``, run it, analyse it.

    Returns ``(result, results)``: the :class:`~mlsgalerkin.simulation.RunResult` and the
    problem's results dict, which is also stored under ``"results"`` in ``summary.json``.
    """
    from mlsgalerkin.simulation import Simulation

    mod = get_problem(name)
    params = parse_overrides(mod.Parameters, overrides or {})
    scene = mod.make_scene(params)
    result = Simulation(scene).run(out=out, progress=progress, restart=restart)
    results = mod.analyse(result, params)
    result.summary["results"] = results
    if out is not None:
        path = Path(out) / "summary.json"
        summary = json.loads(path.read_text())
        summary["results"] = results
        write_json(path, summary)
    return result, results
