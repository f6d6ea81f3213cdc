r"""A :class:`Scene` lists bodies, the solvers' schemes, interactions, end time, outputs, probes and
monitors; it is validated as a whole before step 1, and every problem is reported at once in one
:class:`SceneError`.

Bodies are advanced by the solver their class names (fluid and wall bodies by the
:class:`~mlsgalerkin.fluid.solver.FluidSolver`); each solver's numerical settings are its
:class:`~mlsgalerkin.dynamics.Scheme` (the fluid's :class:`~mlsgalerkin.fluid.scheme.FluidScheme`:
its effects — nothing unlisted is computed —, approximation, integrator, mass, safety, ``dt_max``,
spacing); ``interactions`` exchange forces between bodies. A solver sees its bodies, its scheme
and a read-only :class:`~mlsgalerkin.dynamics.SceneView`, never the scene.

>>> from mlsgalerkin.fluid import FluidBody, FluidScheme, Phase, Gravity
>>> water = FluidBody.block("water", (0, 0), (0.1, 0.05), 0.01, [Phase("water", 1000.0)])
>>> scene = Scene([water], [FluidScheme([Gravity()], stabilisation="as_listed")], t_end=0.1)
>>> try:
...     scene.validate()
... except SceneError as err:
...     print(err)
scene 'scene' has 1 problem:
  - no pressure model: list exactly one of TaitPressure (...)
"""

from __future__ import annotations

import warnings
from typing import Any, Sequence

import numpy as np

from mlsgalerkin.approximation.settings import Approximation
from mlsgalerkin.dynamics import Body, Interaction, SceneView, Scheme, Solver, import_class, solver_class_of
from mlsgalerkin.monitors import Monitor, Output, Probe, Watchdog

__all__ = ["MAX_FRAMES", "Approximation", "Output", "Probe", "Scene", "SceneError", "Watchdog", "solver_class"]

#: The most VTU frames a scene may ask for (a frame of 10⁵ particles is about 5 MB).
MAX_FRAMES = 20_000

#: Where the deprecated ``Scene(bodies, effects, approximation=...)`` form finds the fluid's scheme
#: (an import path, as a body names its solver: the run layer imports no physics).
_LEGACY_FLUID_SCHEME = "mlsgalerkin.fluid.scheme:FluidScheme"
_LEGACY_STRUCTURE_SCHEME = "mlsgalerkin.structure.scheme:StructureScheme"
_LEGACY_OPTIONS = ("approximation", "integrator", "mass", "dt_max", "safety")


class SceneError(ValueError):
    """A scene cannot run; the message lists every problem found."""


def solver_class(body: Body) -> type[Solver]:
    """The :class:`~mlsgalerkin.dynamics.Solver` class that advances ``body`` (its ``solver``
    attribute: a class, or ``"module:Class"``)."""
    return solver_class_of(body)


