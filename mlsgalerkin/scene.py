r"""A :class:`Scene` lists bodies, effects, interactions, end time, outputs, probes and monitors;
it is validated as a whole before step 1, and every problem is reported at once in one
:class:`SceneError`.

Bodies are advanced by the solver their class names (fluid and wall bodies by the
:class:`~mlsgalerkin.fluid.solver.FluidSolver`); ``effects`` are the units of physics of the
fluid (nothing unlisted is computed); ``interactions`` exchange forces between bodies;
``approximation``, ``integrator``, ``mass``, ``safety`` and ``dt_max`` are the particle
solver's options.

>>> from mlsgalerkin.fluid import FluidBody, Phase, Gravity
>>> water = FluidBody.block("water", (0, 0), (0.1, 0.05), 0.01, [Phase("water", 1000.0)])
>>> scene = Scene([water], [Gravity()], t_end=0.1)
>>> try:
...     scene.validate()
... except SceneError as err:
...     print(err)
scene 'scene' has 1 problem:
  - no pressure model: list exactly one of TaitPressure (...)
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from mlsgalerkin.approximation.settings import Approximation
from mlsgalerkin.dynamics import Body, Interaction, Solver
from mlsgalerkin.monitors import Monitor, Output, Probe, Watchdog

__all__ = ["MAX_FRAMES", "Approximation", "Output", "Probe", "Scene", "SceneError", "Watchdog", "solver_class"]

#: The most VTU frames a scene may ask for (a frame of 10⁵ particles is about 5 MB).
MAX_FRAMES = 20_000


class SceneError(ValueError):
    """A scene cannot run; the message lists every problem found."""


def solver_class(body: Body) -> type[Solver]:
    """The :class:`~mlsgalerkin.dynamics.Solver` class that advances ``body`` (its ``solver``
    attribute: a class, or ``"module:Class"``)."""
    spec = body.solver
    if isinstance(spec, str):
        module, _, name = spec.partition(":")
        return getattr(importlib.import_module(module), name)
    return spec


@dataclass
class Scene:
    """Bodies, effects, interactions, end time, outputs, probes and monitors of a simulation.

    Parameters
    ----------
    bodies : list of Body
        Fluid bodies, wall bodies (and, with their solvers, other kinds); unique names.
    effects : list of Effect
        The physics of the fluid (:mod:`mlsgalerkin.fluid`); exactly one pressure model.
    t_end : float
        End time (s).
    name : str
        Used in file names, titles and ``summary.json``.
    approximation, integrator, mass, dt_max, safety
        The particle solver's options (:class:`Approximation`; ``"kdk"`` or
        ``"predictor_corrector"``; ``"lumped"``, ``"particle"`` or ``"consistent"``; the
        largest time step in s; a factor on the stable time step).
    output : Output
        Frames, time-series sampling, checkpoints and pictures.
    probes : list of Probe
        Scalars recorded in ``timeseries.csv``.
    watchdog : Watchdog
        Limits beyond which a run is stopped with a diagnosis.
    interactions : list of Interaction
        Force exchanges between bodies (penalty contact), evaluated every step.
    monitors : list of Monitor
        Extra monitors, after the standard ones.
    parameters : dict
        Copied into ``summary.json`` and the checkpoints (the problem's parameters).
    """

    bodies: list
    effects: list
    t_end: float
    name: str = "scene"
    approximation: Approximation = field(default_factory=Approximation)
    integrator: Any = "kdk"
    mass: str = "lumped"
    dt_max: float | None = None
    safety: float = 1.0
    output: Output = field(default_factory=Output)
    probes: Sequence[Probe] = ()
    watchdog: Watchdog = field(default_factory=Watchdog)
    interactions: Sequence[Interaction] = ()
    monitors: Sequence[Monitor] = ()
    parameters: dict = field(default_factory=dict)

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

    # ------------------------------------------------------------------ validation
    def problems(self) -> list[str]:
        """Every problem with this scene (empty list if it can run)."""
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
        takes_effects = any(getattr(cls, "takes_effects", False) for cls in groups)
        if self.effects and groups and not takes_effects:
            out.append("effects are listed but no body is advanced by a solver that runs effects; add a FluidBody")
        for cls, bodies in groups.items():
            out.extend(cls.problems(bodies, self))
        for i in self.interactions:
            if not isinstance(i, Interaction):
                out.append(f"unknown interaction {i!r}: interactions must be Interaction instances")
            else:
                out.extend(i.problems(self))
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

    def validate(self) -> None:
        """Raise :class:`SceneError` listing every problem, or return if the scene can run."""
        problems = self.problems()
        if problems:
            lines = "\n".join(f"  - {p}" for p in problems)
            n = len(problems)
            raise SceneError(f"scene {self.name!r} has {n} problem{'s' if n > 1 else ''}:\n{lines}")
