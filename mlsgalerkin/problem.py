r"""Problems: a scene with named parameters and its analysis, in a module of its own.

A problem module — a shipped one in :mod:`mlsgalerkin.problems`, or any ``my_case.py`` of a
user's — defines:

``Parameters``
    a dataclass of named parameters with defaults, each field documented by a ``#:`` comment
    that ends with its unit in parentheses, ``dx: float = 0.01  #: particle spacing (m)``
    (:func:`parameter_help` reads them; ``mlsgalerkin problems`` prints them);
``make_scene(params) -> Scene``
    the scene for those parameters;
``analyse(result, params) -> dict`` (optional)
    the results (errors against references, measured speeds), with a one-line ``"headline"``;
``check(params) -> list[str]`` (optional)
    every problem with the parameters (a negative gravity, a tank shorter than its column), each
    saying what is wrong and how to fix it — :func:`require_positive` and friends help;
``SMOKE`` (optional)
    parameter overrides for a seconds-long run (the tests' smoke runs).

:func:`run_problem` loads one by name or path, converts ``--set`` strings to the field types,
builds the scene, runs it (the analysis is part of the run, so ``summary.json`` holds its
results), as ``mlsgalerkin run`` does. The shipped problems use only the public API: copy one
as the starting point of your own case.
"""

from __future__ import annotations

import ast
import dataclasses
import hashlib
import importlib
import importlib.util
import inspect
import io
import math
import re
import sys
import textwrap
import tokenize
from pathlib import Path
from types import ModuleType
from typing import Any, NamedTuple

__all__ = [
    "DEFAULT_MAX_ELEMENTS",
    "DEFAULT_MAX_PARTICLES",
    "ParameterHelp",
    "PreparedProblem",
    "ProblemError",
    "load_problem",
    "numerical_dissipation",
    "origin_of",
    "parameter_help",
    "parameter_table",
    "parse_overrides",
    "prepare_problem",
    "problem_description",
    "problem_notes",
    "require",
    "require_nonnegative",
    "require_positive",
    "run_problem",
    "shipped_problems",
]

#: The largest scene ``mlsgalerkin run`` builds unless ``--max-particles`` raises it: a 2D step of
#: that many particles takes about a second on two cores, and the run needs about 4 GB.
DEFAULT_MAX_PARTICLES = 2_000_000
#: The largest structure mesh ``mlsgalerkin run`` lets scikit-fem assemble unless ``--max-elements``
#: raises it: 2e5 2D Q2 elements take about 3 GB and several minutes to assemble
#: (:mod:`mlsgalerkin.structure.checks`).
DEFAULT_MAX_ELEMENTS = 200_000
#: Bytes per particle of a running scene (state, neighbour and shape tables, temporaries).
_BYTES_PER_PARTICLE = {2: 2_000, 3: 6_000}


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


def require(condition: bool, message: str) -> list[str]:
    """``[message]`` if ``condition`` is false, else ``[]`` (for a problem's ``check``)."""
    return [] if condition else [message]