class Scene:
    """Bodies, schemes, interactions, end time, outputs, probes and monitors of a simulation.

    Parameters
    ----------
    bodies : list of Body
        Fluid bodies, wall bodies, elastic and rigid bodies (and, with their solvers, other
        kinds); unique names.
    schemes : list of Scheme
        The numerical settings of each solver, at most one per solver: the fluid's
        :class:`~mlsgalerkin.fluid.scheme.FluidScheme` (effects — exactly one pressure model —,
        approximation, integrator, mass, safety, ``dt_max``, spacing; ``water(...)`` gives the
        recommended one), a :class:`~mlsgalerkin.structure.scheme.StructureScheme`. A solver
        without one gets its defaults.
    t_end : float
        End time (s).
    name : str
        Used in file names, titles and ``summary.json``.
    output : Output
        Frames, time-series sampling, checkpoints and pictures.
    probes : list of Probe
        Scalars recorded in ``timeseries.csv``.
    watchdog : Watchdog
        Limits beyond which a run is stopped with a diagnosis.
    interactions : list of Interaction
        Force exchanges between bodies (penalty contact, fluid-structure coupling), every step.
    monitors : list of Monitor
        Extra monitors, after the standard ones.
    parameters : dict
        Copied into ``summary.json`` and the checkpoints (the problem's parameters).

    ``Scene(bodies, effects, t_end, approximation=..., integrator=..., mass=..., dt_max=...,
    safety=...)``, the form before schemes, still works for this release with a
    ``DeprecationWarning`` that shows the new form.
    """

    def __init__(self, bodies: Sequence[Body], schemes: Sequence[Scheme] = (), t_end: float | None = None,
                 name: str = "scene", *, output: Output | None = None, probes: Sequence[Probe] = (),
                 watchdog: Watchdog | None = None, interactions: Sequence[Interaction] = (),
                 monitors: Sequence[Monitor] = (), parameters: dict | None = None,
                 effects: Sequence | None = None, **legacy: Any) -> None:
        unknown = sorted(set(legacy) - set(_LEGACY_OPTIONS))
        if unknown:
            raise TypeError(f"Scene() got unexpected keyword arguments {unknown}")
        if t_end is None:
            raise TypeError("Scene() needs t_end, the end time (s)")
        self.bodies = list(bodies)
        schemes = list(schemes)
        if effects is not None or legacy or any(not isinstance(x, Scheme) and _looks_like_effect(x) for x in schemes):
            if any(isinstance(x, Scheme) for x in schemes):
                given = sorted(set(legacy) | ({"effects"} if effects is not None else set()))
                raise TypeError(f"Scene() got schemes and the fluid's options {given or ['effects']} on the scene: give "
                                "them to the FluidScheme (FluidScheme(effects, approximation=..., dt_max=...)), not the "
                                "Scene")
            schemes = _legacy_schemes(self.bodies, schemes, effects, legacy)
        self.schemes: list = schemes
        self.t_end = t_end
        self.name = name
        self.output = output if output is not None else Output()
        self.probes = probes
        self.watchdog = watchdog if watchdog is not None else Watchdog()
        self.interactions = interactions
        self.monitors = monitors
        self.parameters = dict(parameters) if parameters is not None else {}

    def __repr__(self) -> str:
        return (f"Scene(name={self.name!r}, bodies={[getattr(b, 'name', b) for b in self.bodies]}, "
                f"schemes={self.schemes!r}, t_end={self.t_end!r})")

    # ------------------------------------------------------------------ the pieces
    def bodies_of(self, kind: type) -> list:
        """The bodies that are instances of ``kind``, in scene order."""
        return [b for b in self.bodies if isinstance(b, kind)]

    @property
    def dim(self) -> int:
        """The dimension of the bodies (0 if they disagree or there are none)."""
        dims = {b.dim for b in self.bodies if isinstance(b, Body)}
        return dims.pop() if len(dims) == 1 else 0

    def solver_groups(self) -> dict[type[Solver], list[Body]]:
        """The bodies grouped by the solver class that advances them, in scene order."""
        groups: dict[type[Solver], list[Body]] = {}
        for b in self.bodies:
            if isinstance(b, Body):
                groups.setdefault(solver_class(b), []).append(b)
        return groups

    def scheme_for(self, solver: type[Solver]) -> Scheme:
        """The listed scheme for ``solver``, or its defaults (``solver.scheme_class()``)."""
        for sc in self.schemes:
            if isinstance(sc, Scheme) and import_class(sc.solver) is solver:
                return sc
        return solver.scheme_class()

    def view(self) -> SceneView:
        """What solvers, effects and interactions may know of this scene (read only)."""
        return SceneView(name=self.name, dim=self.dim, t_end=self.t_end, bodies=tuple(self.bodies),
                         interactions=tuple(self.interactions), probes=tuple(self.probes))

    # ------------------------------------------------------------------ the form before schemes
    def _fluid_scheme(self) -> Any:
        return next((sc for sc in self.schemes if hasattr(sc, "effects")), None)

    def _legacy_option(self, name: str) -> Any:
        warnings.warn(f"Scene.{name} is deprecated: the fluid's settings live in its scheme; use "
                      f"scene.schemes[k].{name} of the FluidScheme", DeprecationWarning, stacklevel=3)
        fluid = self._fluid_scheme()
        if fluid is None:
            raise AttributeError(f"this scene has no FluidScheme, so no {name}")
        return fluid

    @staticmethod
    def _legacy_property(name: str) -> property:
        def get(self: "Scene") -> Any:
            return getattr(self._legacy_option(name), name)

        def put(self: "Scene", value: Any) -> None:
            setattr(self._legacy_option(name), name, value)

        return property(get, put, doc=f"Deprecated: ``FluidScheme.{name}`` of the scene's fluid scheme.")

    effects = _legacy_property("effects")
    approximation = _legacy_property("approximation")
    integrator = _legacy_property("integrator")
    mass = _legacy_property("mass")
    dt_max = _legacy_property("dt_max")
    safety = _legacy_property("safety")

    # ------------------------------------------------------------------ validation
    def problems(self) -> list[str]:
        """Every problem with this scene (empty list if it can run). Reads only."""
        out: list[str] = []
        names = [getattr(b, "name", repr(b)) for b in self.bodies]
        for b in self.bodies:
            if not isinstance(b, Body):
                out.append(f"unknown body {b!r}: bodies must be FluidBody, WallBody or another Body")
        if not any(isinstance(b, Body) for b in self.bodies):
            out.append("the scene has no bodies")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            out.append(f"body names must be unique, repeated: {dup}")
        dims = {b.dim for b in self.bodies if isinstance(b, Body)}
        if len(dims) > 1:
            out.append(f"bodies mix dimensions {sorted(dims)}")
        if not (isinstance(self.t_end, (int, float)) and np.isfinite(self.t_end) and self.t_end > 0):
            out.append(f"t_end must be positive, got {self.t_end!r}")
        try:
            groups = self.solver_groups()
        except (ImportError, AttributeError) as err:
            out.append(f"a body names a solver that cannot be imported ({err})")
            groups = {}
        out.extend(self._scheme_problems(groups))
        view = self.view()
        for cls, bodies in groups.items():
            out.extend(cls.problems(bodies, self.scheme_for(cls), view))
        for i in self.interactions:
            if not isinstance(i, Interaction):
                out.append(f"unknown interaction {i!r}: interactions must be Interaction instances")
            else:
                out.extend(i.problems(view))
        for m in self.monitors:
            if not isinstance(m, Monitor):
                out.append(f"unknown monitor {m!r}: monitors must be Monitor instances")
        for m in (self.watchdog, *(m for m in self.monitors if isinstance(m, Monitor))):
            out.extend(m.problems())
        out.extend(self.output.problems())
        o = self.output
        valid = lambda v: isinstance(v, (int, float)) and np.isfinite(v) and v > 0  # noqa: E731
        if valid(self.t_end) and valid(o.every) and o.vtu and self.t_end / o.every > MAX_FRAMES:
            out.append(f"output.every = {o.every:g} s would write {self.t_end / o.every:.3g} frames up to t_end = "
                       f"{self.t_end:g} s, more than {MAX_FRAMES:,}; choose a larger interval (--frame-every)")
        if len(o.times) > MAX_FRAMES:
            out.append(f"output.times lists {len(o.times):,} frames, more than {MAX_FRAMES:,}")
        pnames = [p.name for p in self.probes]
        dup_p = sorted({n for n in pnames if pnames.count(n) > 1})
        if dup_p:
            out.append(f"probe names must be unique (they are time-series columns), repeated: {dup_p}")
        return out

    def _scheme_problems(self, groups: dict[type[Solver], list[Body]]) -> list[str]:
        out: list[str] = []
        seen: dict[Any, str] = {}
        for sc in self.schemes:
            if not isinstance(sc, Scheme):
                out.append(f"unknown scheme {sc!r}: schemes must be Scheme instances (FluidScheme, water(...), "
                           "StructureScheme)")
                continue
            try:
                cls = import_class(sc.solver)
            except (ImportError, AttributeError) as err:
                out.append(f"{type(sc).__name__} names a solver that cannot be imported ({err})")
                continue
            if cls in seen:
                out.append(f"two schemes for one solver ({seen[cls]} and {type(sc).__name__}); list one")
            seen[cls] = type(sc).__name__
            if groups and cls not in groups:
                out.append(f"{type(sc).__name__} is listed but no body is advanced by its solver "
                           f"({getattr(cls, '__name__', cls)}); add its bodies (a FluidBody for a FluidScheme) or "
                           "remove the scheme")
            out.extend(sc.problems())
        return out

    def validate(self) -> None:
        """Raise :class:`SceneError` listing every problem, or return if the scene can run."""
        problems = self.problems()
        if problems:
            lines = "\n".join(f"  - {p}" for p in problems)
            n = len(problems)
            raise SceneError(f"scene {self.name!r} has {n} problem{'s' if n > 1 else ''}:\n{lines}")


