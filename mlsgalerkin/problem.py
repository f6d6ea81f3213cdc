r"""Problems: a scene with named parameters and its analysis, in a module of its own.

A problem module — a shipped one in :mod:`mlsgalerkin.problems`, or any ``my_case.py`` of a
user's — defines:

``Parameters``
    a dataclass of named parameters with defaults (units in the comments);
``make_scene(params) -> Scene``
    the scene for those parameters;
``analyse(result, params) -> dict`` (optional)
    the results (errors against references, measured speeds), with a one-line ``"headline"``;
``SMOKE`` (optional)
    parameter overrides for a seconds-long run (the tests' smoke runs).

:func:`run_problem` loads one by name or path, converts ``--set`` strings to the field types,
builds the scene, runs it (the analysis is part of the run, so ``summary.json`` holds its
results), as ``mlsgalerkin run`` does. The shipped problems use only the public API: copy one
as the starting point of your own case.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import math
import re
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["ProblemError", "load_problem", "parse_overrides", "run_problem", "shipped_problems"]


class ProblemError(ValueError):
    """A problem cannot be loaded or its parameters cannot be read; the message says how to fix it."""


def shipped_problems() -> tuple[str, ...]:
    """Names of the problems shipped in :mod:`mlsgalerkin.problems`."""
    return importlib.import_module("mlsgalerkin.problems").PROBLEMS


def _check_module(mod: ModuleType, where: str) -> ModuleType:
    problems = []
    params = getattr(mod, "Parameters", None)
    if params is None or not dataclasses.is_dataclass(params):
        problems.append("a dataclass `Parameters` of named parameters with defaults")
    if not callable(getattr(mod, "make_scene", None)):
        problems.append("a function `make_scene(params) -> Scene`")
    if hasattr(mod, "analyse") and not callable(mod.analyse):
        problems.append("`analyse(result, params) -> dict` must be a function")
    if problems:
        raise ProblemError(f"{where} is not a problem module: it needs " + "; ".join(problems)
                           + " (see docs/howto/write_a_scene_and_an_effect.md)")
    return mod


def load_problem(spec: str | Path) -> ModuleType:
    """The problem module ``spec``: a shipped problem's name, or the path of a ``.py`` file."""
    text = str(spec)
    if text.endswith(".py") or "/" in text or "\\" in text:
        path = Path(text).expanduser()
        if not path.is_file():
            raise ProblemError(f"problem file {path} does not exist")
        if path.suffix != ".py":
            raise ProblemError(f"problem file {path} must be a Python module (.py)")
        stem = re.sub(r"\W", "_", path.stem)
        name = f"mlsgalerkin_user_problem_{stem}"
        loader_spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(loader_spec)
        sys.modules[name] = mod  # dataclasses and pickling look the module up by name
        try:
            loader_spec.loader.exec_module(mod)
        except Exception as exc:
            sys.modules.pop(name, None)
            raise ProblemError(f"could not import the problem file {path}: {type(exc).__name__}: {exc}") from exc
        return _check_module(mod, str(path))
    names = shipped_problems()
    if text not in names:
        raise ProblemError(f"unknown problem {text!r}; choose one of {', '.join(names)} or give the path of "
                           "your own problem file (my_case.py)")
    return _check_module(importlib.import_module(f"mlsgalerkin.problems.{text}"), f"problem {text!r}")


_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


def _convert(name: str, text: str, current: Any) -> Any:
    """``text`` (a ``--set`` value) as the type of the default ``current``."""
    what = type(current).__name__
    try:
        if isinstance(current, bool):
            low = text.strip().lower()
            if low in _TRUE:
                return True
            if low in _FALSE:
                return False
            raise ValueError
        if isinstance(current, int):
            return int(text)
        if isinstance(current, float) or current is None:
            value = float(text)
            if not math.isfinite(value):
                raise ValueError
            return value
        if isinstance(current, tuple):
            return tuple(float(v) for v in text.strip("()").split(","))
        if isinstance(current, str):
            return text
    except ValueError:
        pass
    hint = " (true/false, yes/no, 1/0, on/off)" if isinstance(current, bool) else ""
    raise ProblemError(f"parameter {name}: cannot read {text!r} as {what}{hint}")


def parse_overrides(params_cls: type, overrides: dict[str, Any]) -> Any:
    """``params_cls(**overrides)`` with strings converted to each field's type.

    Unknown names raise a :class:`ProblemError` listing the valid ones; a value that cannot be
    read as its field's type (booleans: true/false, yes/no, 1/0, on/off; numbers: finite)
    names the parameter.
    """
    fields = {f.name: f for f in dataclasses.fields(params_cls)}
    unknown = sorted(set(overrides) - set(fields))
    if unknown:
        valid = ", ".join(sorted(fields))
        raise ProblemError(f"unknown parameter(s) {unknown} for {params_cls.__module__}; valid: {valid}")
    defaults = params_cls()
    kwargs = {}
    for name, value in overrides.items():
        kwargs[name] = _convert(name, value, getattr(defaults, name)) if isinstance(value, str) else value
    return params_cls(**kwargs)


def run_problem(problem: str | Path | ModuleType, overrides: dict[str, Any] | None = None,
                out: str | Path | None = None, *, progress: bool = True, restart: str | Path | None = None):
    """Build problem ``problem`` (name, file or module) with ``overrides``, run it, analyse it.

    Returns ``(result, results)``: the :class:`~mlsgalerkin.simulation.RunResult` and the
    problem's results dict (empty without ``analyse``), which ``summary.json`` holds under
    ``"results"``.
    """
    from mlsgalerkin.simulation import Simulation

    mod = problem if isinstance(problem, ModuleType) else load_problem(problem)
    params = parse_overrides(mod.Parameters, overrides or {})
    scene = mod.make_scene(params)
    analyse = getattr(mod, "analyse", None)
    result = Simulation(scene).run(out=out, progress=progress, restart=restart,
                                   analyse=(lambda r: analyse(r, params)) if analyse else None)
    return result, result.results or {}