def require_positive(params: Any, *names: str) -> list[str]:
    """A message for every named parameter that is not a finite number ``> 0``."""
    out = []
    for name in names:
        v = getattr(params, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            out.append(f"parameter {name} must be a positive number, got {v!r}")
    return out


def require_nonnegative(params: Any, *names: str) -> list[str]:
    """A message for every named parameter that is not a finite number ``>= 0``."""
    out = []
    for name in names:
        v = getattr(params, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            out.append(f"parameter {name} must be a number >= 0, got {v!r}")
    return out


def numerical_dissipation(result: Any, speed: float, length: float) -> dict[str, float | None]:
    """The artificial viscosity a run carried and the Reynolds number it implies for a flow of
    ``speed`` (m/s) over ``length`` (m): ``{"numerical_viscosity_m2_per_s": ν,
    "numerical_reynolds_number": U L/ν}`` from the run's ``summary.json`` (``None`` without
    Monaghan viscosity, and a ``"<key>_not_measured"`` reason), for a problem's analysis to report
    beside its errors."""
    reports = ((getattr(result, "summary", None) or {}).get("fluid") or {}).get("effect_reports") or {}
    nu = (reports.get("monaghan_viscosity") or {}).get("numerical_viscosity_m2_per_s")
    out = {"numerical_viscosity_m2_per_s": nu,
           "numerical_reynolds_number": speed * length / nu if nu else None}
    if not nu:
        why = "the scene has no Monaghan viscosity (no artificial viscosity to report)"
        out.update({f"{key}_not_measured": why for key in ("numerical_viscosity_m2_per_s", "numerical_reynolds_number")})
    return out


def _finite_problems(params: Any) -> list[str]:
    out = []
    for f in dataclasses.fields(params):
        v = getattr(params, f.name)
        if isinstance(v, float) and not math.isfinite(v):
            out.append(f"parameter {f.name} must be a finite number, got {v!r}")
    return out


@dataclasses.dataclass
class PreparedProblem:
    """A problem loaded, its parameters read and checked, its scene built and validated."""

    module: ModuleType
    params: Any
    scene: Any
    origin: dict[str, Any]
    estimate: dict[str, Any]

    def describe(self) -> str:
        """One line: particles, memory, frames and checkpoints of the run."""
        e = self.estimate
        elements = f", {e['structure_elements']:,} structure elements" if e.get("structure_elements") else ""
        substeps = float(f"{e.get('structure_substeps', 0):.2g}")   # two significant digits
        if substeps:
            elements += f", about {substeps:,.0f} structure sub-steps"
        text = (f"{e['particles']:,} particles ({e['fluid_particles']:,} fluid){elements}, about "
                f"{e['memory_mb']:,.0f} MB, {e['frames']} frames")
        ck = e.get("checkpoint_every_s")
        wall = e.get("checkpoint_wall_every_s")
        if ck or wall:
            text += ", a checkpoint every " + " or ".join(
                x for x in (f"{ck:.4g} s of simulated time" if ck else "", f"{wall:g} s of wall clock" if wall else "") if x)
        return text


def prepare_problem(problem: str | Path | ModuleType, overrides: dict[str, Any] | None = None, *,
                    output: dict[str, Any] | None = None, max_particles: int | None = DEFAULT_MAX_PARTICLES,
                    max_elements: int | None = DEFAULT_MAX_ELEMENTS) -> PreparedProblem:
    """Everything before the first step, with every mistake reported before any work: load the
    problem, read and check its parameters (types, finiteness, the problem's ``check``), build
    its scene within ``max_particles`` (a lattice larger than that is refused before it is
    allocated) and ``max_elements`` (a structure mesh larger than that is refused by the
    problem's ``check`` before it is built, and by ``ElasticBody`` before it is assembled), apply
    ``output`` overrides (``Output`` fields: ``every``, ``checkpoint_every``,
    ``checkpoint_wall_every``, …) and validate the scene."""
    from mlsgalerkin.limits import element_limit, particle_limit

    mod = problem if isinstance(problem, ModuleType) else load_problem(problem)
    params = parse_overrides(mod.Parameters, overrides or {})
    problems = _finite_problems(params)
    check = getattr(mod, "check", None)
    if callable(check) and not problems:
        with element_limit(max_elements):
            problems = list(check(params))
    if problems:
        lines = "\n".join(f"  - {p}" for p in problems)
        raise ProblemError(f"{len(problems)} problem{'s' if len(problems) > 1 else ''} with the parameters:\n{lines}")
    from mlsgalerkin.scene import Scene

    try:
        with particle_limit(max_particles), element_limit(max_elements):
            scene = mod.make_scene(params)
    except (ValueError, ArithmeticError) as exc:  # a make_scene that could not build: say so, not a traceback
        raise ProblemError(f"could not build the scene with these parameters: {exc}") from exc
    if not isinstance(scene, Scene):
        raise ProblemError(f"make_scene returned {type(scene).__name__}, not a Scene")
    if output:
        try:
            scene.output = dataclasses.replace(scene.output, **output)
        except TypeError as exc:
            raise ProblemError(f"unknown output setting: {exc}") from exc
    n = sum(getattr(b, "n", 0) for b in scene.bodies)
    if max_particles is not None and n > max_particles:
        raise ProblemError(f"the scene has {n:,} particles, above the limit of {max_particles:,}; coarsen the "
                           "spacing, or raise the limit (--max-particles) if the machine has the memory and the time")
    scene.validate()  # SceneError: every problem at once
    dim = scene.dim or 2
    o = scene.output
    if o.times:
        frames = len(o.times)
    elif o.every:
        frames = int(math.floor(scene.t_end / o.every + 1e-9)) + 1
    else:
        frames = 2
    fluid = sum(getattr(b, "n", 0) for b in scene.bodies if getattr(b, "particle_kind", None) == "fluid")
    # bodies with a mesh report their own size and, when explicit, their sub-step (duck-typed: the
    # run layer imports no body package)
    memory = n * _BYTES_PER_PARTICLE.get(dim, 6000) + sum(b.memory_estimate() for b in scene.bodies
                                                           if hasattr(b, "memory_estimate"))
    substeps = [scene.t_end / s for b in scene.bodies if hasattr(b, "substep_estimate") and (s := b.substep_estimate())]
    estimate = {"particles": n, "fluid_particles": fluid, "memory_mb": memory / 1e6,
                "structure_elements": sum(b.n_elements for b in scene.bodies if hasattr(b, "n_elements")),
                "structure_substeps": max(substeps, default=0),
                "frames": frames if o.vtu else 0,
                "checkpoint_every_s": o.checkpoint_every if o.checkpoint_every is not None else scene.t_end / 10,
                "checkpoint_wall_every_s": o.checkpoint_wall_every}
    origin = origin_of(mod if isinstance(problem, ModuleType) else problem)
    return PreparedProblem(mod, params, scene, origin, estimate)


def origin_of(problem: str | Path | ModuleType) -> dict[str, Any]:
    """Where a problem comes from, for a run's identity: ``{"problem": name}`` for a shipped one,
    ``{"file": name, "sha256": ...}`` for a file (a changed file is another run)."""
    if isinstance(problem, ModuleType):
        path = Path(getattr(problem, "__file__", "") or "")
        if problem.__name__.startswith("mlsgalerkin.problems."):
            return {"problem": problem.__name__.rpartition(".")[2]}
    elif str(problem).endswith(".py") or "/" in str(problem) or "\\" in str(problem):
        path = Path(str(problem)).expanduser()
    else:
        return {"problem": str(problem)}
    if not path.is_file():
        return {"module": getattr(problem, "__name__", str(problem))}
    return {"file": path.name, "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}


def run_problem(problem: str | Path | ModuleType, overrides: dict[str, Any] | None = None,
                out: str | Path | None = None, *, progress: bool = True, restart: str | Path | None = None,
                overwrite: bool = False, allow_changes: bool = False, output: dict[str, Any] | None = None,
                max_particles: int | None = DEFAULT_MAX_PARTICLES, max_elements: int | None = DEFAULT_MAX_ELEMENTS):
    """Build problem ``problem`` (name, file or module) with ``overrides``, run it, analyse it.

    Everything is checked before the first step (:func:`prepare_problem`). ``restart``,
    ``overwrite`` and ``allow_changes`` are those of :meth:`~mlsgalerkin.simulation.Simulation.run`.
    Returns ``(result, results)``: the :class:`~mlsgalerkin.simulation.RunResult` and the
    problem's results dict (empty without ``analyse``), which ``summary.json`` holds under
    ``"results"``.
    """
    from mlsgalerkin.simulation import Simulation

    prepared = prepare_problem(problem, overrides, output=output, max_particles=max_particles,
                               max_elements=max_elements)
    analyse = getattr(prepared.module, "analyse", None)
    params = prepared.params
    result = Simulation(prepared.scene).run(
        out=out, progress=progress, restart=restart, overwrite=overwrite, allow_changes=allow_changes,
        origin=prepared.origin, analyse=(lambda r: analyse(r, params)) if analyse else None)
    return result, result.results or {}


# ------------------------------------------------------------------ parameter help
class ParameterHelp(NamedTuple):
    """One field of a ``Parameters`` dataclass: its name, default, unit and meaning.

    ``unit`` and ``meaning`` are empty strings where the field has no ``#:`` comment (or the
    class's source cannot be read); ``default`` is :data:`dataclasses.MISSING` for a field
    without a default.
    """

    name: str
    default: Any
    unit: str
    meaning: str


_UNIT = re.compile(r"^(?P<meaning>.*?)\s*\((?P<unit>[^()]*)\)\s*$", flags=re.DOTALL)


def split_unit(comment: str) -> tuple[str, str]:
    """``(meaning, unit)`` of a parameter comment ``"meaning (unit)"``: the unit is the last
    parenthesised group, which must close the comment and be a short word or symbol (at most
    15 characters); otherwise the unit is ``""`` and the whole comment is the meaning.

    >>> split_unit("sound speed / sqrt(2 g H) (–)")
    ('sound speed / sqrt(2 g H)', '–')
    >>> split_unit("end time; T = 3 at 0.162 s (s)"), split_unit("no unit given")
    (('end time; T = 3 at 0.162 s', 's'), ('no unit given', ''))
    """
    text = " ".join(comment.split())
    m = _UNIT.match(text)
    unit = m.group("unit").strip() if m else ""
    if not unit or len(unit) > 15:
        return text, ""
    return m.group("meaning").rstrip(" ;,:"), unit


def _field_comments(cls: type) -> dict[str, str]:
    """The ``#:`` comment of each field defined in the body of ``cls``: on the field's last line
    (after the value) or, failing that, the ``#:`` lines directly above it (Sphinx's two forms)."""
    try:
        source = textwrap.dedent(inspect.getsource(cls))
    except (OSError, TypeError):  # defined interactively, or no source file
        return {}
    try:
        tree = ast.parse(source)
        tokens = list(tokenize.generate_tokens(io.StringIO(source).readline))
    except (SyntaxError, tokenize.TokenError):
        return {}
    trailing: dict[int, str] = {}
    alone: dict[int, str] = {}
    for tok in tokens:
        if tok.type == tokenize.COMMENT and tok.string.startswith("#:"):
            row, col = tok.start
            text = tok.string[2:].strip()
            (alone if tok.line[:col].strip() == "" else trailing)[row] = text
    body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
    out: dict[str, str] = {}
    for node in body:
        if not (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name)):
            continue
        if node.end_lineno in trailing:
            out[node.target.id] = trailing[node.end_lineno]
            continue
        lines, row = [], node.lineno - 1
        while row in alone:
            lines.insert(0, alone[row])
            row -= 1
        if lines:
            out[node.target.id] = " ".join(lines)
    return out


def parameter_help(params_cls: type) -> list[ParameterHelp]:
    """Name, default, unit and meaning of every field of the dataclass ``params_cls``, in field
    order, read from the fields' ``#: meaning (unit)`` comments.

    The comment follows the field on its line (or stands on the lines directly above it); the
    unit is the parenthesised group that ends the comment: ``(m)``, ``(kg/m³)``, ``(–)`` for a
    dimensionless number, ``(bool)`` for a switch, ``(choice)`` for one of the named options
    the meaning lists. Fields inherited from a dataclass base get that base's comments.
    """
    if not (isinstance(params_cls, type) and dataclasses.is_dataclass(params_cls)):
        raise ProblemError(f"parameter_help needs a dataclass (a problem's Parameters), "
                           f"got {params_cls!r}")
    comments: dict[str, str] = {}
    for base in reversed(params_cls.__mro__):
        if dataclasses.is_dataclass(base) and "__annotations__" in vars(base):
            comments.update(_field_comments(base))
    out = []
    for f in dataclasses.fields(params_cls):
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = dataclasses.MISSING
        meaning, unit = split_unit(comments.get(f.name, ""))
        out.append(ParameterHelp(f.name, default, unit, meaning))
    return out


def _show_default(value: Any) -> str:
    if value is dataclasses.MISSING:
        return "(required)"
    if isinstance(value, float):
        text = repr(value)
        return text if len(text) <= 10 else format(value, ".6g")
    if isinstance(value, tuple):
        return ",".join(_show_default(v) for v in value)  # as --set NAME=1,2 reads it
    return str(value)


def parameter_table(params_cls: type, width: int = 100) -> str:
    """The fields of ``params_cls`` as a plain-text table: name, default (as ``--set`` takes
    it), unit, meaning (wrapped to ``width`` characters; ``?`` where a field has no comment)."""
    rows = [(h.name, _show_default(h.default), h.unit or "?", h.meaning or "?")
            for h in parameter_help(params_cls)]
    head = ("parameter", "default", "unit", "meaning")
    w = [max(len(r[k]) for r in [head, *rows]) for k in range(3)]
    indent = sum(w) + 6
    lines = []
    for r in [head, *rows]:
        wrapped = textwrap.wrap(r[3], max(width - indent, 30)) or [""]
        lines.append(f"{r[0]:<{w[0]}}  {r[1]:<{w[1]}}  {r[2]:<{w[2]}}  {wrapped[0]}")
        lines += [" " * indent + more for more in wrapped[1:]]
    lines.insert(1, "-" * max(len(line) for line in lines))
    return "\n".join(line.rstrip() for line in lines)


def _plain(text: str) -> str:
    """reStructuredText inline markup as plain text: literals and cross-references unwrapped.

    >>> _plain("a :class:`~mlsgalerkin.fluid.WallBody` moving with ``X(t)``")
    'a WallBody moving with X(t)'
    """
    def role(m: re.Match) -> str:
        return m.group(2).rsplit(".", 1)[-1] if m.group(1) else m.group(2)

    text = re.sub(r":\w+:`(~?)([^`]+)`", role, text)
    return text.replace("``", "")


def problem_description(mod: ModuleType) -> str:
    """The first paragraph of a problem module's docstring, as plain text on one line."""
    doc = inspect.cleandoc(mod.__doc__ or "")
    first = doc.split("\n\n", 1)[0]
    return _plain(" ".join(first.split()))


def problem_notes(mod: ModuleType) -> str:
    """The rest of a problem module's docstring after its first paragraph (what it models, its
    reference and the configuration its numbers were measured in), as plain text with the
    docstring's own line breaks; empty when there is none."""
    doc = inspect.cleandoc(mod.__doc__ or "")
    parts = doc.split("\n\n", 1)
    return _plain(parts[1].strip()) if len(parts) > 1 else ""