def _looks_like_effect(x: Any) -> bool:
    """An item of the old ``effects`` list (a fluid effect: it has stages)."""
    return hasattr(x, "stages")


def _legacy_schemes(bodies: list, listed: list, effects: Sequence | None, options: dict[str, Any]) -> list:
    """The schemes of the form before schemes: ``Scene(bodies, effects, approximation=...,
    integrator=..., mass=..., dt_max=..., safety=...)``, with a warning that shows the new form."""
    if effects is None:
        effects = listed
    schemes: list = []
    shown = ", ".join(f"{k}=..." for k in _LEGACY_OPTIONS if k in options)
    warnings.warn(
        "Scene(bodies, effects, ...) with the fluid's options on the scene is deprecated and will be removed in the "
        "next release; write Scene(bodies, schemes=[FluidScheme(effects" + (", " + shown if shown else "") + ")], "
        "t_end=...) — or water(...) for the recommended set — and StructureScheme(dt_max=...) for the structures "
        "(CHANGELOG.md)", DeprecationWarning, stacklevel=3)
    fluid_options = {k: v for k, v in options.items() if v is not None}
    fluid = import_class(_LEGACY_FLUID_SCHEME)
    fluid_solver = import_class(fluid.solver)
    if effects or any(isinstance(b, Body) and solver_class(b) is fluid_solver for b in bodies):
        schemes.insert(0, fluid(list(effects), **fluid_options))
    if options.get("dt_max") is not None:
        structure = import_class(_LEGACY_STRUCTURE_SCHEME)
        target = import_class(structure.solver)
        if any(isinstance(b, Body) and solver_class(b) is target for b in bodies):
            schemes.append(structure(dt_max=options["dt_max"]))
    return schemes
